"""Every script in benchmarks/ runs to the end at its smallest size, so that none can rot
unnoticed (issue 27: ``benchmarks/codegen.py`` crashed at the 4-link pendulum once the
closed form was refused by its budget).  Each is run with ``--quick`` in a subprocess
and must exit with status 0 and print the last line of its report; the figures are
not checked here (benchmarks print ratios, tests check correctness)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from codegen_support import require_c_compiler

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"

#: script -> (its extra arguments besides --quick, a line its report ends with)
SCRIPTS: dict[str, tuple[tuple[str, ...], str]] = {
    "codegen.py": ((), "total run time:"),
    "contacts.py": ((), "| two-wall contact (enter, settle) |"),
    "derive.py": ((), "Kane/sm >= 20 at n = 8 and 16 for both forms of T"),
    "gait.py": ((), "rimless_wheel    C vs mp"),
    "hostile_checks.py": ((), "ratio"),
    "impacts.py": ((), "3-link cart, tip wall"),
    "mechanics.py": ((), "symmech all functions: the same"),
    "mechanics_roundtrip.py": ((), "total run time:"),
    "steppers.py": ((), "(rodas4 / BDF time:"),
    "stress.py": ((), " 0 failed"),
    "sweep.py": ((), "Dask worker RSS"),
    "work_precision.py": (("--out", "{tmp}"), "plot:"),
}


def test_every_benchmark_script_is_smoke_tested():
    assert {p.name for p in BENCHMARKS.glob("*.py")} == set(SCRIPTS)


@pytest.mark.parametrize("script", sorted(SCRIPTS))
def test_the_script_runs_to_the_end(script, tmp_path):
    require_c_compiler()
    extra, last = SCRIPTS[script]
    if script == "hostile_checks.py":
        known = subprocess.run(
            ["git", "cat-file", "-e", "e785862^{commit}"], cwd=BENCHMARKS, capture_output=True
        )
        if known.returncode != 0:
            pytest.skip("hostile_checks.py compares against revision e785862: not in this clone")
    args = [a.replace("{tmp}", str(tmp_path)) for a in extra]
    proc = subprocess.run(
        [sys.executable, str(BENCHMARKS / script), "--quick", *args],
        cwd=BENCHMARKS.parent,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, f"{script} --quick failed:\n{proc.stderr[-3000:]}"
    assert last in proc.stdout, f"{script} --quick stopped early:\n{proc.stdout[-3000:]}"
