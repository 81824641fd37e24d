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
