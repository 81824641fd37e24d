"""The C backend of the hybrid simulator (``backend="c"``) and ``simulate_batch``.

The NumPy loop (:mod:`symmech.simulate.hybrid`) is the reference: on every scene the C
loop must take the same decisions (same statuses, same event kinds on the same walls, the
same messages) and land on the same states to a small multiple of the tolerance; where a
closed form exists (the bouncing ball's impact and accumulation times, Newton's cradle's
exchange of velocities, free flight) both are checked against it.  The generated C is
compiled with ``-Wall -Wextra -Werror -pedantic``; the rendered simulator of the bouncing
ball is a golden file (``pytest --update-golden`` refreshes it and prints the diff).
"""

from __future__ import annotations

import math
import subprocess
import warnings

import numpy as np
import pytest
import sympy as sp

import symmech as sm
from symmech import Scene, Wall, coordinates
from symmech.declaration.symbols import t as TIME
from symmech.examples import (
    bouncing_ball,
    carnot_3_13,
    disk_3_7_gravity,
    ellipse_gravity,
    newtons_cradle,
    pendulum_on_cart,
    pendulum_wall,
)
from symmech.simulate import SimulationError, simulate_batch, system_for
from symmech.simulate.csim import C_METHODS, simulator_source
from tests.codegen_support import require_c_compiler

STRICT = ["-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-pedantic"]
BALL = {"m": 1.0, "g": 9.81, "alpha": 0.5}
ELLIPSE = {"m": 1, "I": 5 / 16, "a": 1, "b": 0.5, "g": 9.81, "alpha": 0.8}
DISK = {"m": 1.0, "k": 0.5, "R": 1.0, "g": 9.81, "alpha": 0.5}


@pytest.fixture(scope="module", autouse=True)
def _compiler() -> None:
    require_c_compiler()


def both(scene: Scene, q0, v0, t_end: float, **kw):
    """The NumPy and the C run of the same problem."""
    return tuple(sm.simulate(scene, q0, v0, t_end, backend=b, **kw) for b in ("numpy", "c"))


def assert_same_run(a, b, state_tol: float, time_tol: float) -> None:
    """Same status, message form, event kinds and walls; states and times within tolerance."""
    assert a.status == b.status
    assert [(e.kind, e.wall) for e in a.events] == [(e.kind, e.wall) for e in b.events]
    for ea, eb in zip(a.events, b.events, strict=True):
        assert abs(ea.time - eb.time) <= time_tol, (ea, eb)
        np.testing.assert_allclose(eb.v_plus, ea.v_plus, atol=state_tol, rtol=0)
    np.testing.assert_allclose(b.y[-1], a.y[-1], atol=state_tol, rtol=0)
    assert b.t[-1] == pytest.approx(a.t[-1], abs=time_tol)
    assert set(a.stats) == set(b.stats)
    for key in ("impacts", "grazing", "contacts", "releases"):
        assert a.stats[key] == b.stats[key], key


# ----------------------------------------------------------------------- bouncing ball


def ball_impact_times(h: float, g: float, alpha: float, k: int) -> np.ndarray:
    """t_1 = sqrt(2h/g), t_(j+1) = t_j + 2 alpha^j sqrt(2h/g) (dropped from rest at h)."""
    t1 = math.sqrt(2 * h / g)
    return t1 * (1 + 2 * np.concatenate([[0.0], np.cumsum(alpha ** np.arange(1, k))]))


@pytest.mark.parametrize("method", ["dop853", "tsit5", "rk45"])
def test_bouncing_ball_stop_matches_numpy_and_closed_forms(method):
    a, b = both(bouncing_ball(), [1.0], [0.0], 3.0, params=BALL, method=method, contact="stop")
    assert_same_run(a, b, state_tol=1e-7, time_tol=1e-9)
    assert b.status == "zeno"
    assert b.message.startswith("impacts on wall 'floor' accumulate at t* = ")
    t_star = math.sqrt(2 / 9.81) * (1 + 0.5) / (1 - 0.5)
    assert b.accumulation_time == pytest.approx(t_star, abs=1e-7)
    times = np.array([e.time for e in b.impacts()])
    np.testing.assert_allclose(times[:15], ball_impact_times(1.0, 9.81, 0.5, 15), atol=1e-9)
    # located on the dense output to near machine precision (the flight is a parabola)
    assert abs(times[0] - math.sqrt(2 / 9.81)) < 50 * np.finfo(float).eps


