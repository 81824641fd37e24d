"""Seeing a run: sampling, frames and files that read back equal, plots, animations and the
drawing a scene declares.  Reference values are the bouncing ball's closed form
(:func:`symmech.bench.cases.bouncing_ball_state`), never the code under test."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import symmech as sm
from symmech.bench.cases import bouncing_ball_state, bouncing_ball_times
from symmech.declaration.drawing import Disc, Drawing, Point, Segment
from symmech.simulate import SimulationError
from symmech.simulate.animation import frames_rgb, save_animation
from symmech.simulate.table import load_result

H, G, ALPHA, T_END = 1.0, 9.81, 0.5, 1.3
PARAMS = {"m": 1.0, "g": G, "alpha": ALPHA}


@pytest.fixture(scope="module")
def ball() -> sm.Scene:
    return sm.load_scene("bouncing_ball")


@pytest.fixture(scope="module")
def res(ball):
    return sm.simulate(ball, [H], [0.0], T_END, params=PARAMS, rtol=1e-10, atol=1e-12)


def _impacts() -> list[float]:
    return bouncing_ball_times(H, G, ALPHA, T_END)


# ---------------------------------------------------------------------------------------
# results out


def test_sample_is_the_closed_form_with_each_impact_before_and_after(res):
    ts = np.linspace(0.0, T_END, 40)
    s = res.sample(ts)
    impacts = _impacts()
    assert len(impacts) == 5
    assert len(s.t) == len(ts) + 2 * len(impacts)
    plain = s.side == 0
    exact = np.array([bouncing_ball_state(H, G, ALPHA, float(t)) for t in s.t[plain]])
    np.testing.assert_allclose(s.q[plain, 0], exact[:, 0], atol=1e-8)
    np.testing.assert_allclose(s.v[plain, 0], exact[:, 1], atol=1e-8)
    u0 = math.sqrt(2 * G * H)
    for k, t_k in enumerate(impacts):
        (rows,) = np.nonzero(s.event == k)
        assert list(s.side[rows]) == [-1, 1]  # before, then after, at the same time
        np.testing.assert_allclose(s.t[rows], t_k, rtol=1e-10)
        np.testing.assert_allclose(s.q[rows, 0], 0.0, atol=1e-10)
        np.testing.assert_allclose(s.v[rows[0], 0], -(ALPHA**k) * u0, rtol=1e-8)
        np.testing.assert_allclose(s.v[rows[1], 0], ALPHA ** (k + 1) * u0, rtol=1e-8)
    assert np.all(np.diff(s.t) >= 0)


def test_sample_refuses_times_outside_the_run(res):
    with pytest.raises(SimulationError, match="outside the simulated interval"):
        res.sample([0.5, 2.0])
    with pytest.raises(SimulationError, match="finite"):
        res.sample([0.5, float("nan")])


def test_frame_columns_hold_the_energy_and_the_gap(res):
    frame = res.to_frame()
    assert list(frame.columns) == ["t", "y", "ydot", "energy", "gap[floor]", "event", "wall"]
    energy = PARAMS["m"] * G * frame["y"] + PARAMS["m"] * frame["ydot"] ** 2 / 2
    np.testing.assert_allclose(frame["energy"], energy, rtol=1e-12)
    np.testing.assert_allclose(frame["gap[floor]"], frame["y"], rtol=0, atol=0)
    at_impacts = frame[frame["event"] == "impact"]
    assert set(at_impacts["wall"]) == {"floor"}
    np.testing.assert_allclose(sorted(set(at_impacts["t"])), _impacts(), rtol=1e-10)
    assert frame.attrs["status"] == "finished" and frame.attrs["params"] == PARAMS


@pytest.mark.parametrize("suffix", [".csv", ".parquet", ".npz"])
def test_a_saved_run_reloads_equal(res, tmp_path: Path, suffix):
    path = res.save(tmp_path / f"run{suffix}")
    back = load_result(path)
    for name in ("t", "q", "v"):
        assert np.array_equal(getattr(back, name), getattr(res, name)), name
    assert back.events_frame().equals(res.events_frame())
    assert len(back.events) == len(res.events) == 5
    assert (back.status, back.message, back.stats) == (res.status, res.message, res.stats)
    assert (back.params, back.coordinates, back.velocities) == (
        PARAMS,
        ("y",),
        ("ydot",),
    )
    assert back.accumulation_time == res.accumulation_time
    assert back.to_frame().equals(res.to_frame())


def test_save_and_load_refuse_what_they_cannot_read(res, tmp_path: Path):
    with pytest.raises(SimulationError, match=r"run\.xlsx.*unknown file type"):
        res.save(tmp_path / "run.xlsx")
    stranger = tmp_path / "stranger.csv"
    stranger.write_text("t,y\n0,1\n")
    with pytest.raises(SimulationError, match=r"stranger\.csv: not a run saved by symmech"):
        load_result(stranger)


# ---------------------------------------------------------------------------------------
# plots


def test_plot_has_its_panels_and_marks_every_impact(res, tmp_path: Path):
    fig = res.plot(path=tmp_path / "run.png")
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert labels == ["coordinates", "velocities", "gaps psi", "energy T + V"]
    impacts = _impacts()
    for ax in fig.axes:
        (lines,) = [c for c in ax.collections if c.get_gid() == "events:impact"]
        xs = sorted(seg[0][0] for seg in lines.get_segments())
        np.testing.assert_allclose(xs, impacts, rtol=1e-10)
    gaps = fig.axes[2]
    (markers,) = [ln for ln in gaps.get_lines() if ln.get_gid() == "events:impact"]
    assert markers.get_label() == "impact" and markers.get_marker() == "v"
    np.testing.assert_allclose(markers.get_xdata(), impacts, rtol=1e-10)
    from PIL import Image

    with Image.open(tmp_path / "run.png") as img:
        assert img.format == "PNG" and img.size[0] > 300


def test_plot_of_a_reloaded_run_draws_its_steps(res, tmp_path: Path):
    back = load_result(res.save(tmp_path / "run.npz"))
    fig = back.plot()
    (curve,) = [ln for ln in fig.axes[0].get_lines() if ln.get_label() == "y"]
    assert np.array_equal(curve.get_xdata(), res.t)
    assert [ax.get_ylabel() for ax in fig.axes][-1] == "energy T + V"


# ---------------------------------------------------------------------------------------
# animations


def test_animation_frames_are_real_time_plus_the_impacts_and_differ(res, tmp_path: Path):
    anim = res.animate(fps=10)
    expected = np.union1d(np.arange(14) * 0.1, _impacts())  # 0, 0.1, ..., 1.3 and impacts
    np.testing.assert_allclose(anim.times, expected, rtol=1e-9, atol=1e-12)
    # the ball (the drawing's point) is where the closed form puts it, frame by frame
    for i in (0, 3, 9):
        anim.render(i)
        (dot,) = [
            ln
            for ln in anim.scene_figure.axes[0].get_lines()
            if ln.get_marker() == "o" and len(ln.get_ydata()) == 1
        ]
        y = bouncing_ball_state(H, G, ALPHA, float(anim.times[i]))[0]
        assert abs(dot.get_ydata()[0] - y) < 1e-8
    frames = frames_rgb(anim, dpi=40)
    assert len(frames) == len(expected)
    assert not np.array_equal(frames[0], frames[3])
    path = save_animation(anim, tmp_path / "run.gif", fps=10, dpi=40)
    from PIL import Image

    with Image.open(path) as gif:
        assert gif.n_frames == len(expected)


def test_a_scene_without_drawing_warns_and_animates_its_coordinates(ball):
    bare = ball.replace(drawing=None)
    run = sm.simulate(bare, [H], [0.0], 0.5, params=PARAMS)
    with pytest.warns(sm.SymmechWarning, match="has no drawing"):
        anim = run.animate(fps=10)
    assert len(anim.times) == len(np.union1d(np.arange(6) * 0.1, [math.sqrt(2 * H / G)]))
    ax = anim.scene_figure.axes[0]
    assert ax.get_ylabel() == "coordinates"
    frames = frames_rgb(anim, dpi=30)
    assert not np.array_equal(frames[0], frames[-1])  # the time cursor moved


def test_animation_speed_and_frame_limit(res):
    assert len(res.animate(fps=10, speed=2.0).times) == len(
        np.union1d(np.arange(7) * 0.2, _impacts())
    )
    with pytest.raises(SimulationError, match=r"frames \(limit"):
        res.animate(fps=5000)


# ---------------------------------------------------------------------------------------
# the drawing a scene declares


def test_a_drawing_uses_only_the_scenes_symbols():
    x, y = sm.coordinates("x y")
    m, r, stray = sp.symbols("m r stray", positive=True)
    with pytest.raises(sm.SceneError, match=r"drawing\[1\] \(disc\): stray is not a coordinate"):
        sm.Scene(
            (x, y),
            metric=sp.diag(m, m),
            walls=[sm.Wall(y - r)],
            drawing=Drawing([Point((x, y)), Disc((x, y), stray)]),
        )
    with pytest.raises(sm.SceneError, match="expected a number or a sympy expression"):
        Segment(("x", 0), (1, 0))
    scene = sm.Scene(
        (x, y), metric=sp.diag(m, m), walls=[sm.Wall(y - r)], drawing=[Disc((x, y), r, y / r)]
    )
    assert scene.drawing == Drawing([Disc((x, y), r, y / r)])


@pytest.mark.parametrize(
    "bad",
    [
        lambda x, y: sp.Derivative(sp.Function("h")(x), x),  # a derivative
        lambda x, y: x + sp.I * y,  # not real
        lambda x, y: 2 * sp.Function("h")(x),  # an undefined function
        lambda x, y: sp.cos(x) * (1 + sp.sqrt(-1) * y) ** 2,  # I deep inside
    ],
    ids=["derivative", "imaginary", "undefined function", "deep imaginary"],
)
def test_a_drawing_is_a_real_function_of_the_scene(bad):
    """Each shape's expressions are real functions of q, t and the parameters: a shape
    holding a derivative, the imaginary unit or an undefined function is refused, named
    by its place, even when the shapes before it share its subexpressions."""
    x, y = sm.coordinates("x y")
    m, r = sp.symbols("m r", positive=True)
    shared = sp.sin(x) + y
    with pytest.raises(sm.SceneError, match=r"drawing\[2\] \(disc\): .* is not a real function"):
        sm.Scene(
            (x, y),
            metric=sp.diag(m, m),
            drawing=[
                Point((shared, y)),
                Segment((shared, 0), (x, y)),
                Disc((shared, bad(x, y)), r),
            ],
        )


def test_scene_files_read_and_write_the_drawing():
    sf = sm.read_scene("ellipse_gravity")
    text = sm.dump_scene(sf.scene, defaults=sf.defaults)
    assert 'shape = "ellipse"' in text and 'axes = ["a", "b"]' in text
    assert sm.reads_scene(text).scene.drawing == sf.scene.drawing
    bad = text + '\n[[drawing]]\nshape = "disc"\ncenter = ["x", "ydot"]\nradius = 1\n'
    with pytest.raises(sm.SceneFileError, match=r"drawing\[2\]\.center\[1\] \(line \d+"):
        sm.reads_scene(bad)
    with pytest.raises(sm.SceneFileError, match="shape must be one of"):
        sm.reads_scene(text + '\n[[drawing]]\nshape = "blob"\n')


# ---------------------------------------------------------------------------------------
# the command line: a CSV, a PNG and a GIF of a built-in scene


def test_simulate_writes_the_run_its_plot_and_its_animation(tmp_path: Path):
    from PIL import Image
    from test_cli import symmech

    proc = symmech(
        "simulate",
        "bouncing_ball",
        "--out",
        "run.csv",
        "--plot",
        "run.png",
        "--animate",
        "run.gif",
        "--fps",
        "10",
        "--quiet",
        cwd=tmp_path,
    )
    assert proc.returncode == 0, proc.stderr
    for line in ("saved: run.csv", "plot: run.png", "animation: run.gif"):
        assert line in proc.stdout.splitlines()
    back = load_result(tmp_path / "run.csv")
    assert back.status == "finished" and back.t[-1] == T_END
    np.testing.assert_allclose([e.time for e in back.events], _impacts(), rtol=1e-9)
    with Image.open(tmp_path / "run.png") as png:
        assert png.format == "PNG"
    with Image.open(tmp_path / "run.gif") as gif:
        assert gif.n_frames == len(np.union1d(np.arange(14) * 0.1, _impacts()))


def test_simulate_refuses_an_unknown_file_type_before_running(tmp_path: Path):
    from test_cli import assert_one_line_error, symmech

    proc = symmech("simulate", "bouncing_ball", "--animate", "run.mp4", cwd=tmp_path)
    assert_one_line_error(proc, "--animate run.mp4: unknown file type '.mp4'", ".gif, .html")
    assert "status:" not in proc.stdout


def test_a_batch_of_runs_is_a_table_that_reloads_equal(ball, tmp_path: Path):
    import pandas as pd

    batch = sm.simulate_batch(ball, [[1.0], [2.0]], [[0.0], [0.0]], 1.0, params=PARAMS)
    frame = batch.to_frame(["y"])
    assert list(frame.columns[:3]) == ["t", "y", "y_dot"]
    for i, h in enumerate((1.0, 2.0)):  # the final states are the closed form's
        exact = bouncing_ball_state(h, G, ALPHA, 1.0)
        np.testing.assert_allclose(frame.loc[i, ["y", "y_dot"]], exact, atol=1e-7)
    assert list(frame["impact"]) == [len(bouncing_ball_times(h, G, ALPHA, 1.0)) for h in (1, 2)]
    path = batch.save(tmp_path / "batch.parquet", coordinates=["y"])
    pd.testing.assert_frame_equal(pd.read_parquet(path), frame)
    csv = batch.save(tmp_path / "batch.csv", coordinates=["y"])
    pd.testing.assert_frame_equal(pd.read_csv(csv, index_col=0), frame, check_dtype=False)


def test_animating_a_scene_without_drawing_says_so_and_writes_an_html_player(tmp_path: Path):
    from test_cli import symmech

    scene = tmp_path / "drop.toml"
    scene.write_text(
        'coordinates = ["y"]\nmetric = ["m"]\npotential = "m*g*y"\n'
        '[parameters]\nm = 1\ng = 9.81\n[[walls]]\npsi = "y"\nrestitution = 1\n',
        encoding="utf-8",
    )
    args = ["--q0", "2", "--v0", "0", "--t-end", "0.3", "--fps", "10", "--quiet"]
    proc = symmech("simulate", str(scene), *args, "--animate", "drop.html", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "symmech: warning: scene 'drop' has no drawing" in proc.stderr
    page = (tmp_path / "drop.html").read_text(encoding="utf-8")
    assert page.startswith("<!DOCTYPE html>") and "<title>drop</title>" in page
    assert page.count("data:image/png;base64") == 4  # t = 0, 0.1, 0.2, 0.3: four frames
