"""Hostile and extreme arguments of loaded generated modules (issue 10, classes 2 and 3).

Every argument NumPy can convert gives the right answer or a CodegenError naming the
argument, identically on the three routes (C through the CPython extension, C through
ctypes, NumPy); parameters the declaration constrains (a sign, a restitution in [0, 1])
are checked once per call and a value outside its range raises NumericalError naming it.
The right answers come from the scene's symbolic impact map evaluated by sympy, not from
the generated code.
"""

from __future__ import annotations

import ctypes
import datetime

import numpy as np
import pytest
import sympy as sp
from codegen_support import require_c_compiler

import symmech as sm
from symmech.codegen import CodegenError, NumericalError
from symmech.codegen.runtime_checks import parameter_rules, real_array
from symmech.examples import carnot_3_7, carnot_4_4

Q, V = [0.0, 1.0, 0.0], [1.0, -2.0, 0.0]
P = {"R": 1.0, "alpha": 0.5, "k": 1.0, "m": 2.0}
PV = [P[k] for k in ("R", "alpha", "k", "m")]


def _exact_impact(q, v, params) -> np.ndarray:
    """v+ of carnot_3_7 from the scene's symbolic impact map (sympy, not generated code)."""
    scene = carnot_3_7()
    env = {s: sp.nsimplify(x) for s, x in zip(scene.coordinates, q, strict=True)}
    env |= {s: sp.nsimplify(x) for s, x in zip(scene.velocities, v, strict=True)}
    env |= {p: sp.nsimplify(params[p.name]) for p in scene.parameters}
    post = scene.impact_map(0).post_velocity.subs(env)
    return np.array([float(e) for e in post])


@pytest.fixture(scope="module")
def routes():
    """carnot_3_7 loaded three ways."""
    require_c_compiler()
    c = sm.codegen.generate(carnot_3_7(), "c")
    py = sm.codegen.generate(carnot_3_7(), "numpy")
    return {"extension": c.load(), "ctypes": c.load(extension=False), "numpy": py.load()}


EXACT = None


def _exact() -> np.ndarray:
    global EXACT
    if EXACT is None:
        EXACT = _exact_impact(Q, V, P)
    return EXACT


def _readonly(a):
    a = np.array(a, dtype=float)
    a.flags.writeable = False
    return a


#: Arguments that must give the exact answer: (q, v, params) for one state.
CONVERTED = {
    "big-endian q, v": lambda: (np.array(Q, ">f8"), np.array(V, ">f8"), PV),
    "big-endian params": lambda: (Q, V, np.array(PV, ">f8")),
    "little-endian explicit": lambda: (np.array(Q, "<f8"), np.array(V, "<f8"), PV),
    "int64 arrays": lambda: (np.array([0, 1, 0]), np.array([1, -2, 0]), PV),
    "int32 and int8": lambda: (np.array([0, 1, 0], np.int32), np.array([1, -2, 0], np.int8), PV),
    "float32": lambda: (np.array(Q, np.float32), np.array(V, np.float32), PV),
    "float16": lambda: (np.array(Q, np.float16), V, PV),
    "long double": lambda: (np.array(Q, np.longdouble), V, np.array(PV, np.longdouble)),
    "object floats": lambda: (np.array(Q, object), np.array(V, object), PV),
    "python ints": lambda: ([0, 1, 0], [1, -2, 0], [1, 0.5, 1, 2]),
    "tuples": lambda: (tuple(Q), tuple(V), tuple(PV)),
    "numpy scalars in a list": lambda: ([np.float32(0), np.int64(1), np.float64(0)], V, PV),
    "sympy numbers": lambda: ([sp.Integer(0), sp.Float(1), 0], V, [1, sp.Rational(1, 2), 1, 2]),
    "non-contiguous": lambda: (
        np.array([0.0, 9, 1, 9, 0])[::2],
        np.array([1.0, 7, -2, 7, 0])[::2],
        PV,
    ),
    "reversed view": lambda: (np.array(Q[::-1])[::-1], V, PV),
    "read-only": lambda: (_readonly(Q), _readonly(V), _readonly(PV)),
    "unaligned": lambda: (np.frombuffer(b"\0" + np.array(Q).tobytes(), "<f8", 3, 1), V, PV),
    "params dict with symbols": lambda: (Q, V, {sp.Symbol(k): x for k, x in P.items()}),
    "params dict of numpy scalars": lambda: (Q, V, {k: np.float32(x) for k, x in P.items()}),
    "masked array, nothing masked": lambda: (np.ma.array(Q), V, PV),
}