def test_bouncing_ball_persistent_rests_on_the_floor():
    a, b = both(bouncing_ball(), [1.0], [0.0], 3.0, params=BALL)
    assert_same_run(a, b, state_tol=1e-9, time_tol=1e-9)
    assert b.status == "finished" and b.message == "reached t_end = 3.0"
    assert b.stats["contacts"] == 1 and b.events[-1].kind == "contact"
    t_star = math.sqrt(2 / 9.81) * 3
    # contact from the first impact whose bounce would not rise above atol (rebound
    # r <= sqrt(2 g atol)); the remaining flights last at most 2 r / (g (1 - alpha))
    r = math.sqrt(2 * 9.81 * 1e-10)
    assert t_star - 2 * r / (9.81 * 0.5) <= b.events[-1].time <= t_star
    assert b.q[-1, 0] == 0.0 and b.v[-1, 0] == 0.0  # locked contact: the body rests
    # the step sequences agree up to roundoff: on a parabola the error estimate is pure
    # roundoff, and a factor of 10 against 9.2 after an estimate of 1e-9 changes the count
    assert abs(b.stats["steps"] - a.stats["steps"]) <= 0.2 * a.stats["steps"]


def test_rk4_fixed_step_matches_numpy():
    kw = {"params": BALL, "method": "rk4", "max_step": 1e-2, "contact": "stop"}
    a, b = both(bouncing_ball(), [1.0], [0.0], 3.0, **kw)
    assert_same_run(a, b, state_tol=1e-8, time_tol=1e-9)
    assert b.stats["rejected_steps"] == 0
    np.testing.assert_allclose(np.diff(b.t[:5]), 1e-2, rtol=1e-12)


def test_dense_output_is_the_parabola_between_impacts():
    res = sm.simulate(bouncing_ball(), [1.0], [0.0], 0.9, params=BALL, backend="c")
    t1 = math.sqrt(2 / 9.81)
    ts = np.linspace(0, 0.99 * t1, 17)
    np.testing.assert_allclose(res.sol(ts)[:, 0], 1 - 9.81 * ts**2 / 2, atol=1e-12)
    v1 = 0.5 * 9.81 * t1  # rebound speed
    ts = np.linspace(1.01 * t1, 0.9, 11)
    y = v1 * (ts - t1) - 9.81 * (ts - t1) ** 2 / 2
    np.testing.assert_allclose(res.sol(ts)[:, 0], y, atol=1e-9)


def test_thousands_of_elastic_bounces_grow_the_buffers():
    """3000 elastic bounces: more events and steps than the first output buffers hold
    (the C loop pauses and continues); impact times t_k = (2k - 1) sqrt(2h/g)."""
    params = {"m": 1.0, "g": 9.81, "alpha": 1.0}
    period = 2 * math.sqrt(2 / 9.81)
    res = sm.simulate(
        bouncing_ball(), [1.0], [0.0], 3000 * period, params=params, backend="c", rtol=1e-10
    )
    assert res.status == "finished"
    assert res.stats["impacts"] == 3000
    times = np.array([e.time for e in res.impacts()])
    k = np.arange(1, 3001)
    np.testing.assert_allclose(times, (2 * k - 1) * period / 2, rtol=1e-8)
    assert len(res.t) > 1024 and len(res.t) == 1 + len(res.segments) + 3000
    assert res.stats["energy_drift"] < 1e-8
    assert np.all(np.diff(res.t) >= 0)


@pytest.mark.slow
def test_a_hundred_thousand_events_run_without_a_fixed_cap():
    params = {"m": 1.0, "g": 9.81, "alpha": 1.0}
    period = 2 * math.sqrt(2 / 9.81)
    res = sm.simulate(
        bouncing_ball(),
        [1.0],
        [0.0],
        100_000 * period,
        params=params,
        backend="c",
        rtol=1e-10,
        max_events=200_000,
    )
    assert res.status == "finished" and res.stats["impacts"] == 100_000
    times = np.array([e.time for e in res.impacts()])
    # the energy error of the event states accumulates (5.5e-6 of 9.81 after 1e5 impacts)
    assert res.stats["energy_drift"] < 1e-5
    np.testing.assert_allclose(np.diff(times), period, rtol=1e-6)  # each flight
    assert abs(times[-1] - (100_000 - 0.5) * period) < 0.05  # the phase drifts with it


# ------------------------------------------------------------------ the other scenes


def test_ellipse_with_gravity_matches_numpy():
    kw = {"params": ELLIPSE, "rtol": 1e-9}
    a, b = both(ellipse_gravity(), [0, 1.5, 0.3], [0, 0, 2], 6.0, **kw)
    assert b.status == a.status == "finished"
    assert b.stats["impacts"] == a.stats["impacts"] > 20
    assert b.stats["contacts"] == a.stats["contacts"] == 1
    np.testing.assert_allclose(b.y[-1], a.y[-1], atol=1e-6)
    ea, eb = a.impacts()[:20], b.impacts()[:20]
    np.testing.assert_allclose([e.time for e in eb], [e.time for e in ea], atol=1e-8)
    assert b.stats["energy_drift"] < 1e-6
    # never through the floor: psi = y - sqrt(a^2 sin^2 th + b^2 cos^2 th) >= 0 (a=1, b=1/2)
    th = b.q[:, 2]
    psi = b.q[:, 1] - np.sqrt(np.sin(th) ** 2 + 0.25 * np.cos(th) ** 2)
    assert psi.min() >= -1e-9
    ts = np.linspace(0, 3.5, 41)  # DOP853's own dense output (made for the event search)
    np.testing.assert_allclose(b.sol(ts), a.sol(ts), atol=1e-7)


