"""The Python loop's direct paths give the values of the general ones: a bound function
over plain lists (``BoundModule.plain``), the generated augmented right-hand side
(``Functions.augmented``: ``augmented_rhs``), the gap's direct caller
(``Functions.gap_function``) and the continuous output at many times at once
(``Segment.samples``).  Each is compared with the
general path it replaces, computed independently; timings are in
benchmarks/work_precision.py."""

from __future__ import annotations

import numpy as np
import pytest
from codegen_support import require_c_compiler

import symmech as sm
from symmech.examples import carnot_3_7, pendulum_on_cart
from symmech.simulate.flow import RKFlow
from symmech.simulate.functions import Functions
from symmech.simulate.run import system_for
from symmech.simulate.scipy_flow import ScipyFlow
from symmech.simulate.steppers import stepper

PARAMS = {"R": 1.0, "alpha": 0.5, "k": 1.0, "m": 2.0, "g": 9.81}


def _functions(target: str) -> Functions:
    scene = carnot_3_7()
    values = {str(p): PARAMS.get(str(p), 1.3) for p in scene.parameters}
    return Functions(system_for(scene, target), values)


def test_plain_is_the_bound_function_over_lists():
    scene = pendulum_on_cart(2)
    mod = sm.codegen.generate(scene, "numpy", strategy="linear_solve").load()
    bound = mod.bind(1 + np.arange(len(mod.parameters)) / 7)
    plain = bound.plain("rhs")
    rng = np.random.default_rng(1)
    for _ in range(5):
        y = rng.normal(size=2 * mod.n)
        assert plain(y.tolist()) == bound.rhs(y).tolist()
    assert (
        bound.plain("mass_matrix")(y[: mod.n].tolist())
        == bound.mass_matrix(y[: mod.n]).ravel().tolist()
    )


def test_plain_is_none_where_the_evaluation_fails():
    mod = sm.codegen.generate(pendulum_on_cart(1), "numpy", strategy="linear_solve").load()
    plain = mod.bind(np.ones(len(mod.parameters))).plain("rhs")
    y = np.zeros(2 * mod.n)
    y[-1] = np.inf
    assert plain(y.tolist()) is None
    with pytest.raises(sm.codegen.NumericalError):
        mod.bind(np.ones(len(mod.parameters))).rhs(y)


def test_plain_is_none_for_a_c_module():
    require_c_compiler()
    mod = sm.codegen.generate(pendulum_on_cart(1), "c", strategy="linear_solve").load()
    assert mod.bind(np.ones(len(mod.parameters))).plain("rhs") is None


@pytest.mark.parametrize("target", ["numpy", "c"])
def test_augmented_is_rhs_and_rates_concatenated(target):
    if target == "c":
        require_c_compiler()
    fns = _functions(target)
    n = fns.n
    rng = np.random.default_rng(2)
    for _ in range(5):
        y = np.concatenate([[0.0, 1.0 + rng.random(), rng.normal()], rng.normal(size=n)])
        ya = np.concatenate([y, fns.gaps(0.0, y)])
        ydot = fns.flow_rhs(0.0, y)
        rates = [float(fns.gradient(w, 0.0, y[:n]) @ ydot[:n]) for w in range(fns.walls)]
        fused = fns.augmented(0.0, ya)
        assert np.array_equal(fused[: 2 * n], ydot)  # the same acceleration call
        # the rates by the generated augmented_rhs: the chain rule, printed with CSE
        np.testing.assert_allclose(fused[2 * n :], rates, rtol=1e-14, atol=1e-15)
        assert fns._direct((), "augmented_rhs") is not None  # the fused path was taken
        for w in range(fns.walls):
            assert fns.gap_function(w)(0.0, y[:n]) == fns.psi(w, 0.0, y[:n])


def test_augmented_failure_goes_the_general_way():
    fns = _functions("numpy")
    y = np.array([0.0, 1.0, 0.0, np.nan, 0.0, 0.0])
    out = fns.augmented(0.0, np.concatenate([y, [1.0]]))
    assert out.shape == (2 * fns.n + fns.walls,)
    assert np.isnan(out).any()


def _oscillator(t, y):
    return np.array([y[1], -np.sin(y[0]) + 0.1 * np.cos(t), y[3], -4 * y[2]])


@pytest.mark.parametrize("method", ["dop853", "tsit5", "rk45", "scipy"])
def test_samples_equal_the_continuous_output_point_by_point(method):
    if method == "scipy":
        flow = ScipyFlow(_oscillator, "DOP853", 1e-6, 1e-8, np.inf)
    else:
        flow = RKFlow(_oscillator, method, 1e-6, 1e-8, np.inf)
    flow.start(0.0, np.array([0.3, 0.0, 1.0, 0.5]), 5.0)
    for _ in range(3):
        seg = flow.advance()
        assert seg.many is not None
        times = [seg.t0] + [seg.t0 + (seg.t1 - seg.t0) * k / 8 for k in range(1, 8)] + [seg.t1]
        got = seg.samples(times)
        assert got[0] is seg.y0 and got[-1] is seg.y1
        for t, y in zip(times[1:-1], got[1:-1], strict=True):
            assert np.array_equal(y, seg.dense(t))


