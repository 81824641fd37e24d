"""One-state calls at compiled speed (issue 27): ``module.bind(params)``, a mapping of
parameters and a time given to a function that does not read it all take the fast path,
give the same doubles as the general path, and every error is the one the general path
gives (same class, same message).  That a call takes the fast path is shown by replacing
the general caller with one that fails: timings are in benchmarks/codegen.py."""

from __future__ import annotations

import numpy as np
import pytest
from codegen_support import require_c_compiler

import symmech as sm
from symmech.codegen import CodegenError, NumericalError
from symmech.examples import pendulum_on_cart


@pytest.fixture(scope="module", params=["extension", "ctypes", "numpy"])
def mod(request):
    scene = pendulum_on_cart(3)
    if request.param == "numpy":
        return sm.codegen.generate(scene, "numpy", strategy="linear_solve").load()
    require_c_compiler()
    code = sm.codegen.generate(scene, "c", strategy="linear_solve")
    return code.load(extension=request.param == "extension")


def _point(mod, seed=0):
    rng = np.random.default_rng(seed)
    y = 0.3 * rng.normal(size=2 * mod.n)
    return y, 1 + rng.random(len(mod.parameters))


def _no_general_path(mod, monkeypatch, name="rhs"):
    def refuse(*args):
        raise AssertionError(f"{name} took the general path")

    monkeypatch.setitem(mod._raw, name, refuse)


def _same_error(first, second):
    """Both calls raise, the same class with the same message."""
    errors = []
    for call in (first, second):
        with pytest.raises((CodegenError, NumericalError)) as info:
            call()
        errors.append(info.value)
    assert type(errors[0]) is type(errors[1]) and str(errors[0]) == str(errors[1]), errors


def test_bound_functions_equal_the_module_for_every_function(mod):
    y, p = _point(mod)
    q, v = y[: mod.n], y[mod.n :]
    bound = mod.bind(p)
    for name in mod.functions:
        spec = mod._spec[name]
        args = [y] if spec.state == ("y",) else [q, v][: len(spec.state)]
        expected = mod.call(name, *args, params=p)
        assert np.array_equal(getattr(bound, name)(*args), expected), name
        assert np.array_equal(bound.call(name, *args), expected), name
        batch = [np.stack([a, a]) for a in args]  # the general path, bound parameters
        assert np.array_equal(getattr(bound, name)(*batch)[1], expected), name


def test_plain_calls_take_the_fast_path(mod, monkeypatch):
    y, p = _point(mod, 1)
    expected = mod.rhs(y, p)
    rhs = mod.bind(p).rhs
    named = dict(zip(mod.parameters, p.tolist(), strict=True))
    _no_general_path(mod, monkeypatch)
    assert np.array_equal(rhs(y), expected)
    assert np.array_equal(rhs(list(y), t=0.5), expected)
    assert np.array_equal(mod.rhs(y, p, t=0.0), expected)  # rhs reads no time
    assert np.array_equal(mod.rhs(y, named, t=1), expected)
    # numpy.float64 values (as taken from an array) are plain floats too
    floats = {k: np.float64(x) for k, x in named.items()}
    assert np.array_equal(mod.rhs(y, floats, t=np.float64(2.0)), expected)


def test_bound_parameters_are_a_checked_copy(mod):
    y, p = _point(mod, 2)
    expected = mod.rhs(y, p)
    bound = mod.bind(p)
    p[:] = -1.0  # the caller's array changes after binding
    assert np.array_equal(bound.rhs(y), expected)
    assert not bound.params.flags.writeable


@pytest.mark.parametrize(
    "change",
    [
        {"m0": -1.0},  # breaks its declared sign: NumericalError naming it
        {"g": float("nan")},  # not finite: CodegenError naming it
        {"g": True},  # a bool is not a real number
        {"g": "9.81"},  # nor a string
        {"g": 1j},
    ],
    ids=["range", "nan", "bool", "string", "complex"],
)
def test_bind_refuses_what_a_call_refuses(mod, change):
    y, p = _point(mod, 3)
    named = dict(zip(mod.parameters, p.tolist(), strict=True)) | change
    _same_error(lambda: mod.rhs(y, named), lambda: mod.bind(named))
    _same_error(lambda: mod.rhs(y, named, t=0.0), lambda: mod.bind(named))


def test_bind_refuses_a_wrong_mapping_or_count(mod):
    y, p = _point(mod, 4)
    named = dict(zip(mod.parameters, p.tolist(), strict=True))
    missing = {k: x for k, x in named.items() if k != "g"}
    extra = named | {"h": 1.0}
    for bad in (missing, extra, p[:-1], None):
        _same_error(lambda bad=bad: mod.rhs(y, bad), lambda bad=bad: mod.bind(bad))
    with pytest.raises(CodegenError, match=r"missing \['g'\]"):
        mod.bind(missing)


@pytest.mark.parametrize(
    "bad",
    [np.zeros(3), [0.1] * 3, "abc", np.zeros((2, 3)), np.full(8, 1j), [10**400] * 8],
    ids=["short", "short list", "string", "wrong width", "complex", "int beyond float64"],
)
def test_a_bound_call_refuses_what_a_call_refuses(mod, bad):
    _, p = _point(mod, 5)
    rhs = mod.bind(p).rhs
    _same_error(lambda: mod.rhs(bad, p), lambda: rhs(bad))


def test_a_failure_at_a_bound_call_is_numerical_error(mod):
    y, p = _point(mod, 6)
    y[-1] = np.nan  # (the cart position y[0] reaches no output: rhs is finite there)
    rhs = mod.bind(p).rhs
    _same_error(lambda: mod.rhs(y, p), lambda: rhs(y))
    with pytest.raises(NumericalError, match=r"^rhs: an output, or an input"):
        rhs(y)


def test_a_time_that_is_not_a_real_number_is_refused(mod):
    y, p = _point(mod, 7)
    rhs = mod.bind(p).rhs
    for t in ("0", 1j, True):
        _same_error(lambda t=t: mod.rhs(y, p, t=t), lambda t=t: rhs(y, t=t))
    with pytest.raises(CodegenError, match=r"^t: "):
        rhs(y, t="0")


def test_a_function_that_was_not_generated_is_named(mod):
    bound = mod.bind(_point(mod)[1])
    with pytest.raises(AttributeError, match=r"impact was not generated .* \(functions: "):
        bound.impact  # noqa: B018
    with pytest.raises(CodegenError, match="impact was not generated"):
        bound.call("impact", np.zeros(mod.n), np.zeros(mod.n))


def test_a_batch_of_parameter_vectors_is_bound_as_the_module_takes_it(mod):
    """NumPy broadcasts a batch of parameter vectors; C shares one vector across a batch
    and says so; bound, each does what its module does with them."""
    y, p = _point(mod, 8)
    batch = np.stack([p, 1.5 * p])
    bound = mod.bind(batch)
    if mod.backend == "numpy":
        expected = mod.rhs(y, batch)
        assert expected.shape == (2, 2 * mod.n)
        assert np.array_equal(bound.rhs(y), expected)
    else:
        _same_error(lambda: mod.rhs(y, batch), lambda: bound.rhs(y))