@pytest.mark.parametrize("case", CONVERTED)
@pytest.mark.parametrize("route", ["extension", "ctypes", "numpy"])
def test_convertible_arguments_give_the_exact_answer(routes, route, case):
    q, v, p = CONVERTED[case]()
    out = routes[route].impact(q, v, p)
    assert out.dtype == np.float64 and out.shape == (3,)
    np.testing.assert_allclose(out, _exact(), rtol=1e-15, atol=1e-15)


def test_batches_in_any_layout_and_byte_order_agree_with_row_by_row_calls(routes):
    rng = np.random.default_rng(3)
    q = rng.normal(size=(5, 3))
    v = rng.normal(size=(5, 3))
    rows = np.array([_exact_impact(a, b, P) for a, b in zip(q, v, strict=True)])
    layouts = {
        "fortran": (np.asfortranarray(q), np.asfortranarray(v)),
        "big-endian": (q.astype(">f8"), v.astype(">f8")),
        "strided": (np.repeat(q, 2, axis=0)[::2], np.repeat(v, 2, axis=0)[::2]),
        "transposed view": (np.ascontiguousarray(q.T).T, np.ascontiguousarray(v.T).T),
    }
    for name, (a, b) in layouts.items():
        for route, mod in routes.items():
            np.testing.assert_allclose(
                mod.impact(a, b, PV), rows, rtol=1e-13, atol=1e-14, err_msg=f"{route} {name}"
            )


def _bad_state():
    return {
        "complex array": (np.array(Q, complex), "argument q", "complex"),
        "complex with zero imaginary part": (np.array(Q) + 0j, "argument q", "complex"),
        "complex python number": ([0, 1j, 0], "argument q", "complex"),
        "bool array": (np.array([False, True, False]), "argument q", "bool"),
        "bool in an int list": ([0, True, 0], "argument q", "bool"),
        "numpy bool in a list": ([0.0, np.True_, 0.0], "argument q", "bool"),
        "strings": (np.array(["0", "1", "0"]), "argument q", "strings"),
        "string in a list": (["0", 1.0, 0.0], "argument q", "str"),
        "bytes": (np.array([b"0", b"1", b"0"]), "argument q", "bytes"),
        "datetime": (np.array(["2020-01-01"] * 3, "datetime64[D]"), "argument q", "datetime64"),
        "object with a string": (np.array([0.0, "1", 0.0], object), "argument q", "str"),
        "object with None": (np.array([0.0, None, 0.0], object), "argument q", "None"),
        "sympy symbol": ([0, sp.Symbol("x"), 0], "argument q", "x"),
        "int beyond float64": ([0, 10**400, 0], "argument q", "argument q"),
        "ragged": ([[0.0, 1.0, 0.0], [1.0]], "argument q", "argument q"),
        "masked": (np.ma.array(Q, mask=[0, 1, 0]), "argument q", "masked"),
        "0-d array": (np.array(1.0), "argument q", r"\(\)"),
        "scalar": (1.0, "argument q", r"\(\)"),
        "wrong trailing size": (np.zeros(4), "argument q", r"\(4,\)"),
        "wrong trailing size in a batch": (np.zeros((2, 2)), "argument q", r"\(2, 2\)"),
        "a date": (datetime.date(2020, 1, 1), "argument q", "argument q"),
        "None": (None, "argument q", "argument q"),
    }


@pytest.mark.parametrize("case", list(_bad_state()))
@pytest.mark.parametrize("route", ["extension", "ctypes", "numpy"])
def test_unconvertible_state_is_refused_naming_the_argument(routes, route, case):
    value, who, what = _bad_state()[case]
    with pytest.raises(CodegenError, match=who) as info:
        routes[route].impact(value, V, PV)
    assert __import__("re").search(what, str(info.value)), str(info.value)


