"""The ``symmech simulate``, ``symmech bench`` and ``symmech stress`` commands.

``symmech simulate SCENE [--q0 ...] [--v0 ...] [--t-end T] [--param NAME=VALUE ...]
[--define NAME=EXPR ...]``
    Run the scene (a built-in name or a scene file) with :func:`symmech.simulate` and print
    its status, statistics, events and final state.  A built-in scene with a simulation
    case (:mod:`symmech.bench.cases`) needs no state; otherwise ``--q0``, ``--v0`` and
    ``--t-end`` are required.  Parameters default to the scene file's values.  ``--define``
    gives a function of time of the scene (a run-time input, a moving wall's position) an
    expression in t and the parameters for the run (parsed safely: ``definitions=``).
``symmech bench SCENE [--tolerances ...] [--routes ...] [--plot FILE]``
    The work-precision table of a built-in case (:mod:`symmech.bench.work_precision`).
``symmech stress [-k CASE] [--backend B]``
    The stiff and extreme cases (:mod:`symmech.bench.stress`); exit code 1 if one fails.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

import numpy as np

from symmech.bench import stress as stress_cases
from symmech.bench import work_precision as wp
from symmech.bench.cases import CASES
from symmech.codegen.escape import terminal
from symmech.errors import SymmechError
from symmech.simulate.arguments import numbers
from symmech.simulate.hybrid import MAX_STEPS

__all__ = ["COMMANDS", "add_commands", "run_command"]

COMMANDS = ("simulate", "bench", "stress")


def _print(text: str) -> None:
    """Print a line of output with every non-printable character escaped (scene and wall
    names reach it)."""
    print(terminal(text))


def add_commands(sub: Any, common: argparse.ArgumentParser) -> None:
    """Register the three commands on the ``symmech`` sub-parsers."""
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
    sim.add_argument("--contact", default="persistent", choices=("persistent", "stop"))
    sim.add_argument("--max-events", type=int, default=100_000)
    sim.add_argument("--max-steps", type=int, default=MAX_STEPS, help="steps of the run")
    sim.add_argument("--events", type=int, default=20, help="events to print (default 20)")

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


def _simulate(args: argparse.Namespace, load: Callable[[str], Any], say: Callable) -> int:
    import symmech.simulate as simulate_pkg

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
    for item in args.param:
        name, sep, value = item.partition("=")
        if not sep:
            raise SymmechError(f"--param: expected NAME=VALUE, got {item!r}")
        params[name.strip()] = numbers(value, f"--param {name}")[0]
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
    return 0 if res.success else 1


def _bench(args: argparse.Namespace, say: Callable) -> int:
    case = CASES[args.scene]
    routes = [tuple(r.split(":", 1)) for r in args.routes.split(",") if r]
    if any(len(r) != 2 for r in routes):
        raise SymmechError(f"--routes: expected backend:method pairs, got {args.routes!r}")
    tolerances = numbers(args.tolerances, "--tolerances")
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
    """Run ``args.command`` (one of :data:`COMMANDS`); ``load`` reads a scene file or
    built-in name into a :class:`~symmech.scenefile.SceneFile`, ``say`` reports progress."""
    if args.command == "simulate":
        return _simulate(args, load, say)
    if args.command == "bench":
        return _bench(args, say)
    return _stress(args, say)
