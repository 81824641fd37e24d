"""Error against run time of the hybrid simulator (see symmech.bench.work_precision).

For the bouncing ball (alpha 0.5, closed-form reference), the text-001 ellipse with
gravity, the Carnot 3.7 disc with gravity and the rolling sphere of Carnot 3.13 (mpmath
references, 24 digits): every backend and method at tolerances 1e-3 .. 1e-12, and the
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
    "carnot_3_13",
)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", default="benchmarks/out")
    ap.add_argument("--routes", default=",".join(f"{b}:{m}" for b, m in wp.ROUTES))
    args = ap.parse_args(argv)
    routes = [tuple(r.split(":")) for r in args.routes.split(",")]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for name in args.scenes.split(","):
        case = CASES[name]
        clock = time.perf_counter()
        ref, table = wp.rows(case, routes=routes, repeats=args.repeats)  # type: ignore[arg-type]
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
        if best:
            err = min(r.final_error for r in best)
            fast = [r for r in table if r.route == "c" and r.final_error <= err]
            if fast:
                c = min(fast, key=lambda r: r.seconds)
                b = min(
                    (r for r in best if r.final_error <= max(err, c.final_error)),
                    key=lambda r: r.seconds,
                )
                print(
                    f"\nat equal error ({err:.1e}): baseline {b.seconds:.2e} s, C"
                    f" {c.seconds:.2e} s: {b.seconds / c.seconds:.0f}x"
                )
        else:
            print(
                "\nthe baseline reaches t_end at no tolerance: no equal-error comparison;"
                " the table shows its status"
            )
        png = out / f"work_precision_{name}.png"
        wp.plot(case, table, str(png))
        print(f"\nplot: {png} ({time.perf_counter() - clock:.0f} s)\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