@pytest.mark.slow
@pytest.mark.parametrize("method", ["tsit5", "rk45"])
def test_ellipse_with_gravity_matches_numpy_each_method(method):
    kw = {"params": ELLIPSE, "rtol": 1e-9, "method": method}
    a, b = both(ellipse_gravity(), [0, 1.5, 0.3], [0, 0, 2], 6.0, **kw)
    assert b.status == a.status == "finished"
    np.testing.assert_allclose(b.y[-1], a.y[-1], atol=1e-6)
    assert abs(b.stats["impacts"] - a.stats["impacts"]) <= 1


@pytest.mark.parametrize("method", ["dop853", "tsit5", "rk45"])
def test_newtons_cradle_passes_the_velocity_down_the_row(method):
    a, b = both(
        newtons_cradle(3), [0, 2, 4], [1, 0, 0], 2.0, params={"m": 1, "r": 1}, method=method
    )
    assert_same_run(a, b, state_tol=1e-12, time_tol=1e-12)
    assert [e.kind for e in b.events] == ["impact", "impact"]
    assert [e.wall for e in b.events] == [0, 1]
    np.testing.assert_allclose(b.v[-1], [0, 0, 1], atol=1e-14)
    np.testing.assert_allclose(b.q[-1], [0, 2, 6], atol=1e-12)


@pytest.mark.parametrize("method", ["dop853", "tsit5", "rk45"])
def test_disk_3_7_rolls_at_each_impact(method):
    a, b = both(disk_3_7_gravity(), [0, 2, 0], [1, 0, 0], 3.0, params=DISK, method=method)
    assert_same_run(a, b, state_tol=1e-8, time_tol=1e-8)
    assert b.stats["impacts"] > 5 and b.stats["contacts"] == 1
    for e in b.impacts():
        assert e.v_plus[0] - 1.0 * e.v_plus[2] == pytest.approx(0, abs=1e-12)  # x_dot = R th_dot
    # resting on the floor it rolls at constant speed: y = R, y_dot = 0, x_dot = R th_dot
    assert b.q[-1, 1] == pytest.approx(1.0, abs=1e-9)
    assert b.v[-1, 1] == pytest.approx(0.0, abs=1e-9)
    assert b.v[-1, 0] == pytest.approx(b.v[-1, 2], abs=1e-9)


def test_constrained_rolling_sphere_hits_its_wall():
    """Carnot example 3.13: the constrained scene keeps v in D (projection after each step)."""
    v0 = [-1, 0.5, 0, -0.5, -1, 0.3]
    kw = {"params": {"k": 0.6, "r": 1.0, "alpha": 0.5}}
    a, b = both(carnot_3_13(), [1, 0, 0, 0, 1, 0], v0, 2.0, **kw)
    assert_same_run(a, b, state_tol=1e-8, time_tol=1e-9)
    assert b.stats["impacts"] == 1
    assert b.stats["constraint_drift"] < 1e-8
    assert b.v[-1, 0] > 0  # bounced off x = 0
    # the impact's Gram condition (LU solve and Jacobi eigenvalues in C, SVD in NumPy)
    assert b.stats["impact_condition"] == pytest.approx(a.stats["impact_condition"], rel=1e-9)
    assert b.stats["impact_condition"] > 1


def test_moving_wall_matches_numpy():
    """A ball on an oscillating floor psi = y - A sin(w t) (psi_t in the normal rate, the
    accumulation on a moving wall stops the run)."""
    (y,) = coordinates("y")
    m, g = sp.symbols("m g", positive=True)
    wall = Wall(y - sp.sin(7 * TIME) / 20, restitution=sp.Rational(7, 10), name="shaker")
    scene = Scene((y,), metric=sp.Matrix([[m]]), potential=m * g * y, walls=[wall], name="shaker")
    a, b = both(scene, [0.5], [0.0], 4.0, params={"m": 1, "g": 9.81})
    assert_same_run(a, b, state_tol=1e-6, time_tol=1e-8)
    assert b.stats["impacts"] > 3
    for e in b.impacts():  # d psi/dt = y_dot - (7/20) cos(7 t)
        assert e.normal_speed == pytest.approx(
            e.v_minus[0] - 0.35 * math.cos(7 * e.time), abs=1e-12
        )
        assert e.q[0] == pytest.approx(math.sin(7 * e.time) / 20, abs=1e-12)


