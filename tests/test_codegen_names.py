"""Generated names and signatures: wall functions that cannot collide, sanitised wall
names, raw functions that take only the arguments they read, and what ``omitted`` says.
"""

from __future__ import annotations

import inspect
import re
import subprocess

import numpy as np
import pytest
import sympy as sp
from codegen_support import require_c_compiler

import symmech as sm
from symmech import codegen
from symmech.codegen.plan import Block, FunctionPlan, check_unique_names, wall_ids
from symmech.examples import carnot_3_7

STRICT = ["-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-pedantic"]


def _compile_strict(code: codegen.GeneratedCode, folder) -> None:
    code.write(folder)
    proc = subprocess.run(
        [require_c_compiler(), *STRICT, "-c", f"{code.stem}.c", "-o", "out.o"],
        cwd=folder,
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stderr


def _clash_scene() -> sm.Scene:
    """The audit's scene: the psi_t of the moving wall 'floor' and the psi of the wall
    't_floor' were both named psi_t_floor."""
    x, y = sm.coordinates("x y")
    m = sp.Symbol("m", positive=True)
    return sm.Scene(
        (x, y),
        metric=sp.diag(m, m),
        walls=[
            sm.Wall(y - sp.sin(sm.t), restitution=1, name="floor"),
            sm.Wall(x + 2, restitution=1, name="t_floor"),
        ],
        name="clash",
    )


@pytest.mark.parametrize("target", ["c", "numpy"])
def test_psi_t_of_one_wall_and_psi_of_another_do_not_collide(tmp_path, target):
    code = codegen.generate(_clash_scene(), target)
    names = [f.name for f in code.functions]
    assert len(names) == len(set(names))
    if target == "c":
        _compile_strict(code, tmp_path)
    mod = code.load()
    q = [0.5, 0.25]
    # psi_t of floor = d/dt (y - sin t) = -cos t; psi of t_floor = x + 2
    assert mod.psi_t(q, [1.0], wall="floor", t=0.0) == -1.0
    assert mod.psi_t(q, [1.0], wall="floor", t=0.5) == pytest.approx(-np.cos(0.5), rel=1e-15)
    assert mod.psi(q, [1.0], wall="t_floor") == 2.5
    assert mod.psi(q, [1.0], wall="floor", t=0.0) == 0.25
    assert mod.psi_t(q, [1.0], wall="t_floor") == 0.0  # static: not generated, zero
    # elastic bounce off the moving floor: y_dot+ = -y_dot- + 2 d/dt sin(t) = -y_dot- + 2 cos t
    np.testing.assert_allclose(mod.impact(q, [1.0, -1.0], [1.0], wall=0, t=0.0), [1.0, 3.0])
    np.testing.assert_allclose(mod.impact(q, [1.0, -1.0], [1.0], wall=1), [-1.0, -1.0])


def _plan(name: str, kind: str, wall: str | None = None, index: int | None = None):
    return FunctionPlan(
        name=name,
        kind=kind,
        doc="",
        equation="",
        state=("q",),
        blocks=(Block("out", (), (sp.S.Zero,)),),
        out_shape=(),
        wall=wall,
        wall_index=index,
    )


def test_a_name_collision_is_an_error_naming_both_functions():
    with pytest.raises(codegen.CodegenError, match="psi_t_floor") as info:
        check_unique_names(
            [_plan("psi_t_floor", "psi_t", "floor", 0), _plan("psi_t_floor", "psi", "t_floor", 1)]
        )
    message = str(info.value)
    assert "psi_t of wall 'floor' (index 0)" in message
    assert "psi of wall 't_floor' (index 1)" in message
    # a function name equal to the C batch name of another
    with pytest.raises(codegen.CodegenError, match="batch form of psi of wall 'a'"):
        check_unique_names([_plan("psi_a", "psi", "a", 0), _plan("psi_a_batch", "psi", "b", 1)])
    check_unique_names([_plan("psi_a", "psi", "a", 0), _plan("psit_a", "psi_t", "a", 0)])


def test_wall_identifiers_are_sanitised_unique_and_never_end_in_batch():
    ids = wall_ids(["left wall", "left_wall", "x*/y", "floor_batch", "batch", "1st", "int", ""])
    assert ids == ("left_wall", "left_wall_1", "x_y", "floor_batch_w", "batch_w", "1st", "int", "s")
    for wid in ids:
        assert re.fullmatch(r"[0-9A-Za-z]+(_[0-9A-Za-z]+)*", wid), wid


@pytest.mark.parametrize("target", ["c", "numpy"])
def test_wall_names_that_are_not_identifiers_compile_and_are_found_by_name(tmp_path, target):
    x, y = sm.coordinates("x y")
    walls = [
        sm.Wall(y, restitution=sp.Rational(1, 2), name="left wall"),
        sm.Wall(x - 1, restitution=1, name="left_wall"),
        sm.Wall(1 - x, restitution=1, name='odd */ """name\\'),
        sm.Wall(y + 3, restitution=1, name="floor_batch"),
    ]
    scene = sm.Scene((x, y), metric=sp.eye(2), walls=walls, name="named walls")
    code = codegen.generate(scene, target)
    if target == "c":
        _compile_strict(code, tmp_path)
    mod = code.load()
    q = [0.25, 0.5]
    assert mod.psi(q, wall="left wall") == 0.5
    assert mod.psi(q, wall="left_wall") == -0.75
    assert mod.psi(q, wall='odd */ """name\\') == 0.75
    assert mod.psi(q, wall="floor_batch") == 3.5
    np.testing.assert_allclose(mod.impact(q, [1.0, -2.0], wall="left wall"), [1.0, 1.0])
    with pytest.raises(codegen.CodegenError, match="no wall named 'left  wall'"):
        mod.psi(q, wall="left  wall")


def test_walls_with_the_same_name_need_their_index():
    """An unnamed wall at index 1 is called 'wall1' by the scene, like the wall explicitly
    named so: both get functions, and a lookup by that name is refused as ambiguous."""
    x, y = sm.coordinates("x y")
    walls = [sm.Wall(y, restitution=1, name="wall1"), sm.Wall(x + 2, restitution=1)]
    scene = sm.Scene((x, y), metric=sp.eye(2), walls=walls, name="same_names")
    mod = codegen.generate(scene, "numpy").load()
    assert mod.psi([1.0, 2.0], wall=0) == 2.0 and mod.psi([1.0, 2.0], wall=1) == 3.0
    with pytest.raises(codegen.CodegenError, match=r"walls \[0, 1\] are all named 'wall1'"):
        mod.psi([1.0, 2.0], wall="wall1")


# ------------------------------------------------------------------------- signatures


def _numpy_namespace(code: codegen.GeneratedCode) -> dict:
    namespace: dict = {}
    exec(compile(code.files[f"{code.stem}.py"], code.stem, "exec"), namespace)
    return namespace


def test_raw_numpy_functions_take_only_the_arguments_they_read():
    code = codegen.generate(_clash_scene(), "numpy")
    ns = _numpy_namespace(code)

    def params(name):
        return list(inspect.signature(ns[name]).parameters)

    assert params("mass_matrix") == ["q", "p"]
    assert params("forcing") == ["q", "v"]  # V = 0, constant metric: reads no parameter
    assert params("energy") == ["q", "v", "p"]
    assert params("psi_floor") == ["q", "t"]
    assert params("psit_floor") == ["q", "t"]
    assert params("dpsi_floor") == ["q"]
    # the closed-form impact's map does not read m (it cancels), its metric check does
    assert params("impact_floor") == ["q", "v", "p", "t"]
    assert params("rhs") == ["y"]
    assert ns["psi_floor"](np.array([0.0, 0.5]), 0.0) == 0.5
    doc = code.files["symmech_clash.py"].split('"""')[1]
    assert "u (..., 0)" not in doc and "u:" not in doc  # no inputs: not mentioned
    # the wrapper keeps one signature; params may be left out where none is read
    mod = code.load()
    assert mod.dpsi([0.0, 0.5]).tolist() == [0.0, 1.0]
    with pytest.raises(codegen.CodegenError, match="params required"):
        mod.energy([0.0, 0.5], [1.0, 0.0])


def test_c_prototypes_take_only_the_arguments_they_read(tmp_path):
    code = codegen.generate(_clash_scene(), "c")
    header = code.files["symmech_clash.h"]
    assert "int symmech_clash_dpsi_floor(const double *q, double *out);" in header
    assert "int symmech_clash_psi_floor(const double *q, double t, double *out);" in header
    assert "int symmech_clash_mass_matrix(const double *q, const double *p, double *out);" in header
    assert "int symmech_clash_forcing(const double *q, const double *v, double *out);" in header
    assert "long symmech_clash_rhs_batch(long count, const double *y, double *out);" in header
    _compile_strict(code, tmp_path)
    mod = code.load()
    assert mod.psi([0.0, 0.5], wall="floor", t=0.0) == 0.5
    assert mod.dpsi([0.0, 0.5], wall="floor").tolist() == [0.0, 1.0]


def test_omitted_lists_zero_connection_coefficients_and_unused_arguments():
    omitted = " | ".join(codegen.generate(_clash_scene(), "c").omitted)
    assert "6 of the 6 Christoffel symbols Gamma_k(ij)" in omitted
    assert "forcing: entries [0, 1] are identically zero" in omitted
    assert "parameter argument p left out of forcing, acceleration, rhs, psi_floor" in omitted
    assert "time argument t left out of mass_matrix" in omitted
    assert "state arrays taken but not read" in omitted and "mass_matrix (q)" in omitted
    carnot = " | ".join(codegen.generate(carnot_3_7(), "numpy").omitted)
    assert "Christoffel symbols" in carnot or "connection coefficients" in carnot
