"""Worked examples of the Carnot paper (002) and of text 001, reproduced symbolically.

Expected values are typed in from the papers (or derived by the KKT route B of
``test_impacts_support``); none is produced by the code under test.
"""

from __future__ import annotations

import functools

import mpmath as mp
import pytest
import sympy as sp
from test_impacts_support import general_element_of_D, impact_map, is_zero, kkt, kkt_at

import symmech as sm
from symmech import references

m, k, R, r = sp.symbols("m k R r", positive=True)
alpha = sp.Symbol("alpha", nonnegative=True)


# ---------------------------------------------------------------------------------------
# Example 3.7 / 3.12: a disc hits a rough wall y = R (impulsive constraint x_dot = R th_dot)


@functools.cache
def disc():
    x, y, th = sm.coordinates("x y theta")
    xd, yd, thd = sm.velocities((x, y, th))
    wall = sm.Wall(y - R, restitution=alpha, impulsive_constraints=[xd - R * thd], name="rough")
    scene = sm.Scene((x, y, th), metric=sp.diag(m, m, m * k**2), walls=[wall])
    return scene, (xd, yd, thd)


def test_example_3_7_post_impact_velocities():
    scene, (xd, yd, thd) = disc()
    imp = impact_map(scene, "rough")
    paper = sp.Matrix(
        [
            (R**2 * xd + R * k**2 * thd) / (R**2 + k**2),
            -alpha * yd,
            (R * xd + k**2 * thd) / (R**2 + k**2),
        ]
    )
    assert (imp.post_velocity - paper).applyfunc(sp.cancel).is_zero_matrix
    assert (imp.post_velocity - kkt(scene, 0, [xd, yd, thd])).applyfunc(sp.cancel).is_zero_matrix


def test_example_3_7_projector_objects():
    scene, _ = disc()
    p = impact_map(scene, 0).projectors
    # Y^0 = (1/m) d/dy, Y^1 = (1/m) d/dx - R/(m k^2) d/dtheta
    assert p.Y == sp.Matrix([[0, 1 / m], [1 / m, 0], [0, -R / (m * k**2)]])
    assert (
        (p.C - sp.Matrix([[1 / m, 0], [0, (k**2 + R**2) / (m * k**2)]]))
        .applyfunc(sp.cancel)
        .is_zero_matrix
    )
    # T~ = d/dy (x) dy
    assert p.T == sp.Matrix([[0, 0, 0], [0, 1, 0], [0, 0, 0]])
    # Q = (Y^0, Y^1) diag(m, m k^2/(R^2+k^2)) (dy, dx - R dtheta)
    paper_QQ = (
        sp.Matrix([[0, 1 / m], [1 / m, 0], [0, -R / (m * k**2)]])
        * sp.diag(m, m * k**2 / (R**2 + k**2))
        * sp.Matrix([[0, 1, 0], [1, 0, -R]])
    )
    assert (p.QQ - paper_QQ).applyfunc(sp.cancel).is_zero_matrix
    # Im PP (+) Im T~ = <R d/dx + d/dtheta, d/dy>
    image = (p.PP + p.T).columnspace()
    span = sp.Matrix([[R, 0], [0, 1], [1, 0]])
    assert sp.Matrix.hstack(span, *image).rank(simplify=True) == 2


def test_example_3_7_carnot_for_velocities_in_the_image():
    """Theorem 3.6 holds for v- in Im PP (+) Im T~ (Example 3.7)."""
    scene, (_xd, _yd, _thd) = disc()
    result = impact_map(scene, 0).carnot(restrict=True)
    assert result.theorem == "Theorem 3.6"
    assert is_zero(result.residual)


def test_example_3_12_T_C_and_energy_balance():
    scene, (xd, yd, thd) = disc()
    imp = impact_map(scene, 0)
    p = imp.projectors
    v = sp.Matrix([xd, yd, thd])
    # the C-projection of the pre-impact velocity (paper, Example 3.12)
    Cv = (sp.eye(3) - p.PP - p.T) * v
    paper_Cv = sp.Matrix(
        [k**2 / (k**2 + R**2) * (xd - R * thd), 0, -R / (k**2 + R**2) * (xd - R * thd)]
    )
    assert (Cv - paper_Cv).applyfunc(sp.cancel).is_zero_matrix
    result = imp.carnot()
    assert result.theorem == "Theorem 3.11"  # T~ = Q~ here
    assert is_zero(result.residual)
    assert is_zero(result.terms["T_C"] - references.carnot_3_12_t_c(xd, thd, m, k, R))
    # the energy balance with the paper's T_C, from our post velocity
    T = lambda u: (u.T * sp.diag(m, m, m * k**2) * u)[0, 0] / 2  # noqa: E731
    vp = imp.post_velocity
    T_C = references.carnot_3_12_t_c(xd, thd, m, k, R)
    balance = T(vp) - T(v) + (1 - alpha) / (1 + alpha) * T(vp - v) + 2 * alpha / (1 + alpha) * T_C
    assert is_zero(balance)
    # ... and the T_C term is needed: without it (Theorem 3.6's form) it fails off the image
    assert not is_zero(balance - 2 * alpha / (1 + alpha) * T_C)


