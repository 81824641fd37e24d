"""Hostile and careless input, round 3 (issue 26): the items fixed so far, each with the
input that used to pass silently or crash."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import sympy as sp
from test_cli import symmech

import symmech as sm
from symmech.codegen import CodegenError
from symmech.declaration.symbols import t
from symmech.simulate import SimulationError


def _floor_at_h() -> sm.Scene:
    """A ball over the floor y = h(t), h given by the run's definitions."""
    y = sm.coordinates(["y"])[0]
    m, g = sp.symbols("m g", positive=True)
    h = sp.Function("h")(t)
    wall = sm.Wall(y - h, restitution=sp.Rational(1, 2), name="floor")
    return sm.Scene([y], metric=[[m]], potential=m * g * y, walls=[wall], name="floor_at_h")


PARAMS = {"m": 1.0, "g": 9.81}


@pytest.mark.parametrize("backend", ["c", "numpy"])
def test_a_definition_is_a_function_of_t_and_the_parameters_only(backend):
    """{"h": y - 1} made the wall vanish (the ball fell through), {"h": ydot} crashed gcc:
    a definition naming a coordinate, a velocity, a foreign symbol or another function is
    refused, naming what it uses."""
    scene = _floor_at_h()
    y, yd = scene.declaration.coordinates[0], scene.declaration.velocities[0]
    bad = {
        "y": y - 1,
        "ydot": yd,
        "zz": sp.Symbol("zz"),
        "k(t)": sp.Function("k")(t),
    }
    for value, why in ((sp.zeta(t), "calls zeta"), (sp.I * t, "is not real")):
        # printed nowhere (PrintMethodNotImplementedError from the C printer before)
        with pytest.raises(CodegenError, match=why):
            sm.simulate(
                scene, [1.0], [0.0], 1.0, params=PARAMS, backend=backend,
                definitions={"h": value},
            )  # fmt: skip
    for used, value in bad.items():
        why = rf"function of t and the parameters .* uses \['{re.escape(used)}'\]"
        with pytest.raises(CodegenError, match=why):
            sm.simulate(
                scene, [1.0], [0.0], 1.0, params=PARAMS, backend=backend,
                definitions={"h": value},
            )  # fmt: skip
    res = sm.simulate(
        scene, [1.0], [0.0], 1.0, params=PARAMS, backend=backend,
        definitions={"h": "0.1*sin(t)"},
    )  # fmt: skip
    assert res.status == "finished" and res.stats["impacts"] >= 1


@pytest.mark.parametrize("given", ["h", ["h"], 3])
def test_definitions_that_are_not_a_mapping_are_refused(given):
    with pytest.raises(SimulationError, match="definitions: expected a mapping"):
        sm.simulate(_floor_at_h(), [1.0], [0.0], 1.0, params=PARAMS, definitions=given)


@pytest.mark.parametrize("value", ["9,81", "1,2,3", "9 81"])
def test_a_parameter_on_the_command_line_is_one_number(tmp_path: Path, value: str):
    """--param g=9,81 (a decimal comma) ran with g = 9, exit 0."""
    proc = symmech("simulate", "bouncing_ball", "--param", f"g={value}", "--quiet", cwd=tmp_path)
    assert proc.returncode == 2
    assert "--param g: expected one number" in proc.stderr
    assert proc.stderr.count("\n") == 1


def test_a_negative_event_count_is_refused(tmp_path: Path):
    """--events -5 printed 'events: 5' and then '... 10 more'."""
    proc = symmech("simulate", "bouncing_ball", "--events", "-5", "--quiet", cwd=tmp_path)
    assert proc.returncode == 2 and "expected a number >= 0" in proc.stderr


