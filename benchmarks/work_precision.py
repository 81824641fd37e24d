"""Error against run time of the hybrid simulator (see symmech.bench.work_precision).

For the bouncing ball (alpha 0.5, closed-form reference), the text-001 ellipse with
gravity, the Carnot 3.7 disc with gravity (each whole, and over its first impacts, before
the accumulation that the baseline cannot pass) and the rolling sphere of Carnot 3.13
(mpmath references, 24 digits): every backend and method at tolerances 1e-3 .. 1e-12, and the
baseline a user writes today (solve_ivp + lambdify + terminal event), in one run.  Prints
one Markdown table per scene, the C backend's speed-up over the baseline at each
tolerance, and writes log-log plots of error against run time as PNG.

    python3 benchmarks/work_precision.py [--scenes a,b] [--repeats 3] [--out benchmarks/out]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

from symmech.bench import work_precision as wp
from symmech.bench.cases import CASES

SCENES = (
    "bouncing_ball",
    "ellipse_gravity",
    "ellipse_gravity_flight",
    "disk_3_7_gravity",
    "disk_3_7_gravity_flight",
    "carnot_3_13",
)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", default="benchmarks/out")
    ap.add_argument("--routes", default=",".join(f"{b}:{m}" for b, m in wp.ROUTES))
    ap.add_argument(
        "--tolerances", default=",".join(f"{t:g}" for t in wp.TOLERANCES), help="rtol values"
    )
    ap.add_argument(
        "--quick",
        action="store_true",
        help="a smoke test: the bouncing ball at rtol 1e-6, one timed run per row",
    )
    args = ap.parse_args(argv)
    if args.quick:
        args.scenes, args.repeats, args.tolerances = "bouncing_ball", 1, "1e-6"
        wp.MIN_SECONDS = 0.0
    tolerances = [float(t) for t in args.tolerances.split(",")]
    routes = [tuple(r.split(":")) for r in args.routes.split(",")]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for name in args.scenes.split(","):
        case = CASES[name]
        clock = time.perf_counter()
        ref, table = wp.rows(
            case,
            routes=routes,  # type: ignore[arg-type]
            tolerances=tolerances,
            repeats=args.repeats,
        )
        print(wp.format_table(case, ref, table))
        base = {r.rtol: r for r in table if r.route == "baseline"}
        print()
        print("| rtol | C dop853 time | baseline time | baseline / C | C error | baseline error |")
        print("|---|---|---|---|---|---|")
        for r in table:
            if (r.route, r.method) == ("c", "dop853") and r.rtol in base:
                b = base[r.rtol]
                print(
                    f"| {r.rtol:.0e} | {r.seconds:.2e} | {b.seconds:.2e} |"
                    f" {b.seconds / r.seconds:.1f} | {r.final_error:.1e} |"
                    f" {b.final_error:.1e} ({b.status}) |"
                )
        best = [r for r in table if r.route == "baseline" and math.isfinite(r.final_error)]
        crossed = [r for r in best if r.min_gap < -1e-9]
        if crossed:
            print(
                "\nnote: the baseline's finished runs at rtol"
                f" {', '.join(f'{r.rtol:.0e}' for r in crossed)} crossed the wall (their error"
                " is the tunnelling's); the equal-error figures below compare against them"
            )
        if best:
            for route in dict.fromkeys(r.route for r in table if r.route != "baseline"):
                _equal_error(table, best, route)
        else:
            print(
                "\nthe baseline reaches t_end at no tolerance: no equal-error comparison;"
                " the table shows its status"
            )
        png = out / f"work_precision_{name}.png"
        wp.plot(case, table, str(png))
        print(f"\nplot: {png} ({time.perf_counter() - clock:.0f} s)\n")
    return 0


def _equal_error(table: list, best: list, route: str = "c") -> None:
    """Print the speed-up of the backend ``route`` (any of its methods) over the baseline
    at equal error, three ways (below, "C" stands for the backend).

    * strict: the cheapest C run (any method, any tolerance) whose error is at most the
      baseline's smallest error, against the cheapest baseline run as accurate as that C run;
    * along the curve: for every baseline run, the cheapest C run at least as accurate;
      the smallest and largest of these ratios;
    * at the floor: when every run of both is below FLOOR (1e-12 in a state of order one:
      a few thousand ulps, where the error is the rounding of the arithmetic and differs
      between runs by luck), the cheapest run of each.
    """
    c_runs = [r for r in table if r.route == route and math.isfinite(r.final_error)]
    if not c_runs:
        print(f"\n{route}: no run reaches t_end; no equal-error comparison")
        return
    print(f"\n{route} backend against the baseline (> 1: the backend is faster):")
    err = min(r.final_error for r in best)
    fast = [r for r in c_runs if r.final_error <= err]
    if fast:
        c = min(fast, key=lambda r: r.seconds)
        b = min(
            (r for r in best if r.final_error <= max(err, c.final_error)), key=lambda r: r.seconds
        )
        print(
            f"at equal error, strict ({err:.1e}): baseline {b.seconds:.2e} s,"
            f" {route} {c.seconds:.2e} s ({c.method}, rtol {c.rtol:.0e}):"
            f" {b.seconds / c.seconds:.2f}x"
        )
    else:
        print(f"at equal error, strict ({err:.1e}): no {route} run is as accurate")
    ratios = []
    for b in best:
        ok = [r for r in c_runs if r.final_error <= b.final_error]
        if ok:
            ratios.append(b.seconds / min(ok, key=lambda r: r.seconds).seconds)
    if ratios:
        print(
            f"along the curve (each baseline run against the cheapest {route} run at least as"
            f" accurate): {min(ratios):.2f}x to {max(ratios):.2f}x"
        )
    if c_runs and all(r.final_error < FLOOR for r in [*best, *c_runs]):
        b = min(best, key=lambda r: r.seconds)
        c = min(c_runs, key=lambda r: r.seconds)
        print(
            f"at the floor (every error of both below {FLOOR:.0e}): baseline {b.seconds:.2e} s,"
            f" {route} {c.seconds:.2e} s ({c.method}, rtol {c.rtol:.0e}):"
            f" {b.seconds / c.seconds:.2f}x"
        )


#: errors below this, in a state of order one, are the arithmetic's rounding
FLOOR = 1e-12


if __name__ == "__main__":
    sys.exit(main())
