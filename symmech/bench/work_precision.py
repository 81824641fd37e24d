"""Error against run time: every method, tolerance and backend against a trusted reference.

For a case (:mod:`symmech.bench.cases`) the reference is a closed form where one exists
(the bouncing ball: its impact times and its state at t_end) and otherwise the mpmath run
of the same algorithm (:func:`symmech.simulate.reference.reference_run`, 24 digits).  Each
row is one (backend, method, tolerance): the median run time over at least ``repeats`` runs
and :data:`MIN_SECONDS` of runs, the
final-state error ``max |y(t_end) - y_ref(t_end)|``, the worst event-time error over the
impacts both runs have (k-th against k-th), the energy drift the run reports, and the
impacts counted against the reference's.  The baseline a user writes today
(:mod:`symmech.bench.baseline`) is measured the same way, its failures kept in the table
(status ``max_impacts``, a negative ``min gap``: the wall was crossed).  :func:`plot`
draws error against run time on log-log axes (matplotlib, the ``plot`` extra).
"""

from __future__ import annotations

import math
import os
import statistics
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from symmech.bench.baseline import baseline_run, prepare
from symmech.bench.cases import Case, bouncing_ball_state, bouncing_ball_times
from symmech.errors import SymmechError
from symmech.simulate.reference import as_float, reference_run

__all__ = ["Reference", "Row", "format_table", "measure", "plot", "reference", "rows"]

#: Tolerances swept (atol = rtol / 100).
TOLERANCES = (1e-3, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12)

#: (backend, method) pairs measured by default.
ROUTES = (
    ("c", "dop853"),
    ("c", "tsit5"),
    ("numpy", "dop853"),
    ("scipy", "DOP853"),
)


@dataclass(frozen=True)
class Reference:
    """The reference of a case: final state, impact times, and where they come from."""

    y_end: np.ndarray
    impact_times: tuple[float, ...]
    source: str
    seconds: float


@dataclass(frozen=True)
class Row:
    """One measured configuration (see the module docstring)."""

    route: str
    method: str
    rtol: float
    seconds: float
    final_error: float
    event_error: float
    energy_drift: float | None
    impacts: int
    reference_impacts: int
    status: str
    min_gap: float = math.nan


def reference(case: Case, dps: int = 24) -> Reference:
    """The case's reference (closed form for the bouncing ball, else mpmath)."""
    clock = time.perf_counter()
    if case.scene_name == "bouncing_ball" and case.v0 == (0.0,):
        p = case.params()
        h, g, alpha = case.q0[0], p["g"], p["alpha"]
        y, ydot = bouncing_ball_state(h, g, alpha, case.t_end)
        times = bouncing_ball_times(h, g, alpha, case.t_end)
        return Reference(np.array([y, ydot]), tuple(times), "closed form", 0.0)
    res = reference_run(case.scene(), case.q0, case.v0, case.t_end, params=case.params(), dps=dps)
    return Reference(
        as_float(np.asarray(res.y[-1])),
        tuple(float(e.time) for e in res.impacts()),
        f"mpmath, {dps} digits",
        time.perf_counter() - clock,
    )


#: A route is timed over at least ``repeats`` runs and at least this many seconds of runs
#: (at most MAX_RUNS): a fast route's median is then taken over enough runs to be stable.
MIN_SECONDS = 0.2
MAX_RUNS = 2000


def _more(seconds: list[float], repeats: int) -> bool:
    """Whether to time another run (see :data:`MIN_SECONDS`)."""
    n = len(seconds)
    return n < repeats or (sum(seconds) < MIN_SECONDS and n < MAX_RUNS)


def _event_error(times: Sequence[float], ref: Sequence[float]) -> float:
    k = min(len(times), len(ref))
    return max((abs(times[i] - ref[i]) for i in range(k)), default=0.0)


def measure(
    case: Case,
    ref: Reference,
    route: str,
    method: str,
    rtol: float,
    repeats: int = 3,
    prepared: Any = None,
) -> Row:
    """One row: ``route`` is a simulate backend or ``"baseline"``."""
    scene, params = case.scene(), case.params()
    atol = rtol / 100
    seconds: list[float] = []
    if route == "baseline":
        while _more(seconds, repeats):
            b = baseline_run(
                scene,
                case.q0,
                case.v0,
                case.t_end,
                params,
                rtol=rtol,
                atol=atol,
                method=method,
                prepared=prepared,
            )
            seconds.append(b.wall_time)
        return Row(
            "baseline",
            method,
            rtol,
            statistics.median(seconds),
            float(np.max(np.abs(b.y - ref.y_end))) if b.t >= case.t_end else math.inf,
            _event_error(b.impact_times, ref.impact_times),
            None,
            len(b.impact_times),
            len(ref.impact_times),
            b.status,
            b.min_gap,
        )
    first = True  # the first run compiles and loads: not timed
    while first or _more(seconds, repeats):
        clock = time.perf_counter()
        res = case.simulate(backend=route, method=method, rtol=rtol, atol=atol)
        if first:
            first = False
            continue
        seconds.append(time.perf_counter() - clock)
    times = [e.time for e in res.impacts()]
    final = float(np.max(np.abs(res.y[-1] - ref.y_end))) if res.success else math.inf
    return Row(
        route,
        method,
        rtol,
        statistics.median(seconds),
        final,
        _event_error(times, ref.impact_times),
        res.stats["energy_drift"],
        len(times),
        len(ref.impact_times),
        res.status,
    )


