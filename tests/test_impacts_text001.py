"""Text 001 ("Mechanics of nonholonomic hybrid Lagrangian systems"): the elastic impact
map (Theorem 2.12), the bouncing ellipse (section 3.1) and the spinning disk with a
frictional impact (section 3.2, the energy law), including the numerically stable form
of the rebound coefficient."""

from __future__ import annotations

import functools

import mpmath as mp
import numpy as np
import pytest
import sympy as sp
from test_impacts_support import impact_map, is_zero, kkt

import symmech as sm
from symmech import references
from symmech.declaration import shapes
from symmech.declaration.shapes import Plane

m, I, R, a, b = sp.symbols("m I R a b", positive=True)
alpha = sp.Symbol("alpha", nonnegative=True)


# ---------------------------------------------------------------------------------------
# Bouncing ellipse (section 3.1): wall x = 0, ellipse on the side x <= 0, no friction


@functools.cache
def ellipse(restitution=1):
    x, y, th = sm.coordinates("x y theta")
    psi = shapes.ellipse_gap((x, y), th, (a, b), Plane((0, 0), (-1, 0)))
    wall = sm.Wall(psi, restitution=restitution, name="wall")
    scene = sm.Scene((x, y, th), metric=sp.diag(m, m, I), walls=[wall])
    return scene, (x, y, th), sm.velocities((x, y, th))


def test_bouncing_ellipse_map_C_and_Phi():
    """x+ = x- - 2C/m, y+ = y-, th+ = th- - 2 C Phi / I, C = (xd + Phi thd)/(1/m + Phi^2/I)
    with Phi = dh/dtheta, h = x + (distance to the contact point)."""
    scene, (x, _y, th), (xd, yd, thd) = ellipse()
    imp = impact_map(scene, "wall")
    h = x + sp.sqrt(a**2 * sp.cos(th) ** 2 + b**2 * sp.sin(th) ** 2)  # text's h, |theta| < pi/2
    Phi = sp.diff(h, th)
    C = (xd + Phi * thd) / (1 / m + Phi**2 / I)
    text = sp.Matrix([xd - 2 * C / m, yd, thd - 2 * C / I * Phi])
    assert all(is_zero(e) for e in imp.post_velocity - text)
    # Theorem 2.12 with g(grad h, grad h) = 1/m + Phi^2/I
    assert is_zero(imp.projectors.C[0, 0] - (1 / m + Phi**2 / I))


def test_bouncing_ellipse_with_the_printed_Phi():
    """Numerically, with text 001's printed five-term Phi, for |theta| < pi/2."""
    scene, (_x, _y, th), (xd, yd, thd) = ellipse()
    imp = impact_map(scene, 0)
    tau, sec = sp.tan(th), sp.sec(th)
    s = sp.sqrt(b**2 * tau**2 / a**2 + 1)
    Phi = (
        b**2 * sp.sin(th) / (a * s)
        - a * sp.sin(th) / s
        + b**2 * tau * sec / (a * s)
        - b**2 * tau * sec / (a * s**3)
        - b**4 * tau**3 * sec / (a**3 * s**3)
    )
    C = (xd + Phi * thd) / (1 / m + Phi**2 / I)
    text = sp.Matrix([xd - 2 * C / m, yd, thd - 2 * C / I * Phi])
    args = (th, xd, yd, thd, a, b, m, I)
    ours_f = sp.lambdify(args, imp.post_velocity, "numpy")
    text_f = sp.lambdify(args, text, "numpy")
    rng = np.random.default_rng(7)
    for _ in range(40):
        vals = (rng.uniform(-1.5, 1.5), *rng.normal(size=3), *rng.uniform(0.3, 3, size=4))
        np.testing.assert_allclose(ours_f(*vals), text_f(*vals), rtol=1e-10, atol=1e-12)