def test_pendulum_wall_and_a_scene_without_walls():
    p = {"m": 1.0, "l": 1.0, "g": 9.81, "d": 0.5, "alpha": 0.9}
    a, b = both(pendulum_wall(), [0.0], [3.0], 3.0, params=p)
    assert_same_run(a, b, state_tol=1e-8, time_tol=1e-9)
    assert b.stats["impacts"] >= 2
    scene = pendulum_on_cart(1)
    params = {str(s): 1.0 for s in scene.parameters}
    a, b = both(scene, [0.0, 0.3], [0.0, 0.0], 2.0, params=params, method="tsit5")
    assert a.status == b.status == "finished" and not b.events
    np.testing.assert_allclose(b.y[-1], a.y[-1], atol=1e-8)
    ts = np.linspace(0, 2, 23)
    np.testing.assert_allclose(b.sol(ts), a.sol(ts), atol=1e-8)  # the same dense output


def test_tangential_touches_grazing_and_creeping_contact_match_numpy():
    """A touch slower than tol_v pushed away is a grazing event; a creeping approach with
    nothing pushing apart becomes a contact, never a tunnel (hybrid.py's rules)."""
    (x,) = coordinates("x")
    k = sp.Symbol("k", positive=True)
    pushed = Scene(
        (x,), metric=sp.Matrix([[1]]), potential=-k * x, walls=[Wall(x, restitution=1)], name="px"
    )
    kw = {"params": {"k": 1e-12}, "rtol": 1e-8, "atol": 1e-10}
    a, b = both(pushed, [1e-13], [-1e-12], 3.0, **kw)
    assert_same_run(a, b, state_tol=1e-20, time_tol=1e-12)
    assert [e.kind for e in b.events] == ["grazing"]
    kw = {"params": {"m": 1, "r": 0.5}, "rtol": 1e-8, "atol": 1e-10}
    a, b = both(newtons_cradle(2), [0.0, 1.0 + 1e-12], [1e-12, 0.0], 3.0, **kw)
    assert_same_run(a, b, state_tol=1e-20, time_tol=1e-9)
    assert [e.kind for e in b.events] == ["contact"]
    assert np.min(b.q[:, 1] - b.q[:, 0] - 1.0) >= -1e-15
    np.testing.assert_allclose(b.v[-1], [5e-13, 5e-13], rtol=1e-9)


