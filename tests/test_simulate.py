"""The hybrid simulator's Python routes (backend "numpy" and "scipy") against closed forms.

References: the bouncing ball's impact times ``t_1 = sqrt(2h/g)``,
``t_(k+1) = t_k + 2 alpha^k sqrt(2gh)/g`` and accumulation time
``t* = sqrt(2h/g)(1 + alpha)/(1 - alpha)``; free flight (a parabola); energy of elastic
runs; the velocity exchange of equal elastic balls; the symbolic impact map evaluated by
sympy; convergence of a run to itself as the tolerance tightens.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

import symmech as sm
from symmech.examples import (
    bouncing_ball,
    carnot_3_13,
    disk_3_7_gravity,
    ellipse_gravity,
    newtons_cradle,
    pendulum_wall,
)
from symmech.simulate import SimulationError, simulate

BALL = {"m": 1.0, "g": 9.81, "alpha": 0.5}
ELLIPSE = {"m": 1, "I": 5 / 16, "a": 1, "b": 0.5, "g": 9.81, "alpha": 0.8}
ROUTES = [("numpy", "dop853"), ("numpy", "tsit5"), ("scipy", "DOP853")]


def ball_impact_times(h: float, g: float, alpha: float, k: int) -> list[float]:
    """t_1 = sqrt(2h/g), then flights of 2 u_j / g with u_j = alpha^j sqrt(2 g h)."""
    u0 = math.sqrt(2 * g * h)
    times = [math.sqrt(2 * h / g)]
    for j in range(1, k):
        times.append(times[-1] + 2 * alpha**j * u0 / g)
    return times


@pytest.fixture(scope="module")
def ball():
    return bouncing_ball()


@pytest.mark.parametrize("backend,method", ROUTES)
def test_bouncing_ball_impact_times_and_accumulation(ball, backend, method):
    res = simulate(
        ball,
        [1.0],
        [0.0],
        3.0,
        params=BALL,
        backend=backend,
        method=method,
        contact="stop",
        rtol=1e-10,
        atol=1e-12,
    )
    assert res.status == "zeno", res.message
    t_star = math.sqrt(2 / 9.81) * 1.5 / 0.5
    assert res.accumulation_time == pytest.approx(t_star, rel=1e-9, abs=0)
    exact = ball_impact_times(1.0, 9.81, 0.5, 12)
    got = [e.time for e in res.impacts()[:12]]
    np.testing.assert_allclose(got, exact, rtol=0, atol=1e-10)
    # each impact reverses and halves the normal speed: v+ = -alpha v-
    for e in res.impacts()[:12]:
        assert e.v_plus[0] == pytest.approx(-0.5 * e.v_minus[0], rel=1e-12)
        assert e.normal_speed < 0
    # the state never goes below the floor
    assert res.q.min() >= -1e-12


@pytest.mark.parametrize("backend,method", ROUTES)
def test_bouncing_ball_comes_to_rest_with_persistent_contact(ball, backend, method):
    res = simulate(ball, [1.0], [0.0], 3.0, params=BALL, backend=backend, method=method)
    assert res.status == "finished", res.message
    kinds = [e.kind for e in res.events]
    assert kinds[-1] == "contact" and set(kinds[:-1]) == {"impact"}
    contact = res.events[-1]
    t_star = math.sqrt(2 / 9.81) * 1.5 / 0.5
    # contact begins at the first impact whose bounce would not rise above atol: rebound
    # r <= sqrt(2 g atol), the remaining flights last at most 2 r / (g (1 - alpha))
    r = math.sqrt(2 * 9.81 * 1e-10)
    assert t_star - 2 * r / (9.81 * 0.5) <= contact.time <= t_star
    assert contact.normal_speed <= r
    assert res.q[-1, 0] == pytest.approx(0.0, abs=1e-9)
    assert res.v[-1, 0] == 0.0
    assert res.t[-1] == 3.0


@pytest.mark.parametrize("backend,method", ROUTES)
def test_free_flight_and_dense_output_are_the_parabola(ball, backend, method):
    # thrown up from 1 m at 2 m/s: no impact before t = 0.6 s
    res = simulate(
        ball,
        [1.0],
        [2.0],
        0.6,
        params=BALL,
        backend=backend,
        method=method,
        rtol=1e-10,
        atol=1e-12,
    )
    assert res.status == "finished" and res.events == []
    ts = np.linspace(0, 0.6, 13)
    exact = np.column_stack([1 + 2 * ts - 9.81 * ts**2 / 2, 2 - 9.81 * ts])
    np.testing.assert_allclose(res.sol(ts), exact, rtol=0, atol=1e-10)
    np.testing.assert_allclose(res(0.6), exact[-1], rtol=0, atol=1e-10)


def test_elastic_ball_keeps_its_energy_and_period(ball):
    params = {**BALL, "alpha": 1.0}
    res = simulate(ball, [1.0], [0.0], 20.0, params=params, backend="numpy", rtol=1e-10, atol=1e-12)
    assert res.status == "finished"
    period = 2 * math.sqrt(2 / 9.81)
    times = np.array([e.time for e in res.impacts()])
    assert len(times) == int((20 - period / 2) / period) + 1
    np.testing.assert_allclose(np.diff(times), period, rtol=0, atol=1e-9)
    assert abs(sum(e.energy_change for e in res.events)) < 1e-9
    assert res.stats["energy_drift"] < 1e-9


@pytest.mark.parametrize("backend,method", ROUTES)
def test_newtons_cradle_passes_the_velocity_down_the_row(backend, method):
    cradle = newtons_cradle(3)
    # the balls touch (zero gaps): the impact happens at t0, by the sequential rule
    res = simulate(
        cradle,
        [0.0, 1.0, 2.0],
        [1.0, 0.0, 0.0],
        1.0,
        params={"m": 1, "r": 0.5},
        backend=backend,
        method=method,
    )
    assert res.status == "finished"
    assert [e.wall for e in res.impacts()] == [0, 1]
    assert all(e.time == 0.0 for e in res.impacts())
    np.testing.assert_allclose(res.v[-1], [0.0, 0.0, 1.0], atol=1e-14)
    np.testing.assert_allclose(res.q[-1], [0.0, 1.0, 3.0], atol=1e-9)


def test_ellipse_with_gravity_settles_and_converges_across_tolerances():
    scene = ellipse_gravity()
    finals = {}
    for rtol in (1e-7, 1e-9, 1e-11):
        res = simulate(
            scene,
            [0, 1.5, 0.3],
            [0, 0, 2.0],
            6.0,
            params=ELLIPSE,
            backend="scipy",
            method="DOP853",
            rtol=rtol,
            atol=rtol / 100,
        )
        assert res.status == "finished", res.message
        assert res.stats["contacts"] == 1  # it comes to rest on the floor, then rocks
        psi = res.q[:, 1] - np.sqrt(np.sin(res.q[:, 2]) ** 2 + 0.25 * np.cos(res.q[:, 2]) ** 2)
        assert psi.min() > -1e-9  # never through the floor
        finals[rtol] = res.y[-1]
    assert np.max(np.abs(finals[1e-9] - finals[1e-11])) < 1e-7
    assert np.max(np.abs(finals[1e-7] - finals[1e-11])) < 1e-5
    numpy_run = simulate(
        scene,
        [0, 1.5, 0.3],
        [0, 0, 2.0],
        6.0,
        params=ELLIPSE,
        backend="numpy",
        rtol=1e-9,
        atol=1e-11,
    )
    assert np.max(np.abs(numpy_run.y[-1] - finals[1e-11])) < 1e-7


def test_impacts_apply_the_scenes_symbolic_map():
    scene = disk_3_7_gravity()
    params = {"R": 0.5, "alpha": 0.8, "g": 9.81, "k": math.sqrt(2) / 4, "m": 1}
    res = simulate(scene, [0, 1.0, 0], [1.0, 0, 3.0], 0.5, params=params, backend="numpy")
    first = res.impacts()[0]
    post = scene.impact_map(0).post_velocity
    subs = {sp.Symbol(k, positive=True): v for k, v in params.items() if k != "alpha"}
    subs[sp.Symbol("alpha", nonnegative=True)] = params["alpha"]
    subs.update(dict(zip(scene.coordinates, first.q, strict=True)))
    subs.update(dict(zip(scene.velocities, first.v_minus, strict=True)))
    expected = np.array([float(e) for e in post.xreplace(subs)])
    np.testing.assert_allclose(first.v_plus, expected, rtol=1e-13, atol=1e-13)
    # rolling after the impact: x_dot = R theta_dot
    assert first.v_plus[0] == pytest.approx(0.5 * first.v_plus[2], rel=1e-12)


def test_exactly_tangent_touch_applies_no_impact():
    scene = pendulum_wall()
    params = {"alpha": 0.9, "d": 0.5, "g": 9.81, "l": 1.0, "m": 1.0}
    # released at rest at the mirror angle: it swings up to touch the wall with zero speed
    res = simulate(
        scene, [-math.asin(0.5)], [0.0], 4.0, params=params, backend="numpy", rtol=1e-12, atol=1e-14
    )
    assert res.status == "finished"
    assert res.impacts() == []
    assert res.stats["energy_drift"] < 1e-10


def test_a_touch_slower_than_the_tolerance_is_a_grazing_event_not_an_impact():
    # a particle pushed away from the wall x = 0 by a constant force k that still reaches it,
    # at a normal speed of about 1e-12 (below tol_v = atol + rtol |v| = 1e-10)
    (x,) = sm.coordinates("x")
    k = sp.Symbol("k", positive=True)
    scene = sm.Scene(
        (x,),
        metric=sp.Matrix([[1]]),
        potential=-k * x,
        walls=[sm.Wall(x, restitution=1)],
        name="pushed_away",
    )
    res = simulate(
        scene, [1e-13], [-1e-12], 3.0, params={"k": 1e-12}, backend="numpy", rtol=1e-8, atol=1e-10
    )
    assert [e.kind for e in res.events] == ["grazing"]
    assert -1e-12 < res.events[0].normal_speed < 0
    np.testing.assert_array_equal(res.events[0].v_plus, res.events[0].v_minus)


def test_a_slow_approach_with_nothing_pushing_apart_becomes_a_contact_not_a_tunnel():
    cradle = newtons_cradle(2)
    res = simulate(
        cradle,
        [0.0, 1.0 + 1e-12],
        [1e-12, 0.0],
        3.0,
        params={"m": 1, "r": 0.5},
        backend="numpy",
        rtol=1e-8,
        atol=1e-10,
    )
    assert [e.kind for e in res.events] == ["contact"]
    gap = res.q[:, 1] - res.q[:, 0] - 1.0
    assert gap.min() >= -1e-15
    # momentum is shared: the two balls move on together at 5e-13
    np.testing.assert_allclose(res.v[-1], [5e-13, 5e-13], rtol=1e-9)


def test_constrained_sphere_keeps_its_rolling_constraints_and_hits_its_wall():
    scene = carnot_3_13()
    params = {"alpha": 0.5, "k": 0.6, "r": 1.0}
    # rolling towards the wall x = 0 from x = 2 (v_x = -1 = r omega_y, v_y = 0 = -r omega_x)
    q0 = [2.0, 0.0, 1.0, 0.1, 1.0, 0.2]
    v0 = [-1.0, 0.0, 0.0, 0.0, -1.0, 0.3]
    res = simulate(scene, q0, v0, 3.0, params=params, backend="numpy")
    assert res.status == "finished", res.message
    assert len(res.impacts()) == 1
    assert res.impacts()[0].time == pytest.approx(2.0, abs=1e-9)
    assert res.stats["constraint_drift"] < 1e-8


def test_bad_input_is_refused_naming_the_argument(ball):
    def run(**kw):
        args = {"q0": [1.0], "v0": [0.0], "t_end": 1.0, "params": BALL, "backend": "numpy"}
        args.update(kw)
        return simulate(ball, args.pop("q0"), args.pop("v0"), args.pop("t_end"), **args)

    cases = [
        ({"q0": [1.0, 2.0]}, "q0: expected shape"),
        ({"q0": [float("nan")]}, "q0: every entry must be finite"),
        ({"v0": [1j]}, "v0: complex"),
        ({"v0": ["a"]}, "v0: str 'a' is not a real number"),
        ({"q0": [-0.5]}, "wrong side of wall 'floor'"),
        ({"t_end": 0.0}, "t_end must be greater than t0"),
        ({"t_end": float("inf")}, "must be finite"),
        ({"rtol": 0.0}, "rtol"),
        ({"rtol": 1e-17}, "below 100 eps"),
        ({"rtol": 2.0}, "rtol must be below 1"),
        ({"atol": -1.0}, "atol"),
        ({"params": {"m": 1, "g": 9.81}}, "missing ['alpha']"),
        ({"params": {**BALL, "m": -1}}, "['m'] is declared positive"),
        ({"params": {**BALL, "alpha": 5}}, "outside [0, 1]"),
        ({"params": {**BALL, "g": float("nan")}}, "finite"),
        ({"backend": "fortran"}, "backend must be one of"),
        ({"contact": "sticky"}, "contact must be one of"),
        ({"max_events": 0}, "max_events"),
        ({"method": "euler"}, "euler"),
    ]
    for kw, needle in cases:
        with pytest.raises(sm.SymmechError) as info:
            run(**kw)
        assert needle in str(info.value), (kw, str(info.value))
    with pytest.raises(SimulationError, match=r"expected a symmech\.Scene"):
        simulate("ball", [1.0], [0.0], 1.0)


def test_velocity_outside_the_constraints_is_refused():
    scene = carnot_3_13()
    with pytest.raises(SimulationError, match="not in the constraint distribution"):
        simulate(
            scene,
            [2.0, 0, 1, 0.1, 1, 0.2],
            [1, 0, 0, 0, 0, 0],
            1.0,
            params={"alpha": 0.5, "k": 0.6, "r": 1.0},
            backend="numpy",
        )


def test_max_events_stops_an_elastic_run(ball):
    res = simulate(
        ball, [1.0], [0.0], 100.0, params={**BALL, "alpha": 1.0}, backend="numpy", max_events=5
    )
    assert res.status == "max_events" and len(res.events) == 5


def test_the_package_is_callable_as_the_api_promises(ball):
    res = sm.simulate(ball, [1.0], [0.0], 0.1, params=BALL, backend="numpy")
    assert res.status == "finished" and res.success


@pytest.mark.parametrize(
    "backend,method", [("numpy", "rodas4"), ("scipy", "Radau"), ("scipy", "BDF")]
)
def test_implicit_methods_take_large_steps_where_the_stiff_mode_rests(backend, method):
    from symmech.examples import stiff_dumbbell

    scene = stiff_dumbbell()
    params = {"L": 1.0, "alpha": 0.5, "g": 9.81, "k": 1e8, "m": 1.0}
    # free fall with the spring at its rest length: the exact motion is a parabola
    res = simulate(
        scene,
        [1.0, 2.0],
        [0.0, 0.0],
        0.4,
        params=params,
        backend=backend,
        method=method,
        rtol=1e-6,
        atol=1e-8,
    )
    assert res.status == "finished" and res.events == []
    assert res.stats["steps"] < 40
    assert res.stats["jacobian_calls"] > 0
    drop = 9.81 * 0.4**2 / 2
    np.testing.assert_allclose(res.y[-1], [1 - drop, 2 - drop, -3.924, -3.924], atol=1e-5)
    explicit = simulate(
        scene,
        [1.0, 2.0],
        [0.0, 0.0],
        0.4,
        params=params,
        backend="scipy",
        method="DOP853",
        rtol=1e-6,
        atol=1e-8,
    )
    assert explicit.stats["steps"] > 20 * res.stats["steps"]


def test_implicit_route_agrees_with_the_explicit_one_through_impacts():
    from symmech.examples import stiff_dumbbell

    scene = stiff_dumbbell()
    params = {"L": 1.0, "alpha": 0.5, "g": 9.81, "k": 1e4, "m": 1.0}
    runs = [
        simulate(
            scene,
            [0.5, 1.5],
            [0.0, 0.0],
            0.6,
            params=params,
            backend="scipy",
            method=m,
            rtol=1e-10,
            atol=1e-12,
        )
        for m in ("Radau", "DOP853")
    ]
    times = [[e.time for e in r.impacts()] for r in runs]
    assert len(times[0]) == len(times[1]) >= 1
    np.testing.assert_allclose(times[0], times[1], atol=1e-7)
    np.testing.assert_allclose(runs[0].y[-1], runs[1].y[-1], atol=1e-6)


def test_implicit_method_on_the_c_backend_is_refused_with_the_alternatives(ball):
    with pytest.raises(SimulationError, match="implicit"):
        simulate(ball, [1.0], [0.0], 1.0, params=BALL, backend="c", method="rodas4")
