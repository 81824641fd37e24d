"""A wall's declared velocity field W(t, q) (``sm.Wall(..., velocity=...)``).

The case that needs it: a disc whose mass centre is off its geometric centre, rolling onto a
floor that moves up and down.  The floor's material velocity is vertical, so a rolling
impact must leave no slip relative to it.  The default W (the metric normal) has a
horizontal part when the metric couples the vertical with the rotation, and the impact then
leaves the disc slipping; the declared W = (0, h'(t), 0) does not.  The oracle is an
independent numerical solve of the impulse-momentum (KKT) system, Carnot paper eqs. 6, 15
and 20: ``g (v+ - v-) = A^T lambda``, ``dpsi v+ + psi_t = -alpha (dpsi v- + psi_t)``,
``nu (v+ - W) = 0``.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import symmech as sm
from symmech.simulate import SimulationError

x, y, th = sm.coordinates("x y theta")
xd, yd, thd = sm.velocities((x, y, th))
m, R, e, J, A, w, alpha = sp.symbols("m R e J A omega alpha", positive=True)
H = A * sp.sin(w * sm.t)  # the floor's height
VALUES = {m: 1.3, R: 0.5, e: 0.2, J: 0.1, A: 0.3, w: 2.0, alpha: 0.5}


def _scene(velocity=None) -> sm.Scene:
    xc, yc = x + e * sp.sin(th), y - e * sp.cos(th)  # the mass centre
    T = (
        m * (sp.diff(xc, x) * xd + sp.diff(xc, th) * thd) ** 2 / 2
        + m * (yd + sp.diff(yc, th) * thd) ** 2 / 2
        + J * thd**2 / 2
    )
    floor = sm.Wall(
        y - R - H,
        restitution=alpha,
        impulsive_constraints=[xd + R * thd],  # no slip of the contact point (floor: vertical)
        name="floor",
        velocity=velocity,
    )
    return sm.Scene(
        (x, y, th), kinetic_energy=T, potential=m * 9.81 * yc, walls=[floor], name="offset_disc"
    )


def _kkt(scene: sm.Scene, q, v, t, W) -> np.ndarray:
    sub = {**VALUES, sm.t: t, **dict(zip(scene.coordinates, q, strict=True))}
    g = np.array(scene.mass_matrix().xreplace(sub), dtype=float)
    psi = scene.walls[0].psi
    dpsi = np.array([float(sp.diff(psi, c).xreplace(sub)) for c in scene.coordinates])
    psi_t = float(sp.diff(psi, sm.t).xreplace(sub))
    nu = np.array(scene.walls[0].impulsive_matrix.xreplace(sub), dtype=float)
    Amat = np.vstack([dpsi, nu])
    K = np.block([[g, -Amat.T], [Amat, np.zeros((2, 2))]])
    a = VALUES[alpha]
    rhs = np.concatenate([g @ v, [-a * (dpsi @ v + psi_t) - psi_t], nu @ W])
    return np.linalg.solve(K, rhs)[:3]


STATE = (np.array([0.1, 0.5, 0.7]), np.array([0.3, -1.0, 0.2]), 0.4)


def _floor_velocity(t: float) -> np.ndarray:
    return np.array([0.0, float(sp.diff(H, sm.t).xreplace({**VALUES, sm.t: t})), 0.0])


def _post(scene: sm.Scene, q, v, t) -> np.ndarray:
    sub = {
        **VALUES,
        sm.t: t,
        **dict(zip(scene.coordinates, q, strict=True)),
        **dict(zip(scene.velocities, v, strict=True)),
    }
    return np.array([float(c.xreplace(sub)) for c in scene.impact_map(0).post_velocity])


def test_declared_wall_velocity_leaves_no_slip_and_matches_the_kkt_solve():
    scene = _scene(velocity=[0, sp.diff(H, sm.t), 0])
    q, v, t = STATE
    q = q.copy()
    q[1] = 0.5 + float(H.xreplace({**VALUES, sm.t: t}))  # on the floor
    Wf = _floor_velocity(t)
    got = _post(scene, q, v, t)
    np.testing.assert_allclose(got, _kkt(scene, q, v, t, Wf), rtol=1e-12, atol=1e-12)
    assert abs(got[0] + VALUES[R] * got[2]) < 1e-13  # no slip relative to the floor
    # normal relative velocity reversed and scaled by alpha
    assert got[1] - Wf[1] == pytest.approx(-VALUES[alpha] * (v[1] - Wf[1]), abs=1e-13)


def test_default_wall_velocity_is_the_metric_normal_and_slips_here():
    scene = _scene()
    q, v, t = STATE
    q = q.copy()
    q[1] = 0.5 + float(H.xreplace({**VALUES, sm.t: t}))
    got = _post(scene, q, v, t)
    # the default W: -psi_t g^-1 dpsi^T / (dpsi g^-1 dpsi^T), which has a horizontal part
    sub = {**VALUES, sm.t: t, **dict(zip(scene.coordinates, q, strict=True))}
    g = np.array(scene.mass_matrix().xreplace(sub), dtype=float)
    dpsi = np.array([0.0, 1.0, 0.0])
    psi_t = -_floor_velocity(t)[1]
    Z = np.linalg.solve(g, dpsi)
    W_default = -psi_t * Z / (dpsi @ Z)
    np.testing.assert_allclose(got, _kkt(scene, q, v, t, W_default), rtol=1e-12, atol=1e-12)
    assert abs(got[0] + VALUES[R] * got[2]) > 1e-3  # it slips relative to the real floor


@pytest.mark.parametrize("strategy", ["closed_form", "linear_solve"])
@pytest.mark.parametrize("target", ["c", "numpy"])
def test_generated_impact_uses_the_declared_wall_velocity(target, strategy):
    scene = _scene(velocity=[0, sp.diff(H, sm.t), 0])
    mod = sm.codegen.generate(scene, target=target, strategy=strategy).load()
    q, v, t = STATE
    params = {str(k): val for k, val in VALUES.items()}
    want = _kkt(scene, q, v, t, _floor_velocity(t))
    np.testing.assert_allclose(mod.impact(q, v, params, t=t), want, rtol=1e-12, atol=1e-12)


def test_wall_velocity_refused_with_the_reason():
    with pytest.raises(sm.SceneError, match="does not move with the wall"):
        _scene(velocity=[0, 0, 0])
    with pytest.raises(sm.SceneError, match="velocity: 2 components for 3"):
        _scene(velocity=[0, 0])
    with pytest.raises(sm.SceneError, match="velocity must be a sequence"):
        sm.Wall(y, velocity="0, 1")
    with pytest.raises(sm.SceneError, match=r"velocity: contains velocity symbols"):
        _scene(velocity=[xd, sp.diff(H, sm.t), 0])


def test_a_conveyor_belt_is_refused_by_the_simulator_only():
    belt_speed = sp.Symbol("b", positive=True)
    s = sm.Scene(
        (x, y, th),
        metric=sp.diag(1, 1, sp.Rational(1, 2)),
        potential=9.81 * y,
        walls=[
            sm.Wall(
                y - 1,
                restitution=0,
                impulsive_constraints=[xd + thd],
                velocity=[belt_speed, 0, 0],
                name="belt",
            )
        ],
    )
    imp = s.impact_map("belt")
    post = imp.post_velocity.xreplace({belt_speed: 2, xd: 0, yd: -1, thd: 0})
    assert post[0] + post[2] == 2  # the contact point leaves with the belt's speed
    with pytest.raises(SimulationError, match="conveyor"):
        sm.simulate(s, [0, 1.5, 0], [0, 0, 0], 1.0, params={"b": 1.0})


def test_scene_file_wall_velocity_round_trip():
    scene = _scene(velocity=[0, sp.diff(H, sm.t), 0])
    text = sm.dump_scene(scene)
    assert "velocity = [" in text
    again = sm.reads_scene(text).scene
    assert again.walls[0].velocity == scene.walls[0].velocity
    with pytest.raises(sm.SceneError, match=r"walls\[0\]\.velocity.*expected an array of 3"):
        sm.reads_scene(text.replace("velocity = [", "velocity = [0, "))
