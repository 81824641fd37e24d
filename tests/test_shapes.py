"""Contact geometry (symmech.declaration.shapes): gaps of disks, spheres and ellipses.

The ellipse gap is checked against a brute-force numeric minimum over the boundary
parameter for many orientations (including theta near and beyond pi/2), against text 001's
contact-angle route (which agrees only for |theta| < pi/2), and against text 001's printed
Phi(theta) = dh/dtheta.
"""

from __future__ import annotations

import math

import mpmath as mp
import numpy as np
import pytest
import sympy as sp
from scipy.optimize import minimize_scalar

import symmech as sm
from symmech.declaration import shapes
from symmech.declaration.shapes import Plane

a, b, theta, x, y = sp.symbols("a b theta x y", real=True)
A, B = sp.symbols("A B", positive=True)


def brute_force_gap(cx, cy, th, sa, sb, p, n) -> float:
    """min over phi of n . (X(phi) - p), X(phi) = c + R(th) (a cos phi, b sin phi)."""

    def gap(phi: float) -> float:
        X = cx + math.cos(th) * sa * math.cos(phi) - math.sin(th) * sb * math.sin(phi)
        Y = cy + math.sin(th) * sa * math.cos(phi) + math.cos(th) * sb * math.sin(phi)
        return n[0] * (X - p[0]) + n[1] * (Y - p[1])

    grid = np.linspace(0.0, 2 * math.pi, 2001)
    values = [gap(g) for g in grid]
    i = int(np.argmin(values))
    res = minimize_scalar(
        gap,
        bounds=(grid[max(i - 1, 0)], grid[min(i + 1, 2000)]),
        method="bounded",
        options={"xatol": 1e-12},
    )
    return min(res.fun, values[i])


def text001_gap(cx, th, sa, sb):
    """Text 001, section 3.1: x + a cos(phi_c) cos(theta) - b sin(phi_c) sin(theta) with
    phi_c = arctan(-(b/a) tan(theta)): the X coordinate of the 'contact point'."""
    phic = sp.atan(-sb / sa * sp.tan(th))
    return cx + sa * sp.cos(phic) * sp.cos(th) - sb * sp.sin(phic) * sp.sin(th)


ORIENTATIONS = [
    -3.0,
    -2.0,
    -1.6,
    -1.2,
    -0.5,
    0.0,
    0.3,
    1.0,
    1.5,
    1.5707,
    1.57079632,
    1.5708,
    1.6,
    2.0,
    2.5,
    3.0,
    3.1,
    4.0,
    5.5,
    6.2,
]
NORMALS = [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.6, 0.8), (-0.28, 0.96)]


@pytest.mark.parametrize("normal", NORMALS)
def test_ellipse_gap_equals_brute_force_minimum(normal):
    nx, ny = (sp.nsimplify(c) for c in normal)
    plane = Plane((sp.Rational(1, 3), -1), (nx, ny))
    psi = shapes.ellipse_gap((x, y), theta, (A, B), plane)
    f = sp.lambdify((x, y, theta, A, B), psi, "math")
    for th in ORIENTATIONS:
        for cx, cy, sa, sb in [(0.7, 2.0, 2.0, 0.5), (-1.0, 0.3, 0.8, 1.7)]:
            expected = brute_force_gap(cx, cy, th, sa, sb, (1 / 3, -1.0), normal)
            assert f(cx, cy, th, sa, sb) == pytest.approx(expected, abs=1e-9)


def test_ellipse_contact_point_is_on_the_boundary_and_attains_the_gap():
    plane = Plane((0, 0), (sp.Rational(3, 5), sp.Rational(4, 5)))
    X, Y = shapes.ellipse_contact_point((x, y), theta, (A, B), plane)
    psi = shapes.ellipse_gap((x, y), theta, (A, B), plane)
    for th in ORIENTATIONS:
        vals = {x: 0.4, y: 3.0, theta: th, A: 2.0, B: 0.7}
        Xn, Yn = float(X.subs(vals)), float(Y.subs(vals))
        # body coordinates of the point: on the ellipse (u/a)^2 + (w/b)^2 = 1
        u = math.cos(th) * (Xn - 0.4) + math.sin(th) * (Yn - 3.0)
        w = -math.sin(th) * (Xn - 0.4) + math.cos(th) * (Yn - 3.0)
        assert (u / 2.0) ** 2 + (w / 0.7) ** 2 == pytest.approx(1.0, abs=1e-12)
        assert 0.6 * Xn + 0.8 * Yn == pytest.approx(float(psi.subs(vals)), abs=1e-12)


