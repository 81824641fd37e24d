"""The ``omitted`` note on the forcing's velocity-quadratic part (codegen.forcing_notes):
terms that are products of sums are expanded in the velocities only, coefficients kept
whole, so cancellations of velocity monomials are seen; a velocity inside a function
makes the count a bound ("at least")."""

from __future__ import annotations

import sympy as sp

from symmech.codegen.forcing_notes import forcing_notes

q = sp.symbols("q0:3")
v = sp.symbols("v0:3")


def _zeros(note: str) -> tuple[bool, int]:
    bound = note.startswith("forcing: at least ")
    return bound, int(note.removeprefix("forcing: ").removeprefix("at least ").split()[0])


def test_products_of_sums_are_expanded_in_the_velocities_and_cancel():
    # (v0 + v1)(v0 - v1) cos(q0)^3: v0^2 and v1^2 stay, v0 v1 cancels; 2 of 18 present
    cancel = (v[0] + v[1]) * (v[0] - v[1]) * sp.cos(q[0]) ** 3
    f = sp.Matrix([cancel, sp.sin(q[1]) * v[2] ** 2 + q[2], 0])
    notes = forcing_notes(f, v, False)
    assert _zeros(notes[0]) == (False, 18 - 3)
    assert notes[1].startswith("forcing: entries [2] are identically zero")


def test_a_coefficient_repeated_in_two_sums_cancels_as_the_same_part():
    c = sp.cos(q[0] + q[1]) ** 2 + sp.sin(q[2])
    # one term: c^2 v0^2 - v1^2, the v0 v1 products cancel (c stands for the same part)
    f = sp.Matrix([(c * v[0] + v[1]) * (c * v[0] - v[1]) * sp.exp(q[2]), 0, 0])
    assert _zeros(forcing_notes(f, v, True)[0]) == (False, 18 - 2)
    # a velocity in a denominator: every pair of the term's velocities, as a bound
    f = sp.Matrix([v[1] * (v[2] + c * v[0] * v[2] / v[1]), 0, 0])
    assert _zeros(forcing_notes(f, v, False)[0]) == (True, 18 - 6)


def test_a_velocity_inside_a_function_counts_every_pair_of_its_velocities():
    f = sp.Matrix([sp.sin(v[0]) * v[1] * sp.cos(q[0]), 0, v[2] ** 2])
    # entry 0: (0,0), (0,1), (1,1) as a bound; entry 2: (2,2)
    assert _zeros(forcing_notes(f, v, False)[0]) == (True, 18 - 4)


def test_numbers_that_are_not_rational_are_coefficients_like_any_other():
    # pi, E, I, floats: parts of the coefficients (sympy's ring over QQ takes none of them)
    for c in (sp.pi, sp.E, sp.I, sp.Float(0.25)):
        f = sp.Matrix([c * (v[0] + c * v[1]) * (v[0] - c * v[1]), 0, 0])
        assert _zeros(forcing_notes(f, v, False)[0]) == (False, 18 - 2), c
