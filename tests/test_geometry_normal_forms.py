"""Exact normal forms of the geometry layer: Christoffel symbols of the second kind by a
fraction-free adjugate, the Pythagorean reduction (sin^2 -> 1 - cos^2), and the textbook
forms it yields.

Independent routes used here: the pendulum-on-cart metric rebuilt from the positions of
its masses (g = sum_b m_b J_b^T J_b), differentiated by sympy and inverted numerically by
mpmath at 40 digits; Euler's equations of a rigid body; the car's projector
``P = X1 X1^T g / g(X1, X1) + e4 e4^T`` (X1 = (cos, sin, kappa, 0) is g-orthogonal to
e4); sympy's own determinant and adjugate (Berkowitz).  Nothing expected is read off
symmech.
"""

from __future__ import annotations

import itertools
import random

import mpmath
import pytest
import sympy as sp

import symmech as sm
from symmech.algebra import budget
from symmech.algebra.budget import BudgetExceeded
from symmech.algebra.field import RationalField, field_solve
from symmech.algebra.laplace import adjugate_det
from symmech.algebra.simplification import normal_form
from symmech.examples import car, pendulum_on_cart

DPS = 40
TOL = mpmath.mpf(10) ** -30

# ------------------------------------------------------------------------------ helpers


def pendulum_metric(scene: sm.Scene) -> sp.Matrix:
    """g = sum_b m_b J_b^T J_b from the positions of the cart and the bobs (angles q_i
    from the downward vertical, link lengths l_i, bob masses m_{i+1})."""
    q = scene.coordinates
    links = len(q) - 1
    by_name = {s.name: s for s in scene.parameters}
    m = [by_name[f"m{i}"] for i in range(links + 1)]
    l = [by_name[f"l{i}"] for i in range(links)]
    positions = [(q[0], sp.S.Zero)]
    x, y = q[0], sp.S.Zero
    for i in range(links):
        x, y = x + l[i] * sp.sin(q[i + 1]), y - l[i] * sp.cos(q[i + 1])
        positions.append((x, y))
    g = sp.zeros(links + 1, links + 1)
    for mass, (px, py) in zip(m, positions, strict=True):
        J = sp.Matrix([[sp.diff(px, a) for a in q], [sp.diff(py, a) for a in q]])
        g += mass * J.T * J
    return g


def mp_matrix(M: sp.Matrix, symbols, values) -> mpmath.matrix:
    f = sp.lambdify(symbols, M, "mpmath")
    return mpmath.matrix(f(*values).tolist())


def random_values(symbols, rng: random.Random) -> list:
    return [mpmath.mpf(rng.randint(1, 60)) / 17 for _ in symbols]


def reference_christoffel(g: sp.Matrix, q, symbols, values) -> list:
    """Gamma^k_ij = g^kl Gamma_lij at a point: first kind differentiated by sympy, the
    inverse by mpmath (40 digits)."""
    n = len(q)
    first = [
        [
            [
                (sp.diff(g[j, k], q[i]) + sp.diff(g[i, k], q[j]) - sp.diff(g[i, j], q[k])) / 2
                for j in range(n)
            ]
            for i in range(n)
        ]
        for k in range(n)
    ]
    ginv = mp_matrix(g, symbols, values) ** -1
    low = [mp_matrix(sp.Matrix(first[k]), symbols, values) for k in range(n)]
    return [
        [[sum(ginv[k, l] * low[l][i, j] for l in range(n)) for j in range(n)] for i in range(n)]
        for k in range(n)
    ]


def no_pythagorean_sum(e: sp.Expr) -> bool:
    """False when sin(a)^2 and cos(a)^2 of one argument occur together in the numerator
    or in the denominator (a form that the normal form must have reduced)."""
    for part in sp.fraction(e):
        squares = {p.base for p in part.atoms(sp.Pow) if p.exp.is_Integer and p.exp >= 2}
        if any(isinstance(b, sp.sin) and sp.cos(b.args[0]) in squares for b in squares):
            return False
    return True


# ------------------------------------------------------- Christoffel symbols, pendulum


@pytest.mark.parametrize("links", [1, 2, 3, 4])
def test_pendulum_christoffel_second_kind_exact(links):
    mpmath.mp.dps = DPS
    scene = pendulum_on_cart(links)
    q, n = scene.coordinates, scene.n
    g = pendulum_metric(scene)
    gamma = scene.christoffel()  # the API default: kind 2, "light"
    assert gamma.shape == (n, n, n)
    symbols = [*q, *scene.parameters]
    values_fn = sp.lambdify(symbols, sp.Array(gamma).tolist(), "mpmath")
    rng = random.Random(100 + links)
    for _ in range(3):
        values = random_values(symbols, rng)
        # the scene's metric is the one of the positions (checked against Kane elsewhere)
        diff = mp_matrix(sp.Matrix(scene.mass_matrix()) - g, symbols, values)
        assert mpmath.mnorm(diff, 1) < TOL
        ours = values_fn(*values)
        ref = reference_christoffel(g, q, symbols, values)
        for k, i, j in itertools.product(range(n), repeat=3):
            scale = 1 + abs(ref[k][i][j])
            assert abs(ours[k][i][j] - ref[k][i][j]) < TOL * scale, (k, i, j)
    for k, i, j in itertools.product(range(n), repeat=3):
        assert gamma[k, i, j] == gamma[k, j, i]
        assert no_pythagorean_sum(gamma[k, i, j]), (k, i, j)


