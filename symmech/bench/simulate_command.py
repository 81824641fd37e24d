"""The ``symmech simulate`` command.

``symmech simulate SCENE [--q0 ...] [--v0 ...] [--t-end T] [--param NAME=VALUE ...] ...``
    (and ``[--define NAME=EXPR ...] [--impact-law LAW]``, the files below).  Run the scene
    (a built-in name or a scene file) with :func:`symmech.simulate` and print its status,
    statistics, events and final state.  A built-in scene with a simulation case
    (:mod:`symmech.bench.cases`) needs no state; otherwise ``--q0``, ``--v0`` and
    ``--t-end`` are required.  Parameters default to the scene file's values.  ``--define``
    gives a function of time of the scene (a run-time input, a moving wall's position) an
    expression in t and the parameters for the run (parsed safely: ``definitions=``).  The
    run options are those of :class:`symmech.simulate.options.RunOptions`.

    Files (:func:`add_file_options`): ``--out run.csv`` (or ``.parquet``, ``.npz``) saves the
    run (:meth:`~symmech.simulate.result.SimulationResult.save`), ``--plot run.png`` its plot
    (:func:`symmech.simulate.plotting.plot`), ``--animate run.gif`` (or ``.html``) its
    animation at real time times ``--speed``, ``--fps`` frames a second
    (:mod:`symmech.simulate.animation`).  Each path written is printed.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from symmech.bench.cases import CASES
from symmech.bench.commands import print_line
from symmech.codegen.escape import terminal
from symmech.errors import SymmechError, SymmechWarning
from symmech.simulate.arguments import numbers, parameter_values
from symmech.simulate.hybrid import MAX_STEPS
from symmech.simulate.options import CONTACT_MODES, IMPACT_LAWS

__all__ = ["add_command", "run_command"]

_print = print_line


def _count(text: str) -> int:
    """A non-negative whole number for argparse (a negative one is refused, exit 2)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {value}")
    return value


def add_command(sub: Any, common: argparse.ArgumentParser) -> None:
    """Register ``simulate`` on the ``symmech`` sub-parsers."""
    sim = sub.add_parser("simulate", parents=[common], help="simulate a scene with walls")
    sim.add_argument("scene", help="scene file or built-in name")
    sim.add_argument("--q0", help="initial coordinates, comma separated")
    sim.add_argument("--v0", help="initial velocities, comma separated")
    sim.add_argument("--t-end", type=float, help="final time")
    sim.add_argument(
        "--param", action="append", default=[], metavar="NAME=VALUE", help="a parameter value"
    )
    sim.add_argument(
        "--define",
        action="append",
        default=[],
        metavar="NAME=EXPR",
        help="an expression in t and the parameters for a function of time (an input)",
    )
    sim.add_argument("--backend", default="c", choices=("c", "numpy", "scipy"))
    sim.add_argument("--method", default="dop853")
    sim.add_argument("--rtol", type=float, default=1e-8)
    sim.add_argument("--atol", type=float, default=1e-10)
    sim.add_argument("--contact", default="persistent", choices=CONTACT_MODES)
    sim.add_argument("--max-events", type=int, default=100_000)
    sim.add_argument("--max-steps", type=int, default=MAX_STEPS, help="steps of the run")
    sim.add_argument(
        "--events", type=_count, default=20, help="events to print (default 20; 0: none)"
    )

    sim.add_argument(
        "--impact-law",
        default="simultaneous",
        choices=IMPACT_LAWS,
        help="walls struck at one instant: together (default) or one at a time",
    )
    add_file_options(sim)


