"""A constrained textbook system against an independent route: the Chaplygin sleigh.

The sleigh (mass m, inertia I about its centre of mass (x, y), heading theta) slides on a
plane tilted by beta, with a knife edge at distance a behind the centre of mass that
cannot slip sideways: the contact point (x - a cos theta, y - a sin theta) moves along the
heading, ``-sin(theta) x_dot + cos(theta) y_dot - a theta_dot = 0`` (Carnot paper
section 2.2: one non-holonomic one-form).  The equations of motion and the multiplier are
compared with ``sympy.physics.mechanics.LagrangesMethod`` given the same Lagrangian and the
same non-holonomic constraint; both use ``d/dt dL/dq_dot - dL/dq = mu^T lambda``.
"""

from __future__ import annotations

import random

import sympy as sp
from sympy.physics.mechanics import LagrangesMethod, dynamicsymbols

import symmech as sm

m, I, a, g, beta = sp.symbols("m I a g beta", positive=True)
x, y, th = sm.coordinates("x y theta")
xd, yd, thd = sm.velocities((x, y, th))


def _lagranges_method():
    X, Y, TH = dynamicsymbols("x y theta")
    t = dynamicsymbols._t
    Xd, Yd, THd = (s.diff(t) for s in (X, Y, TH))
    L = m / 2 * (Xd**2 + Yd**2) + I / 2 * THd**2 - m * g * sp.sin(beta) * X
    constraint = -sp.sin(TH) * Xd + sp.cos(TH) * Yd - a * THd
    lm = LagrangesMethod(L, [X, Y, TH], nonhol_coneqs=[constraint])
    lm.form_lagranges_equations()
    rhs = lm.rhs()  # (q_dot, q_ddot, lambda)
    to_plain = {Xd: xd, Yd: yd, THd: thd, X: x, Y: y, TH: th}
    acc = [sp.sympify(rhs[3 + i]).subs(to_plain) for i in range(3)]
    return acc, sp.sympify(rhs[6]).subs(to_plain)


def _points(count: int, seed: int = 5):
    """Exact rational states with the velocity in D (y_dot solved from the constraint)."""
    rng = random.Random(seed)
    out = []
    for _ in range(count):
        pt = {s: sp.Rational(rng.randint(1, 40), rng.randint(10, 30)) for s in (m, I, a, g)}
        pt[beta] = sp.Rational(rng.randint(1, 9), 10)
        pt[x], pt[y] = sp.Rational(rng.randint(-9, 9), 7), sp.Rational(rng.randint(-9, 9), 7)
        pt[th] = sp.Rational(rng.randint(-14, 14), 10)
        pt[xd], pt[thd] = sp.Rational(rng.randint(-9, 9), 4), sp.Rational(rng.randint(-9, 9), 5)
        pt[yd] = (sp.sin(pt[th]) * pt[xd] + pt[a] * pt[thd]) / sp.cos(pt[th])
        out.append(pt)
    return out


def test_sleigh_matches_lagranges_method():
    scene = sm.Scene(
        (x, y, th),
        metric=sp.diag(m, m, I),
        potential=m * g * sp.sin(beta) * x,
        constraints=[-sp.sin(th) * xd + sp.cos(th) * yd - a * thd],
        name="chaplygin_sleigh",
    )
    acc_ref, lam_ref = _lagranges_method()
    acc, lam = scene.acceleration(), scene.multipliers()
    for pt in _points(4):
        for i in range(3):
            ours, theirs = sp.N(acc[i].subs(pt), 40), sp.N(acc_ref[i].subs(pt), 40)
            assert abs(ours - theirs) < sp.Float(10) ** -30 * (1 + abs(theirs)), (i, pt)
        ours, theirs = sp.N(lam[0].subs(pt), 40), sp.N(lam_ref.subs(pt), 40)
        assert abs(ours - theirs) < sp.Float(10) ** -30 * (1 + abs(theirs)), pt
        # the motion stays in D: mu v_dot + mu_dot v = 0
        rate = sp.N(scene.constraint_rate()[0].subs(pt), 40)
        mu_vdot = sp.N(sum(scene.constraint_matrix[0, j] * acc[j] for j in range(3)).subs(pt), 40)
        assert abs(mu_vdot + rate) < sp.Float(10) ** -30


def test_sleigh_generated_code_matches_lagranges_method():
    """The same comparison through generated C (linear solve of the constrained system)."""
    import numpy as np

    scene = sm.Scene(
        (x, y, th),
        metric=sp.diag(m, m, I),
        potential=m * g * sp.sin(beta) * x,
        constraints=[-sp.sin(th) * xd + sp.cos(th) * yd - a * thd],
        name="chaplygin_sleigh",
    )
    mod = sm.codegen.generate(scene, "c", strategy="linear_solve").load()
    acc_ref, lam_ref = _lagranges_method()
    for pt in _points(3, seed=11):
        params = [float(pt[sp.Symbol(name, positive=True)]) for name in mod.parameters]
        q = [float(pt[s]) for s in (x, y, th)]
        v = [float(pt[s]) for s in (xd, yd, thd)]
        ref = np.array([float(sp.N(e.subs(pt), 30)) for e in acc_ref])
        np.testing.assert_allclose(mod.acceleration(q, v, params), ref, rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(
            mod.multipliers(q, v, params), [float(sp.N(lam_ref.subs(pt), 30))], rtol=1e-13
        )