def test_pendulum_acceleration_exact():
    mpmath.mp.dps = DPS
    for links in (1, 2, 3):
        scene = pendulum_on_cart(links)
        acc = scene.acceleration()
        symbols = [*scene.coordinates, *scene.velocities, *scene.parameters]
        rng = random.Random(7 * links)
        for _ in range(2):
            values = random_values(symbols, rng)
            g = mp_matrix(sp.Matrix(scene.mass_matrix()), symbols, values)
            f = mp_matrix(sp.Matrix(scene.forcing()), symbols, values)
            ref = mpmath.lu_solve(g, f)
            ours = mp_matrix(sp.Matrix(acc), symbols, values)
            for k in range(scene.n):
                assert abs(ours[k] - ref[k]) < TOL * (1 + abs(ref[k])), (links, k)
        assert all(no_pythagorean_sum(e) for e in acc)


def test_fallback_beyond_the_term_budget_is_exact(monkeypatch):
    # With a tiny budget the solve declines and the symbols are the LU solution: exact.
    mpmath.mp.dps = DPS
    monkeypatch.setattr(budget, "FIELD_MINOR_TERMS", 5)
    scene = pendulum_on_cart(2)
    q = scene.coordinates
    gamma = scene.christoffel()
    symbols = [*q, *scene.parameters]
    values = random_values(symbols, random.Random(5))
    ours = sp.lambdify(symbols, sp.Array(gamma).tolist(), "mpmath")(*values)
    ref = reference_christoffel(pendulum_metric(scene), q, symbols, values)
    for k, i, j in itertools.product(range(scene.n), repeat=3):
        assert abs(ours[k][i][j] - ref[k][i][j]) < TOL * (1 + abs(ref[k][i][j]))
    g = sp.Matrix(scene.mass_matrix())
    assert field_solve(g, sp.eye(3)) is None


# -------------------------------------------------------------- textbook normal forms


def test_rigid_body_is_exactly_euler():
    phi, theta, psi = sm.coordinates("phi theta psi")
    w = sp.symbols("w1:4", real=True)
    I1, I2, I3 = sp.symbols("I1:4", positive=True)
    s, c = sp.sin, sp.cos
    # (phi_dot, theta_dot, psi_dot) = S Omega for ZXZ Euler angles (Goldstein 4.125)
    S = sp.Matrix(
        [
            [s(psi) / s(theta), c(psi) / s(theta), 0],
            [c(psi), -s(psi), 0],
            [-s(psi) * c(theta) / s(theta), -c(psi) * c(theta) / s(theta), 1],
        ]
    )
    scene = sm.Scene((phi, theta, psi), metric=sp.diag(I1, I2, I3), frame=S, quasi_velocities=w)
    cc = scene.commutation_coefficients()
    for m, k, l in itertools.product(range(3), repeat=3):
        assert cc[m, k, l] == sp.LeviCivita(k, l, m), (m, k, l)  # structurally
    acc = scene.acceleration()
    euler = [
        (I2 - I3) * w[1] * w[2] / I1,
        (I3 - I1) * w[2] * w[0] / I2,
        (I1 - I2) * w[0] * w[1] / I3,
    ]
    for k in range(3):
        assert sp.expand(acc[k]) == sp.expand(euler[k]), k  # expanded: a canonical form
        assert not acc[k].has(sp.sin, sp.cos)
    assert sp.count_ops(acc) <= 15


def test_car_projector_is_the_textbook_one():
    scene = car()
    _x, _y, th, kap = scene.coordinates
    m, J, cc = (next(s for s in scene.parameters if s.name == n) for n in ("m", "J", "c"))
    g = sp.diag(m, m, J, cc)
    X1 = sp.Matrix([sp.cos(th), sp.sin(th), kap, 0])
    e4 = sp.Matrix([0, 0, 0, 1])
    expected = X1 * (X1.T * g) / (m + J * kap**2) + e4 * e4.T
    P, Q = scene.projectors()
    assert sp.expand(P - expected).is_zero_matrix  # no trig simplification needed
    pythagoras = {sp.sin(th) ** 2: 1 - sp.cos(th) ** 2}
    assert sp.expand((P + Q - sp.eye(4)).applyfunc(sp.together).subs(pythagoras)).is_zero_matrix
    assert sp.count_ops(P) <= 80
    for e in P:
        assert not sp.fraction(sp.together(e))[1].has(sp.sin, sp.cos)