def test_non_finite_rhs_in_a_trial_stage_rejects_the_step():
    """V = k sqrt(y): the force is NaN below the floor, where trial stages land as the
    ball nears it; those steps are rejected (shrunk), as in the NumPy loop, until the step
    size underflows at the singular force (both loops stop with the same message)."""
    (y,) = coordinates("y")
    m, k = sp.symbols("m k", positive=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # sqrt(y) is not real below the floor
        scene = Scene(
            (y,),
            metric=sp.Matrix([[m]]),
            potential=k * sp.sqrt(y),
            walls=[Wall(y, restitution=sp.Rational(1, 2), name="floor")],
            name="sqrt_well",
        )
    a, b = both(scene, [1.0], [0.0], 3.0, params={"m": 1, "k": 1})
    assert a.status == b.status == "failed"
    assert b.message.startswith("step size ") and "too small at t = 1.88561808" in b.message
    assert b.stats["rejected_steps"] == a.stats["rejected_steps"] > 20
    assert np.all(np.isfinite(b.y))
    # the speed reached is that of the closed form: v^2 = 2 k sqrt(y0) / m
    assert b.v[-1, 0] == pytest.approx(-math.sqrt(2), rel=1e-6)


def test_nan_trial_stage_with_a_curved_gap_is_rejected_not_raised():
    """The walls' gap rates of a NaN trial stage are NaN (the step is rejected) even when
    the wall's gradient reads q: psi = y + y^3/100 under the V = k sqrt(y) well."""
    (y,) = coordinates("y")
    m, k = sp.symbols("m k", positive=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = Scene(
            (y,),
            metric=sp.Matrix([[m]]),
            potential=k * sp.sqrt(y),
            walls=[Wall(y + y**3 / 100, restitution=sp.Rational(1, 2), name="floor")],
            name="sqrt_well_curved",
        )
    res = sm.simulate(scene, [1.0], [0.0], 3.0, params={"m": 1, "k": 1}, backend="c")
    assert res.status == "failed" and res.message.startswith("step size ")
    assert res.stats["rejected_steps"] > 20 and np.all(np.isfinite(res.y))


FAST_STRESS = ["mass_ratio", "aspect_ratio", "grazing", "nearly_dependent", "zeno", "cradle"]


@pytest.mark.parametrize("name", FAST_STRESS)
def test_stress_cases_pass_on_the_c_route(name):
    from symmech.bench import stress

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        results = stress.run_all("c", [name])
    assert results and all(r.passed for r in results), stress.format_table(results)
    if name == "nearly_dependent":
        refused = [r for r in results if r.error != r.error]
        assert refused and all("nearly dependent" in r.detail for r in refused)


# ------------------------------------------------------------------------------- batch


def test_batch_equals_looping_simulate_bit_for_bit_and_threads_do_not_matter():
    rng = np.random.default_rng(12)
    N = 12
    Q0 = np.column_stack([rng.uniform(-1, 1, N), rng.uniform(1, 2, N), rng.uniform(0, 3, N)])
    V0 = rng.uniform(-2, 2, (N, 3))
    kw = {"params": ELLIPSE, "rtol": 1e-7, "atol": 1e-9, "max_events": 47}
    scene = ellipse_gravity()
    one = simulate_batch(scene, Q0, V0, 5.0, threads=1, **kw)
    two = simulate_batch(scene, Q0, V0, 5.0, threads=2, **kw)
    assert {"finished", "max_events"} <= set(one.statuses) and one.events[:, 2].sum() > 3
    for field in ("t", "q", "v", "status", "events", "steps"):
        assert np.array_equal(getattr(one, field), getattr(two, field)), field
    assert np.array_equal(one.accumulation_time, two.accumulation_time, equal_nan=True)
    for i in range(N):
        r = sm.simulate(scene, Q0[i], V0[i], 5.0, backend="c", **kw)
        assert one.statuses[i] == r.status and one.messages[i] == r.message
        assert np.array_equal(one.q[i], r.q[-1]) and np.array_equal(one.v[i], r.v[-1])
        assert one.t[i] == r.t[-1]
        counts = [r.stats[k] for k in ("impacts", "grazing", "contacts", "releases")]
        assert one.events[i].tolist() == counts
        assert one.steps[i] == r.stats["steps"]


def test_batch_accumulation_times_of_the_bouncing_ball():
    h = np.array([0.5, 1.0, 2.0, 3.0])
    res = simulate_batch(
        bouncing_ball(), h[:, None], np.zeros((4, 1)), 10.0, params=BALL, contact="stop"
    )
    assert res.statuses.tolist() == ["zeno"] * 4
    np.testing.assert_allclose(res.accumulation_time, np.sqrt(2 * h / 9.81) * 3, atol=1e-7)
    persistent = simulate_batch(bouncing_ball(), h[:, None], np.zeros((4, 1)), 10.0, params=BALL)
    assert persistent.statuses.tolist() == ["finished"] * 4
    assert np.all(persistent.events[:, 2] == 1) and np.all(np.isnan(persistent.accumulation_time))
    assert np.all(persistent.q == 0) and np.all(persistent.t == 10.0)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"Q0": [[1.0, 2.0]]}, r"Q0: expected shape \(N, 1\)"),
        ({"Q0": [[1.0], [np.nan]]}, r"Q0: row 1 is not finite"),
        ({"Q0": [[1.0], [-1.0]]}, r"Q0 row 1 is on the wrong side of wall 'floor'"),
        ({"V0": [[0.0]]}, r"Q0 and V0: 2 rows against 1 rows"),
        ({"V0": [["a"], ["b"]]}, r"V0: str 'a' is not a real number"),
        ({"t_end": 0.0}, r"t_end must be greater than t0"),
        ({"rtol": 2.0}, r"rtol must be below 1"),
        ({"atol": -1.0}, r"atol: expected a finite positive number"),
        ({"threads": 0}, r"threads must be a positive integer"),
        ({"max_events": 0}, r"max_events must be a positive integer"),
        ({"contact": "glue"}, r"contact must be one of"),
        ({"method": "rodas4"}, r"method 'rodas4' is not available with backend='c'"),
        ({"params": {"m": 1.0, "g": 9.81}}, r"params: missing \['alpha'\]"),
        ({"params": {"m": 1.0, "g": 9.81, "alpha": 2.0}}, r"restitution"),
    ],
)
def test_batch_bad_input_names_the_argument(kwargs, match):
    args = {"Q0": [[1.0], [2.0]], "V0": [[0.0], [0.0]], "t_end": 1.0, "params": BALL}
    args.update(kwargs)
    Q0, V0, t_end = args.pop("Q0"), args.pop("V0"), args.pop("t_end")
    with pytest.raises(SimulationError, match=match):
        simulate_batch(bouncing_ball(), Q0, V0, t_end, **args)


