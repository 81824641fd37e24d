"""The stride loop in generated C (symmech.gait.native) against its Python reference.

The Python loop of :mod:`symmech.gait.stride_map` and the C loop of
``templates/c/stride.c.jinja`` are two implementations of one algorithm over the same
generated functions: they must give the same stride, the same Jacobian and the same
events to rounding, on every built-in gait (one mode and two modes of different sizes).
The multipliers' agreement with mpmath central differences is in test_gait_reference.py.
"""

from __future__ import annotations

import itertools
import re

import numpy as np
import pytest
import sympy as sp

from symmech.declaration.symbols import coordinates, t, velocities
from symmech.declaration.wall import Wall
from symmech.errors import SceneError
from symmech.gait.evaluation import CompiledGait
from symmech.gait.models import GAITS
from symmech.gait.modes import Gait, Reset, Transition
from symmech.gait.stride_map import GaitError, StrideOptions, stride
from symmech.scene import Scene


@pytest.fixture(scope="module", params=sorted(GAITS))
def case(request):
    spec = GAITS[request.param]
    return spec, CompiledGait(spec.build(), spec.parameters)


def _close(a, b, tol):
    scale = max(1.0, float(np.max(np.abs(a))))
    assert np.max(np.abs(np.asarray(a) - np.asarray(b))) <= tol * scale


@pytest.mark.parametrize("variational", [False, True])
def test_the_c_loop_is_the_python_loop(case, variational):
    spec, fns = case
    x0 = np.array(spec.guess)
    ref = stride(fns, spec.section, x0, variational=variational, loop="python")
    out = stride(fns, spec.section, x0, variational=variational)
    _close(out.x, ref.x, 1e-13)
    assert abs(out.period - ref.period) <= 1e-13 * max(1.0, abs(ref.period))
    assert [k for k, _, _ in out.events] == [k for k, _, _ in ref.events]
    for (_, ta, ya), (_, tb, yb) in zip(out.events, ref.events, strict=True):
        assert abs(ta - tb) <= 1e-13 * max(1.0, abs(tb))
        _close(ya, yb, 1e-13)
    assert out.steps == ref.steps  # the same steps accepted: the same algorithm
    if variational:
        _close(out.DP, ref.DP, 1e-11)
        _close(out.monodromy, ref.monodromy, 1e-11)
    else:
        assert out.DP is None and out.monodromy is None


def test_numpy_target_runs_the_python_loop_to_the_same_stride():
    spec = GAITS["compass_gait"]
    gait = spec.build()
    c = CompiledGait(gait, spec.parameters)
    numpy = CompiledGait(gait, spec.parameters, target="numpy")
    assert numpy.native_stride() is None and c.native_stride() is not None
    a = stride(c, 0, spec.guess, variational=True)
    b = stride(numpy, 0, spec.guess, variational=True)
    _close(a.x, b.x, 1e-13)
    _close(a.DP, b.DP, 1e-11)


def test_other_parameters_rebind_the_compiled_loop():
    spec = GAITS["rimless_wheel"]
    fns = CompiledGait(spec.build(), spec.parameters)
    x0 = spec.guess
    before = stride(fns, 0, x0).x
    other = {**spec.parameters, "gamma": 0.05}
    moved = fns.with_parameters(other)
    fresh = CompiledGait(spec.build(), other)
    np.testing.assert_array_equal(stride(moved, 0, x0).x, stride(fresh, 0, x0).x)
    assert not np.allclose(stride(moved, 0, x0).x, before, rtol=1e-6, atol=0)
    np.testing.assert_array_equal(stride(fns, 0, x0).x, before)  # the original unchanged


def _ball(force=0) -> Gait:
    """A ball bouncing on the ground with restitution e, and an applied force."""
    (y,) = coordinates("y")
    (yd,) = velocities((y,))
    m, g, e = sp.symbols("m g e", positive=True)
    scene = Scene(
        [y],
        kinetic_energy=m * yd**2 / 2,
        potential=m * g * y,
        forces=[force(y) if callable(force) else force],
        walls=[Wall(y, name="ground")],
        parameters=[m, g, e],
        name="ball",
    )
    reset = Reset(sp.ImmutableMatrix([y]), sp.ImmutableMatrix([-e * yd]))
    return Gait("ball", {"air": scene}, (Transition("air", "air", "ground", reset),))


BALL = {"m": 1.0, "g": 9.81, "e": 0.9}


def test_a_ball_bounce_matches_its_closed_form():
    """From the ground at speed w: flight 2 w / g, then w -> e w; DP of (y, v) on the
    section y = 0 is [[0, 0], [*, e]] (the position stays on the guard)."""
    fns = CompiledGait(_ball(), BALL)
    out = stride(fns, 0, [0.0, 2.0], variational=True)
    assert abs(out.period - 2 * 2.0 / 9.81) <= 1e-14
    assert abs(out.x[1] - 0.9 * 2.0) <= 1e-14 and abs(out.x[0]) <= 1e-14
    assert abs(out.DP[1, 1] - 0.9) <= 1e-13 and np.max(np.abs(out.DP[0])) <= 1e-14


