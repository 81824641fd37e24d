"""Shared helpers for the impact tests, and tests of the helpers themselves.

``impact_map(scene, wall, law)`` goes through ``Scene.impact_map`` (the public entry
point).  ``kkt(scene, wall, v_minus)`` is route (B): the impulse-momentum system built
here from the declaration alone (metric, constraint rows, d psi computed in this file),
solved by :func:`kkt_oracle.kkt_post_velocity` (tests/kkt_oracle.py), sharing no code with
the projector route.  ``basis_of_D(scene)`` parametrises D by a nullspace basis (not by
the projector P).
"""

from __future__ import annotations

import sympy as sp
from kkt_oracle import kkt_post_velocity

import symmech as sm


def impact_map(scene: sm.Scene, wall, law=None, **kwargs):
    """``scene.impact_map(wall, law=law, **kwargs)`` (e.g. ``wall_velocity=...``)."""
    return scene.impact_map(wall, law=law, **kwargs)


def wall_one_form(scene: sm.Scene, index: int) -> tuple[sp.Matrix, sp.Expr]:
    """(d psi in the velocity basis, d psi/d t), computed independently of symmech.impacts."""
    w = scene.walls[index]
    row = sp.Matrix([[sp.diff(w.psi, q) for q in scene.coordinates]])
    if scene.frame is not None:
        row = row * sp.Matrix(scene.frame)
    return row, sp.diff(w.psi, sm.t)


def kkt(scene: sm.Scene, index: int, v_minus, alpha=None, V=None) -> sp.Matrix:
    """Route (B): v+ from the impulse-momentum (KKT) system."""
    w = scene.walls[index]
    dpsi, psi_t = wall_one_form(scene, index)
    return kkt_post_velocity(
        scene.mass_matrix(),
        scene.constraint_matrix,
        dpsi,
        w.impulsive_matrix,
        sp.Matrix(v_minus),
        w.restitution if alpha is None else alpha,
        psi_t,
        V,
    )


def basis_of_D(scene: sm.Scene) -> sp.Matrix:
    """Columns spanning D = ker mu (a nullspace basis; the identity without constraints)."""
    mu = sp.Matrix(scene.constraint_matrix)
    if mu.rows == 0:
        return sp.eye(scene.n)
    return sp.Matrix.hstack(*[sp.simplify(c) for c in mu.nullspace()])


def general_element_of_D(scene: sm.Scene, name: str = "z") -> tuple[sp.Matrix, tuple]:
    """``(B z, z)``: the general element of D with fresh real symbols z."""
    B = basis_of_D(scene)
    z = sp.symbols(f"{name}0:{B.cols}", real=True)
    return B * sp.Matrix(z), z


def is_zero(expr) -> bool:
    expr = sp.sympify(expr)
    return expr == 0 or sp.simplify(sp.cancel(expr)) == 0


def test_kkt_route_reproduces_a_hand_computed_bounce():
    """A point mass m bouncing on y = 0 with restitution 1/2: v+ = (vx, -vy/2)."""
    x, y = sm.coordinates("x y")
    m = sp.Symbol("m", positive=True)
    scene = sm.Scene(
        (x, y), metric=sp.diag(m, m), walls=[sm.Wall(y, restitution=sp.Rational(1, 2))]
    )
    vx, vy = sp.symbols("vx vy", real=True)
    assert kkt(scene, 0, [vx, vy]) == sp.Matrix([vx, -vy / 2])


def test_basis_of_D_spans_the_constraint_kernel():
    x, y, th = sm.coordinates("x y theta")
    xd, _yd, thd = sm.velocities((x, y, th))
    R = sp.Symbol("R", positive=True)
    scene = sm.Scene((x, y, th), metric=sp.eye(3), constraints=[xd - R * thd])
    B = basis_of_D(scene)
    assert B.shape == (3, 2)
    assert (sp.Matrix(scene.constraint_matrix) * B).applyfunc(sp.simplify).is_zero_matrix


def kkt_at(scene: sm.Scene, index: int, point: dict, v_minus, dps: int = 40, V=None):
    """Route (B) numerically: the impulse-momentum system at a state ``point`` (values of
    q, t and the parameters), assembled from the declaration and solved with mpmath at
    ``dps`` digits.  For states where the entries are transcendental (sin of a rational)."""
    import mpmath as mp

    w = scene.walls[index]
    dpsi, psi_t = wall_one_form(scene, index)
    g = scene.mass_matrix()
    mu = sp.Matrix(scene.constraint_matrix)
    nu = sp.Matrix(w.impulsive_matrix)
    n, m, l = g.rows, mu.rows, nu.rows
    A = mu.col_join(dpsi).col_join(nu)
    alpha = sp.sympify(w.restitution).xreplace(point)

    def num(e) -> mp.mpf:
        return mp.mpf(sp.N(sp.sympify(e).xreplace(point), dps + 10))

    with mp.workdps(dps):
        G = mp.matrix([[num(g[i, j]) for j in range(n)] for i in range(n)])
        rows = [[num(A[i, j]) for j in range(n)] for i in range(A.rows)]
        vm = [num(e) for e in v_minus]
        pt = num(psi_t)

        def form(row: list, x: list) -> mp.mpf:
            return mp.fsum(a * b for a, b in zip(row, x, strict=True))

        if V is not None:
            Vm = [num(e) for e in V]
        elif pt != 0:
            grad = mp.lu_solve(G, mp.matrix(rows[m]))
            grad = [grad[i] for i in range(n)]
            Vm = [-pt * e / form(rows[m], grad) for e in grad]
        else:
            Vm = [mp.mpf(0)] * n
        k = len(rows)
        big = mp.matrix(n + k, n + k)
        rhs = mp.matrix(n + k, 1)
        for i in range(n):
            for j in range(n):
                big[i, j] = G[i, j]
            for j in range(k):
                big[i, n + j] = -rows[j][i]
                big[n + j, i] = rows[j][i]
            rhs[i] = mp.fsum(G[i, j] * vm[j] for j in range(n))
        rhs[n + m] = -num(alpha) * (form(rows[m], vm) + pt) - pt
        for a in range(l):
            rhs[n + m + 1 + a] = form(rows[m + 1 + a], Vm)
        sol = mp.lu_solve(big, rhs)
        return [sol[i] for i in range(n)]


def kkt_exact_at(scene: sm.Scene, index: int, point: dict, v_minus, alpha=None) -> sp.Matrix:
    """Route (B) exactly at a rational state: the declaration's matrices evaluated at
    ``point`` (values of q, t and the parameters), then the impulse-momentum system."""
    w = scene.walls[index]
    dpsi, psi_t = wall_one_form(scene, index)
    return kkt_post_velocity(
        scene.mass_matrix().xreplace(point),
        sp.Matrix(scene.constraint_matrix).xreplace(point),
        dpsi.xreplace(point),
        sp.Matrix(w.impulsive_matrix).xreplace(point),
        sp.Matrix(v_minus),
        sp.sympify(w.restitution if alpha is None else alpha).xreplace(point),
        sp.sympify(psi_t).xreplace(point),
    )