BAD_PARAMS = {
    "complex": (np.array(PV, complex), "params", "complex"),
    "bool": ([True, 0.5, 1.0, 2.0], "params", "bool"),
    "string": (["1", 0.5, 1, 2], "params", "str"),
    "too few": ([1.0, 0.5, 1.0], "params", "expected 4"),
    "too many": ([1.0, 0.5, 1.0, 2.0, 3.0], "params", "expected 4"),
    "nan": ([np.nan, 0.5, 1, 2], "params: parameter 'R'", "nan"),
    "inf": ([1, 0.5, 1, np.inf], "params: parameter 'm'", "inf"),
    "-inf restitution": ([1, -np.inf, 1, 2], "params: parameter 'alpha'", "not finite"),
    "dict missing": ({"R": 1, "alpha": 0.5, "k": 1}, "params", r"missing \['m'\]"),
    "dict unknown": ({**P, "g": 9.8}, "params", r"unknown \['g'\]"),
    "dict twice": ({**P, sp.Symbol("m"): 1.0}, "params", "'m' is given twice"),
    "dict non-name key": ({**P, 3: 1.0}, "params", "key 3"),
    "dict complex value": ({**P, "m": 2j}, r"params\['m'\]", "complex"),
    "dict nan value": ({**P, "k": float("nan")}, "parameter 'k'", "not finite"),
    "None": (None, "params required", "R"),
}


@pytest.mark.parametrize("case", BAD_PARAMS)
@pytest.mark.parametrize("route", ["extension", "ctypes", "numpy"])
def test_bad_params_are_refused_naming_them(routes, route, case):
    value, who, what = BAD_PARAMS[case]
    with pytest.raises(CodegenError, match=who) as info:
        routes[route].impact(Q, V, value)
    assert __import__("re").search(what, str(info.value)), str(info.value)


def test_a_function_that_reads_no_parameter_still_checks_the_ones_it_is_given(routes):
    for mod in routes.values():
        assert not mod._spec["dpsi_rough_wall"].takes_parameters
        np.testing.assert_array_equal(mod.dpsi(Q, PV), [0.0, 1.0, 0.0])
        np.testing.assert_array_equal(mod.dpsi(Q), [0.0, 1.0, 0.0])
        with pytest.raises(NumericalError, match=r"'alpha' = 2\.0"):
            mod.dpsi(Q, [1, 2.0, 1, 2])
        with pytest.raises(CodegenError, match="complex"):
            mod.dpsi(Q, np.array(PV, complex))


def test_dict_params_of_arrays_are_one_column_per_parameter():
    """A mapping of per-state values is stacked on the last axis (not transposed: with 4
    states and 4 parameters a transposition would not be noticed by the shape check)."""
    mod = sm.codegen.generate(carnot_3_7(), "numpy").load()
    rng = np.random.default_rng(5)
    q, v = rng.normal(size=(4, 3)), rng.normal(size=(4, 3))
    values = {"R": 1 + rng.random(4), "alpha": rng.random(4), "k": 1 + rng.random(4), "m": 2.0}
    out = mod.impact(q, v, values)
    for i in range(4):
        row = {k: (x[i] if np.ndim(x) else x) for k, x in values.items()}
        np.testing.assert_allclose(out[i], _exact_impact(q[i], v[i], row), rtol=1e-13, atol=1e-14)
    with pytest.raises(CodegenError, match="do not broadcast"):
        mod.impact(q, v, {**values, "m": np.ones(3)})


@pytest.mark.parametrize("target", ["c", "numpy"])
@pytest.mark.parametrize("example", [carnot_3_7, carnot_4_4])
def test_zero_length_batches_return_empty_results_of_the_right_shape(target, example):
    if target == "c":
        require_c_compiler()
    mod = sm.codegen.generate(example(), target).load()
    p = np.full(len(mod.parameters), 0.5)
    for name in mod.functions:
        spec = mod._spec[name]
        states = [np.zeros((0, 2 * mod.n if s == "y" else mod.n)) for s in spec.state]
        out = mod.call(
            name,
            *states,
            params=p,
            t=np.zeros(0) if spec.takes_time else None,
            inputs=np.zeros((0, len(mod.inputs))) if spec.takes_inputs else None,
        )
        assert out.shape == (0, *spec.out_shape), name
        assert out.dtype == np.float64


