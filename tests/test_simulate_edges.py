"""The simulator at the edges of float64 and of its input: spans a few ulps long, an
overflowing right-hand side or energy, and the real numbers it accepts.

References are the bouncing ball's closed form (drop from height 1: impact at
T = sqrt(2/g) with speed sqrt(2 g), rebound alpha sqrt(2 g)) and the generated code's own
rule for real arguments (:func:`symmech.codegen.runtime_checks.real_array`).
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
import sympy as sp

import symmech as sm
from symmech.examples import bouncing_ball
from symmech.simulate import SimulationError
from symmech.simulate.steppers import initial_step

P = {"m": 1.0, "g": 9.81, "alpha": 0.5}
T = math.sqrt(2 / 9.81)
BACKENDS = ["numpy", "c", "scipy"]


@pytest.fixture(scope="module")
def ball():
    return bouncing_ball()


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize(
    "t_end",
    [T, float(np.nextafter(T, 1)), float(np.nextafter(np.nextafter(T, 1), 1)), T * (1 + 1e-15)],
)
def test_a_run_ending_at_or_just_after_an_impact_reaches_t_end(ball, backend, t_end):
    """The impact leaves a span of a few ulps to t_end: it is the last step, not a step
    size collapse (this used to end with status 'failed', 'step size ... too small')."""
    res = sm.simulate(ball, [1.0], [0.0], t_end, params=P, backend=backend, contact="stop")
    assert res.status == "finished", res.message
    assert res.t[-1] == t_end
    assert abs(res.q[-1, 0]) < 1e-9
    impacts = [e for e in res.events if e.kind == "impact"]
    assert len(impacts) == len(res.events) <= 1
    rebound = P["alpha"] if impacts else -1.0
    assert res.v[-1, 0] == pytest.approx(rebound * math.sqrt(2 * P["g"]), rel=1e-8)


@pytest.mark.parametrize("backend", ["numpy", "c"])
def test_a_span_below_the_resolution_of_time_is_one_step(ball, backend):
    res = sm.simulate(ball, [1.0], [0.0], 1e-300, params=P, backend=backend)
    assert res.status == "finished", res.message
    assert res.stats["steps"] == 1
    assert res.q[-1, 0] == 1.0 and res.v[-1, 0] == pytest.approx(-P["g"] * 1e-300, rel=1e-12)


@pytest.mark.parametrize("backend", ["numpy", "c"])
def test_a_right_hand_side_beyond_float64_ends_the_run_as_failed(ball, backend):
    """g = 1e300: the scaled rhs overflows, the first step is 0 and the run fails with a
    status, on both loops alike (the NumPy loop used to raise ZeroDivisionError)."""
    res = sm.simulate(ball, [1.0], [0.0], 1.0, params={**P, "g": 1e300}, backend=backend)
    assert res.status == "failed"
    assert res.message == "step size 0 too small at t = 0.0"


@pytest.mark.parametrize("backend", ["numpy", "c"])
def test_an_initial_energy_beyond_float64_ends_the_run_as_failed(ball, backend):
    """v0 = 1e200: the energy overflows at t0; the run fails with a status naming the
    generated function (the NumPy loop used to raise NumericalError out of simulate)."""
    res = sm.simulate(ball, [1.0], [1e200], 1.0, params=P, backend=backend)
    assert res.status == "failed"
    assert "energy" in res.message and res.message.endswith("at t = 0.0")


def test_the_first_step_of_an_overflowing_rhs_is_zero():
    def f(t, y):
        return np.array([1e300])

    assert initial_step(f, 0.0, [1.0], [1e300], 1, 4, 1e-6, 1e-9) == 0.0
    # and a plain one is positive and finite
    h = initial_step(lambda t, y: -y, 0.0, [1.0], [-1.0], 1, 4, 1e-6, 1e-9)
    assert 0 < h < math.inf


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"q0": [True]}, "q0: bool True is not a real number"),
        ({"q0": np.ma.masked_array([1.0], mask=[True])}, "q0: masked values"),
        ({"v0": [1 + 0j]}, r"v0: complex \(1\+0j\) is not a real number"),
        ({"params": {**P, "g": "9.81"}}, "params\\['g'\\]: str '9.81' is not a real number"),
        ({"params": {**P, "m": True}}, "params\\['m'\\]: bool True is not a real number"),
        ({"params": {**P, "g": np.array([9.81])}}, "params\\['g'\\]: expected a real number"),
    ],
)
def test_values_the_generated_code_refuses_are_refused_before_a_run(ball, change, match):
    args = {"q0": [1.0], "v0": [0.0], "params": P, **change}
    with pytest.raises(SimulationError, match=match):
        sm.simulate(ball, args["q0"], args["v0"], 0.5, params=args["params"], backend="numpy")


def test_real_numbers_of_any_type_give_the_float_run(ball):
    plain = sm.simulate(ball, [1.0], [0.5], 1.0, params=P, backend="numpy")
    other = sm.simulate(
        ball,
        [sp.Integer(1)],
        np.array([0.5], dtype=">f4"),
        Fraction(1),
        params={"m": sp.Integer(1), "g": np.float64(9.81), "alpha": Fraction(1, 2)},
        backend="numpy",
    )
    assert other.status == plain.status == "finished"
    np.testing.assert_array_equal(other.t, plain.t)
    np.testing.assert_array_equal(other.q, plain.q)
    np.testing.assert_array_equal(other.v, plain.v)


def test_a_grid_column_follows_the_same_rule():
    from symmech.sweep.grid import read_grid

    with pytest.raises(SimulationError, match="grid column 'g': str '1' is not a real number"):
        read_grid({"g": ["1", "2"]})
    with pytest.raises(SimulationError, match="grid column 'g': masked values"):
        read_grid({"g": np.ma.masked_array([1.0, 2.0], mask=[False, True])})
    names, table = read_grid({"g": [sp.Rational(1, 2), Fraction(3, 2)]})
    assert names == ("g",) and table[:, 0].tolist() == [0.5, 1.5]


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_run_stops_at_max_steps_with_its_own_status(ball, backend):
    """max_step = 1e-12 over 1 s would be 10^12 steps: the bound on a run's work stops it,
    at the same step on every backend, in free fall (q = 1 - g t^2 / 2)."""
    res = sm.simulate(
        ball, [1.0], [0.0], 1.0, params=P, backend=backend, max_step=1e-12, max_steps=1000
    )
    assert res.status == "max_steps"
    assert res.stats["steps"] == 1000
    t = float(res.t[-1])
    assert t == pytest.approx(1e-9, rel=1e-9)
    assert res.message == f"stopped after 1000 steps at t = {t!r}"
    assert res.q[-1, 0] == pytest.approx(1 - P["g"] * t * t / 2, abs=1e-15)


def test_max_steps_bounds_every_row_of_a_batch_and_of_a_sweep(ball):
    b = sm.simulate_batch(
        ball, [[1.0], [2.0]], [[0.0], [0.0]], 1.0, params=P, max_step=1e-12, max_steps=50
    )
    assert list(b.statuses) == ["max_steps", "max_steps"]
    assert all(m.startswith("stopped after 50 steps") for m in b.messages)
    pytest.importorskip("pandas")
    tab = sm.sweep(
        ball, {"q0[0]": [1.0, 2.0]}, 1.0, v0=[0.0], params=P, max_step=1e-12, max_steps=50
    )
    assert tab["status"].astype(str).tolist() == ["max_steps", "max_steps"]
    assert tab["steps"].tolist() == [50, 50]


def test_the_default_bound_leaves_an_ordinary_run_alone(ball):
    res = sm.simulate(ball, [1.0], [0.0], 3.0, params=P, backend="c", contact="stop")
    assert res.status == "zeno"  # sqrt(2/g) (1 + alpha)/(1 - alpha)
    assert res.accumulation_time == pytest.approx(3 * T, rel=1e-9)


@pytest.mark.parametrize("bad", [0, -1, True, 1.5, "10"])
def test_max_steps_must_be_a_positive_integer(ball, bad):
    with pytest.raises(SimulationError, match="max_steps must be a positive integer"):
        sm.simulate(ball, [1.0], [0.0], 1.0, params=P, max_steps=bad)
    with pytest.raises(SimulationError, match="max_steps must be a positive integer"):
        sm.simulate_batch(ball, [[1.0]], [[0.0]], 1.0, params=P, max_steps=bad)


@pytest.mark.parametrize("backend", BACKENDS)
def test_continuous_output_inside_the_run_and_refused_outside(ball, backend):
    res = sm.simulate(ball, [1.0], [0.0], 1.0, params=P, backend=backend, rtol=1e-10, atol=1e-12)
    np.testing.assert_array_equal(res(0.0), [1.0, 0.0])
    t = 0.3  # before the first impact: free fall
    np.testing.assert_allclose(res(t), [1 - P["g"] * t * t / 2, -P["g"] * t], atol=1e-9)
    assert res([0.1, 0.2]).shape == (2, 2)
    for bad in (-1e-9, 1.0 + 1e-9, math.nan, [0.1, math.nan]):
        with pytest.raises(ValueError, match="outside the simulated interval"):
            res(bad)


@pytest.mark.parametrize(
    ("option", "bad", "match"),
    [
        ("max_events", 2**60, r"max_events must be a positive integer up to 9007199254740992"),
        ("max_steps", 2**60, r"max_steps must be a positive integer up to"),
        ("event_samples", 10**7, r"event_samples must be a positive integer up to 1000000"),
        ("rtol", "1e-8", r"rtol: str '1e-8' is not a real number"),
        ("t0", "0", r"t0: str '0' is not a real number"),
    ],
)
def test_simulate_batch_and_sweep_check_options_alike(ball, option, bad, match):
    """Counts the C loop could not hold and text where a number belongs are refused the
    same way by simulate, simulate_batch and sweep (one rule, simulate.arguments)."""
    with pytest.raises(SimulationError, match=match):
        sm.simulate(ball, [1.0], [0.0], 1.0, params=P, **{option: bad})
    with pytest.raises(SimulationError, match=match):
        sm.simulate_batch(ball, [[1.0]], [[0.0]], 1.0, params=P, **{option: bad})
    pytest.importorskip("pandas")
    with pytest.raises(SimulationError, match=match):
        sm.sweep(ball, {"q0[0]": [1.0]}, 1.0, v0=[0.0], params=P, **{option: bad})


def test_numpy_integers_are_counts(ball):
    res = sm.simulate(ball, [1.0], [0.0], 3.0, params=P, max_events=np.int64(3), contact="stop")
    assert res.status == "max_events" and len(res.events) == 3


def test_a_sweep_refuses_text_parameters_and_boolean_states(ball):
    pytest.importorskip("pandas")
    grid = {"q0[0]": [1.0]}
    with pytest.raises(SimulationError, match=r"params\['g'\]: str '9.81' is not a real number"):
        sm.sweep(ball, grid, 1.0, v0=[0.0], params={**P, "g": "9.81"})
    with pytest.raises(SimulationError, match="v0: bool True is not a real number"):
        sm.sweep(ball, grid, 1.0, v0=[True], params=P)


def test_definitions_that_print_alike_are_not_confused_by_the_system_cache():
    """{"f": 2 + r sin(t)} with the scene's r, then with a plain Symbol("r") (which prints
    the same): the second is not the scene's parameter and is refused, not served the
    first one's compiled system."""
    from symmech.codegen import CodegenError

    scene = sm.load_scene("carnot_4_4")
    params = {"alpha": 0.5, "k": math.sqrt(0.1), "r": 0.5}
    q0, v0 = [5, 0, 0, 0.3, 1.0, 0.2], [-1.0, 0, 0, 0, -2.0, 0]
    r = next(p for p in scene.parameters if str(p) == "r")
    ok = sm.simulate(
        scene, q0, v0, 4.0, params=params, backend="numpy", definitions={"f": 2 + r * sp.sin(sm.t)}
    )
    assert ok.status == "finished" and len(ok.impacts()) == 1
    with pytest.raises(CodegenError, match=r"function of t and the parameters .* uses \['r'\]"):
        sm.simulate(
            scene,
            q0,
            v0,
            4.0,
            params=params,
            backend="numpy",
            definitions={"f": 2 + sp.Symbol("r") * sp.sin(sm.t)},
        )


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_force_defined_for_the_run_lifts_a_resting_body_off_the_floor(backend):
    """x'' = -g + tau(t) on the floor x >= 0 with tau = 2 g t given by definitions=: the
    body rests (locked contact, normal force g - 2 g t) until t = 1/2, then flies with
    v = g (t - 1/2)^2, x = g (t - 1/2)^3 / 3 (closed form).  The locked contact's force
    used to be printed without the definition (C: an unprintable tau(t))."""
    x = sm.coordinates("x")
    g = sp.Symbol("g", positive=True)
    scene = sm.Scene(
        x,
        metric=sp.eye(1),
        potential=g * x[0],
        forces=[sp.Function("tau")(sm.t)],
        walls=[sm.Wall(x[0], restitution=0)],
        name="lifted",
    )
    res = sm.simulate(
        scene,
        [0.0],
        [0.0],
        1.0,
        params={"g": 9.81},
        definitions={"tau": "2*g*t"},
        backend=backend,
        rtol=1e-10,
        atol=1e-12,
    )
    assert res.status == "finished", res.message
    assert [e.kind for e in res.events] == ["contact", "release"]
    assert res.events[1].time == pytest.approx(0.5, abs=1e-9)
    assert res.q[-1, 0] == pytest.approx(9.81 / 24, abs=1e-12)
    assert res.v[-1, 0] == pytest.approx(9.81 / 4, abs=1e-12)


