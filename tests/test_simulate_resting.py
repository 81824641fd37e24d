"""Resting and sliding on several walls (issue 24, item 3).

Closed forms: the ladder (uniform rod of length L = 2 l, frictionless floor and wall)
released at rest at theta0 slides with thetadot^2 = (3 g / L) (sin theta0 - sin theta) and
leaves the wall when sin theta = (2/3) sin theta0, at the time
t = int_theta^theta0 dtheta / sqrt((3 g / L)(sin theta0 - sin theta)) (mpmath quadrature,
with theta = theta0 - s^2 to remove the endpoint singularity); a rod dropped flat with
alpha = 0 lies on both ends; a ball in a V corner comes to rest at the vertex.
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest
import sympy as sp

import symmech as sm

G = 9.81
LADDER = {"alpha": 0.0, "g": G, "l": 1.0, "m": 1.0}
BACKENDS = ["c", "numpy", "scipy"]


def leave_wall_time(theta0: float, l: float = 1.0) -> float:
    """The time the ladder leaves the wall, from the energy integral."""
    k = 3 * G / (2 * l)
    theta1 = mpmath.asin(mpmath.mpf(2) / 3 * mpmath.sin(theta0))
    s1 = mpmath.sqrt(theta0 - theta1)

    def integrand(s: mpmath.mpf) -> mpmath.mpf:  # theta = theta0 - s^2, dtheta = -2 s ds
        # sin theta0 - sin theta = 2 cos(theta0 - s^2/2) sin(s^2/2), free of cancellation
        gap = 2 * mpmath.cos(theta0 - s * s / 2) * mpmath.sin(s * s / 2)
        return 2 * s / mpmath.sqrt(k * gap)

    return float(mpmath.quad(integrand, [0, s1]))


def ladder_run(theta0: float, backend: str) -> sm.SimulationResult:
    q0 = [math.cos(theta0), math.sin(theta0), theta0]  # foot and top on the walls
    return sm.simulate(
        sm.load_scene("ladder"), q0, [0.0, 0.0, 0.0], 1.5 * leave_wall_time(theta0),
        params=LADDER, backend=backend, rtol=1e-10, atol=1e-12,
    )  # fmt: skip


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("theta0", [1.3, 1.0, 0.6])
def test_the_ladder_leaves_the_wall_where_and_when_the_energy_integral_says(backend, theta0):
    res = ladder_run(theta0, backend)
    assert res.status == "finished", res.message
    kinds = [(e.kind, e.wall_name) for e in res.events]
    assert kinds[:3] == [("contact", "floor"), ("contact", "wall"), ("release", "wall")]
    leave = res.events[2]
    assert math.sin(leave.q[2]) == pytest.approx(2 / 3 * math.sin(theta0), rel=1e-6)
    assert leave.time == pytest.approx(leave_wall_time(theta0), rel=1e-6)
    # the floor still holds the foot after the wall lets go
    assert all(e.wall_name != "floor" or e.kind != "release" for e in res.events[:4])
    assert res.stats["energy_drift"] < 1e-8


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_rod_dropped_flat_without_restitution_lies_on_both_ends(backend):
    params = {"alpha": 0.0, "g": G, "l": 1.0, "m": 1.0}
    res = sm.simulate(
        sm.load_scene("falling_rod"), [0.0, 1.0, 0.0], [0.4, 0.0, 0.0], 5.0, params=params,
        backend=backend,
    )  # fmt: skip
    assert res.status == "finished", res.message
    assert [e.kind for e in res.events] == ["impact", "impact", "contact", "contact"]
    np.testing.assert_allclose(res.impacts()[0].v_plus, [0.4, 0.0, 0.0], atol=1e-12)
    # sliding on both ends at the speed it had: the gaps stay within atol
    np.testing.assert_allclose(res.v[-1], [0.4, 0.0, 0.0], atol=1e-12)
    after = res.t >= res.events[-1].time
    y, th = res.q[after, 1], res.q[after, 2]
    assert np.max(np.abs(y - np.sin(th))) < 1e-10 and np.max(np.abs(y + np.sin(th))) < 1e-10


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("alpha", [0.5, 1.0])
def test_a_rod_dropped_flat_with_restitution_finishes(backend, alpha):
    """alpha = 0.5: bounces accumulate on both ends, then it lies on both; alpha = 1:
    it bounces straight up and down for ever."""
    params = {"alpha": alpha, "g": G, "l": 1.0, "m": 1.0}
    res = sm.simulate(
        sm.load_scene("falling_rod"), [0.0, 1.0, 0.0], [0.0, 0.0, 0.0], 4.0, params=params,
        backend=backend,
    )  # fmt: skip
    assert res.status == "finished", res.message
    if alpha < 1:
        np.testing.assert_allclose(res.q[-1], [0.0, 0.0, 0.0], atol=1e-9)
        np.testing.assert_allclose(res.v[-1], [0.0, 0.0, 0.0], atol=1e-9)
    assert all(abs(e.v_plus[2]) < 1e-9 for e in res.impacts())


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_ball_in_a_v_corner_comes_to_rest_at_the_vertex(backend):
    params = {"alpha": 0.5, "beta": 0.6, "g": G, "m": 1.0}
    res = sm.simulate(
        sm.load_scene("ball_in_corner"), [0.1, 0.5], [0.0, 0.0], 3.0, params=params,
        backend=backend,
    )  # fmt: skip
    assert res.status == "finished", res.message
    np.testing.assert_allclose(res.q[-1], [0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(res.v[-1], [0.0, 0.0], atol=1e-12)
    assert res.events[-1].kind == "contact"


def test_a_locked_rest_on_more_walls_than_coordinates_is_refused_with_a_reason():
    """A ball on a floor with a second, identical floor: two rows for one coordinate."""
    y = sm.coordinates(["y"])[0]
    m, g = sp.symbols("m g", positive=True)
    scene = sm.Scene(
        [y], metric=[[m]], potential=m * g * y,
        walls=[sm.Wall(y, restitution=0, name="a"), sm.Wall(2 * y, restitution=0, name="b")],
    )  # fmt: skip
    for backend in ("c", "numpy"):
        res = sm.simulate(scene, [0.0], [0.0], 1.0, params={"m": 1.0, "g": G}, backend=backend)
        assert res.status == "failed"
        assert "statically indeterminate" in res.message, (backend, res.message)


def test_c_builds_the_contact_modes_a_run_reaches_and_batches_agree_with_single_runs():
    """The C library starts with each wall's own contact mode; a run that comes to rest on
    both ends of the rod stops for the pair's mode, which is built in, and runs again: the
    result equals the NumPy loop's decisions, and a batch row equals its single run."""
    scene = sm.load_scene("falling_rod")
    params = {"alpha": 0.5, "g": G, "l": 1.0, "m": 1.0}
    Q = [[0.0, 1.0, 0.0], [0.0, 2.0, 0.0], [0.0, 1.5, 0.0]]
    V = [[0.3, 0.0, 0.0]] * 3
    batch = sm.simulate_batch(scene, Q, V, 4.0, params=params)
    assert list(batch.statuses) == ["finished"] * 3
    system = sm.simulate.system_for(scene, "c")
    assert (0, 1) in system.c_modes
    for i in range(3):
        c = sm.simulate(scene, Q[i], V[i], 4.0, params=params)
        py = sm.simulate(scene, Q[i], V[i], 4.0, params=params, backend="numpy")
        np.testing.assert_array_equal(c.q[-1], batch.q[i])
        assert [(e.kind, e.wall) for e in c.events] == [(e.kind, e.wall) for e in py.events]
        np.testing.assert_allclose(c.q[-1], py.q[-1], atol=1e-9)


