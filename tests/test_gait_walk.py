"""Walking many strides (symmech.gait.walking) and ``symmech gait --walk``."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from symmech.gait.evaluation import CompiledGait
from symmech.gait.models import GAITS
from symmech.gait.stride_map import GaitError, stride
from symmech.gait.walking import walk
from tests.test_cli import assert_one_line_error, symmech


def _mcgeer(p, w0: float, strides: int) -> list[float]:
    """The rimless wheel's return map in closed form (McGeer 1990): the hub's angular
    speed just after impact, w -> -eta sqrt(w^2 + K) (w < 0, rolling downhill)."""
    r, l, g, a, gam = p["r"], p["l"], p["g"], p["alpha"], p["gamma"]
    eta = (r * r + l * l * math.cos(2 * a)) / (r * r + l * l)
    K = 4 * g * l * math.sin(a) * math.sin(gam) / (r * r + l * l)
    out = [w0]
    for _ in range(strides):
        out.append(-eta * math.sqrt(out[-1] ** 2 + K))
    return out


@pytest.mark.parametrize("target", ["c", "numpy"])
def test_the_rimless_wheel_walks_its_closed_form(target):
    spec = GAITS["rimless_wheel"]
    fns = CompiledGait(spec.build(), spec.parameters, target=target)
    w = walk(fns, 0, spec.guess, 10, record=True)
    assert not w.stopped and w.sections.shape == (11, 2)
    assert np.max(np.abs(w.sections[:, 1] - _mcgeer(spec.parameters, spec.guess[1], 10))) <= 1e-11
    assert np.max(np.abs(w.sections[:, 0] - spec.parameters["alpha"])) <= 1e-12
    assert np.all(w.periods > 0) and np.all(np.diff(w.trajectory[:, 0]) >= 0)
    assert [k for k, _, _ in w.events] == [0] * 10
    np.testing.assert_allclose([t for _, t, _ in w.events], w.times[1:], rtol=0, atol=1e-13)
    frame = w.to_frame()
    assert list(frame.columns) == ["stride", "t", "period", "x0", "x1"] and len(frame) == 11
    assert set(w.trajectory_frame()["mode"]) == {"stance"}


def test_a_walk_is_its_strides_one_after_another():
    spec = GAITS["hopper"]
    fns = CompiledGait(spec.build(), spec.parameters)
    w = walk(fns, spec.section, spec.guess, 3, record=True)
    x = np.array(spec.guess)
    for k in range(3):
        x = stride(fns, spec.section, x).x
        np.testing.assert_array_equal(w.sections[k + 1], x)
    assert set(w.trajectory[:, 1]) == {0.0, 1.0} and np.all(np.diff(w.trajectory[:, 0]) >= 0)
    assert len(w.events) == 6


def test_a_falling_walker_stops_the_walk_with_the_reason():
    spec = GAITS["compass_gait"]
    fns = CompiledGait(spec.build(), spec.parameters)
    w = walk(fns, 0, [0.27, -0.27, -1.0, -0.38], 8)
    assert w.stopped.startswith("stride 3: mode 'stance': no transition fired")
    assert w.sections.shape == (3, 4) and w.trajectory is None


def test_bad_walks_are_clear_errors():
    spec = GAITS["rimless_wheel"]
    fns = CompiledGait(spec.build(), spec.parameters)
    for bad in (-1, 2.5, True):
        with pytest.raises(GaitError, match="strides must be a whole number"):
            walk(fns, 0, spec.guess, bad)
    with pytest.raises(GaitError, match="no motion recorded"):
        walk(fns, 0, spec.guess, 1).trajectory_frame()


def test_gait_walk_prints_each_stride_and_writes_the_table_and_plot(tmp_path: Path):
    csv, png = tmp_path / "walk.csv", tmp_path / "walk.png"
    proc = symmech(
        "gait", "rimless_wheel", "--walk", "6", "--out", str(csv), "--plot", str(png),
        cwd=tmp_path, timeout=300,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    rows = [line.split() for line in proc.stdout.splitlines() if line[:6].strip().isdigit()]
    assert [int(r[0]) for r in rows] == list(range(7))
    # near the fixed point the distance shrinks by McGeer's multiplier eta^2 per stride
    eta = (0.09 + math.cos(math.pi / 5)) / 1.09
    assert float(rows[-1][4]) == pytest.approx(eta**2, rel=1e-3)
    assert csv.read_text().splitlines()[0].endswith("stride,t,period,x0,x1")
    assert png.stat().st_size > 10_000


def test_gait_walk_reports_a_fall_with_exit_code_1(tmp_path: Path):
    proc = symmech(
        "gait", "compass_gait", "--walk", "5", "--start", "0.27,-0.27,-1.0,-0.38", cwd=tmp_path,
        timeout=300,
    )  # fmt: skip
    assert proc.returncode == 1
    assert "stopped: stride 3: mode 'stance': no transition fired" in proc.stdout


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("--walk", "0"), "--walk 0: choose 1 to 100000"),
        (("--walk", "3", "--start", "1,2,3"), "--start '1,2,3': expected 2 numbers"),
        (("--walk", "3", "--start", "1,nan"), "--start"),
    ],
)
def test_gait_walk_refusals(tmp_path: Path, args, message):
    proc = symmech("gait", "rimless_wheel", *args, cwd=tmp_path)
    assert_one_line_error(proc, message)


def test_off_the_gait_the_distance_shrinks_by_the_leading_multiplier():
    """Two routes to one number: the variational-saltation multipliers and the walk."""
    from symmech.gait.periodic import fixed_point

    spec = GAITS["hopper"]  # a real leading multiplier: the ratio converges monotonically
    fns = CompiledGait(spec.build(), spec.parameters)
    fp = fixed_point(fns, spec.section, spec.guess)
    w = walk(fns, spec.section, fp.x + np.array([0.01, 0, 0.05, 0]), 8)
    d = np.max(np.abs(w.sections - fp.x), axis=1)
    assert d[-1] / d[-2] == pytest.approx(abs(fp.multipliers[0]), rel=1e-3)
