"""Every model of sympy's mechanics tests, docstring examples and
``sympy.physics.mechanics.models`` that builds with the installed sympy
(:func:`mechanics_harvest.harvest`; test classes' methods that need no pytest fixture,
such as ``TestSystemExamples``, included) imports and agrees with the model's own
``mass_matrix_full \\ forcing_full`` at random states to 1e-9, or is refused with the
reason listed here.

Two models are left to other tests: the Whipple bicycle (``test_kane3::test_bicycle``,
whose sympy test takes 100 s; ``tests/test_bicycle.py`` imports the same model) and
``test_kane::test_issue_24887`` (its test simplifies for 9 s;
``tests/test_mechanics_loads.py`` builds the same model).  Run with ``-s`` to see the
table and the counts.
"""

from __future__ import annotations

import re
import warnings

import pytest
from mechanics_harvest import harvest
from mechanics_support import round_trip

pytestmark = pytest.mark.slow

SKIP = ("test_kane3::test_bicycle", "test_kane::test_issue_24887")

_AUXILIARY = r"KanesMethod\.u_auxiliary \[.*\]: auxiliary speeds .* not supported"
#: source -> the reason it is refused (a regular expression its message must match)
REFUSED = {
    # u_auxiliary: speeds for constraint forces, a known limit
    "test_kane::test_aux#1": _AUXILIARY,
    "test_kane2::test_aux_dep#0": _AUXILIARY,
    "test_kane2::test_non_central_inertia#0": _AUXILIARY,
    "test_kane2::test_sub_qdot#0": _AUXILIARY,
    "test_system_class::TestSystemExamples::test_box_on_ground#0": (
        r"System\.u_aux \[ua\(t\)\]: auxiliary speeds are not supported"
    ),
    # a unit quaternion: 7 coordinates, 6 speeds
    "test_kane::test_implicit_kinematics#0": r"7 coordinates .* and only 6 speeds: .* quaternion",
    # generalized active forces only: kanes_equations([], forces)
    "test_kane2::test_sub_qdot2#0": r"the model has no bodies",
    "test_kane2::test_sub_qdot2#1": r"the model has no bodies",
    # the velocity constraint sqrt((q1**2 + q2**2)/q1**2) q1 ...: sign(q1), not smooth
    "test_linearize::test_linearize_pendulum_kane_nonminimal#0": (
        r"a velocity or configuration constraint \(KanesMethod\.velocity_constraints"
        r" / configuration_constraints\) contains the non-smooth functions \['Abs'\]"
    ),
    # Coulomb friction: sign(v)
    "actuator docstring sympy.physics.mechanics.actuator.CoulombKineticFriction#0": (
        r"the load on O contains the non-smooth functions \['Abs', 'sign'\]"
    ),
}
TOLERANCE = 1e-9


def test_every_sympy_model_imports_right_or_is_refused_with_its_reason():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        found, _ = harvest(skip=SKIP)
        outcomes = {h.source: round_trip(h.model, name="model") for h in found}
    assert set(REFUSED) <= set(outcomes), set(REFUSED) - set(outcomes)
    imported = [s for s, (kind, _) in outcomes.items() if kind == "imported"]
    refused = [s for s in outcomes if s in REFUSED and outcomes[s][0] == "refused"]
    wrong = {
        s: what
        for s, (kind, what) in outcomes.items()
        if (kind == "imported" and (s in REFUSED or not what < TOLERANCE))
        or (kind == "refused" and not (s in REFUSED and re.search(REFUSED[s], what)))
    }
    for source, (kind, what) in outcomes.items():
        print(f"{kind:9s} {source}: {what}")
    print(
        f"sympy models: {len(outcomes)}; imported and agreeing to {TOLERANCE}: {len(imported)};"
        f" refused with the listed reason: {len(refused)}; wrong: {len(wrong)}"
    )
    assert not wrong, wrong
    assert len(outcomes) >= 74  # the harvest still finds sympy's models