def test_a_simulated_scene_is_freed_with_its_compiled_systems():
    """The simulator's systems are kept with the scene, not in a module-level cache that
    held every scene ever simulated (and its compiled code) for the life of the process."""
    import gc
    import weakref

    x = sm.coordinates("x")
    refs = []
    for k in (1, 2):
        scene = sm.Scene(
            x, metric=sp.eye(1), potential=k * x[0] ** 2 / 2, walls=[sm.Wall(x[0] + 2)]
        )
        for backend in BACKENDS:
            assert sm.simulate(scene, [1.0], [0.0], 0.1, backend=backend).status == "finished"
        again = sm.simulate.system_for(scene, "c")
        assert sm.simulate.system_for(scene, "c") is again  # built once per scene
        refs.append(weakref.ref(scene))
        del scene, again
    gc.collect()
    assert [r() for r in refs] == [None, None]


def test_attached_keys_name_their_layer(ball):
    assert ball.attached(("test", 1), lambda: [1]) is ball.attached(("test", 1), lambda: [2])
    with pytest.raises(sm.SceneError, match="attached: key must be a tuple naming its layer"):
        ball.attached("test", list)


@pytest.mark.parametrize("backend", BACKENDS)
def test_five_touching_elastic_balls_pass_the_velocity_down_the_row(backend):
    """Newton's cradle of 5 balls at x = 0, 0.2, ..., 0.8 (gaps 0 and +-5.6e-17 in
    float64): the first ball's velocity passes to the last; the others stay at rest.  The
    impact maps leave residues of 1e-16 between balls at rest; such an approach, below the
    rounding level 100 eps |v|, is no approach (it used to start a resting contact, then
    a second one, and the run stopped: "contact with two walls at once is not
    supported")."""
    from symmech.examples import newtons_cradle

    res = sm.simulate(
        newtons_cradle(5),
        [0, 0.2, 0.4, 0.6, 0.8],
        [1.0, 0, 0, 0, 0],
        1.0,
        params={"m": 1.0, "r": 0.1},
        backend=backend,
    )
    assert res.status == "finished", res.message
    assert [e.kind for e in res.events[:4]] == ["impact"] * 4
    assert "contact" not in [e.kind for e in res.events]
    np.testing.assert_allclose(res.v[-1], [0, 0, 0, 0, 1], atol=1e-12)
    assert res.q[-1, 4] == pytest.approx(1.8, abs=1e-12)