def test_text001_contact_angle_route_fails_beyond_pi_over_2():
    """Text 001's wall is x = 0 with the ellipse on the side x <= 0: psi = -(its X)."""
    ours = shapes.ellipse_gap((x, y), theta, (A, B), Plane((0, 0), (-1, 0)))
    text = -text001_gap(x, theta, A, B)
    f_ours = sp.lambdify((x, theta, A, B), ours, "math")
    f_text = sp.lambdify((x, theta, A, B), text, "math")
    for th in [-1.5, -0.7, 0.0, 0.4, 1.2, 1.55]:
        assert f_text(-3.0, th, 2.0, 1.0) == pytest.approx(f_ours(-3.0, th, 2.0, 1.0), abs=1e-12)
    for th in [1.7, 2.0, 2.8, -2.0, 3.5]:
        exact = brute_force_gap(-3.0, 0.0, th, 2.0, 1.0, (0.0, 0.0), (-1.0, 0.0))
        assert f_ours(-3.0, th, 2.0, 1.0) == pytest.approx(exact, abs=1e-9)
        # the text's formula picks the far point: its gap is off by 2 h(theta)
        assert abs(f_text(-3.0, th, 2.0, 1.0) - exact) > 1.0


def text001_Phi(th, sa, sb):
    """Text 001's printed Phi(theta) (the five-term formula), transcribed as printed."""
    tau, sec = sp.tan(th), sp.sec(th)
    s = sp.sqrt(sb**2 * tau**2 / sa**2 + 1)
    return (
        sb**2 * sp.sin(th) / (sa * s)
        - sa * sp.sin(th) / s
        + sb**2 * tau * sec / (sa * s)
        - sb**2 * tau * sec / (sa * s**3)
        - sb**4 * tau**3 * sec / (sa**3 * s**3)
    )


def test_text001_Phi_is_dh_dtheta_inside_the_half_turn():
    h = sp.sqrt(A**2 * sp.cos(theta) ** 2 + B**2 * sp.sin(theta) ** 2)
    psi = shapes.ellipse_gap((x, y), theta, (A, B), Plane((0, 0), (-1, 0)))
    assert sp.simplify(psi - (-x - h)) == 0
    dh = sp.lambdify((theta, A, B), -sp.diff(psi, theta), "mpmath")
    phi_text = sp.lambdify((theta, A, B), text001_Phi(theta, A, B), "mpmath")
    with mp.workdps(30):
        for th in np.linspace(-1.55, 1.55, 41):
            for sa, sb in [(2.0, 1.0), (0.5, 1.5)]:
                diff = phi_text(mp.mpf(th), sa, sb) - dh(mp.mpf(th), sa, sb)
                assert abs(diff) < mp.mpf(10) ** -20
        # beyond pi/2 the printed formula has the wrong sign (it differentiates the far point)
        th = mp.mpf(2)
        assert abs(phi_text(th, 2.0, 1.0) + dh(th, 2.0, 1.0)) < mp.mpf(10) ** -20
        assert abs(dh(th, 2.0, 1.0)) > 0.5


