"""Shared pytest configuration: the golden-file switch and the accuracy report."""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))


def pytest_addoption(parser):
    parser.addoption(
        "--update-golden",
        action="store_true",
        default=False,
        help="rewrite tests/golden/ from the current code generator (prints the diff)",
    )


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    rows = getattr(config, "_symmech_accuracy", None)
    if not rows:
        return
    worst: dict[tuple[str, str], tuple[float, float]] = {}
    for label, ulp, ratio in rows:
        parts = label.split("/")
        key = (parts[2], parts[3].split("[")[0].split("_")[0])
        u0, r0 = worst.get(key, (0.0, 0.0))
        worst[key] = (max(u0, ulp), max(r0, ratio))
    tr = terminalreporter
    tr.section("symmech codegen accuracy (worst over scenes and states)")
    tr.write_line(f"{'route':10} {'function':22} {'worst ulps':>12} {'err/bound':>10}")
    for (route, fn), (ulp, ratio) in sorted(worst.items()):
        tr.write_line(f"{route:10} {fn:22} {ulp:12.1f} {ratio:10.3f}")
    tr.write_line(
        "ulps are relative to the largest entry of each output; err/bound is the error over"
        " its first-order bound (tests accept <= 2)."
    )