def test_simulate_c_refuses_a_method_it_does_not_run():
    with pytest.raises(SimulationError, match="rodas4"):
        sm.simulate(bouncing_ball(), [1.0], [0.0], 1.0, params=BALL, method="rodas4")
    assert C_METHODS == ("dop853", "tsit5", "rk45", "rk4")


def test_batch_does_not_modify_its_inputs():
    Q0, V0 = np.array([[1.0]]), np.array([[0.0]])
    simulate_batch(bouncing_ball(), Q0, V0, 0.1, params=BALL, threads=1)
    assert Q0.tolist() == [[1.0]] and V0.tolist() == [[0.0]]


# ------------------------------------------------------------------- generated C itself


@pytest.mark.parametrize(
    "make", [bouncing_ball, ellipse_gravity, carnot_3_13, lambda: pendulum_on_cart(1)]
)
def test_simulator_compiles_with_strict_warnings(tmp_path, make):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        files = simulator_source(system_for(make(), "c"))
    for name, text in files.items():
        (tmp_path / name).write_text(text, encoding="utf-8")
    (source,) = [name for name in files if name.endswith("_simulator.c")]
    proc = subprocess.run(
        [require_c_compiler(), *STRICT, "-c", source], cwd=tmp_path, capture_output=True, text=True
    )
    assert proc.returncode == 0, proc.stderr


def test_equations_alone_get_no_simulator_code():
    code = sm.codegen.generate(bouncing_ball(), "c")
    assert not any("simulator" in name for name in code.files)
    assert not any("sim_run" in text for text in code.files.values())


def test_simulator_golden_file(golden):
    """The rendered simulator of the bouncing ball equals its golden file."""
    files = simulator_source(system_for(bouncing_ball(), "c"))
    name = "symmech_bouncing_ball_simulator.c"
    golden("simulator_bouncing_ball", name, files[name])


def test_tableaux_are_printed_exactly():
    """Every coefficient in the C source reads back to the double of c_tableau."""
    from symmech.simulate.c_tableaux import c_tableau

    text = simulator_source(system_for(bouncing_ball(), "c"))["symmech_bouncing_ball_simulator.c"]
    for method in C_METHODS:
        for key, values in c_tableau(method).items():
            line = next(x for x in text.splitlines() if f" m_{method}_{key}[" in x)
            printed = line.split("{", 1)[1].rsplit("}", 1)[0].split(",")
            assert [float(v) for v in printed] == values, (method, key)


_DRIVER = r"""
#include <stdio.h>
#include <stdlib.h>
void *PREFIXnew(int, const double *, const double *, int);
void PREFIXbegin(void *, double, const double *);
int PREFIXrun(void *, double *, long, double *, long, double *, int *, long, long *);
void PREFIXinfo(const void *, double *);
void PREFIXfree(void *);
int PREFIXbatch(long, const double *, double, int, const double *, const double *, double *);
int main(void)
{
    double P[] = { PARAMS }, y0[] = { Y0 }, info[64], Y[2 * NYV];
    long cap = 64, ecap = 512, counts[3], total = 0;
    for (int method = 0; method < 4; ++method) {
        double opts[] = { OPTS };
        opts[FIXEDI] = method == 3 ? TEND / 2000 : 0.0;
        void *s = PREFIXnew(method, opts, P, 1);
        double *rec = malloc(sizeof(double) * cap * (NYV + 1));
        double *seg = malloc(sizeof(double) * cap * (4 + 8 * NYV));
        double *ev = malloc(sizeof(double) * ecap * (3 + 3 * NYV));
        int *evi = malloc(sizeof(int) * ecap * 2);
        PREFIXbegin(s, 0.0, y0);
        while (PREFIXrun(s, rec, cap, seg, cap, ev, evi, ecap, counts)) total += counts[0];
        total += counts[0];
        PREFIXinfo(s, info);
        printf("method %d status %g events %g\n", method, info[0], info[EVENTSI]);
        PREFIXfree(s);
        free(rec); free(seg); free(ev); free(evi);
        for (int i = 0; i < NYV; ++i) Y[i] = Y[NYV + i] = y0[i];
        double binfo[2 * (INFOHEAD + NYV)];
        if (PREFIXbatch(2, Y, 0.0, method, opts, P, binfo) != 0) return 1;
    }
    printf("records %ld\n", total);
    return 0;
}
"""


ROD = {"alpha": 0.5, "g": 9.81, "l": 1.0, "m": 1.0}


def falling_rod() -> sm.Scene:
    return sm.load_scene("falling_rod")