@pytest.mark.parametrize("route", ["extension", "ctypes", "numpy"])
def test_batches_that_do_not_broadcast_are_refused(routes, route):
    with pytest.raises(CodegenError, match="do not broadcast"):
        routes[route].impact(np.zeros((2, 3)), np.zeros((3, 3)), PV)


@pytest.mark.parametrize("target", ["c", "numpy"])
def test_time_and_inputs_are_converted_or_refused(target):
    if target == "c":
        require_c_compiler()
    mod = sm.codegen.generate(carnot_4_4(), target).load()
    p = np.full(len(mod.parameters), 0.5)
    q, v = np.full(mod.n, 0.1), np.full(mod.n, 0.2)
    u = np.full(len(mod.inputs), 0.3)
    ref = mod.impact(q, v, p, t=0.25, inputs=u)
    np.testing.assert_array_equal(
        mod.impact(q, v, p, t=np.array(0.25, ">f8"), inputs=u.astype(">f8")), ref
    )
    np.testing.assert_array_equal(mod.impact(q, v, p, t=np.float32(0.25), inputs=list(u)), ref)
    with pytest.raises(CodegenError, match=r"^t: "):
        mod.impact(q, v, p, t=0.25 + 1j, inputs=u)
    with pytest.raises(CodegenError, match=r"^t: "):
        mod.impact(q, v, p, t="0.25", inputs=u)
    with pytest.raises(CodegenError, match="inputs"):
        mod.impact(q, v, p, t=0.25, inputs=u.astype(complex))
    with pytest.raises(CodegenError, match="inputs"):
        mod.impact(q, v, p, t=0.25, inputs=[True] * len(u))


# ------------------------------------------------------------ class 3: declared ranges


@pytest.mark.parametrize("route", ["extension", "ctypes", "numpy"])
def test_restitution_outside_0_1_and_negative_mass_raise_numerical_error(routes, route):
    mod = routes[route]
    for alpha in (5.0, -1.0, 1.0 + 2**-52, -5e-324):
        with pytest.raises(NumericalError, match=r"'alpha' = .* breaks 0 <= alpha <= 1"):
            mod.impact(Q, V, {**P, "alpha": alpha})
    for alpha in (0.0, 1.0, -0.0):  # the closed range
        out = mod.impact(Q, V, {**P, "alpha": alpha})
        np.testing.assert_allclose(out, _exact_impact(Q, V, {**P, "alpha": abs(alpha)}), atol=1e-15)
    for m in (-2.0, 0.0, -0.0):
        with pytest.raises(NumericalError, match=r"'m' = .* breaks 0 < m \(declared positive\)"):
            mod.impact(Q, V, {**P, "m": m})
    # a batch is checked once, for every state, with the same message
    with pytest.raises(NumericalError, match=r"'alpha' = 5\.0"):
        mod.impact(np.zeros((3, 3)), np.ones((3, 3)), {**P, "alpha": 5.0})


def test_numpy_batches_of_parameters_are_checked_entry_by_entry():
    mod = sm.codegen.generate(carnot_3_7(), "numpy").load()
    p = np.tile(PV, (3, 1))
    p[2, 1] = 1.5
    with pytest.raises(NumericalError, match=r"'alpha' = 1\.5"):
        mod.impact(np.zeros((3, 3)), np.ones((3, 3)), p)


def _signed_scene() -> sm.Scene:
    """A parameter of every declared sign, and one restitution that is also declared
    positive (so its range is (0, 1])."""
    x, y = sm.coordinates("x y")
    m = sp.Symbol("m", positive=True)
    g = sp.Symbol("g", negative=True)
    c = sp.Symbol("c", nonpositive=True)
    h = sp.Symbol("h", real=True, nonzero=True)
    r = sp.Symbol("r", real=True)
    e = sp.Symbol("e", positive=True)
    return sm.Scene(
        (x, y),
        metric=sp.diag(m, m),
        potential=-g * y + c * x + h * x * y + r * x,
        walls=[sm.Wall(y, restitution=e, name="floor")],
        name="signed",
    )