# ---------------------------------------------------------------------------------------
# Example 3.13 / 4.4: a rolling sphere hits a rough wall x = 0 (or x = f(t)), in angular
# velocities: a frame S = blockdiag(I3, B^-1) with (wx, wy, wz) = B (phi_dot, th_dot, psi_dot)


def euler_frame():
    x, y, z, ph, th, ps = sm.coordinates("x y z phi theta psi")
    # Carnot paper, Example 3.13:
    #   wx = th_dot cos(psi) + phi_dot sin(th) sin(psi)
    #   wy = th_dot sin(psi) - phi_dot sin(th) cos(psi)
    #   wz = phi_dot cos(th) + psi_dot
    B = sp.Matrix(
        [
            [sp.sin(th) * sp.sin(ps), sp.cos(ps), 0],
            [-sp.sin(th) * sp.cos(ps), sp.sin(ps), 0],
            [sp.cos(th), 0, 1],
        ]
    )
    Binv = sp.simplify(B.inv())
    assert sp.simplify(B * Binv) == sp.eye(3)
    return (x, y, z, ph, th, ps), sp.diag(sp.eye(3), Binv)


f = sp.Function("f")


@functools.cache
def sphere(moving: bool):
    q, S = euler_frame()
    v = sp.symbols("xd yd zd omega_x omega_y omega_z", real=True)
    xd, yd, zd, wx, wy, wz = v
    psi = q[0] - f(sm.t) if moving else q[0]
    wall = sm.Wall(psi, restitution=alpha, impulsive_constraints=[yd - r * wz], name="wall")
    scene = sm.Scene(
        q,
        metric=sp.diag(1, 1, 1, k**2, k**2, k**2),
        frame=S,
        quasi_velocities=v,
        constraints=[xd - r * wy, yd + r * wx, zd],
        walls=[wall],
    )
    return scene, v


def pre_in_D(v):
    """The paper's pre-impact velocity (x0, y0, 0, -y0/r, x0/r, wz0) in D."""
    xd, yd, zd, wx, wy, wz = v
    x0, y0, w0 = sp.symbols("x0 y0 wz0", real=True)
    return {xd: x0, yd: y0, zd: 0, wx: -y0 / r, wy: x0 / r, wz: w0}, (x0, y0, w0)


def test_example_3_13_post_impact_velocities():
    scene, v = sphere(False)
    imp = impact_map(scene, 0)
    sub, (x0, y0, w0) = pre_in_D(v)
    post = imp.apply(sub)
    paper = references.carnot_3_13_post_velocity(x0, y0, w0, k, r, alpha)
    assert (post - paper).applyfunc(sp.cancel).is_zero_matrix
    z_vec, _ = general_element_of_D(scene)
    assert (imp.apply(list(z_vec)) - kkt(scene, 0, z_vec)).applyfunc(sp.cancel).is_zero_matrix


def test_example_3_13_projectors():
    scene, _v = sphere(False)
    p = impact_map(scene, "wall").projectors
    # P(Y^0) = r^2/(k^2+r^2) d/dx + r/(k^2+r^2) d/dq2
    PY0 = sp.Matrix([r**2, 0, 0, 0, r, 0]) / (k**2 + r**2)
    # P(Y^1) = r^2/(k^2+r^2) d/dy - r/(k^2+r^2) d/dq1 - r/k^2 d/dq3
    # (as printed; the d/dq3 coefficient is -r/k^2 exactly)
    PY1 = sp.Matrix([0, r**2 / (k**2 + r**2), 0, -r / (k**2 + r**2), 0, -r / k**2])
    assert (p.PY[:, 0] - PY0).applyfunc(sp.cancel).is_zero_matrix
    assert (p.PY[:, 1] - PY1).applyfunc(sp.cancel).is_zero_matrix
    # P(Y^0) in F, and T~ = Q~ = 1/(k^2+r^2) (r d/dx + d/dq2) (x) (r dx + k^2 dq2)
    assert (sp.Matrix(p.nu) * p.PY[:, 0]).applyfunc(sp.cancel).is_zero_matrix
    paper_T = sp.Matrix([r, 0, 0, 0, 1, 0]) * sp.Matrix([[r, 0, 0, 0, k**2, 0]]) / (k**2 + r**2)
    assert (p.T - paper_T).applyfunc(sp.cancel).is_zero_matrix
    assert (p.Qt - paper_T).applyfunc(sp.cancel).is_zero_matrix
    # C^AB = diag(r^2/(k^2+r^2), r^2 (2k^2+r^2)/(k^2 (k^2+r^2))): the inverse of the
    # paper's diag((k^2+r^2)/r^2, k^2 (k^2+r^2)/(r^2 (2k^2+r^2)))
    paper_Cinv = sp.diag((k**2 + r**2) / r**2, k**2 * (k**2 + r**2) / (r**2 * (2 * k**2 + r**2)))
    assert (p.K - paper_Cinv).applyfunc(sp.cancel).is_zero_matrix


