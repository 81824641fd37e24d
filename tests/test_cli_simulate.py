"""``symmech simulate``, ``symmech bench`` and ``symmech stress`` from the command line."""

from __future__ import annotations

import math
import re
from pathlib import Path

from test_cli import assert_one_line_error, symmech


def test_simulate_a_builtin_case_prints_status_events_and_final_state(tmp_path: Path):
    proc = symmech("simulate", "bouncing_ball", "--quiet", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "status: finished: reached t_end = 1.3" in proc.stdout
    times = [float(t) for t in re.findall(r"impact at t=([0-9.e-]+)", proc.stdout)]
    exact = [math.sqrt(2 / 9.81) * (1 + 2 * sum(0.5**j for j in range(1, k + 1))) for k in range(5)]
    assert len(times) == 5
    assert max(abs(a - b) for a, b in zip(times, exact, strict=True)) < 1e-12


def test_simulate_stops_at_the_accumulation_with_contact_stop(tmp_path: Path):
    proc = symmech(
        "simulate",
        "bouncing_ball",
        "--t-end",
        "3",
        "--contact",
        "stop",
        "--backend",
        "scipy",
        "--quiet",
        cwd=tmp_path,
    )
    assert proc.returncode == 0, proc.stderr
    assert "status: zeno" in proc.stdout
    (t_star,) = re.findall(r"accumulation time: ([0-9.e-]+)", proc.stdout)
    assert abs(float(t_star) - math.sqrt(2 / 9.81) * 3) < 1e-9


def test_simulate_a_scene_file_with_state_and_parameters(tmp_path: Path):
    scene = tmp_path / "drop.toml"
    scene.write_text(
        'coordinates = ["y"]\nmetric = ["m"]\npotential = "m*g*y"\n'
        "[parameters]\nm = 1\ng = 9.81\n"
        '[[walls]]\npsi = "y"\nrestitution = 1\n',
        encoding="utf-8",
    )
    proc = symmech(
        "simulate",
        str(scene),
        "--q0",
        "2",
        "--v0",
        "0",
        "--t-end",
        "0.5",
        "--param",
        "g=2",
        "--backend",
        "numpy",
        "--quiet",
        cwd=tmp_path,
    )
    assert proc.returncode == 0, proc.stderr
    (q,) = re.findall(r"q = \[([^\]]+)\]", proc.stdout)
    assert abs(float(q) - (2 - 2 * 0.5**2 / 2)) < 1e-14


def test_simulate_without_a_state_for_a_scene_without_a_case_is_refused(tmp_path: Path):
    proc = symmech("simulate", "car", cwd=tmp_path)
    assert_one_line_error(proc, "give --q0, --v0 and --t-end")


def test_simulate_bad_state_is_a_one_line_error(tmp_path: Path):
    proc = symmech("simulate", "bouncing_ball", "--q0", "-1", cwd=tmp_path)
    assert_one_line_error(proc, "wrong side of wall 'floor'")


def test_stress_runs_a_case_and_reports_pass(tmp_path: Path):
    proc = symmech("stress", "-k", "cradle", "--backend", "scipy", "--quiet", cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "| Newton's cradle | 5 balls, zero gaps |" in proc.stdout
    assert "| pass |" in proc.stdout and "FAIL" not in proc.stdout


def test_bench_prints_the_table_and_writes_the_plot(tmp_path: Path):
    plot = tmp_path / "wp.png"
    proc = symmech(
        "bench",
        "bouncing_ball",
        "--routes",
        "scipy:DOP853",
        "--tolerances",
        "1e-4,1e-8",
        "--repeats",
        "1",
        "--plot",
        str(plot),
        "--quiet",
        cwd=tmp_path,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    rows = [line for line in proc.stdout.splitlines() if line.startswith("| scipy | DOP853")]
    assert len(rows) == 2
    baseline = [line for line in proc.stdout.splitlines() if line.startswith("| baseline")]
    assert len(baseline) == 2
    assert plot.is_file() and plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_sweep_from_the_command_line_writes_the_table(tmp_path: Path):
    grid = tmp_path / "grid.csv"
    grid.write_text("alpha,y0\n0.25,1.0\n0.5,1.0\n0.5,2.0\n", encoding="utf-8")
    out = tmp_path / "table.csv"
    proc = symmech(
        "sweep",
        "bouncing_ball",
        "--grid",
        str(grid),
        "--out",
        str(out),
        "--t-end",
        "10",
        "--v0",
        "0",
        "--contact",
        "stop",
        "--no-progress",
        "--quiet",
        cwd=tmp_path,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    import csv

    rows = list(csv.DictReader(out.open(encoding="utf-8")))
    assert [r["status"] for r in rows] == ["zeno"] * 3
    for r in rows:
        a, h = float(r["alpha"]), float(r["y0"])
        exact = math.sqrt(2 * h / 9.81) * (1 + a) / (1 - a)
        assert abs(float(r["time_to_rest"]) - exact) < 1e-9 * exact


def test_simulate_max_steps_bounds_the_run(tmp_path: Path):
    proc = symmech("simulate", "bouncing_ball", "--max-steps", "3", "--quiet", cwd=tmp_path)
    assert proc.returncode == 1, proc.stderr  # the run did not reach t_end
    assert re.search(r"status: max_steps: stopped after 3 steps at t = 0\.\d+", proc.stdout)


FORCED = """format = 1
name = "forced_spring"
coordinates = ["x"]
metric = ["m"]
potential = "k*x**2/2"
forces = ["-c*xdot + tau"]

[parameters]
m = 1
k = 4
c = 0.1

[inputs]
tau = { description = "motor" }

[[walls]]
name = "stop"
psi = "x + 1"
restitution = 0.5
"""


def test_simulate_defines_a_run_time_input(tmp_path: Path):
    """--define tau=sin(3*t): x'' = -4 x - 0.1 x' + sin(3 t) from (0.5, 0), the wall never
    reached; the final state against scipy's solve_ivp at 1e-12."""
    from scipy.integrate import solve_ivp

    (tmp_path / "forced.toml").write_text(FORCED, encoding="utf-8")
    args = ["simulate", "forced.toml", "--q0", "0.5", "--v0", "0", "--t-end", "2"]
    proc = symmech(*args, "--define", "tau=sin(3*t)", "--rtol", "1e-11", "--quiet", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "status: finished" in proc.stdout and "events: 0" in proc.stdout
    q = float(re.search(r"^q = \[(\S+)\]", proc.stdout, re.M).group(1))
    v = float(re.search(r"^v = \[(\S+)\]", proc.stdout, re.M).group(1))
    ref = solve_ivp(
        lambda t, y: [y[1], -4 * y[0] - 0.1 * y[1] + math.sin(3 * t)],
        (0, 2),
        [0.5, 0.0],
        rtol=1e-12,
        atol=1e-14,
        method="DOP853",
    )
    assert abs(q - ref.y[0, -1]) < 1e-9 and abs(v - ref.y[1, -1]) < 1e-9
    missing = symmech(*args, "--quiet", cwd=tmp_path)
    assert missing.returncode != 0 and "--define f=EXPR" in missing.stderr
    hostile = symmech(*args, "--define", "tau=__import__('os')", "--quiet", cwd=tmp_path)
    assert hostile.returncode != 0 and "is not allowed" in hostile.stderr


def test_simulate_chooses_the_impact_law(tmp_path: Path):
    """The rod dropped flat: both ends together by default (no spin, the final state of a
    rod lying flat), one at a time with --impact-law sequential (it spins)."""
    common = ("simulate", "falling_rod", "--q0", "0,1,0", "--v0", "0,0,0", "--quiet")
    flat = symmech(*common, "--t-end", "3", cwd=tmp_path)
    assert flat.returncode == 0, flat.stderr
    assert "status: finished" in flat.stdout
    (v_final,) = re.findall(r"^v = \[(.*)\]$", flat.stdout, re.M)
    assert all(abs(float(x)) < 1e-9 for x in v_final.split())
    spun = symmech(*common, "--t-end", "0.46", "--impact-law", "sequential", cwd=tmp_path)
    assert spun.returncode == 0, spun.stderr
    (v_spun,) = re.findall(r"^v = \[(.*)\]$", spun.stdout, re.M)
    assert abs(float(v_spun.split()[2])) > 0.1
    bad = symmech(*common, "--t-end", "1", "--impact-law", "random", cwd=tmp_path)
    assert bad.returncode != 0 and "invalid choice" in bad.stderr