def rows(
    case: Case,
    routes: Sequence[tuple[str, str]] = ROUTES,
    tolerances: Sequence[float] = TOLERANCES,
    repeats: int = 3,
    baseline: bool = True,
    ref: Reference | None = None,
) -> tuple[Reference, list[Row]]:
    """The work-precision table of ``case``."""
    ref = reference(case) if ref is None else ref
    out = []
    for route, method in routes:
        for rtol in tolerances:
            out.append(measure(case, ref, route, method, rtol, repeats))
    if baseline:
        prepared = prepare(case.scene(), case.params())
        for rtol in tolerances:
            out.append(measure(case, ref, "baseline", "DOP853", rtol, repeats, prepared))
    return ref, out


def format_table(case: Case, ref: Reference, table: Sequence[Row]) -> str:
    """A Markdown table of the rows."""
    lines = [
        f"### {case.name}: {case.description}",
        f"reference: {ref.source} ({len(ref.impact_times)} impacts, {ref.seconds:.1f} s)",
        "",
        "| route | method | rtol | median time [s] | final error | worst event-time error"
        " | energy drift | impacts (ref) | status |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in table:
        energy = "-" if r.energy_drift is None else f"{float(r.energy_drift):.1e}"
        status = r.status
        if r.route == "baseline" and r.min_gap < -1e-9:
            status += f", crossed the wall (min gap {r.min_gap:.2g})"
        lines.append(
            f"| {r.route} | {r.method} | {r.rtol:.0e} | {r.seconds:.2e} | {r.final_error:.1e}"
            f" | {r.event_error:.1e} | {energy} | {r.impacts} ({r.reference_impacts}) | {status} |"
        )
    return "\n".join(lines)


def plot(case: Case, table: Sequence[Row], path: str) -> None:
    """Final-state error against median run time, log-log, one curve per route and method;
    failed runs (infinite error) are drawn at the top of the axes with a cross.  In the look
    of every symmech figure (:func:`symmech.simulate.plotting.new_figure`)."""
    from symmech.simulate.plotting import new_figure, save_figure, style

    fig, ax = new_figure(width=7, height=5)
    finite = [r.final_error for r in table if math.isfinite(r.final_error) and r.final_error > 0]
    top = max(finite, default=1.0) * 10
    for key in dict.fromkeys((r.route, r.method) for r in table):
        sel = [r for r in table if (r.route, r.method) == key]
        xs = [r.seconds for r in sel]
        ys = [r.final_error if math.isfinite(r.final_error) else top for r in sel]
        ys = [max(y, 1e-17) for y in ys]
        ax.loglog(xs, ys, marker="o", label=f"{key[0]} {key[1]}")
        for r, x, y in zip(sel, xs, ys, strict=True):
            if not math.isfinite(r.final_error) or r.status not in ("finished", "zeno"):
                ax.plot([x], [y], marker="x", color="red", markersize=10)
    ax.set_xlabel("median run time [s]")
    ax.set_ylabel("final-state error (max abs)")
    ax.set_title(f"work-precision: {case.name} (red x: failed or stopped)")
    with style():
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    # through the one writer of output files: a link at ``path`` is replaced, not followed
    save_figure(fig, path)


def check_plot_path(path: str) -> None:
    """Refuse, before anything runs, a plot path the figure writer cannot write: an image
    format other than :data:`symmech.simulate.plotting.IMAGE_FORMATS` (a raw ValueError
    after the whole benchmark, exit 3, before), or a folder that does not exist."""
    from symmech.simulate.plotting import IMAGE_FORMATS

    suffix = os.path.splitext(str(path))[1].lower() or ".png"
    if suffix not in IMAGE_FORMATS:
        raise SymmechError(
            f"--plot {path!r}: no {suffix!r} images; name a file ending in one of"
            f" {', '.join(IMAGE_FORMATS)}"
        )
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise SymmechError(f"--plot {path!r}: the folder {folder!r} does not exist")