def _rule_cases():
    # parameters in order c, e, g, h, m, r
    good = [-1.0, 0.5, -9.8, 2.0, 1.0, -3.0]
    bad = {
        0: [1e-300, 5e-324],  # c <= 0
        1: [0.0, 1.0000000000000002, -1.0],  # e in (0, 1]
        2: [0.0, 9.8, -0.0],  # g < 0
        3: [0.0, -0.0],  # h != 0
        4: [0.0, -1.0],  # m > 0
    }
    fine = {0: [0.0, -0.0, -1e300], 1: [1.0, 5e-324], 3: [-1e-300], 5: [0.0, 1e300, -1e300]}
    return good, bad, fine


@pytest.mark.parametrize("target", ["c", "numpy"])
def test_every_declared_sign_is_checked_at_run_time(target):
    if target == "c":
        require_c_compiler()
    code = sm.codegen.generate(_signed_scene(), target)
    mod = code.load()
    assert mod.parameters == ("c", "e", "g", "h", "m", "r")
    good, bad, fine = _rule_cases()
    q, v = [0.1, 0.2], [0.3, -0.4]
    mod.impact(q, v, good)
    for i, values in bad.items():
        for x in values:
            p = list(good)
            p[i] = x
            with pytest.raises(NumericalError, match=f"parameter '{mod.parameters[i]}'"):
                mod.energy(q, v, p)
    for i, values in fine.items():
        for x in values:
            p = list(good)
            p[i] = x
            assert np.isfinite(mod.energy(q, v, p))


@pytest.mark.parametrize("target", ["c", "numpy"])
def test_generated_check_parameters_agrees_with_the_python_rules(target):
    """The generated check (C function, NumPy function) and the wrapper's rules accept and
    refuse the same vectors, on the edges of every range and on non-finite values."""
    if target == "c":
        require_c_compiler()
    code = sm.codegen.generate(_signed_scene(), target)
    mod = code.load()
    if target == "c":
        fn = getattr(mod._library, f"{code.stem}_check_parameters")
        fn.argtypes, fn.restype = [ctypes.c_void_p], ctypes.c_int

        def generated(p):
            return fn(np.ascontiguousarray(p, dtype=np.float64).ctypes.data)
    else:
        module = __import__("sys").modules[
            next(
                k
                for k in __import__("sys").modules
                if k.startswith(f"_symmech_generated_{code.stem}_")
            )
        ]
        generated = module.check_parameters
    good, bad, fine = _rule_cases()
    edges = sorted({x for vs in [*bad.values(), *fine.values()] for x in vs})
    values = [*edges, np.nan, np.inf, -np.inf]
    for i in range(len(good)):
        for x in values:
            p = list(good)
            p[i] = x
            rule = code.parameter_rules[i]
            expected_ok = bool(np.isfinite(x) and rule.holds(np.array(x)))
            assert (generated(p) == 0) == expected_ok, (rule.text, x)
            if not expected_ok:
                assert generated(p) == i + 1


def test_rules_come_from_assumptions_and_restitutions():
    e, a = sp.Symbol("e", nonnegative=True), sp.Symbol("a", positive=True)
    rules = parameter_rules([a, e], {e: ["floor", "roof"]})
    assert [r.text for r in rules] == ["0 < a", "0 <= e <= 1"]
    assert "restitution of walls 'floor', 'roof'" in rules[1].why
    assert parameter_rules([sp.Symbol("r")], {})[0].text == "r finite"


def test_a_baked_restitution_outside_0_1_is_refused_at_generation():
    with pytest.raises(
        CodegenError, match=r"restitution of wall 'rough_wall': it must lie in \[0, 1\]"
    ):
        sm.codegen.generate(carnot_3_7(), "numpy", constants={"alpha": 5})
    mod = sm.codegen.generate(carnot_3_7(), "numpy", constants={"alpha": 1}).load()
    assert "alpha" not in mod.parameters


def test_real_array_never_returns_a_silently_converted_value():
    assert real_array([1, 2], "x").dtype == np.float64
    out = real_array(np.array([1.5, -2.0], ">f8"), "x")
    assert out.dtype == np.float64 and out.dtype.isnative and list(out) == [1.5, -2.0]
    for bad in (True, "1", b"1", 1j, np.complex64(1), [[1.0], [1.0, 2.0]]):
        with pytest.raises(CodegenError, match=r"^x: "):
            real_array(bad, "x")


