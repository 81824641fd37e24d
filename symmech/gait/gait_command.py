"""``symmech gait NAME``: a built-in gait's fixed point and multipliers by each route.

``symmech gait NAME|FILE [--param k=v ...] [--routes c,numpy,fd,mp,mp-cd] [--digits 30]
[--out FILE]``
prints the table of :func:`symmech.gait.report.solve_routes` (fixed point, multipliers,
error against the mpmath reference, seconds) and the cost of the multipliers in C against
one stride.  ``--continue gamma=a:b [--steps N] [--plot FILE]`` follows the gait from
``a`` to ``b`` (natural continuation, :func:`symmech.gait.periodic.continuation`), prints
each fixed point's multipliers and writes a PNG of their moduli and real parts (default
``NAME_continuation.png``), with the parameter intervals where a multiplier crosses -1
(period doubling) marked.  ``--walk N [--start X,...] [--out FILE] [--plot FILE]`` walks
N strides in C (:func:`symmech.gait.walking.walk`) and prints each one with its distance to
the fixed point; the exit code is 1 when the walker falls.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

from symmech.codegen.escape import terminal
from symmech.errors import SymmechError
from symmech.gait.evaluation import CompiledGait
from symmech.gait.models import GAITS, GaitCase
from symmech.gait.periodic import continuation, period_doublings
from symmech.gait.report import (
    ROUTES,
    continuation_frame,
    figures_frame,
    format_figures,
    solve_routes,
    stride_costs,
)

__all__ = ["add_command", "run_gait_command"]


def add_command(sub: Any, common: argparse.ArgumentParser) -> None:
    """The ``gait`` sub-command's parser."""
    p = sub.add_parser("gait", parents=[common], help="a gait's fixed point and multipliers")
    p.add_argument(
        "name", metavar="NAME", help=f"a built-in gait ({', '.join(GAITS)}) or a gait file"
    )
    p.add_argument("--param", action="append", default=[], metavar="K=V", help="set a parameter")
    p.add_argument(
        "--routes",
        default="c,numpy,fd,mp,mp-cd",
        help=f"comma-separated routes among {','.join(ROUTES)} (default: all)",
    )
    p.add_argument("--digits", type=int, default=30, help="digits of the mpmath routes")
    p.add_argument(
        "--continue", dest="continue_", metavar="P=A:B", help="follow the gait in P from A to B"
    )
    p.add_argument("--steps", type=int, default=11, help="parameter values of --continue")
    p.add_argument("--walk", type=int, metavar="N", help="walk N strides (in C) and print each one")
    p.add_argument(
        "--start",
        metavar="X,...",
        help="the state just after the section where --walk starts (default: the gait's guess)",
    )
    p.add_argument("--plot", metavar="FILE", help="PNG of the continuation, or of the walk")
    p.add_argument(
        "--out",
        metavar="FILE",
        help="the table of routes (or of the continuation, or of the strides): .csv, .parquet",
    )


def _case(name: str) -> GaitCase:
    """A built-in gait by name, or a gait file (``*.toml``, :mod:`symmech.gait.gaitfile`)."""
    if name in GAITS:
        return GAITS[name]
    if name.endswith(".toml"):
        from symmech.gait.gaitfile import read_gait

        gf = read_gait(name)
        return GaitCase(
            gf.gait.name,
            lambda: gf.gait,
            gf.defaults,
            gf.guess,
            gf.description or f"gait file {name}",
            section=gf.section,
        )
    raise SymmechError(
        f"unknown gait {name!r}; built-in gaits: {', '.join(GAITS)}, or a gait file (.toml)"
    )


def _parameters(case: GaitCase, items: list[str]) -> dict[str, float]:
    from symmech.simulate.arguments import number

    values = dict(case.parameters)
    for item in items:
        key, sep, text = item.partition("=")
        if not sep or key not in values:
            raise SymmechError(f"--param {item!r}: expected K=V with K among {sorted(values)}")
        values[key] = number(text, f"--param {key}")
    return values


def _range(text: str, case: GaitCase) -> tuple[str, float, float]:
    from symmech.simulate.arguments import number

    key, sep, rest = text.partition("=")
    a, sep2, b = rest.partition(":")
    if not sep or not sep2 or key not in case.parameters:
        raise SymmechError(
            f"--continue {text!r}: expected P=A:B with P among {sorted(case.parameters)}"
        )
    return key, number(a, "--continue A"), number(b, "--continue B")


