"""The ``symmech`` command line.

``symmech show [SCENE]`` derives and prints a built-in scene's equations: metric, forcing,
Christoffel symbols, constrained equations, each wall's impact map and Carnot residual.
``symmech examples`` lists the built-in scenes.  With no command, ``show`` runs on the
bouncing ellipse of text 001.  Progress goes to stderr (``--quiet`` silences it); errors
exit non-zero with one readable line (``--debug`` shows the traceback).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence

import sympy as sp

from symmech.errors import SymmechError
from symmech.examples import EXAMPLES, example
from symmech.scene import Scene

__all__ = ["main"]

DEFAULT_SCENE = "bouncing_ellipse"


class _Progress:
    def __init__(self, quiet: bool):
        self.quiet = quiet
        self.start = time.perf_counter()

    def __call__(self, stage: str) -> None:
        if not self.quiet:
            print(f"[symmech {time.perf_counter() - self.start:6.2f}s] {stage}", file=sys.stderr)


def _fmt(expr: object, latex: bool) -> str:
    return sp.latex(expr) if latex else sp.pretty(expr, use_unicode=True)


def _show(scene: Scene, latex: bool, progress: _Progress) -> None:
    out = []

    def section(title: str, value: object) -> None:
        out.append(f"== {title}\n{_fmt(value, latex)}\n")

    progress(f"scene {scene.name}: {scene!r}")
    section("coordinates", sp.Matrix(scene.coordinates).T)
    section("velocities", sp.Matrix(scene.velocities).T)
    if scene.frame is not None:
        section("frame S (q_dot = S v)", scene.frame)
    section("mass matrix", scene.mass_matrix())
    progress("forcing")
    section("forcing f (mass matrix * acceleration = f)", scene.forcing())
    if scene.frame is None and scene.n <= 6:
        progress("Christoffel symbols")
        gam = scene.christoffel()
        nonzero = {
            f"Gamma^{scene.coordinates[k]}_{scene.coordinates[i]}{scene.coordinates[j]}": gam[
                k, i, j
            ]
            for k in range(scene.n)
            for i in range(scene.n)
            for j in range(i, scene.n)
            if gam[k, i, j] != 0
        }
        out.append("== Christoffel symbols (non-zero, i <= j)")
        out.extend(f"{name} = {_fmt(val, latex)}" for name, val in nonzero.items())
        out.append("")
    if scene.is_constrained:
        progress("projectors and multipliers")
        section("constraint one-forms mu (rows)", scene.constraint_matrix)
        section("projector P onto D", scene.projectors()[0])
        section("multipliers lambda", scene.multipliers())
    if scene.n <= 6:
        progress("acceleration")
        section("acceleration", scene.acceleration())
    for wall in scene.walls:
        progress(f"impact map of wall {wall.name!r}")
        imp = scene.impact_map(wall.index)
        section(f"wall {wall.name!r}: psi", wall.psi)
        section(f"wall {wall.name!r}: post-impact velocity ({wall.law} law)", imp.post_velocity)
        if wall.law == "newton":
            res = imp.carnot()
            section(f"wall {wall.name!r}: {res.theorem} residual", res.residual)
    print("\n".join(out))


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``symmech`` console script (and ``python -m symmech``)."""
    parser = argparse.ArgumentParser(prog="symmech", description=__doc__.split("\n\n")[0])
    parser.add_argument("--quiet", action="store_true", help="no progress on stderr")
    parser.add_argument("--debug", action="store_true", help="show tracebacks on errors")
    sub = parser.add_subparsers(dest="command")
    show = sub.add_parser("show", help="derive and print a built-in scene's equations")
    show.add_argument("scene", nargs="?", default=DEFAULT_SCENE, help="built-in scene name")
    show.add_argument("--latex", action="store_true", help="print LaTeX instead of text")
    sub.add_parser("examples", help="list the built-in scenes")
    args = parser.parse_args(argv)
    progress = _Progress(args.quiet)
    try:
        if args.command == "examples":
            for name, (_, description) in EXAMPLES.items():
                print(f"{name:22s} {description}")
            return 0
        name = getattr(args, "scene", DEFAULT_SCENE)
        progress(f"building scene {name}")
        _show(example(name), getattr(args, "latex", False), progress)
        progress("done")
        return 0
    except SymmechError as exc:
        if args.debug:
            raise
        first = str(exc).splitlines()
        print(f"symmech: error: {' '.join(s.strip() for s in first)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("symmech: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
