"""Shared pytest configuration: the golden-file switch and the accuracy report."""

from __future__ import annotations

import difflib
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))

#: The committed generated files (tests/golden/<case>/<file>).
GOLDEN = Path(__file__).parent / "golden"


def pytest_addoption(parser):
    parser.addoption(
        "--update-golden",
        action="store_true",
        default=False,
        help="rewrite tests/golden/ from the current code generator (prints the diff)",
    )


def _diff(old: str, new: str, path: Path) -> str:
    name = str(path.relative_to(GOLDEN.parent))
    return "".join(
        difflib.unified_diff(
            old.splitlines(keepends=True), new.splitlines(keepends=True), f"a/{name}", f"b/{name}"
        )
    )


@pytest.fixture
def golden(request, capsys):
    """``golden(case, filename, text)``: ``text`` must equal tests/golden/<case>/<filename>;
    with ``pytest --update-golden`` the file is rewritten instead and the diff printed.
    The one implementation of the switch for every golden test."""

    def check(case: str, filename: str, text: str) -> None:
        path = GOLDEN / case / filename
        old = path.read_text(encoding="utf-8") if path.is_file() else ""
        if request.config.getoption("--update-golden"):
            if old != text:
                with capsys.disabled():
                    print(_diff(old, text, path))
                path.parent.mkdir(parents=True, exist_ok=True)
                path.write_text(text, encoding="utf-8")
            return
        assert path.is_file(), f"{path} is missing; run pytest --update-golden"
        if old != text:
            diff = "".join(_diff(old, text, path).splitlines(keepends=True)[:80])
            why = f"{filename} differs from its golden file (pytest --update-golden)"
            pytest.fail(f"{why}:\n{diff}")

    return check


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