def test_example_3_13_T_C_and_elastic_energy_loss():
    scene, v = sphere(False)
    imp = impact_map(scene, 0)
    sub, (_x0, y0, w0) = pre_in_D(v)
    paper_TC = references.carnot_3_13_t_c(y0, w0, k, r)
    result = imp.carnot()
    assert result.theorem == "Theorem 3.11"
    assert is_zero(result.residual)
    assert is_zero(result.terms["T_C"].xreplace(sub) - paper_TC)
    # alpha = 1: T1 - T0 = -T_C
    dT = imp.energy_change().xreplace(sub).subs(alpha, 1)
    assert is_zero(dT + paper_TC)
    # the restricted case y0 = r wz0: equation (13), Theorem 3.6
    restricted = imp.carnot(restrict=True)
    assert restricted.theorem == "Theorem 3.6" and is_zero(restricted.residual)


def test_example_3_13_drops_the_dependent_constraint_omega_y():
    """psi^2 = omega_y is a combination of phi^1 and d psi (the paper drops it)."""
    q, S = euler_frame()
    v = sp.symbols("xd yd zd omega_x omega_y omega_z", real=True)
    xd, yd, zd, wx, wy, wz = v
    wall = sm.Wall(q[0], restitution=alpha, impulsive_constraints=[yd - r * wz, wy])
    scene = sm.Scene(
        q,
        metric=sp.diag(1, 1, 1, k**2, k**2, k**2),
        frame=S,
        quasi_velocities=v,
        constraints=[xd - r * wy, yd + r * wx, zd],
        walls=[wall],
    )
    with pytest.raises(sm.ImpactError, match=r"nu\^2 = omega_y is linearly dependent"):
        impact_map(scene, 0)


def paper_M():
    """Example 4.4's 6 x 6 matrix M, as printed (symmech.references)."""
    return references.carnot_4_4_matrix(k, r, alpha)


def test_example_4_4_wall_velocity_and_W():
    scene, _v = sphere(True)
    imp = impact_map(scene, 0)
    fd = sp.Derivative(f(sm.t), sm.t)
    assert (imp.wall_velocity - sp.Matrix([fd, 0, 0, 0, 0, 0])).is_zero_matrix
    assert (imp.W - sp.Matrix([fd, 0, 0, 0, fd / r, 0])).applyfunc(sp.cancel).is_zero_matrix
    # W in F
    assert (sp.Matrix(imp.projectors.nu) * imp.W).applyfunc(sp.cancel).is_zero_matrix


def test_example_4_4_matrix_multiplies_columns_not_rows():
    """The paper writes (separation) = (approach) M with row vectors; M reproduces our
    map only acting on columns, separation = M (approach)."""
    scene, v = sphere(True)
    imp = impact_map(scene, 0)
    fd = sp.Derivative(f(sm.t), sm.t)
    sub, (x0, y0, w0) = pre_in_D(v)
    approach = sp.Matrix([x0 - fd, y0, 0, -y0 / r, (x0 - fd) / r, w0])
    separation = imp.apply(sub) - imp.W
    M = paper_M()
    assert (M * approach - separation).applyfunc(sp.cancel).is_zero_matrix
    assert not ((approach.T * M).T - separation).applyfunc(sp.cancel).is_zero_matrix
    # the matrix is P_t - alpha T~_t, entry by entry
    assert (imp.matrix - M).applyfunc(sp.cancel).is_zero_matrix
    # route B, relative to the wall velocity V = (f', 0, ...)
    z_vec, _ = general_element_of_D(scene)
    assert (imp.apply(list(z_vec)) - kkt(scene, 0, z_vec)).applyfunc(sp.cancel).is_zero_matrix