def test_samples_without_many_call_dense():
    st = stepper("rk4")
    assert not hasattr(
        st.step(_oscillator, 0.0, np.ones(4), np.ones(4), 0.1, 1e-6, 1e-8).dense, "many"
    )
    flow = RKFlow(_oscillator, "rk4", 1e-6, 1e-8, np.inf, fixed_step=0.1)
    flow.start(0.0, np.array([0.3, 0.0, 1.0, 0.5]), 1.0)
    seg = flow.advance()
    assert seg.many is None
    mid = 0.5 * (seg.t0 + seg.t1)
    assert np.array_equal(seg.samples([seg.t0, mid, seg.t1])[1], seg.dense(mid))


@pytest.mark.parametrize("make", [RKFlow, ScipyFlow], ids=["dop853", "scipy DOP853"])
def test_head_equals_the_continuous_output_entry_by_entry(make):
    flow = make(_oscillator, "dop853" if make is RKFlow else "DOP853", 1e-6, 1e-8, np.inf)
    flow.start(0.0, np.array([0.3, 0.0, 1.0, 0.5]), 5.0)
    for _ in range(3):
        seg = flow.advance()
        assert seg.head is not None
        for k in range(9):
            t = seg.t0 + (seg.t1 - seg.t0) * k / 8
            # DOP853's state at one time is itself formed entry by entry on floats: the
            # array evaluation of many times stands beside it
            whole = seg.dense(t) if seg.many is None else seg.many(np.array([t]))[0]
            for m in (1, 2, 4):
                assert seg.head(t, m) == whole[:m].tolist()
            assert seg.dense(t).tolist() == whole.tolist()


def test_a_long_state_of_dop853_is_formed_on_arrays_with_the_same_values():
    """Past ``FLOAT_LOOP_SIZE`` entries the continuous output is evaluated on arrays
    (cheaper there than entry by entry): the same values as the entry-by-entry form."""
    from symmech.simulate.steppers import FLOAT_LOOP_SIZE

    n = 2 * FLOAT_LOOP_SIZE

    def f(t, y):
        return np.cos(y + t)

    flow = RKFlow(f, "dop853", 1e-6, 1e-8, np.inf)
    flow.start(0.0, np.linspace(0.0, 1.0, n), 2.0)
    seg = flow.advance()
    for k in range(9):
        t = seg.t0 + (seg.t1 - seg.t0) * k / 8
        assert seg.dense(t).tolist() == seg.head(t, n)


def test_scipy_rk45_has_no_head():
    rk45 = ScipyFlow(_oscillator, "RK45", 1e-6, 1e-8, np.inf)
    rk45.start(0.0, np.array([0.3, 0.0, 1.0, 0.5]), 5.0)
    assert rk45.advance().head is None  # SciPy's continuous output only


@pytest.mark.parametrize("target", ["numpy", "c"])
def test_point_evaluations_equal_the_bound_functions(target):
    if target == "c":
        require_c_compiler()
    fns = _functions(target)
    n = fns.n
    bound = fns._bound_module(())
    rng = np.random.default_rng(3)
    for _ in range(5):
        y = np.concatenate([[0.0, 1.0 + rng.random(), rng.normal()], rng.normal(size=n)])
        q, v = y[:n], y[n:]
        assert np.array_equal(fns.rhs((), 0.0, y), bound.rhs(y))
        assert fns.energy(0.0, q, v) == float(bound.energy(q, v))
        for w in range(fns.walls):
            name = fns._wall_name("psi", w)
            assert fns.psi(w, 0.0, q) == float(bound.call(name, q))
            assert fns.gap_function(w)(0.0, q.tolist()) == fns.psi(w, 0.0, q)
            assert np.array_equal(
                fns.impact(w, 0.0, q, v), bound.call(fns._wall_name("impact", w), q, v)
            )
            rate = fns.rate(w, 0.0, y, fns.rhs((), 0.0, y))
            assert fns.normal_rate(w, 0.0, y) == rate
            assert fns.normal_rate(w, 0.0, y.copy()) == rate  # kept: the same value
        # a state of another size goes the general way, which explains
        with pytest.raises(sm.codegen.CodegenError):
            fns.psi(0, 0.0, np.zeros(n + 1))


@pytest.mark.parametrize(("backend", "method"), [("numpy", "dop853"), ("scipy", "DOP853")])
def test_searches_on_the_coordinates_give_the_same_run(monkeypatch, backend, method):
    """The samples and the root search read the coordinates through ``Segment.head``;
    without it (the states through ``dense`` and ``many``) the run is the same, bit for
    bit: the ellipse bouncing on its floor, and the disc rolling (a contact force searched
    through the whole state)."""
    from symmech.bench.cases import CASES
    from symmech.simulate import scipy_flow, steppers

    if backend == "scipy":
        require_c_compiler()

    def runs() -> list:
        out = []
        for name in ("ellipse_gravity_flight", "disk_3_7_gravity"):
            res = CASES[name].simulate(backend=backend, method=method, rtol=1e-4, atol=1e-6)
            out.append((res.t, res.q, res.v, [(e.time, e.wall, e.kind) for e in res.events]))
        return out

    fast = runs()
    monkeypatch.delattr(steppers._Dop853Dense, "head")
    monkeypatch.setattr(scipy_flow, "_scipy_head", lambda dense: None)
    slow = runs()
    for a, b in zip(fast, slow, strict=True):
        for x, y in zip(a[:3], b[:3], strict=True):
            assert np.array_equal(x, y)
        assert a[3] == b[3]