@pytest.mark.parametrize(
    "args",
    [
        ("simulate", "bouncing_ball", "--backend", "scipy", "--method", "evil"),
        ("bench", "bouncing_ball", "--routes", "scipy:evil", "--no-baseline"),
    ],
)
def test_an_unknown_method_is_bad_input_not_an_internal_error(tmp_path: Path, args):
    """Both used to end as "internal error", exit 3."""
    proc = symmech(*args, "--quiet", cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    assert "method 'evil' is not available with backend='scipy'" in proc.stderr


@pytest.mark.parametrize("backend", ["c", "numpy", "scipy"])
def test_short_time_scales_and_tiny_atol_run_and_locate_events_relatively(backend):
    """The step floor and the event location were absolute near t = 0: g = 1e8, h = 1e-12
    (first impact at 1.4e-10 s) ended 'step size ... too small at t = 0' on C and NumPy
    and was off by 3e-6 relative on SciPy; atol = 1e-30 failed likewise.  Now the run's
    time scale min(1, |t_end|) sets them: the impact time of sqrt(2h/g) to 1e-14 relative."""
    from symmech.examples import bouncing_ball

    scene = bouncing_ball()
    p = {"m": 1.0, "g": 1e8, "alpha": 0.5}
    res = sm.simulate(
        scene, [1e-12], [0.0], 3e-10, params=p, backend=backend, rtol=1e-10, atol=1e-22
    )
    assert res.status == "finished", res.message
    first = res.impacts()[0].time
    assert first == pytest.approx((2e-12 / 1e8) ** 0.5, rel=1e-14)
    p = {"m": 1.0, "g": 9.81, "alpha": 0.5}
    res = sm.simulate(scene, [1.0], [0.0], 1.0, params=p, backend=backend, atol=1e-30)
    assert res.status == "finished", res.message
    assert res.impacts()[0].time == pytest.approx((2 / 9.81) ** 0.5, rel=1e-12)


def test_far_from_t0_every_backend_refuses_a_motion_below_the_resolution_of_t():
    """t0 = 1e16 (t resolved to 2 s), a ball dropped from 1 m: C and NumPy failed 'step size
    too small', while SciPy reported the ball at rest on the floor after no impact."""
    from symmech.examples import bouncing_ball

    p = {"m": 1.0, "g": 9.81, "alpha": 0.5}
    for backend in ("c", "numpy", "scipy"):
        res = sm.simulate(
            bouncing_ball(), [1.0], [0.0], 1e16 + 10, t0=1e16, params=p, backend=backend
        )
        assert res.status == "failed", (backend, res.message)
        assert res.message.startswith("step size ") and "too small at t = 1e+16" in res.message


def test_plots_tables_and_scene_files_replace_a_link_never_write_through_it(tmp_path: Path):
    """`symmech bench --plot LINK.png` wrote through a symbolic link and overwrote its
    target; every output file now goes through one writer (symmech.files.write_atomic)."""
    pytest.importorskip("matplotlib")
    target = tmp_path / "precious.txt"
    target.write_text("keep me")
    for name in ("plot.png", "table.csv", "scene.toml"):
        (tmp_path / name).symlink_to(target)
    proc = symmech(
        "bench", "bouncing_ball", "--routes", "c:dop853", "--tolerances", "1e-6",
        "--repeats", "1", "--no-baseline", "--plot", "plot.png", "--quiet", cwd=tmp_path,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    grid = tmp_path / "grid.csv"
    grid.write_text("q0[0]\n1.0\n")
    proc = symmech(
        "sweep", "bouncing_ball", "--grid", "grid.csv", "--out", "table.csv", "--t-end", "1",
        "--v0", "0", "--quiet", cwd=tmp_path,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    sm.save_scene(sm.load_scene("bouncing_ball"), tmp_path / "scene.toml")
    assert target.read_text() == "keep me"
    for name in ("plot.png", "table.csv", "scene.toml"):
        path = tmp_path / name
        assert path.is_file() and not path.is_symlink(), name
    assert (tmp_path / "plot.png").read_bytes()[:4] == b"\x89PNG"
    assert "q0[0]" in (tmp_path / "table.csv").read_text()


def test_an_unpickled_scene_is_validated_like_any_declaration():
    """A pickle from a Dask worker or a file is input: a crafted declaration whose floor is
    psi = y**2 (no gradient on the wall: the ball went through it) is refused on loading."""
    import dataclasses
    import pickle

    from symmech.errors import SceneError
    from symmech.examples import bouncing_ball

    scene = bouncing_ball()
    y = scene.declaration.coordinates[0]
    decl = scene.declaration
    bad_wall = dataclasses.replace(
        decl.walls[0], psi=y**2, wall=dataclasses.replace(decl.walls[0].wall, psi=y**2)
    )
    crafted = object.__new__(sm.Scene)
    object.__setattr__(crafted, "_decl", dataclasses.replace(decl, walls=(bad_wall,)))
    object.__setattr__(crafted, "_Scene__derived", {})
    data = pickle.dumps(crafted)
    with pytest.raises(SceneError, match="psi"):
        pickle.loads(data)
    good = pickle.loads(pickle.dumps(scene))
    assert good.declaration == scene.declaration


def _tiny_sources() -> dict[str, str]:
    return {"tiny.c": "double tiny_answer(void) { return 42.0; }\n"}


def test_a_relative_cache_folder_works(tmp_path: Path, monkeypatch):
    """A relative SYMMECH_CACHE_DIR broke every C build (gcc's -o relative to its build
    folder)."""
    import ctypes

    from symmech.codegen.build import compile_library, load_library

    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("SYMMECH_CACHE_DIR", "relative_cache")
    path = compile_library(_tiny_sources())
    assert path.is_absolute() and path.parent == tmp_path / "relative_cache"
    fn = load_library(path).tiny_answer
    fn.restype = ctypes.c_double
    assert fn() == 42.0


def test_a_cache_path_that_is_a_file_is_refused_with_its_name(tmp_path: Path):
    from symmech.codegen import CompileError
    from symmech.codegen.build import compile_library

    blocker = tmp_path / "not_a_folder"
    blocker.write_text("x")
    with pytest.raises(CompileError, match=r"cache folder .*not_a_folder"):
        compile_library(_tiny_sources(), cache=blocker)
    with pytest.raises(CompileError, match=r"cache folder .*not_a_folder"):
        compile_library(_tiny_sources(), cache=blocker / "below")


def test_a_truncated_cached_library_is_rebuilt_not_loaded(tmp_path: Path):
    """A truncated library of the same user (a full disk, a killed copy) crashed the
    process with a bus error when loaded; its digest no longer matches and it is rebuilt."""
    import ctypes

    from symmech.codegen.build import compile_library, load_library

    path = compile_library(_tiny_sources(), cache=tmp_path)
    full = path.read_bytes()
    path.write_bytes(full[: len(full) // 3])
    again = compile_library(_tiny_sources(), cache=tmp_path)
    assert again == path and again.read_bytes() == full
    fn = load_library(again).tiny_answer
    fn.restype = ctypes.c_double
    assert fn() == 42.0
