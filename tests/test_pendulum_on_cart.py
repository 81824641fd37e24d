"""The n-link pendulum on a cart declared by T and V agrees with sympy.physics.mechanics.

Independent route: KanesMethod on the same system built from points, frames and
particles (the PyDy model).  Kane's mass matrix and forcing, in u = q_dot, must equal
symmech's g and f (g q_ddot = f) at random states, and both routes' accelerations agree.
"""

from __future__ import annotations

import random

import pytest
import sympy as sp
from sympy.physics import mechanics as me

from symmech.examples import pendulum_on_cart


def _kane(n: int):
    q = me.dynamicsymbols(f"q:{n + 1}")
    u = me.dynamicsymbols(f"u:{n + 1}")
    m = sp.symbols(f"m:{n + 1}", positive=True)
    l = sp.symbols(f"l:{n}", positive=True)
    g, t = sp.Symbol("g", positive=True), me.dynamicsymbols._t
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P0", q[0] * N.x)
    P.set_vel(N, u[0] * N.x)
    bodies, loads = [me.Particle("p0", P, m[0])], [(P, -m[0] * g * N.y)]
    for i in range(n):
        B = N.orientnew(f"B{i}", "Axis", [q[i + 1], N.z])
        B.set_ang_vel(N, u[i + 1] * N.z)
        Pi = P.locatenew(f"P{i + 1}", -l[i] * B.y)
        Pi.v2pt_theory(P, N, B)
        bodies.append(me.Particle(f"p{i + 1}", Pi, m[i + 1]))
        loads.append((Pi, -m[i + 1] * g * N.y))
        P = Pi
    kane = me.KanesMethod(N, q_ind=q, u_ind=u, kd_eqs=[q[i].diff(t) - u[i] for i in range(n + 1)])
    kane.kanes_equations(bodies, loads)
    return q, u, m, l, g, kane.mass_matrix, kane.forcing


@pytest.mark.parametrize("n", [1, 3])
def test_mass_matrix_and_forcing_match_kane(n):
    scene = pendulum_on_cart(n)
    q_k, u_k, m_k, l_k, g_k, M_k, f_k = _kane(n)
    G, f = scene.mass_matrix(), scene.forcing()
    rng = random.Random(7 + n)
    by_name = {s.name: s for s in scene.parameters}
    for _ in range(3):
        params = {p: sp.Rational(rng.randint(5, 20), 10) for p in scene.parameters}
        state_q = [sp.Rational(rng.randint(-30, 30), 10) for _ in range(n + 1)]
        state_u = [sp.Rational(rng.randint(-30, 30), 10) for _ in range(n + 1)]
        ours = {**params, **dict(zip(scene.coordinates, state_q, strict=True))}
        ours.update(dict(zip(scene.velocities, state_u, strict=True)))
        theirs = {sym: params[by_name[sym.name]] for sym in (*m_k, *l_k, g_k)}
        theirs.update(dict(zip(q_k, state_q, strict=True)))
        theirs.update(dict(zip(u_k, state_u, strict=True)))
        Gn, fn = G.xreplace(ours).evalf(30), f.xreplace(ours).evalf(30)
        Mk, fk = M_k.xreplace(theirs).evalf(30), f_k.xreplace(theirs).evalf(30)
        assert (Gn - Mk).norm() < 1e-20 * (1 + Mk.norm())
        assert (fn - fk).norm() < 1e-20 * (1 + fk.norm())


def test_acceleration_matches_kane_small():
    scene = pendulum_on_cart(2)
    q_k, u_k, m_k, l_k, g_k, M_k, f_k = _kane(2)
    by_name = {s.name: s for s in scene.parameters}
    params = {p: sp.Rational(3 + i, 4) for i, p in enumerate(scene.parameters)}
    state = [sp.Rational(1, 3), sp.Rational(-2, 5), sp.Rational(7, 10)]
    speeds = [sp.Rational(-1, 2), sp.Rational(3, 4), sp.Rational(1, 5)]
    ours = {**params, **dict(zip(scene.coordinates, state, strict=True))}
    ours.update(dict(zip(scene.velocities, speeds, strict=True)))
    theirs = {sym: params[by_name[sym.name]] for sym in (*m_k, *l_k, g_k)}
    theirs.update(dict(zip(q_k, state, strict=True)))
    theirs.update(dict(zip(u_k, speeds, strict=True)))
    a_ours = scene.acceleration().xreplace(ours).evalf(30)
    a_kane = M_k.xreplace(theirs).evalf(30).LUsolve(f_k.xreplace(theirs).evalf(30))
    assert (a_ours - a_kane).norm() < 1e-20


def test_mass_matrix_and_forcing_need_no_inverse_or_solve(monkeypatch):
    """g and f (first-kind contraction, no inverse) for the 8-link pendulum: every route
    to an inverse or a linear solve is made to fail, and they are still formed."""

    def refuse(*args, **kwargs):
        raise AssertionError("g and f must not invert or solve")

    for name in ("inv", "LUsolve", "solve", "adjugate", "det", "cholesky_solve", "LDLsolve"):
        monkeypatch.setattr(sp.MatrixBase, name, refuse)
    import sys

    for module in [m for name, m in sys.modules.items() if name.startswith("symmech.")]:
        for fn in ("field_solve", "solve_spd", "adjugate_det"):
            if hasattr(module, fn):
                monkeypatch.setattr(module, fn, refuse)
    scene = pendulum_on_cart(8)
    with pytest.raises(AssertionError, match="must not"):  # the patch does bite
        pendulum_on_cart(1).acceleration()
    g, f = scene.mass_matrix(), scene.forcing()
    assert g.shape == (9, 9) and f.shape == (9, 1)
    assert all(e != 0 for e in f[1:])  # gravity and velocity terms are there