def test_a_field_that_is_not_finite_is_named():
    fns = CompiledGait(_ball(lambda y: sp.sqrt(3 - y)), BALL)
    with pytest.raises(GaitError, match=r"mode 'air': the generated rhs gave a value that is not"):
        stride(fns, 0, [0.0, 20.0])


def test_limits_and_bad_states_are_clear_errors():
    fns = CompiledGait(_ball(), BALL)
    with pytest.raises(GaitError, match=r"no transition fired within t_max = 0\.1"):
        stride(fns, 0, [0.0, 20.0], options=StrideOptions(t_max=0.1))
    with pytest.raises(GaitError, match="no transition fired"):
        stride(fns, 0, [0.0, 20.0], options=StrideOptions(max_steps=2))
    with pytest.raises(GaitError, match="not finite"):
        stride(fns, 0, [0.0, float("nan")])
    with pytest.raises(GaitError, match="has 2 entries"):
        stride(fns, 0, [0.0, 1.0, 2.0])
    with pytest.raises(GaitError, match="section 3 is not a transition"):
        stride(fns, 3, [0.0, 1.0])
    with pytest.raises(GaitError, match="loop must be"):
        stride(fns, 0, [0.0, 1.0], loop="c")
    for section in (True, 0.0, "0", -1):
        with pytest.raises(GaitError, match="is not a transition"):
            stride(fns, section, [0.0, 1.0])
    for state in (["a", 1.0], [[0.0, 1.0]], [1j, 0.0], None):
        with pytest.raises(GaitError):
            stride(fns, 0, state)


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"rtol": 0.0}, "rtol = 0.0 must be a finite number > 0"),
        ({"atol": float("nan")}, "atol = nan"),
        ({"t_max": float("inf")}, "t_max = inf"),
        ({"h0": -1e-3}, "h0 = -0.001"),
        ({"max_events": 10**9}, "max_events = 1000000000 must be a whole number in 1 .. 10000"),
        ({"max_steps": 0}, "max_steps = 0"),
        ({"max_steps": 2.5}, "max_steps = 2.5"),
        ({"rtol": True}, "rtol = True"),
    ],
)
def test_stride_options_are_checked(options, message):
    with pytest.raises(GaitError, match=re.escape(message)):
        StrideOptions(**options)


def test_a_mode_that_depends_on_time_is_refused():
    with pytest.raises(SceneError, match="mode 'air' depends on the time t"):
        _ball(sp.sin(t))


def test_limits_of_a_gait_are_finite_or_refused():
    from symmech.gait.limits import limit_gait

    m, g, e = sp.symbols("m g e", positive=True)
    gait = _ball(lambda y: m * g * e)  # lifted by a force m g e: the flight lasts 2w/(g(1-e))
    limit = limit_gait(gait, "e", 1, name="floating")
    assert sp.simplify(limit.modes["air"].acceleration()[0]) == 0
    assert limit.transitions[0].reset.velocity[0] == -limit.modes["air"].velocities[0]
    with pytest.raises(SceneError, match=r"acceleration\[0\]: the limit m -> 0 is not finite"):
        limit_gait(_ball(lambda y: g), "m", 0)
    with pytest.raises(SceneError, match="'k' is not one of its parameters"):
        limit_gait(gait, "k")


def test_the_recorded_motion_is_a_solution_in_both_loops():
    """Between consecutive rows of one mode the record follows the mode's flow (checked
    by SciPy's DOP853 at rtol 1e-12 from each row to the next), and both loops record the
    same events.  (Their accepted steps may differ where a step's error estimate is 1 to
    rounding, so the rows between events are compared through the flow, not one by one.)"""
    from scipy.integrate import solve_ivp

    spec = GAITS["hopper"]  # two modes of different sizes: rows padded with NaN
    fns = CompiledGait(spec.build(), spec.parameters)
    a = stride(fns, spec.section, spec.guess, record=True, loop="python")
    b = stride(fns, spec.section, spec.guess, record=True)
    for out in (a, b):
        rec = out.trajectory
        # the start, each accepted step but those cut by an event, each event before/after
        assert rec.shape[0] == 1 + (out.steps - len(out.events)) + 2 * len(out.events)
        assert np.all(np.diff(rec[:, 0]) >= 0) and set(rec[:, 1]) == {0.0, 1.0}
        np.testing.assert_array_equal(rec[-1, 2 : 2 + len(out.x)], out.x)
        worst = 0.0
        for r0, r1 in itertools.pairwise(rec):
            if r0[1] != r1[1] or r1[0] == r0[0]:
                continue  # a jump
            mode = fns.mode_names[int(r0[1])]
            n = fns.size(mode)
            sol = solve_ivp(
                lambda t, y, m=mode: fns.rhs(m, y), (r0[0], r1[0]), r0[2 : 2 + n],
                method="DOP853", rtol=1e-12, atol=1e-12,
            )  # fmt: skip
            worst = max(worst, float(np.max(np.abs(sol.y[:, -1] - r1[2 : 2 + n]))))
        assert worst <= 1e-9
    assert len(a.events) == len(b.events)
    for (ka, ta, ya), (kb, tb, yb) in zip(a.events, b.events, strict=True):
        assert ka == kb and abs(ta - tb) <= 1e-12
        _close(ya, yb, 1e-12)
    assert stride(fns, spec.section, spec.guess).trajectory is None