def test_bouncing_ellipse_restitution_map_against_kkt():
    scene, _, v = ellipse(alpha)
    imp = impact_map(scene, 0)
    assert all(is_zero(e) for e in imp.post_velocity - kkt(scene, 0, v))
    assert imp.carnot().theorem == "Theorem 3.2"
    assert imp.carnot().is_zero()


def test_bouncing_ellipse_elastic_map_is_an_involution_and_conserves_energy():
    scene, _, v = ellipse()
    imp = impact_map(scene, 0)
    twice = imp.apply(list(imp.post_velocity))
    assert all(is_zero(e) for e in twice - sp.Matrix(v))
    assert is_zero(imp.energy_change())


# ---------------------------------------------------------------------------------------
# Spinning disk with frictional impact (section 3.2): wall x = 0, disk on x <= 0,
# rolling at impact y_dot + R th_dot = 0, energy law


@functools.cache
def disk(law="energy", restitution=1):
    x, y, th = sm.coordinates("x y theta")
    xd, yd, thd = sm.velocities((x, y, th))
    wall = sm.Wall(
        -x, restitution=restitution, impulsive_constraints=[yd + R * thd], name="rough", law=law
    )
    scene = sm.Scene((x, y, th), metric=sp.diag(m, m, I), walls=[wall])
    return scene, (xd, yd, thd)


def test_spinning_disk_energy_law_general_formula():
    """x1^2 = x0^2 + y0^2 + (I/m) th0^2 - beta^2 R^2 - (I/m) beta^2, y1 = -R beta,
    th1 = beta, beta = (I th0 - m R y0)/I1 (text 001 calls beta 'alpha'); x1 < 0."""
    scene, (xd, yd, thd) = disk()
    imp = impact_map(scene, "rough")
    I1 = I + m * R**2
    beta = (I * thd - m * R * yd) / I1
    assert is_zero(imp.post_velocity[1] - (-R * beta))
    assert is_zero(imp.post_velocity[2] - beta)
    x1_squared = xd**2 + yd**2 + I / m * thd**2 - beta**2 * R**2 - I / m * beta**2
    assert is_zero(imp.post_velocity[0] ** 2 - x1_squared)
    point = {xd: 2, yd: -1, thd: 3, m: 1, I: 2, R: sp.Rational(1, 2)}
    assert imp.post_velocity[0].subs(point) < 0  # separates from the wall x = 0
    assert is_zero(imp.energy_change())


def test_spinning_disk_special_cases():
    scene, (_xd, _yd, _thd) = disk()
    imp = impact_map(scene, 0)
    x0, th0 = sp.symbols("x0 th0", positive=True)
    # q0 = (x0, 0, 0): x1 = -x0
    assert imp.apply([x0, 0, 0]) == sp.Matrix([-x0, 0, 0])
    # q0 = (x0, 0, th0)
    I1 = I + m * R**2
    post = imp.apply([x0, 0, th0])
    text_coeff = I / m - I**2 * R**2 / I1**2 - I**3 / (m * I1**2)
    assert is_zero(post[0] ** 2 - (x0**2 + text_coeff * th0**2))
    assert post[0].subs({x0: 1, th0: 2, m: 3, I: 5, R: 7}) < 0  # the negative root
    assert is_zero(post[1] + R * I * th0 / I1)
    assert is_zero(post[2] - I / I1 * th0)


def test_spinning_disk_perfectly_inelastic():
    """alpha = 0: the x velocity is absorbed, (y, th) projected onto the rolling constraint."""
    scene, (_xd, yd, thd) = disk(restitution=0)
    imp = impact_map(scene, 0)
    beta = references.disk_beta(yd, thd, m, I, R)
    expected = sp.Matrix([0, -R * beta, beta])
    assert all(is_zero(e) for e in imp.post_velocity - expected)


