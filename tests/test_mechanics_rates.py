"""The import's fast kinematics (symmech.mechanics.rates) and the stable step's quick
factorisation give the very expressions of sympy's own routes: partial velocities
(``Vector.diff``), accelerations with u_dot = 0 (``Vector.dt`` then substitution), dot
products (``Vector.dot``) and ``sympy.factor``."""

from __future__ import annotations

import random

import sympy as sp
from sympy.physics import mechanics as me

from symmech.algebra.stability import _evidently_irreducible
from symmech.geometry.derivatives import Derivative
from symmech.mechanics.rates import (
    TimeDerivative,
    dyadic_dot,
    expanded_dots,
    speed_partials,
    time_derivative,
    vector_cross,
    vector_dot,
)

T = me.dynamicsymbols._t


def _rolling_disc():
    """A disc rolling on its contact point (sympy's test_kane.py::test_rolling_disc
    kinematics): velocities in three frames, q_dot = u through kinematic equations."""
    q1, q2, q3, u1, u2, u3 = me.dynamicsymbols("q1 q2 q3 u1 u2 u3")
    r = sp.Symbol("r")
    N = me.ReferenceFrame("N")
    Y = N.orientnew("Y", "Axis", [q1, N.z])
    L = Y.orientnew("L", "Axis", [q2, Y.x])
    R = L.orientnew("R", "Axis", [q3, L.y])
    R.set_ang_vel(N, u1 * L.x + u2 * L.y + u3 * L.z)
    C = me.Point("C")
    C.set_vel(N, 0)
    Dmc = C.locatenew("Dmc", r * L.z)
    Dmc.v2pt_theory(C, N, R)
    P = Dmc.locatenew("P", r * sp.cos(q2) * R.x + r**2 * Y.y)
    P.v2pt_theory(Dmc, N, R)
    speeds = [u1, u2, u3]
    rates = {q1: u1 + u2 * q2, q2: u2, q3: sp.sin(q1) * u3}
    return N, [Dmc.vel(N), R.ang_vel_in(N), P.vel(N)], speeds, rates


def test_partials_time_derivatives_and_dots_are_sympys():
    N, vectors, speeds, rates = _rolling_disc()
    plain = [sp.Dummy(str(w)) for w in speeds]
    D = Derivative(plain)
    d = TimeDerivative(rates, set(speeds), T)
    still = {w.diff(T): 0 for w in speeds}
    qdot = {q.diff(T): r for q, r in rates.items()}
    for vec in vectors:
        fast = speed_partials(vec, dict(zip(speeds, plain, strict=True)), D)
        assert fast == [vec.diff(w, N, var_in_dcm=False) for w in speeds]
        expected = vec.dt(N).xreplace(still).xreplace(qdot)
        assert time_derivative(vec, N, d).xreplace(qdot) == expected
        for other in vectors:
            assert vector_dot(vec, other) == (vec & other)


def test_time_derivative_leaves_other_time_dependence_to_sympy():
    N, vectors, speeds, rates = _rolling_disc()
    tau = me.dynamicsymbols("tau")
    vec = vectors[0] + tau * N.x + T * N.y
    d = TimeDerivative(rates, set(speeds), T)
    still = {w.diff(T): 0 for w in speeds}
    qdot = {q.diff(T): r for q, r in rates.items()}
    assert time_derivative(vec, N, d) == vec.dt(N).xreplace(still).xreplace(qdot)


def test_evidently_irreducible_polynomials_factor_as_sympy_writes_them():
    xs = sp.symbols("a b c d e")
    gens = [*xs, sp.sin(xs[0]), sp.cos(xs[1])]
    rng = random.Random(3)
    quick = 0
    for _ in range(600):
        e = sp.S.Zero
        for _ in range(rng.randint(1, 5)):
            term = sp.Integer(rng.choice([1, -1, 2, -3, 6]))
            for g in rng.sample(gens, rng.randint(0, 3)):
                term *= g ** rng.randint(1, 3)
            e += term
        if rng.random() < 0.3:
            e = sp.expand(e * rng.choice(gens) * rng.choice([1, -2]))
        if rng.random() < 0.2:
            e = sp.expand(e * (xs[0] + xs[1]))
        got = _evidently_irreducible(e)
        if got is not None:
            quick += 1
            assert got == sp.factor(e), e
    assert quick > 200  # the quick path is taken often
    a, b = xs[:2]
    assert _evidently_irreducible(sp.expand((a + b) * (a - b))) is None  # not evident
    e = -6 * a * b**2 - 2 * b  # -2 b (3 a b + 1): a is of degree one, in one term
    assert _evidently_irreducible(e) == sp.factor(e) == -2 * b * (3 * a * b + 1)


def test_expanded_dots_are_sympys_expansions():
    N, vectors, _, _ = _rolling_disc()
    pairs = [(a, b) for a in vectors for b in vectors]
    assert expanded_dots(pairs) == [sp.expand(a & b) for a, b in pairs]
    # a float (or a function whose argument expand would change) takes sympy's route
    x = sp.Symbol("x")
    odd = [(vectors[0], 0.5 * N.x + sp.sin(2 * (x + 1)) * N.y), (vectors[1], N.z)]
    assert expanded_dots(odd) == [sp.expand(a & b) for a, b in odd]


def test_cross_products_and_dyadic_dots_are_sympys():
    N, vectors, _, _ = _rolling_disc()
    inertia = me.inertia(N, 1, 2, 3, sp.Symbol("ixy"), 0, sp.Symbol("izx"))
    for a in vectors:
        assert dyadic_dot(inertia, a) == (inertia & a)
        for b in [*vectors, me.Vector(0)]:
            assert vector_cross(a, b) == (a ^ b)
