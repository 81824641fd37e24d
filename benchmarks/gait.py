"""Issue 29's figures: each built-in gait's fixed point and multipliers by every route.

For the rimless wheel, the simplest walker and the compass gait, prints the table of
``symmech gait NAME`` (C and NumPy variational-saltation routes, forward differences at
their best step, the mpmath reference at 30 digits and its central differences), then a
summary: the C route's error against the reference, forward differences' error and the
ratio of the two (target >= 1000), the cost of the multipliers in C against one stride
(target <= about 3x), and for the published models the distance to the published
figures.  ``--quick`` runs the rimless wheel alone at 20 digits (the CI smoke test).

    python3 benchmarks/gait.py [--quick]
"""

from __future__ import annotations

import argparse
import math
import sys
import warnings

from symmech.gait.evaluation import CompiledGait
from symmech.gait.models import GAITS
from symmech.gait.periodic import fixed_point
from symmech.gait.report import format_figures, solve_routes, stride_costs

#: Published figures: Garcia et al. 1998 (simplest walker, gamma = 0.009, long-period
#: gait, theta and theta' just after heel strike, and their multipliers from finite
#: differences); Goswami et al. 1996 (compass gait at 3 degrees, angles from the vertical:
#: add gamma for the slope's normal).
PUBLISHED = {
    "simplest_walker": {
        "fixed point": {0: 0.20031090049483, 2: -0.19983247291764},
        "multipliers": (complex(-0.19120868949940, 0.55633363687106),),
    },
    "compass_gait": {
        "fixed point": {
            0: 0.2187 + 3 * math.pi / 180,
            1: -0.3234 + 3 * math.pi / 180,
            2: -1.0918,
            3: -0.3772,
        },
    },
}


def figures_of(name: str, digits: int) -> list[float]:
    """The C route's fixed point of a built-in gait."""
    case = GAITS[name]
    (c,) = solve_routes(case.build(), case.parameters, case.guess, ("c",), digits=digits)
    return c.x


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the rimless wheel at 20 digits")
    args = parser.parse_args(argv)
    names = ["rimless_wheel"]
    if not args.quick:
        names += ["simplest_walker", "compass_gait", "hopper"]
    digits = 20 if args.quick else 30
    warnings.simplefilter("ignore")
    summary = []
    for name in names:
        case = GAITS[name]
        gait = case.build()
        figures = {
            f.route: f
            for f in solve_routes(
                gait,
                case.parameters,
                case.guess,
                ("c", "numpy", "fd", "mp", "mp-cd"),
                digits=digits,
                section=case.section,
            )
        }
        print(f"== {name}: {case.description}")
        print(format_figures(list(figures.values())))
        plain, full = stride_costs(
            CompiledGait(gait, case.parameters), figures["c"].x, case.section
        )
        c, fd = figures["c"], figures["fd"]
        line = (
            f"{name:16s} C vs mp {c.error:.2e}  mp-cd vs mp {figures['mp-cd'].error:.2e}"
            f"  forward differences {fd.error:.2e} ({fd.note})"
            f"  accuracy ratio {fd.error / max(c.error, 1e-300):.3g}"
            f"  cost {full / plain:.2f}x one stride ({plain * 1e3:.2f} ms)"
        )
        published = PUBLISHED.get(name)
        if published:
            ref = figures["mp"]
            dx = max(abs(ref.x[i] - v) for i, v in published["fixed point"].items())
            line += f"  fixed point - published {dx:.2e}"
            for m in published.get("multipliers", ()):
                near = min(abs(z - m) for z in ref.multipliers)
                line += f"  multiplier - published {near:.2e}"
        summary.append(line)
    if not args.quick:
        print("== the simplest walker with feet of mass beta against the exact limit")
        limit = figures_of("simplest_walker", digits)
        case = GAITS["simplest_walker_feet"]
        base = CompiledGait(case.build(), case.parameters)
        for beta in (1e-2, 1e-3, 1e-4, 1e-5, 1e-6):
            fns = base.with_parameters({"beta": beta, "gamma": 0.009})
            fp = fixed_point(fns, 0, limit)
            print(
                f"beta {beta:7.0e}  theta* - limit {fp.x[0] - limit[0]:+.3e}"
                f"  theta_dot* - limit {fp.x[2] - limit[2]:+.3e}"
            )
    print("== summary")
    print("\n".join(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