def run_gait_command(args: argparse.Namespace, progress: Callable[[str], None]) -> int:
    """Run ``symmech gait`` (module docstring); returns the exit code."""
    case = _case(args.name)
    params = _parameters(case, args.param)
    routes = [r.strip() for r in args.routes.split(",") if r.strip()]
    if not 10 <= args.digits <= 60:
        raise SymmechError(f"--digits {args.digits}: choose 10 to 60")
    progress(f"deriving gait {case.name}")
    gait = case.build()
    if args.continue_:
        return _continue(args, case, gait, params, progress)
    if args.walk is not None:
        return _walk(args, case, gait, params, progress)
    progress(f"routes {', '.join(routes)}")
    _check_out(args.out)
    figures = solve_routes(
        gait, params, case.guess, routes, digits=args.digits, section=case.section
    )
    print(f"gait {case.name}: {case.description}")
    print("parameters: " + ", ".join(f"{k} = {v:g}" for k, v in params.items()))
    print(format_figures(figures))
    if args.out:
        from symmech.simulate.table import save_frame

        save_frame(figures_frame(figures), args.out)
        print(f"wrote {terminal(args.out)}")
    c = next((f for f in figures if f.route == "c"), None)
    if c is not None:
        plain, full = stride_costs(CompiledGait(gait, params), c.x, case.section)
        print(
            f"cost in C: one stride {plain * 1e3:.3f} ms, stride with its Jacobian"
            f" {full * 1e3:.3f} ms ({full / plain:.2f}x)"
        )
    return 0


def _start(text: str | None, case: GaitCase) -> list[float]:
    from symmech.simulate.arguments import number

    if text is None:
        return list(case.guess)
    values = [number(v, "--start") for v in text.split(",")]
    if len(values) != len(case.guess):
        raise SymmechError(
            f"--start {text!r}: expected {len(case.guess)} numbers (the state just after the"
            " section transition)"
        )
    return values


def _walk(args, case: GaitCase, gait, params, progress) -> int:
    """``--walk N``: the strides from ``--start``, each with its distance to the gait's
    fixed point (found first, in C), and the ratio of successive distances (near a
    stable gait it tends to the leading multiplier's modulus)."""
    import numpy as np

    from symmech.gait.periodic import fixed_point
    from symmech.gait.walking import walk

    _check_out(args.out)
    if not 1 <= args.walk <= 100_000:
        raise SymmechError(f"--walk {args.walk}: choose 1 to 100000 strides")
    fns = CompiledGait(gait, params)
    start = _start(args.start, case)
    progress(f"the fixed point of {case.name}")
    try:
        star = fixed_point(fns, case.section, case.guess).x
    except SymmechError as exc:
        star = None
        print(f"no fixed point from the guess ({exc}): distances left out")
    progress(f"walking {args.walk} strides")
    w = walk(fns, case.section, start, args.walk, record=bool(args.plot))
    print(f"gait {case.name}: {args.walk} strides from {start}")
    print("stride          t      period   distance   ratio   state just after the section")
    last = None
    for k, (t, x) in enumerate(zip(w.times, w.sections, strict=True)):
        d = None if star is None else float(np.max(np.abs(x - star)))
        ratio = f"{d / last:7.4f}" if d is not None and last else "      -"
        period = f"{w.periods[k - 1]:10.6f}" if k else "         -"
        dist = f"{d:10.3e}" if d is not None else "         -"
        xs = ", ".join(f"{v:+.10f}" for v in x)
        print(f"{k:6d} {t:10.6f} {period} {dist} {ratio}   [{xs}]")
        last = d
    if w.stopped:
        print(f"stopped: {w.stopped}")
    if args.out:
        from symmech.simulate.table import save_frame

        save_frame(w.to_frame(), args.out)
        print(f"wrote {terminal(args.out)}")
    if args.plot:
        _plot_walk(w, gait, args.plot)
        print(f"wrote {terminal(args.plot)}")
    return 0 if not w.stopped else 1


