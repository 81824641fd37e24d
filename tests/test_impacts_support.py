"""Shared helpers for the impact tests, and tests of the helpers themselves.

``impact_map(scene, wall, law)`` goes through ``Scene.impact_map`` (the public entry
point).  ``kkt(scene, wall, v_minus)`` is route (B): the impulse-momentum system built
here from the declaration alone (metric, constraint rows, d psi computed in this file),
solved by :func:`symmech.impacts.kkt_post_velocity`, sharing no code with the projector
route.  ``basis_of_D(scene)`` parametrises D by a nullspace basis (not by the projector P).
"""

from __future__ import annotations

import sympy as sp

import symmech as sm
from symmech.impacts import kkt_post_velocity


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
