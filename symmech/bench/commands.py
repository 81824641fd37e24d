"""The ``symmech bench`` and ``symmech stress`` commands (``symmech simulate`` is
:mod:`symmech.bench.simulate_command`).

``symmech bench SCENE [--tolerances ...] [--routes ...] [--plot FILE]``
    The work-precision table of a built-in case (:mod:`symmech.bench.work_precision`).
``symmech stress [-k CASE] [--backend B]``
    The stiff and extreme cases (:mod:`symmech.bench.stress`); exit code 1 if one fails.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

from symmech.bench import stress as stress_cases
from symmech.bench import work_precision as wp
from symmech.bench.cases import CASES
from symmech.codegen.escape import terminal
from symmech.errors import SymmechError
from symmech.simulate.arguments import numbers

__all__ = ["COMMANDS", "add_commands", "print_line", "run_command"]

COMMANDS = ("bench", "stress")


def print_line(text: str) -> None:
    """Print a line of output with every non-printable character escaped (scene and wall
    names reach it)."""
    print(terminal(text))


_print = print_line


def add_commands(sub: Any, common: argparse.ArgumentParser) -> None:
    """Register ``bench`` and ``stress`` on the ``symmech`` sub-parsers."""
    bench = sub.add_parser("bench", parents=[common], help="error against run time")
    bench.add_argument("scene", choices=sorted(CASES), help="a built-in simulation case")
    bench.add_argument("--tolerances", default="1e-3,1e-6,1e-9,1e-12")
    bench.add_argument(
        "--routes",
        default=",".join(f"{b}:{m}" for b, m in wp.ROUTES),
        help="backend:method pairs, comma separated",
    )
    bench.add_argument("--repeats", type=int, default=3)
    bench.add_argument("--no-baseline", action="store_true", help="skip solve_ivp + lambdify")
    bench.add_argument("--plot", help="write the log-log plot to this PNG file")

    st = sub.add_parser("stress", parents=[common], help="stiff and extreme cases")
    st.add_argument("-k", dest="cases", action="append", choices=sorted(stress_cases.CASES))
    st.add_argument("--backend", default="c", choices=("c", "numpy", "scipy"))


def _bench(args: argparse.Namespace, say: Callable) -> int:
    case = CASES[args.scene]
    routes = [tuple(r.split(":", 1)) for r in args.routes.split(",") if r]
    if any(len(r) != 2 for r in routes):
        raise SymmechError(f"--routes: expected backend:method pairs, got {args.routes!r}")
    tolerances = numbers(args.tolerances, "--tolerances")
    if args.repeats < 1:
        raise SymmechError(f"--repeats: expected a number >= 1, got {args.repeats}")
    if args.plot:
        wp.check_plot_path(args.plot)
    say(f"reference for {case.scene_name}")
    ref, table = wp.rows(
        case,
        routes=routes,
        tolerances=tolerances,
        repeats=args.repeats,
        baseline=not args.no_baseline,
    )
    _print(wp.format_table(case, ref, table))
    if args.plot:
        wp.plot(case, table, args.plot)
        _print(f"plot: {args.plot}")
    return 0


def _stress(args: argparse.Namespace, say: Callable) -> int:
    say(f"stress cases on backend {args.backend}")
    results = stress_cases.run_all(args.backend, args.cases)
    _print(stress_cases.format_table(results))
    return 0 if all(r.passed for r in results) else 1


def run_command(
    args: argparse.Namespace, load: Callable[[str], Any], say: Callable[[str], None]
) -> int:
    """Run ``args.command`` (one of :data:`COMMANDS`); ``say`` reports progress."""
    del load
    if args.command == "bench":
        return _bench(args, say)
    return _stress(args, say)
