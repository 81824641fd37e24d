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
    from test_codegen_numerics import ULPS_BOUND

    worst: dict[tuple[str, str], tuple[float, float, float]] = {}
    for label, kind, ulp, ratio, bound in rows:
        key = (label.split("/")[2], kind)
        u0, r0, b0 = worst.get(key, (0.0, 0.0, 0.0))
        worst[key] = (max(u0, ulp), max(r0, ratio), max(b0, bound))
    tr = terminalreporter
    tr.section("symmech codegen accuracy (worst over scenes and states)")
    tr.write_line(
        f"{'route':9} {'kind':20} {'worst ulps':>10} {'2 x bound':>10} {'ulps cap':>8}"
        f" {'err/bound':>9}"
    )
    for (route, kind), (ulp, ratio, bound) in sorted(worst.items()):
        tr.write_line(
            f"{route:9} {kind:20} {ulp:10.1f} {bound:10.1f} {ULPS_BOUND[kind]:8d} {ratio:9.3f}"
        )
    tr.write_line(
        "ulps of the largest entry of each output; '2 x bound' is the first-order bound the"
        " test accepts, in the same ulps; tests assert err <= 2 x bound and ulps <= cap."
    )