def _positive(text: str) -> float:
    """A positive finite number for argparse."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (np.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}")
    return value


def add_file_options(parser: argparse.ArgumentParser) -> None:
    """``--out``, ``--plot``, ``--animate``, ``--speed``, ``--fps`` (module docstring)."""
    files = parser.add_argument_group("files")
    files.add_argument("--out", metavar="FILE", help="save the run: .csv, .parquet or .npz")
    files.add_argument("--plot", metavar="FILE", help="plot the run: .png, .svg or .pdf")
    files.add_argument("--animate", metavar="FILE", help="animate the run: .gif or .html")
    files.add_argument(
        "--speed", type=_positive, default=1.0, help="animation speed (1: real time)"
    )
    files.add_argument("--fps", type=_positive, default=25.0, help="animation frames a second")


def check_file_options(args: argparse.Namespace) -> None:
    """Refuse an unknown file type before the run (a long run is not lost to a typo)."""
    from symmech.simulate.animation import ANIMATION_FORMATS
    from symmech.simulate.plotting import IMAGE_FORMATS
    from symmech.simulate.table import FORMATS

    for option, path, kinds in (
        ("--out", args.out, FORMATS),
        ("--plot", args.plot, IMAGE_FORMATS),
        ("--animate", args.animate, ANIMATION_FORMATS),
    ):
        if path and Path(path).suffix.lower() not in kinds:
            raise SymmechError(
                f"{option} {path}: unknown file type {Path(path).suffix or '(none)'!r};"
                f" expected one of {', '.join(kinds)}"
            )


def write_files(args: argparse.Namespace, res: Any, say: Callable) -> None:
    """Write the files that ``--out``, ``--plot`` and ``--animate`` ask for."""
    if args.out:
        say(f"saving the run to {args.out}")
        _print(f"saved: {res.save(args.out)}")
    if args.plot:
        say(f"plotting to {args.plot}")
        from symmech.simulate.plotting import save_figure

        _print(f"plot: {save_figure(res.plot(), args.plot)}")
    if args.animate:
        import warnings

        from symmech.simulate.animation import save_animation

        say(f"animating to {args.animate} (speed {args.speed:g}, {args.fps:g} frames/s)")
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", SymmechWarning)
            anim = res.animate(fps=args.fps, speed=args.speed)
        for w in caught:  # said even with --quiet: the animation is not what was asked
            print(f"symmech: warning: {terminal(str(w.message))}", file=sys.stderr)
        _print(f"animation: {save_animation(anim, args.animate, fps=args.fps)}")


def run_command(args: argparse.Namespace, load: Callable[[str], Any], say: Callable) -> int:
    """Run ``symmech simulate`` (see the module docstring); ``load`` reads a scene file or
    built-in name into a :class:`~symmech.scenefile.SceneFile`, ``say`` reports progress."""
    return _simulate(args, load, say)


def _simulate(args: argparse.Namespace, load: Callable[[str], Any], say: Callable) -> int:
    import symmech.simulate as simulate_pkg

    check_file_options(args)
    sf = load(args.scene)
    scene = sf.scene
    params = {str(k): float(v) for k, v in sf.defaults.items()}
    case = CASES.get(scene.name)
    q0 = numbers(args.q0, "--q0") if args.q0 else (list(case.q0) if case else None)
    v0 = numbers(args.v0, "--v0") if args.v0 else (list(case.v0) if case else None)
    t_end = args.t_end if args.t_end is not None else (case.t_end if case else None)
    if q0 is None or v0 is None or t_end is None:
        raise SymmechError(
            f"scene {scene.name!r} has no built-in simulation case: give --q0, --v0 and --t-end"
        )
    if case is not None:
        params.update(case.overrides)
    params.update(parameter_values(args.param))
    definitions: dict[str, str] = {}
    for item in args.define:
        name, sep, text = item.partition("=")
        if not sep or not name.strip():
            raise SymmechError(f"--define: expected NAME=EXPR, got {item!r}")
        definitions[name.strip()] = text
    say(f"simulating {scene.name} to t = {t_end} ({args.backend}, {args.method})")
    res = simulate_pkg.simulate(
        scene,
        q0,
        v0,
        t_end,
        params=params,
        backend=args.backend,
        method=args.method,
        rtol=args.rtol,
        atol=args.atol,
        contact=args.contact,
        max_events=args.max_events,
        max_steps=args.max_steps,
        impact_law=args.impact_law,
        definitions=definitions or None,
    )
    _print(f"status: {res.status}: {res.message}")
    if res.accumulation_time is not None:
        _print(f"accumulation time: {float(res.accumulation_time)!r}")
    for key, value in res.stats.items():
        _print(f"{key}: {value}")
    _print(f"events: {len(res.events)}")
    for e in res.events[: args.events]:
        _print(f"  {e!r}")
    if len(res.events) > args.events:
        _print(f"  ... {len(res.events) - args.events} more")
    with np.printoptions(precision=17):
        _print(f"t = {float(res.t[-1])!r}")
        _print(f"q = {np.asarray(res.q[-1], dtype=float)}")
        _print(f"v = {np.asarray(res.v[-1], dtype=float)}")
    write_files(args, res, say)
    return 0 if res.success else 1
