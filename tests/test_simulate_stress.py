"""Stiff and extreme cases of the simulator (symmech.bench.stress): every case passes.

Each case measures an error against a reference that is not the simulator (closed form,
conserved quantity, exact property of the impact law) and fails on NaN, Inf or
tunnelling; the slow ones (10^4 bounces, k = 1e8 with an explicit method in Python) run in
benchmarks/slow_tests.sh and ``symmech stress``.
"""

from __future__ import annotations

import pytest

from symmech.bench import stress

FAST = ["mass_ratio", "aspect_ratio", "grazing", "nearly_dependent", "zeno", "cradle"]


@pytest.mark.parametrize("name", FAST)
def test_stress_case_passes_on_the_scipy_route(name):
    results = stress.run_all("scipy", [name])
    assert results
    failed = [r for r in results if not r.passed]
    assert not failed, stress.format_table(failed)


def test_nearly_dependent_wall_error_follows_the_condition_number_then_is_refused():
    results = stress.run_all("scipy", ["nearly_dependent"])
    measured = [r for r in results if r.error == r.error]  # not NaN: an impact was applied
    refused = [r for r in results if r.error != r.error]
    assert len(measured) >= 3 and len(refused) >= 1
    assert all("nearly dependent" in r.detail for r in refused)
    errors = [r.error for r in measured]
    assert errors == sorted(errors)  # grows as the wall turns towards the constraint


@pytest.mark.slow
@pytest.mark.parametrize("name", ["stiff", "elastic_bounces"])
def test_slow_stress_case_passes(name):
    results = stress.run_all("scipy", [name])
    assert all(r.passed for r in results), stress.format_table(results)


CONTACTS = ["ladder", "rod_flat", "box_corner", "disc_stack", "cradles", "touching_rest"]


@pytest.mark.parametrize("name", CONTACTS)
def test_contact_stress_case_passes_on_the_c_loop(name):
    """Several contacts at once (symmech.bench.stress_contacts) on the C loop."""
    results = stress.run_all("c", [name])
    assert results
    failed = [r for r in results if not r.passed]
    assert not failed, stress.format_table(failed)


@pytest.mark.parametrize(
    "name",
    [
        "ladder",
        "rod_flat",
        "touching_rest",
        pytest.param("box_corner", marks=pytest.mark.slow),
        pytest.param("disc_stack", marks=pytest.mark.slow),
        pytest.param("cradles", marks=pytest.mark.slow),
    ],
)
def test_contact_stress_case_passes_on_the_numpy_loop(name):
    results = stress.run_all("numpy", [name])
    failed = [r for r in results if not r.passed]
    assert results and not failed, stress.format_table(failed)
