"""compile_library with several C files: compiled side by side and linked, or one
compiler run on a single CPU; the same library and the same errors either way."""

from __future__ import annotations

import ctypes

import pytest

from symmech.codegen import build
from symmech.codegen.build import CompileError, compile_library

SOURCES = {
    "a.c": "double twice(double x) { return 2.0 * x; }\n",
    "b.c": "double twice(double x);\ndouble four_times(double x) { return twice(twice(x)); }\n",
}


@pytest.mark.parametrize("cpus", [1, 2])
def test_several_files_link_into_one_library(tmp_path, monkeypatch, cpus):
    monkeypatch.setattr(build, "_cpus", lambda: cpus)
    lib = ctypes.CDLL(str(compile_library(SOURCES, cache=tmp_path)))
    lib.four_times.restype = ctypes.c_double
    lib.four_times.argtypes = [ctypes.c_double]
    assert lib.four_times(1.5) == 6.0


@pytest.mark.parametrize("cpus", [1, 2])
def test_a_file_that_does_not_compile_is_named(tmp_path, monkeypatch, cpus):
    monkeypatch.setattr(build, "_cpus", lambda: cpus)
    broken = {**SOURCES, "c.c": "double broken(double x) { return x +; }\n"}
    with pytest.raises(CompileError, match=r"c\.c.*(error|expected)"):
        compile_library(broken, cache=tmp_path)
    assert not list(tmp_path.glob("*.so"))  # nothing left in the cache


def test_a_large_source_is_written_as_two_files_with_the_same_functions(tmp_path, monkeypatch):
    """Over SPLIT_SOURCE_CHARACTERS the functions are printed in two C files (compiled side
    by side): the parameter checks once, every function once, and the loaded module gives
    the doubles of the single file's."""
    import importlib

    import numpy as np

    from symmech import codegen
    from symmech.examples import carnot_3_7

    generation = importlib.import_module("symmech.codegen.generate")

    scene = carnot_3_7()
    whole = codegen.generate(scene, "c")
    monkeypatch.setattr(generation, "SPLIT_SOURCE_CHARACTERS", 100)
    split = codegen.generate(scene, "c")
    sources = sorted(name for name in split.files if name.endswith(".c"))
    assert sources == [f"{split.stem}.c", f"{split.stem}_2.c"]
    assert sorted(whole.files) == sorted(set(split.files) - {f"{split.stem}_2.c"})
    text = [split.files[name] for name in sources]
    assert sum(t.count("_check_parameters(const double *p)\n{") for t in text) == (
        whole.files[f"{whole.stem}.c"].count("_check_parameters(const double *p)\n{")
    )
    for f in whole.functions:
        definition = f"int {whole.stem}_{f.name}("
        assert sum(t.count(definition) for t in text) == 1, f.name
    a, b = whole.load(cache=tmp_path / "a"), split.load(cache=tmp_path / "b")
    rng = np.random.default_rng(3)
    params = {str(s): rng.uniform(0.5, 2.0) for s in scene.parameters}
    y = rng.uniform(-1.0, 1.0, (5, 2 * scene.n))
    assert np.array_equal(a.rhs(y, params), b.rhs(y, params))
    q, v = y[:, : scene.n], y[:, scene.n :]
    for name in ("mass_matrix", "energy"):
        args = (q,) if name == "mass_matrix" else (q, v)
        assert np.array_equal(getattr(a, name)(*args, params), getattr(b, name)(*args, params))
