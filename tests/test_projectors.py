"""Projector identities of the Carnot paper, section 2.2, on several scenes and on random
metrics and constraints (hypothesis): P^2 = P, P is g-self-adjoint (g P = P^T g), the
constraints annihilate P v (mu P = 0), P + Q = I, and Q = C_ab Z^a (x) mu^b computed here
from its definition (Z^a = g^-1 mu^a, C^ab = mu^a g^-1 mu^b)."""

from __future__ import annotations

import random

import pytest
import sympy as sp
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import symmech as sm
from symmech.examples import car, carnot_3_13, rolling_ball


def _points(symbols, seed: int = 3, count: int = 3):
    """Random rational points: the identities are checked there in exact arithmetic
    (entries with sin/cos are evaluated to 40 digits)."""
    rng = random.Random(seed)
    for _ in range(count):
        yield {s: sp.Rational(rng.randint(3, 29), rng.randint(7, 13)) for s in symbols}


def _vanishes(M: sp.MatrixBase) -> bool:
    for e in M:
        if e.is_Rational:
            if e != 0:
                return False
        elif abs(sp.N(e, 40)) > sp.Float(10) ** -30:
            return False
    return True


def assert_projector_identities(g, mu, P, Q, symbols):
    """Substitute a point first, then check each identity there; Q is compared with
    Z C^-1 mu formed independently from g and mu at the same point."""
    n = g.rows
    for pt in _points(symbols):
        g0, mu0, P0, Q0 = (sp.Matrix(M).xreplace(pt) for M in (g, mu, P, Q))
        assert _vanishes(P0 * P0 - P0), "P^2 != P"
        assert _vanishes(g0 * P0 - P0.T * g0), "P is not g-self-adjoint"
        assert _vanishes(mu0 * P0), "mu(P v) != 0"
        assert _vanishes(P0 + Q0 - sp.eye(n)), "P + Q != I"
        Z = g0.LUsolve(mu0.T)  # columns Z^a = g^-1 mu^a
        C = mu0 * Z  # C^ab
        assert _vanishes(Q0 - Z * C.LUsolve(mu0)), "Q != C_ab Z^a (x) mu^b"


@pytest.mark.parametrize("build", [car, carnot_3_13, rolling_ball])
def test_projector_identities_on_builtin_scenes(build):
    scene = build()
    P, Q = scene.projectors()
    symbols = [*scene.coordinates, *scene.parameters]
    assert_projector_identities(scene.mass_matrix(), scene.constraint_matrix, P, Q, symbols)


Q3 = sm.coordinates("q1 q2 q3 q4")
small = st.integers(-3, 3)
entry = st.tuples(small, small, st.sampled_from([0, 1, 2])).map(
    lambda c: c[0] + c[1] * Q3[c[2]]  # constant or linear in a coordinate
)


@st.composite
def systems(draw):
    n = draw(st.integers(2, 4))
    m = draw(st.integers(1, n - 1))
    A = sp.Matrix(n, n, draw(st.lists(entry, min_size=n * n, max_size=n * n)))
    g = (A.T * A + sp.eye(n)).applyfunc(sp.expand)  # symmetric positive definite for all q
    rows = draw(st.lists(st.lists(small, min_size=n, max_size=n), min_size=m, max_size=m))
    mu = sp.Matrix(rows)
    mu[0, 0] += Q3[0]  # a q-dependent (possibly non-holonomic) one-form
    return n, g, mu


@settings(max_examples=25, deadline=None, derandomize=True)
@given(systems())
def test_projector_identities_on_random_metrics_and_constraints(system):
    n, g, mu = system
    q = Q3[:n]
    # constraints must be independent at generic points; hypothesis discards draws that are not
    pt = {s: sp.Rational(i + 2, 7) for i, s in enumerate(Q3)}
    assume(mu.xreplace(pt).rank() == mu.rows)
    qd = sm.velocities(q)
    constraints = [sum(mu[a, j] * qd[j] for j in range(n)) for a in range(mu.rows)]
    scene = sm.Scene(q, metric=g, constraints=constraints)
    P, Q = scene.projectors()
    assert_projector_identities(g, mu, P, Q, list(Q3))
