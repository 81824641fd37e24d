"""The round trip over the table of models (:mod:`mechanics_table`): each model, built
as sympy's tests and docstrings, ``sympy.physics.mechanics.models`` and PyDy's examples
build it, imports and agrees with its own ``mass_matrix_full \\ forcing_full`` at random
states to 1e-9 (the generated C too, for the entries marked ``c``), or is refused with
the reason the table lists.  ``benchmarks/mechanics_roundtrip.py`` prints the counts."""

from __future__ import annotations

import pytest
from codegen_support import require_c_compiler
from mechanics_entry import judge
from mechanics_table import TABLE


def _cases(entries, slow_mark: bool = True):
    return [
        pytest.param(e, id=e.name, marks=[pytest.mark.slow] if e.slow and slow_mark else [])
        for e in entries
    ]


def test_the_table_holds_about_fifty_models_each_with_its_source():
    assert len(TABLE) >= 50
    assert len({e.name for e in TABLE}) == len(TABLE)
    assert all(e.source for e in TABLE)
    # refusals and imports both present, each reason a specific message
    assert 5 <= sum(e.refused is not None for e in TABLE) < len(TABLE) / 2


@pytest.mark.parametrize("entry", _cases(TABLE))
def test_each_model_imports_and_agrees_or_is_refused_with_its_reason(entry):
    outcome = judge(entry)
    expected = "imported" if entry.refused is None else "refused"
    assert outcome.kind == expected, outcome.what


@pytest.mark.parametrize("entry", _cases([e for e in TABLE if e.c]))
def test_the_generated_c_agrees_with_the_models_own_equations(entry):
    require_c_compiler()
    outcome = judge(entry, c=True)
    assert outcome.kind == "imported", outcome.what