# ------------------------------------- class 3: the closed forms check the metric as well


def _constrained_scene() -> sm.Scene:
    x, y, th = sm.coordinates("x y theta")
    _, yd, thd = sm.velocities((x, y, th))
    m, inertia, r = sp.symbols("m I R", positive=True)
    return sm.Scene(
        (x, y, th),
        metric=sp.diag(m, m, inertia),
        potential=m * y,
        constraints=[yd + r * thd],
        walls=[sm.Wall(x + 1, restitution=sp.Rational(1, 2), name="wall")],
        name="metric_checks",
    )


@pytest.mark.parametrize("target", ["c", "numpy"])
def test_closed_forms_raise_the_error_of_the_linear_solves_for_an_indefinite_metric(target):
    """With a negative mass the wrapper refuses the call naming m; the generated code
    itself (called without the wrapper) refuses it too: the closed forms check the metric's
    Cholesky pivots as the linear solves do, with the same NumericalError."""
    if target == "c":
        require_c_compiler()
    q, v = np.array([0.2, 0.3, 0.4]), np.array([-1.0, 0.5, -0.5])  # in D: y' + R theta' = 0
    good, negative = np.array([1.5, 1.0, 2.0]), np.array([1.5, -1.0, 2.0])  # I, R, m
    negative_m = np.array([1.5, 1.0, -2.0])
    scene = _constrained_scene()
    results = {}
    for strategy in ("closed_form", "linear_solve"):
        code = sm.codegen.generate(scene, target, strategy=strategy, projectors=True)
        mod = code.load()
        names = ["acceleration", "multipliers", "impact_wall", "rhs"]
        names += ["projector_P", "projector_Q"] if strategy == "closed_form" else []
        for name in names:
            spec = mod._spec[name]
            if strategy == "closed_form" and name != "rhs":
                assert spec.metric_check, name
            state = [np.concatenate([q, v])] if spec.state == ("y",) else [q, v][: len(spec.state)]
            results[strategy, name] = mod.call(name, *state, params=good)
            with pytest.raises(NumericalError, match=r"'m' = -2\.0 breaks 0 < m"):
                mod.call(name, *state, params=negative_m)
            with pytest.raises(NumericalError, match=r"'R' = -1\.0"):
                mod.call(name, *state, params=negative)
            with pytest.raises(NumericalError, match="positive definite"):
                mod._raw[name](tuple(state), negative_m, None, None)
    for name in ("acceleration", "multipliers", "impact_wall", "rhs"):
        np.testing.assert_allclose(
            results["closed_form", name], results["linear_solve", name], rtol=1e-12, atol=1e-14
        )


def test_a_metric_check_is_left_out_where_nothing_is_evaluated():
    """The free body's acceleration is the constant 0: no metric check, no parameters."""
    x, y = sm.coordinates("x y")
    m = sp.Symbol("m", positive=True)
    scene = sm.Scene((x, y), metric=sp.diag(m, m), walls=[sm.Wall(y)], name="free")
    code = sm.codegen.generate(scene, "numpy", strategy="closed_form")
    spec = {f.name: f for f in code.functions}
    assert not spec["acceleration"].metric_check and not spec["acceleration"].takes_parameters
    impact = next(f for f in code.functions if f.kind == "impact")
    assert impact.metric_check and impact.takes_parameters


@pytest.mark.parametrize("target", ["c", "numpy"])
def test_a_scene_without_parameters_accepts_none_or_empty_and_refuses_values(target):
    if target == "c":
        require_c_compiler()
    x, y = sm.coordinates("x y")
    scene = sm.Scene((x, y), metric=sp.eye(2), walls=[sm.Wall(y, name="floor")], name="bare")
    mod = sm.codegen.generate(scene, target).load()
    for empty in (None, [], (), {}, np.zeros(0)):
        np.testing.assert_array_equal(mod.impact([0.0, 0.0], [1.0, -2.0], empty), [1.0, 2.0])
    for given in ([1.0], {"m": 1.0}, np.ones(2)):
        with pytest.raises(CodegenError, match="no run-time parameters"):
            mod.impact([0.0, 0.0], [1.0, -2.0], given)