def _plot_walk(w, gait, path: str) -> None:
    """Each mode's coordinates against time over the walk, the events as vertical lines."""
    from symmech.simulate.plotting import new_figure, save_figure

    fig, ax = new_figure(1, 1, height=4.0)
    rec = w.trajectory
    for j, mode in enumerate(w.modes):
        names = [str(q) for q in gait.modes[mode].coordinates]
        rows = rec[rec[:, 1] == j]
        for i, name in enumerate(names):
            label = name if len(w.modes) == 1 else f"{name} ({mode})"
            ax.plot(rows[:, 0], rows[:, 2 + i], ".", ms=2, label=label)
    for _, t, _ in w.events:
        ax.axvline(t, color="0.8", lw=0.6, zorder=0)
    ax.set_xlabel("t")
    ax.set_ylabel("coordinates")
    ax.set_title(f"{w.gait}: {len(w.times) - 1} strides")
    ax.legend(fontsize="small")
    save_figure(fig, path)


def _bar(total: int, key: str) -> Any:
    """A tqdm bar of the parameter values done, on stderr when it is a terminal (tqdm is
    in the ``sweep`` extra; without it, or off a terminal, the progress lines stay)."""
    import sys

    if not sys.stderr.isatty():
        return None
    try:
        from tqdm import tqdm
    except ImportError:
        return None
    return tqdm(total=total, file=sys.stderr, desc=f"continuation in {key}", unit="gait")


def _check_out(path: str | None) -> None:
    """Refuse an ``--out`` suffix the table writer cannot write, before anything runs."""
    from pathlib import Path

    from symmech.simulate.table import FRAME_FORMATS

    if path and Path(path).suffix.lower() not in FRAME_FORMATS:
        raise SymmechError(f"--out {path!r}: expected a file ending in {', '.join(FRAME_FORMATS)}")


def _continue(args, case: GaitCase, gait, params, progress) -> int:
    _check_out(args.out)
    key, a, b = _range(args.continue_, case)
    n = max(2, int(args.steps))
    values = [a + (b - a) * i / (n - 1) for i in range(n)]

    base = CompiledGait(gait, params)
    bar = _bar(len(values), key)

    started = [0]  # values begun; each begun after the first means one more done

    def make(value: float) -> CompiledGait:
        if bar is None:
            progress(f"{key} = {value:.6g}")
        elif started[0]:
            bar.update(1)
        started[0] += 1
        return base.with_parameters({**params, key: value})

    try:
        points = continuation(make, case.section, values, case.guess)
    finally:
        if bar is not None:
            bar.update(bar.total - bar.n)
            bar.close()
    for p in points:
        if p.point is None:
            print(f"{key} = {p.value:.6g}: no fixed point ({p.failure})")
            continue
        ms = ", ".join(f"{m.real:+.6f}{m.imag:+.6f}i" for m in p.point.multipliers)
        state = "stable" if p.point.stable else "unstable"
        print(f"{key} = {p.value:.6g}: {state}, multipliers [{ms}]")
    if args.out:
        from symmech.simulate.table import save_frame

        save_frame(continuation_frame(points, key), args.out)
        print(f"wrote {terminal(args.out)}")
    doublings = period_doublings(points)
    for lo, hi in doublings:
        print(f"period doubling between {key} = {lo:.6g} and {hi:.6g}")
    path = args.plot or f"{case.name}_continuation.png"
    _plot(points, key, doublings, path)
    print(f"wrote {terminal(path)}")
    return 0


def _plot(points, key: str, doublings, path: str) -> None:
    """Moduli and real parts of the multipliers against the parameter, in the style of
    every symmech figure (:mod:`symmech.simulate.plotting`)."""
    from symmech.simulate.plotting import new_figure, save_figure

    ok = [p for p in points if p.point is not None]
    fig, (top, bottom) = new_figure(2, 1, height=6.0, sharex=True)
    xs = [p.value for p in ok]
    width = max((len(p.point.multipliers) for p in ok), default=0)
    for i in range(width):
        top.plot(xs, [abs(p.point.multipliers[i]) for p in ok], "o-", ms=3, label=f"{i + 1}")
        bottom.plot(xs, [p.point.multipliers[i].real for p in ok], "o-", ms=3)
    top.axhline(1.0, color="k", lw=0.8, ls="--")
    bottom.axhline(-1.0, color="k", lw=0.8, ls="--")
    for lo, hi in doublings:
        for ax in (top, bottom):
            ax.axvspan(lo, hi, color="tab:red", alpha=0.15)
    top.set_ylabel("|multiplier|")
    bottom.set_ylabel("Re multiplier")
    bottom.set_xlabel(key)
    top.legend(title="multiplier", fontsize="small")
    top.set_title("multipliers of the stride map along the continuation")
    save_figure(fig, path)