def test_example_4_4_carnot():
    scene, v = sphere(True)
    imp = impact_map(scene, 0)
    sub, (_x0, y0, w0) = pre_in_D(v)
    result = imp.carnot()
    assert result.theorem == "Theorem 4.3 (P(Y0) in F)"
    assert is_zero(result.residual)
    paper_TC = references.carnot_3_13_t_c(y0, w0, k, r)
    assert is_zero(result.terms["T_C'"].xreplace(sub) - paper_TC)
    restricted = imp.carnot(restrict=True)
    assert is_zero(restricted.residual)


def test_extended_carnot_theorem_3_9_needs_the_cross_term():
    """Disc with the skew impulsive constraint x_dot + y_dot - R th_dot: P(Y^0) is not in F
    (C^{10} = 1/m), so Theorem 3.9 applies, with the term alpha g(T~ v, C v)."""
    x, y, th = sm.coordinates("x y theta")
    xd, yd, thd = sm.velocities((x, y, th))
    wall = sm.Wall(y - R, restitution=alpha, impulsive_constraints=[xd + yd - R * thd])
    scene = sm.Scene((x, y, th), metric=sp.diag(m, m, m * k**2), walls=[wall])
    imp = impact_map(scene, 0)
    assert is_zero(imp.projectors.C[1, 0] - 1 / m)
    result = imp.carnot()
    assert result.theorem == "Theorem 3.9"
    assert is_zero(result.residual)
    assert not is_zero(result.terms["cross"])
    assert not is_zero(result.residual - alpha * result.terms["cross"])
    v = [xd, yd, thd]
    assert (imp.post_velocity - kkt(scene, 0, v)).applyfunc(sp.cancel).is_zero_matrix


# ---------------------------------------------------------------------------------------
# frames: the map in quasi-velocities is the coordinate map seen through q_dot = S v


def test_frame_map_equals_coordinate_map():
    """A planar ellipse with body-frame velocities v = (u1, u2, w), q_dot = S v,
    S = blockdiag(R(theta), 1), hits the floor y = 0 (psi depends on theta) and rolls on it
    at impact.  Declared once in the frame and once in coordinates (metric S^-T g S^-1,
    constraint row nu S^-1), the two maps agree: S v+ = q_dot+(q_dot- = S v-), and the
    framed map agrees with the KKT route at sampled states (40 digits)."""
    from symmech.declaration import shapes

    x, y, th = sm.coordinates("x y theta")
    qd = sp.Matrix(sm.velocities((x, y, th)))
    u1, u2, w = sp.symbols("u1 u2 w", real=True)
    c, s = sp.cos(th), sp.sin(th)
    S = sp.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    g = sp.diag(m, m, m * k**2)
    psi = shapes.ellipse_gap((x, y), th, (2 * R, R))
    # rolling at the contact: x_dot + (contact height) th_dot = 0 with the contact
    # point at distance psi + y = h below the centre: written in the frame
    h = y - psi
    nu_q = (sp.Matrix([[1, 0, h]]) * S).applyfunc(sp.simplify)
    framed = sm.Scene(
        (x, y, th),
        metric=g,
        frame=S,
        quasi_velocities=(u1, u2, w),
        walls=[sm.Wall(psi, restitution=alpha, impulsive_constraints=[list(nu_q)])],
    )
    Sinv = S.T  # a rotation
    plain = sm.Scene(
        (x, y, th),
        metric=(Sinv.T * g * Sinv).applyfunc(sp.simplify),
        walls=[sm.Wall(psi, restitution=alpha, impulsive_constraints=[list(nu_q * Sinv)])],
    )
    vq = impact_map(framed, 0).post_velocity
    vc = impact_map(plain, 0).post_velocity.xreplace(
        dict(zip(qd, S * sp.Matrix([u1, u2, w]), strict=True))
    )
    point = {
        th: sp.Rational(7, 10),
        y: 3,
        x: -1,
        R: 1,
        k: sp.Rational(1, 2),
        m: 2,
        alpha: sp.Rational(1, 3),
    }
    for vals in [(1, -2, 3), (0, 1, 0), (-2, 5, 1)]:
        at = {**point, u1: vals[0], u2: vals[1], w: vals[2]}
        diff = (S * vq - vc).xreplace(at).evalf(30)
        assert max(abs(e) for e in diff) < 1e-25
        # and both against the KKT route (in the frame: metric, d psi S and nu in v)
        with mp.workdps(30):
            route_b = kkt_at(framed, 0, point, vals, dps=30)
            ours = [mp.mpf(sp.N(e.xreplace(at), 40)) for e in vq]
            assert max(abs(a - b) for a, b in zip(ours, route_b, strict=True)) < 1e-25