def test_text001_Phi_is_dh_dtheta_symbolically_inside_the_half_turn():
    """For |theta| < pi/2, cos(theta) > 0 and theta -> tau = tan(theta) is a bijection
    onto the reals with sec(theta) = +sqrt(1 + tau^2), cos = 1/sec, sin = tau/sec.  In
    tau the printed Phi minus dh/dtheta (h the support-function gap) is an algebraic
    expression with positive square roots; writing w = sqrt(1 + tau^2) and
    r = sqrt(A^2 + B^2 tau^2) (both positive) makes it a rational function of tau, w, r
    that vanishes modulo w^2 = 1 + tau^2, r^2 = A^2 + B^2 tau^2: zero for every such
    theta, not only at sampled points."""
    tau = sp.Symbol("tau", real=True)
    w, r = sp.symbols("w r", positive=True)
    h = sp.sqrt(A**2 * sp.cos(theta) ** 2 + B**2 * sp.sin(theta) ** 2)
    psi = shapes.ellipse_gap((x, y), theta, (A, B), Plane((0, 0), (-1, 0)))
    assert sp.simplify(psi - (-x - h)) == 0
    diff = text001_Phi(theta, A, B) - sp.diff(h, theta)
    sec = sp.sqrt(1 + tau**2)
    in_tau = diff.subs(
        {sp.sin(theta): tau / sec, sp.cos(theta): 1 / sec, sp.tan(theta): tau, sp.sec(theta): sec}
    )
    assert not in_tau.has(theta)
    radicals = {
        sp.sqrt(1 + tau**2): w,
        sp.sqrt(1 + B**2 * tau**2 / A**2): r / A,  # A > 0
        sp.sqrt(A**2 / (tau**2 + 1) + B**2 * tau**2 / (tau**2 + 1)): r / w,
    }
    rational = sp.together(in_tau.subs(radicals))
    assert not any(
        isinstance(p, sp.Pow) and not p.exp.is_Integer for p in sp.preorder_traversal(rational)
    )
    numerator = sp.expand(sp.fraction(rational)[0])
    _, remainder = sp.reduced(numerator, [w**2 - 1 - tau**2, r**2 - A**2 - B**2 * tau**2], w, r)
    assert remainder == 0
    # the same difference without the substitution, by simplify
    assert sp.simplify(in_tau) == 0


def test_support_function_route_is_accurate_near_pi_over_2():
    """In float64, d psi/d theta from the support function keeps full relative accuracy
    near theta = pi/2; through phi_c = arctan(-(b/a) tan theta) it loses digits."""
    psi = shapes.ellipse_gap((x, y), theta, (A, B), Plane((0, 0), (-1, 0)))
    ours = sp.lambdify((theta, A, B), sp.diff(psi, theta), "numpy")
    text = sp.lambdify((theta, A, B), -sp.diff(text001_gap(x, theta, A, B), theta), "numpy")
    exact = sp.lambdify((theta, A, B), sp.diff(psi, theta), "mpmath")
    worst_ours = worst_text = 0.0
    with mp.workdps(50):
        for d in [1e-4, 1e-6, 1e-8, 1e-10]:
            th = math.pi / 2 - d
            ref = exact(mp.mpf(th), 2, 1)  # exact value at the float64 input
            worst_ours = max(worst_ours, float(abs((ours(th, 2.0, 1.0) - ref) / ref)))
            worst_text = max(worst_text, float(abs((text(th, 2.0, 1.0) - ref) / ref)))
    assert worst_ours < 1e-14
    assert worst_text > 1e-3


def test_disk_and_sphere_gaps():
    assert shapes.disk_gap((x, y), 2) == y - 2
    n = (sp.Rational(3, 5), sp.Rational(4, 5))
    assert (
        sp.expand(
            shapes.disk_gap((x, y), A, Plane((1, 1), n)) - (3 * (x - 1) + 4 * (y - 1)) / 5 + A
        )
        == 0
    )
    z = sp.Symbol("z", real=True)
    assert shapes.sphere_gap((x, y, z), A) == z - A
    assert shapes.sphere_gap((x, y, z), A, Plane.axis("x", dim=3)) == x - A


def test_moving_plane_gives_a_moving_wall():
    f = sp.Function("f")
    psi = shapes.disk_gap((x, y), A, Plane.axis("x", at=f(sm.t), side=-1))
    assert psi == -(x - f(sm.t)) - A
    xs, ys = sm.coordinates("x y")
    scene = sm.Scene((xs, ys), metric=sp.eye(2), walls=[sm.Wall(psi.subs({x: xs, y: ys}))])
    assert scene.walls[0].moving


def test_plane_validation():
    with pytest.raises(sm.SceneError, match="not a unit vector"):
        Plane((0, 0), (1, 1))
    with pytest.raises(sm.SceneError, match="expected 2 components"):
        Plane((0, 0), (0, 0, 1))
    with pytest.raises(sm.SceneError, match="axis"):
        Plane.axis("z")
    with pytest.raises(sm.SceneError, match="positive"):
        shapes.disk_gap((x, y), -1)
    with pytest.raises(sm.SceneError, match="positive"):
        shapes.ellipse_gap((x, y), theta, (1, 0))
    with pytest.raises(sm.SceneError, match="3-dimensional"):
        shapes.sphere_gap((x, y, x), 1, Plane.axis("y"))
    # a symbolic unit normal is accepted
    Plane((0, 0), (sp.cos(a), sp.sin(a)))