def test_energy_law_against_the_kkt_route():
    """Route B: v+ = u + lam (K1 - K0), K_alpha the KKT map with restitution alpha,
    u = K0 (perfectly inelastic), lam >= 0 from energy conservation."""
    scene, v = disk()
    imp = impact_map(scene, 0)
    K0, K1 = kkt(scene, 0, v, alpha=0), kkt(scene, 0, v, alpha=1)
    lam = sp.Symbol("lam", nonnegative=True)
    g = sp.diag(m, m, I)
    vp = K0 + lam * (K1 - K0)
    energy = sp.expand((vp.T * g * vp)[0, 0] - (sp.Matrix(v).T * g * sp.Matrix(v))[0, 0])
    point = {v[0]: sp.Rational(3, 2), v[1]: -2, v[2]: 5, m: 2, I: sp.Rational(1, 3), R: 3}
    (root,) = [s for s in sp.solve(energy.subs(point), lam) if s.is_nonnegative]
    assert sp.simplify(imp.apply(point).subs(point) - vp.subs(point).subs(lam, root)) == sp.zeros(
        3, 1
    )


def test_energy_law_has_no_matrix_and_no_carnot():
    scene, _ = disk()
    imp = impact_map(scene, 0)
    assert not imp.is_linear
    with pytest.raises(sm.ImpactError, match="not linear"):
        _ = imp.matrix
    with pytest.raises(sm.ImpactError, match="not linear"):
        _ = imp.offset
    with pytest.raises(sm.ImpactError, match="energy law"):
        imp.carnot()
    assert any("square root" in s.description for s in imp.singularities)


def test_both_laws_on_the_same_scene():
    """Newton (Prop. 3.4) loses T_C at alpha = 1 (Theorem 3.11); the energy law conserves."""
    scene, _v = disk()
    newton = impact_map(scene, 0, law="newton")
    energy = impact_map(scene, 0, law="energy")
    assert newton.is_linear and not energy.is_linear
    # same tangential part
    assert all(is_zero(e) for e in (newton.post_velocity - energy.post_velocity)[1:, :])
    result = newton.carnot()
    assert result.theorem == "Theorem 3.11"
    assert is_zero(newton.energy_change() + result.terms["T_C"])
    assert is_zero(energy.energy_change())


# ---------------------------------------------------------------------------------------
# numerical stability of the rebound coefficient (m R^2 << I)


def test_rebound_coefficient_is_stable_in_float64():
    scene, (xd, yd, thd) = disk()
    imp = impact_map(scene, 0)
    s2 = imp.energy_law.speed_squared
    coeff = sp.Poly(s2.subs(yd, 0), xd, thd).coeff_monomial(thd**2)
    I1 = I + m * R**2
    text_coeff = I / m - I**2 * R**2 / I1**2 - I**3 / (m * I1**2)
    assert is_zero(coeff - text_coeff)
    ours = sp.lambdify((m, I, R), coeff, "numpy")
    text = sp.lambdify((m, I, R), text_coeff, "numpy")
    x1 = sp.lambdify((xd, yd, thd, m, I, R), imp.post_velocity[0], "numpy")
    with mp.workdps(50):
        for Rv in [1e-3, 1e-5, 1e-7, 1e-9]:
            mv, Iv = 1.0, 1.0
            exact = mp.mpf(Iv) * mp.mpf(Rv) ** 2 / (mp.mpf(Iv) + mp.mpf(mv) * mp.mpf(Rv) ** 2)
            assert abs(ours(mv, Iv, Rv) - exact) / exact < 1e-14
            # the printed form loses digits: ~4 left at R = 1e-7, none at 1e-9
            lost = {1e-7: 1e-4, 1e-9: 0.5}
            if Rv in lost:
                assert abs(text(mv, Iv, Rv) - exact) / exact > lost[Rv]
            # x1 for a disk that only spins: -sqrt(coeff) th0
            th0 = 3.0
            assert (
                abs(x1(0.0, 0.0, th0, mv, Iv, Rv) + mp.sqrt(exact) * th0) / (mp.sqrt(exact) * th0)
                < 1e-14
            )
