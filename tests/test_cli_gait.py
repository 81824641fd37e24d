"""``symmech gait``: the table of routes, the continuation's PNG, refusals in one line."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

from tests.test_cli import assert_one_line_error, symmech


def test_gait_prints_each_route_and_the_cost(tmp_path: Path):
    proc = symmech("gait", "rimless_wheel", "--routes", "c,fd,mp", "--digits", "20", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    rows = {
        line.split()[0]: line
        for line in proc.stdout.splitlines()
        if line[:3] in ("c  ", "fd ", "mp ")
    }
    assert set(rows) == {"c", "fd", "mp"}
    # McGeer's multiplier eta^2 for the default wheel (r = 0.3, l = 1, alpha = pi/10)
    eta = (0.09 + math.cos(math.pi / 5)) / 1.09
    assert f"{eta**2:+.12f}"[:14] in rows["c"]
    error_c = float(rows["c"].split()[2])
    error_fd = float(rows["fd"].split()[2])
    assert error_c <= 1e-13 and error_fd >= 1e3 * error_c
    assert re.search(
        r"cost in C: one stride [\d.]+ ms, stride with its Jacobian [\d.]+ ms", proc.stdout
    )


def test_gait_continuation_writes_a_png_and_finds_the_period_doubling(tmp_path: Path):
    png = tmp_path / "walker.png"
    proc = symmech(
        "gait", "simplest_walker", "--continue", "gamma=0.009:0.017", "--steps", "5",
        "--plot", str(png), cwd=tmp_path, timeout=300,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert "gamma = 0.013: stable" in proc.stdout, proc.stdout
    assert "gamma = 0.017: unstable" in proc.stdout
    assert "period doubling between gamma = 0.015 and 0.017" in proc.stdout
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_gait_refusals_are_one_line(tmp_path: Path):
    assert_one_line_error(symmech("gait", "moonwalker", cwd=tmp_path), "unknown gait 'moonwalker'")
    assert_one_line_error(
        symmech("gait", "rimless_wheel", "--param", "g=9,81", cwd=tmp_path), "--param g"
    )
    assert_one_line_error(
        symmech("gait", "rimless_wheel", "--routes", "c,evil", cwd=tmp_path), "unknown ['evil']"
    )
    assert_one_line_error(
        symmech("gait", "rimless_wheel", "--continue", "zeta=0:1", cwd=tmp_path), "--continue"
    )


def test_gait_reads_a_gait_file(tmp_path: Path):
    from symmech.gait.gaitfile import BUILTIN_DIR

    for f in ("hopper.gait.toml", "hopper_flight.toml", "hopper_stance.toml"):
        (tmp_path / f).write_text((BUILTIN_DIR / f).read_text())
    proc = symmech("gait", "hopper.gait.toml", "--routes", "c", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "gait hopper:" in proc.stdout
    assert "-0.1576880663" in proc.stdout  # the hopper's multiplier (test_gait.py's gait)
    (tmp_path / "hopper.gait.toml").write_text("format = 1\nname = 'hopper'\n")
    assert_one_line_error(symmech("gait", "hopper.gait.toml", cwd=tmp_path), "modes")


def test_continuation_shows_a_bar_on_a_terminal(tmp_path: Path, monkeypatch, capsys):
    """On a terminal the continuation counts its parameter values with a tqdm bar on
    stderr (the wheel's multiplier eta^2 does not depend on the slope)."""
    import io
    import sys

    from symmech.cli import main

    class Terminal(io.StringIO):
        def isatty(self) -> bool:
            return True

    err = Terminal()
    monkeypatch.setattr(sys, "stderr", err)
    png = tmp_path / "w.png"
    args = ["gait", "rimless_wheel", "--continue", "gamma=0.08:0.1", "--steps", "3"]
    assert main([*args, "--plot", str(png)]) == 0
    assert "continuation in gamma: 100%" in err.getvalue() and "3/3" in err.getvalue()
    out = capsys.readouterr().out
    assert out.count("stable, multipliers [+0.680272") == 3


def test_gait_tables_to_files(tmp_path: Path):
    """--out writes the routes' table (and the continuation's) as CSV that pandas reads
    back with the printed figures."""
    import pandas as pd

    out = tmp_path / "wheel.csv"
    proc = symmech("gait", "rimless_wheel", "--routes", "c,fd", "--out", str(out), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    table = pd.read_csv(out, index_col=0)
    eta = (0.09 + math.cos(math.pi / 5)) / 1.09
    assert list(table.index) == ["c", "fd"]
    assert abs(table.loc["c", "mult0_re"] - eta**2) <= 1e-13
    assert table.loc["fd", "error"] > 1e3 * table.loc["c", "error"]
    cont = tmp_path / "cont.csv"
    args = ["--continue", "gamma=0.08:0.1", "--steps", "3", "--plot", str(tmp_path / "c.png")]
    proc = symmech("gait", "rimless_wheel", *args, "--out", str(cont), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    frame = pd.read_csv(cont, index_col=0)
    assert list(frame.index) == pytest.approx([0.08, 0.09, 0.1])
    assert frame["stable"].all() and (abs(frame["mult0_re"] - eta**2) <= 1e-12).all()
    assert_one_line_error(
        symmech("gait", "rimless_wheel", "--out", "x.xlsx", cwd=tmp_path), "--out 'x.xlsx'"
    )