@pytest.mark.slow
@pytest.mark.parametrize(
    ("make", "y0", "t_end"),
    [
        (bouncing_ball, [1.0, 0.0], 3.0),
        (ellipse_gravity, [0, 1.5, 0.3, 0, 0, 2], 6.0),
        (falling_rod, [0, 1.0, 0, 0, 0, 0], 3.0),  # simultaneous impacts on two walls
    ],
)
def test_simulator_is_clean_under_address_and_undefined_sanitizers(tmp_path, make, y0, t_end):
    """Every method, pausing output buffers and the batch entry, under ASan and UBSan."""
    from symmech.simulate import protocol
    from symmech.simulate.csim import library, options_vector
    from symmech.simulate.hybrid import Options

    system = system_for(make(), "c")
    if make is falling_rod:  # both ends held: the contact mode of the pair built in
        system.add_c_mode((0, 1))
    lib = library(system)
    params = {bouncing_ball: BALL, ellipse_gravity: ELLIPSE, falling_rod: ROD}[make]
    P = lib.parameters({k: float(v) for k, v in params.items()})
    loop = Options(t_end=float(t_end), rtol=1e-8, atol=1e-10, max_events=400)
    opts = options_vector(loop, "dop853", float(t_end) / 50, 0.0)[1]
    driver = (
        _DRIVER.replace("PREFIX", lib.spec.prefix)
        .replace("PARAMS", ", ".join(repr(float(x)) for x in P))
        .replace("Y0", ", ".join(repr(float(x)) for x in y0))
        .replace("NYV", str(len(y0)))
        .replace("TEND", repr(float(t_end)))
        .replace("OPTS", ", ".join(repr(float(x)) for x in opts))
        .replace("FIXEDI", str(protocol.OPTIONS.index("fixed_step")))
        .replace("EVENTSI", str(protocol.INFO.index("events")))
        .replace("INFOHEAD", str(protocol.INFO_HEAD))
    )
    for name, text in lib.sources.items():
        (tmp_path / name).write_text(text, encoding="utf-8")
    (tmp_path / "driver.c").write_text(driver, encoding="utf-8")
    sources = [name for name in lib.sources if name.endswith(".c")] + ["driver.c"]
    flags = ["-std=c99", "-O1", "-g", "-fsanitize=address,undefined", "-fno-sanitize-recover=all"]
    exe = tmp_path / "driver"
    build = subprocess.run(
        [require_c_compiler(), *flags, "-o", str(exe), *sources, "-lm"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
    )
    assert build.returncode == 0, build.stderr
    run = subprocess.run([str(exe)], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout + run.stderr
    assert run.stdout.count("status 1 ") == 4, run.stdout  # every method finished


# -- one run from Python: workspaces, lazy events, cached checks, compiler flags ----------


def _ellipse_run(**kw):
    return sm.simulate(
        ellipse_gravity(), (0.0, 1.5, 0.3), (0.0, 0.0, 2.0), 3.5, params=ELLIPSE, **kw
    )


def test_runs_in_threads_equal_the_sequential_run_bit_for_bit():
    from concurrent.futures import ThreadPoolExecutor

    ref = _ellipse_run(rtol=1e-8)
    with ThreadPoolExecutor(4) as pool:
        runs = list(pool.map(lambda _: _ellipse_run(rtol=1e-8), range(16)))
    for r in runs:
        assert np.array_equal(r.t, ref.t) and np.array_equal(r.q, ref.q)
        assert np.array_equal(r.v, ref.v)
        assert [e.time for e in r.events] == [e.time for e in ref.events]


def test_a_run_longer_than_the_buffers_continues_across_pauses(monkeypatch):
    """Buffers of 8 step rows (the least the loop works with): it pauses every few steps;
    the run equals the one with the usual buffers (a fresh thread, so a fresh workspace of
    the patched size)."""
    import threading

    from symmech.simulate import c_run

    ref = _ellipse_run(rtol=1e-6)
    monkeypatch.setattr(c_run, "STEP_ROWS", 1)
    out = []
    worker = threading.Thread(target=lambda: out.append(_ellipse_run(rtol=1e-6)))
    worker.start()
    worker.join()
    (small,) = out
    assert len(ref.t) > 40 and len(ref.events) > 8
    assert np.array_equal(small.t, ref.t) and np.array_equal(small.y, ref.y)
    assert [(e.time, e.kind) for e in small.events] == [(e.time, e.kind) for e in ref.events]
    assert np.allclose(small(1.234), ref(1.234), rtol=0, atol=0)


def test_events_are_built_on_first_access_and_compare_as_a_list():
    from symmech.simulate.result import EventTable

    res = _ellipse_run()
    assert isinstance(res.events, EventTable) and res.events._built is None
    assert len(res.events) == res.stats["impacts"] == 11 and res.events._built is None
    first, last = res.events[0], res.events[-1]
    assert res.events[:2] == [first, res.events[1]][:2] and res.events[1:3][0] is res.events[1]
    assert first.kind == "impact" and first.wall_name == "floor" and first.time < last.time
    assert res.impacts() == list(res.events)
    assert len(first.q) == 3 and first.v_plus[1] > 0 > first.v_minus[1]
    none = sm.simulate(ellipse_gravity(), (0.0, 3.0, 0.0), (0.0, 0.0, 0.0), 0.1, params=ELLIPSE)
    assert none.events == [] and not none.events and none.events != [first]


def test_parameters_checked_again_whenever_they_change():
    ok = _ellipse_run(rtol=1e-6)
    assert ok.status == "finished"
    bad = dict(ELLIPSE, alpha=1.5)
    with pytest.raises(SimulationError, match=r"restitution .* outside \[0, 1\]"):
        sm.simulate(ellipse_gravity(), (0.0, 1.5, 0.3), (0.0, 0.0, 2.0), 1.0, params=bad)
    with pytest.raises(SimulationError, match="declared positive"):
        sm.simulate(
            ellipse_gravity(), (0.0, 1.5, 0.3), (0.0, 0.0, 2.0), 1.0, params=dict(ELLIPSE, m=-1.0)
        )
    nan = dict(ELLIPSE, g=float("nan"))
    for _ in range(2):  # NaN never equals the cached parameters
        with pytest.raises(SimulationError, match="finite"):
            sm.simulate(ellipse_gravity(), (0.0, 1.5, 0.3), (0.0, 0.0, 2.0), 1.0, params=nan)
    heavier = sm.simulate(
        ellipse_gravity(), (0.0, 1.5, 0.3), (0.0, 0.0, 2.0), 3.5, params=dict(ELLIPSE, g=20.0)
    )
    assert heavier.events[0].time < ok.events[0].time  # the new g was used


def test_simulator_flags_do_not_change_the_bits():
    """The simulator library is built at -O3; the same run built at the code generator's
    -O2 gives the same bits (C99 mode: no FMA contraction, no reassociation)."""
    from symmech.codegen.build import DEFAULT_FLAGS
    from symmech.simulate.c_run import run_c
    from symmech.simulate.csim import SIMULATOR_FLAGS, CLibrary, library
    from symmech.simulate.hybrid import Options
    from symmech.simulate.parameters import check_parameters

    assert "-O3" in SIMULATOR_FLAGS and "-O2" in DEFAULT_FLAGS
    scene = ellipse_gravity()
    system = system_for(scene, "c")
    values = check_parameters(scene, ELLIPSE)
    y0 = np.array([0.0, 1.5, 0.3, 0.0, 0.0, 2.0])
    opts = Options(t_end=6.0, rtol=1e-9, atol=1e-11, max_events=100_000, contact="persistent")
    fast = run_c(system, values, y0, 0.0, opts, max_step=6.0)
    assert library(system).flags == SIMULATOR_FLAGS
    system.__dict__["_c_simulator"] = CLibrary(system, flags=DEFAULT_FLAGS)
    try:
        plain = run_c(system, values, y0, 0.0, opts, max_step=6.0)
    finally:
        del system.__dict__["_c_simulator"]
    assert fast.status == plain.status and len(fast.events) == len(plain.events) > 11
    assert np.array_equal(fast.t, plain.t) and np.array_equal(fast.y, plain.y)


def test_a_release_with_zero_normal_force_does_not_chatter():
    """The ellipse sliding on the floor is released where its normal force reaches zero;
    just after, its free gap grows like (t - t_r)^3, below the rounding of y for a while.
    The released wall is searched through psi + tol_psi until the body leaves that band:
    no re-contact at the release time, no grazing cascade, no step collapse (before: status
    failed, "step size 4.4e-16 too small" at t = 0.828 on both backends).  Both loops take
    the same events and land on the mpmath run of the same algorithm (24 digits)."""
    from symmech.simulate.reference import reference_run

    params = dict(ELLIPSE, alpha=0.10800800800800801)
    q0, v0 = (0.0, 1.5, 1.3327969736464463), (0.0, 0.0, 2.0)
    runs = both(ellipse_gravity(), q0, v0, 1.5, params=params, rtol=1e-8, atol=1e-10)
    for res in runs:
        assert res.status == "finished", res.message
        kinds = [e.kind for e in res.events]
        k = kinds.index("release")
        assert 0.82 < res.events[k].time < 0.83
        assert kinds[k + 1] != "contact" and "grazing" not in kinds[k + 1 : k + 3]
    assert_same_run(*runs, state_tol=1e-7, time_tol=1e-9)
    ref = reference_run(ellipse_gravity(), q0, v0, 1.5, params=params, dps=24)
    assert ref.status == "finished"
    y_ref = np.array([float(x) for x in ref.y[-1]])
    assert np.max(np.abs(runs[1].y[-1] - y_ref)) < 1e-7
