"""The single-state fast path of the loaded C module, by both of its routes (the CPython
extension built next to the library, and ctypes): the same results as the general path
(and as the NumPy backend), arguments it does not handle are passed on to the general path
and refused there with its messages, nothing is broadcast silently, threads do not share
its buffers, and a failure raises NumericalError."""

from __future__ import annotations

import subprocess
import threading

import numpy as np
import pytest
from codegen_support import require_c_compiler

import symmech as sm
from symmech.codegen import CodegenError, NumericalError
from symmech.codegen.build import extension_includes, find_compiler
from symmech.codegen.module import extension_source
from symmech.examples import carnot_3_7, carnot_4_4, pendulum_on_cart


@pytest.fixture(scope="module", params=["extension", "ctypes"])
def modules(request):
    require_c_compiler()
    scene = pendulum_on_cart(3)
    code_c = sm.codegen.generate(scene, "c", strategy="linear_solve")
    code_np = sm.codegen.generate(scene, "numpy", strategy="linear_solve")
    c = code_c.load(extension=request.param == "extension")
    if request.param == "ctypes":
        assert c.fast_path == "ctypes (extension=False)"
    return c, code_np.load()


def test_the_extension_is_used_where_the_headers_are():
    """With the CPython and NumPy headers (as on any python.org, pyenv, conda or Docker
    Python) one-state calls go through the extension; without them through ctypes, and
    the module says why."""
    require_c_compiler()
    c = sm.codegen.generate(carnot_3_7(), "c").load()
    _, missing = extension_includes()
    if missing is None:
        assert c.fast_path.startswith("CPython extension _symmech_ext_"), c.fast_path
        assert type(c._fast["impact_rough_wall"]).__name__ == "builtin_function_or_method"
    else:
        assert c.fast_path == f"ctypes (no CPython extension: {missing})"


def test_both_routes_give_the_same_doubles_for_every_function():
    require_c_compiler()
    code = sm.codegen.generate(pendulum_on_cart(2), "c", strategy="linear_solve", projectors=False)
    ext, plain = code.load(), code.load(extension=False)
    rng = np.random.default_rng(7)
    for _ in range(5):
        q, v = rng.normal(size=ext.n), rng.normal(size=ext.n)
        p = 1 + rng.random(len(ext.parameters))
        for name in ext.functions:
            spec = ext._spec[name]
            args = [np.concatenate([q, v])] if spec.state == ("y",) else [q, v][: len(spec.state)]
            a = ext.call(name, *args, params=p)
            b = plain.call(name, *args, params=p)
            assert a.shape == b.shape and np.array_equal(a, b), name
            # lists of Python floats and ints are read too
            assert np.array_equal(ext.call(name, *[list(x) for x in args], params=list(p)), a)


def test_a_failure_in_the_fast_path_raises_numerical_error(modules):
    c, _ = modules
    q, _, p = _state(c, 5)
    with pytest.raises(NumericalError, match=r"^acceleration: an output, or an input"):
        c.acceleration(q, np.full(c.n, np.inf), p)
    with pytest.raises(NumericalError, match=r"^mass_matrix: an output"):
        c.mass_matrix(np.full(c.n, np.nan), p)


def _state(mod, seed):
    rng = np.random.default_rng(seed)
    return rng.normal(size=mod.n), rng.normal(size=mod.n), 1 + rng.random(len(mod.parameters))


def test_fast_path_is_taken_and_agrees_with_the_general_path(modules):
    c, npm = modules
    assert "acceleration" in c._fast and "mass_matrix" in c._fast
    for seed in range(5):
        q, v, p = _state(c, seed)
        fast = c.acceleration(q, v, p)
        general = c.acceleration(q[None, :], v[None, :], p)[0]  # the batch route
        assert np.array_equal(fast, general)
        np.testing.assert_allclose(fast, npm.acceleration(q, v, p), rtol=1e-12, atol=1e-12)
        M = c.mass_matrix(q, p)
        assert M.shape == (c.n, c.n)
        assert np.array_equal(M, c.mass_matrix(q[None, :], p)[0])
        # lists, tuples and a mapping of parameters give the same numbers
        named = dict(zip(c.parameters, p, strict=True))
        assert np.array_equal(c.acceleration(list(q), tuple(v), named), fast)


def test_fast_path_returns_fresh_arrays(modules):
    c, _ = modules
    q, v, p = _state(c, 1)
    first = c.acceleration(q, v, p)
    kept = first.copy()
    c.acceleration(*_state(c, 2))
    assert np.array_equal(first, kept)  # not a view on a reused buffer


@pytest.mark.parametrize(
    "bad_q",
    [0.5, [0.5], np.zeros(1), np.zeros((2, 2)), "abc", [[0.0] * 3]],
    ids=["scalar", "short list", "short array", "matrix", "string", "nested"],
)
def test_what_the_fast_path_does_not_take_is_refused_by_the_general_path(modules, bad_q):
    c, _ = modules
    _, v, p = _state(c, 3)
    with pytest.raises((CodegenError, ValueError)):
        c.acceleration(bad_q, v, p)


def test_wrong_parameter_count_is_refused(modules):
    c, _ = modules
    q, v, p = _state(c, 4)
    with pytest.raises(CodegenError, match="params"):
        c.acceleration(q, v, p[:-1])


def test_threads_do_not_share_buffers(modules):
    c, npm = modules
    states = [_state(c, 10 + i) for i in range(4)]
    expected = [npm.acceleration(*s) for s in states]
    failures: list[str] = []

    def work(i: int) -> None:
        for _ in range(300):
            got = c.acceleration(*states[i])
            if not np.allclose(got, expected[i], rtol=1e-12, atol=1e-12):
                failures.append(f"thread {i}")
                return

    threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    assert not failures


def test_functions_of_time_or_walls_keep_working():
    """The impact of a wall goes through the fast path too (no t); same map as NumPy."""
    require_c_compiler()
    scene = carnot_3_7()
    c = sm.codegen.generate(scene, "c").load()
    npm = sm.codegen.generate(scene, "numpy").load()
    params = {"R": 1.0, "alpha": 0.5, "k": 1.0, "m": 2.0}
    q, v = [0.0, 1.0, 0.0], [1.0, -2.0, 0.0]
    np.testing.assert_allclose(c.impact(q, v, params), npm.impact(q, v, params), rtol=1e-14)


def test_the_extension_source_compiles_without_warnings(tmp_path):
    """The extension wrapper is held to the generated code's standard (bar -pedantic,
    which the CPython headers themselves do not meet)."""
    require_c_compiler()
    folders, missing = extension_includes()
    if missing is not None:
        pytest.skip(f"no CPython extension can be built here: {missing}")
    code = sm.codegen.generate(carnot_4_4(), "c", strategy="linear_solve", projectors=True)
    code.write(tmp_path)
    (tmp_path / "ext.c").write_text(extension_source(code, "ext"))
    flags = ["-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-fPIC", "-shared"]
    includes = [f"-I{d}" for d in folders]
    proc = subprocess.run(
        [find_compiler(), *flags, *includes, "-o", "ext.so", "ext.c", f"{code.stem}.c", "-lm"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stderr