@pytest.mark.parametrize("backend", BACKENDS)
def test_the_ladder_falls_flat_and_its_top_lands_while_the_foot_is_held(backend):
    """After leaving the wall the ladder falls; its top strikes the floor while the foot is
    held (an impact during a resting contact, resolved with the held wall: one impact, no
    cascade of partial ones), and it lies flat, sliding at the horizontal speed it had when
    it left the wall (no horizontal force acts after that).  The impact equals the
    closed-form map of the pair {floor, top_floor} at that state."""
    scene = sm.load_scene("ladder")
    theta0 = 1.2
    res = sm.simulate(
        scene, [math.cos(theta0), math.sin(theta0), theta0], [0.0, 0.0, 0.0], 1.0,
        params=LADDER, backend=backend, rtol=1e-10, atol=1e-12,
    )  # fmt: skip
    assert res.status == "finished", res.message
    kinds = [(e.kind, e.wall_name) for e in res.events]
    assert kinds == [
        ("contact", "floor"), ("contact", "wall"), ("release", "wall"),
        ("impact", "top_floor"), ("contact", "top_floor"),
    ]  # fmt: skip
    vx = res.events[2].v_plus[0]
    np.testing.assert_allclose(res.v[-1], [vx, 0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(res.q[-1, 1:], [0.0, 0.0], atol=1e-10)
    hit = res.events[3]
    pair = scene.impact_map(["floor", "top_floor"])
    values = {p: LADDER[str(p)] for p in scene.parameters}
    values.update(dict(zip(scene.declaration.coordinates, hit.q, strict=True)))
    want = np.array(pair.apply(list(hit.v_minus)).xreplace(values), dtype=float).ravel()
    np.testing.assert_allclose(hit.v_plus, want, atol=1e-9)


def test_a_sweep_builds_the_contact_sets_in_and_its_rows_equal_single_runs():
    """A sweep's chunks run the library they are sent, so the sweep builds every set of
    its (at most 4) static walls in first: rods that come to rest on both ends finish, and
    each row equals simulate(...) of its state bit for bit."""
    pytest.importorskip("pandas")
    scene = sm.load_scene("falling_rod")  # a fresh scene: no set reached before
    params = {"alpha": 0.5, "g": G, "l": 1.0, "m": 1.0}
    heights = [1.0, 1.5, 2.0]
    table = sm.sweep(
        scene, {"q0[1]": heights}, 4.0, q0=[0.0, 1.0, 0.0], v0=[0.3, 0.0, 0.0], params=params,
        threads=1,
    )  # fmt: skip
    assert list(table["status"]) == ["finished"] * 3
    for i, h in enumerate(heights):
        res = sm.simulate(scene, [0.0, h, 0.0], [0.3, 0.0, 0.0], 4.0, params=params)
        assert table["y_final"].iloc[i] == res.q[-1, 1] == 0.0
        assert table["xdot_final"].iloc[i] == res.v[-1, 0]