# ---------------------------------------------------------------- the normal form


def test_normal_form_reduces_pythagorean_sums():
    a, b, m = sp.symbols("a b m", real=True)
    s, c = sp.sin(a), sp.cos(a)
    assert normal_form(m * s**2 + m * c**2) == m
    assert normal_form((s**2 + c**2) ** 3 - 1) == 0
    assert normal_form((1 - c**2) / s) == s
    assert normal_form(s**4 - c**4 - (s**2 - c**2)) == 0
    # different arguments are independent: nothing to reduce
    e = sp.sin(a) ** 2 + sp.cos(b) ** 2
    assert sp.expand(normal_form(e) - e) == 0


def test_normal_form_is_canonical_for_trig_polynomials():
    a, b, k = sp.symbols("a b k", real=True)
    gens = [sp.sin(a), sp.cos(a), sp.sin(b), sp.cos(b), k]
    rng = random.Random(3)
    mpmath.mp.dps = DPS
    for _ in range(10):
        p = sp.Add(
            *[
                rng.randint(-3, 3) * sp.Mul(*[gg ** rng.randint(0, 3) for gg in gens])
                for _ in range(4)
            ]
        )
        r = sp.Add(*[rng.randint(-2, 2) * gg for gg in gens])
        ideal = (sp.sin(a) ** 2 + sp.cos(a) ** 2 - 1) * r + (
            sp.sin(b) ** 2 + sp.cos(b) ** 2 - 1
        ) * k
        disguised = sp.expand(p + ideal)
        assert normal_form(disguised) == normal_form(sp.expand(p))
        # and the normal form is the same function (numerically, 40 digits)
        f1 = sp.lambdify((a, b, k), p, "mpmath")
        f2 = sp.lambdify((a, b, k), normal_form(disguised), "mpmath")
        pt = (mpmath.mpf(1) / 3, mpmath.mpf(5) / 7, mpmath.mpf(2))
        assert abs(f1(*pt) - f2(*pt)) < TOL * (1 + abs(f1(*pt)))


def test_field_solve_matches_sympy_on_polynomial_matrices():
    x, y = sp.symbols("x y")
    rng = random.Random(9)
    for n in (1, 2, 3, 4):
        A = sp.Matrix(n, n, lambda i, j: rng.randint(-3, 3) + rng.randint(0, 2) * x * y**j)
        A = A + sp.eye(n) * (5 + x**2)
        B = sp.Matrix(n, 2, lambda i, j: rng.randint(-3, 3) * x + j)
        X = field_solve(A, B)
        assert X is not None
        assert (A * X - B).applyfunc(sp.cancel).is_zero_matrix


def test_rational_field_blocks_and_diagonal():
    x, y = sp.symbols("x y", positive=True)
    A = sp.diag(sp.Matrix([[1 + x, y], [y, 2]]), x**2)
    B = sp.Matrix([[1], [x], [y]])
    X = field_solve(A, B)
    assert (A * X - B).applyfunc(sp.cancel).is_zero_matrix
    assert X[2] == y / x**2


# ---------------------------------------------------------------------- adjugate


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5])
def test_adjugate_det_matches_sympy(n):
    ring = RationalField([sp.Symbol("x"), sp.Symbol("y")])
    R = ring.K.field.ring
    x, y = R.gens
    rng = random.Random(n)
    pool = [R.one, x, y, x * y, x**2 - y, R.zero]
    A = [
        [rng.randint(-2, 2) * rng.choice(pool) + rng.choice(pool) for _ in range(n)]
        for _ in range(n)
    ]
    adj, det = adjugate_det(A, R.one)
    M = sp.Matrix(n, n, lambda i, j: A[i][j].as_expr())
    assert sp.expand(M.det(method="berkowitz") - det.as_expr()) == 0
    ours = sp.Matrix([[p.as_expr() for p in row] for row in adj])
    assert sp.expand(M.adjugate(method="berkowitz") - ours).is_zero_matrix


def test_adjugate_budget():
    ring = RationalField([sp.Symbol("x")])
    R = ring.K.field.ring
    x = R.gens[0]
    A = [[(x + i + j) ** 3 for j in range(4)] for i in range(4)]
    with pytest.raises(BudgetExceeded):
        adjugate_det(A, R.one, budget=10)


def test_rolling_sphere_rolls_uniformly():
    # Carnot paper ex. 3.13 without the wall: a homogeneous sphere rolling on a plane with
    # no potential moves uniformly (the contact force vanishes: v and omega are constant).
    # The frame S = B^-1 carries tan(theta); written with sin and cos and reduced, every
    # component of v_dot is exactly 0, and so is lambda.
    from symmech.examples import carnot_3_13

    scene = carnot_3_13()
    assert scene.acceleration() == sp.zeros(6, 1)
    assert scene.multipliers() == sp.zeros(3, 1)
