"""Plots of a run (matplotlib, the ``plot`` extra), in one look shared by every figure
symmech draws (``res.plot()``, ``res.animate()``, the work-precision report).

:func:`plot` stacks, against time: the coordinates, the velocities, the gaps psi of the
walls (the admissible side psi >= 0 above the dashed zero line) and the energy T + V, each
from :meth:`~symmech.simulate.result.SimulationResult.sample` on a fine grid (each event's
instant twice, so the jumps of the velocities and of the energy are drawn vertical).  Every
event is a vertical line coloured by its kind (:data:`EVENT_STYLE`) on every panel, and a
marker on the gaps panel; the legend names the kinds.  A result read from a file (no
continuous output) is drawn from its steps.

:func:`new_figure` makes every figure: a :class:`matplotlib.figure.Figure` (not pyplot: no
global state, no window; Jupyter shows it inline) with :data:`STYLE`'s settings, and
:func:`save_figure` writes one through :func:`symmech.files.write_atomic`.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from symmech.files import write_atomic
from symmech.simulate.result import SimulationResult
from symmech.simulate.system import SimulationError

__all__ = ["EVENT_STYLE", "STYLE", "new_figure", "plot", "save_figure", "style"]

#: The matplotlib settings of every symmech figure.
STYLE: dict[str, Any] = {
    "figure.dpi": 100,
    "savefig.dpi": 120,
    "font.size": 9,
    "axes.titlesize": 10,
    "axes.labelsize": 9,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "axes.spines.top": False,
    "axes.spines.right": False,
    "legend.fontsize": 8,
    "legend.frameon": False,
    "lines.linewidth": 1.3,
}
#: Colour and marker of each event kind.
EVENT_STYLE: dict[str, tuple[str, str]] = {
    "impact": ("tab:red", "v"),
    "grazing": ("tab:orange", "o"),
    "contact": ("tab:green", "s"),
    "release": ("tab:purple", "^"),
}
#: Image formats :func:`save_figure` writes (by the file's suffix).
IMAGE_FORMATS = (".png", ".svg", ".pdf")


def _matplotlib() -> Any:
    try:
        import matplotlib
    except ImportError as exc:
        raise SimulationError(
            f"plots need matplotlib ({exc}): python3 -m pip install 'symmech[plot]'"
        ) from None
    return matplotlib


@contextmanager
def style() -> Iterator[None]:
    """Inside the block, matplotlib draws with :data:`STYLE` and the tab10 colours
    (restored after)."""
    mpl = _matplotlib()
    from cycler import cycler

    settings = dict(STYLE, **{"axes.prop_cycle": cycler(color=list(mpl.colormaps["tab10"].colors))})
    with mpl.rc_context(settings):
        yield


def new_figure(
    rows: int = 1, cols: int = 1, *, width: float = 7.0, height: float = 4.5, sharex: bool = False
) -> tuple[Any, Any]:
    """A Figure in :data:`STYLE` and its axes (an array when several)."""
    _matplotlib()
    from matplotlib.figure import Figure

    with style():
        fig = Figure(figsize=(width, height), layout="constrained")
        axes = fig.subplots(rows, cols, sharex=sharex)
    return fig, axes


def save_figure(fig: Any, path: str | os.PathLike[str]) -> Path:
    """Write ``fig`` to ``path`` (PNG, SVG or PDF by its suffix; PNG when it has none)."""
    suffix = Path(path).suffix.lower() or ".png"
    if suffix not in IMAGE_FORMATS:
        raise SimulationError(
            f"{os.fspath(path)!r}: unknown image type {suffix!r}; expected one of"
            f" {', '.join(IMAGE_FORMATS)}"
        )
    with style():
        return write_atomic(path, lambda fh: fig.savefig(fh, format=suffix[1:]))


def trajectory(res: SimulationResult, points: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(t, q, v)`` to draw: ``points`` times evenly spaced and the steps, sampled with the
    events (module docstring); the steps of a result read from a file."""
    if not res.segments:
        return np.asarray(res.t, float), np.asarray(res.q, float), np.asarray(res.v, float)
    grid = np.union1d(np.linspace(float(res.t[0]), float(res.t[-1]), points), res.t)
    s = res.sample(grid)
    return s.t, s.q, s.v


def plot(
    res: SimulationResult,
    *,
    points: int = 600,
    path: str | os.PathLike[str] | None = None,
    title: str | None = None,
) -> Any:
    """Coordinates, velocities, gaps and energy of ``res`` against time, events marked by
    kind (module docstring); written to ``path`` when given.  Returns the Figure; its axes
    are labelled ``coordinates``, ``velocities``, ``gaps psi`` and ``energy T + V`` (the
    last two when the run has walls / an energy)."""
    from symmech.simulate.table import observables

    t, q, v = trajectory(res, points)
    extra = observables(res, t, q, v)
    gaps = {k[4:-1]: x for k, x in extra.items() if k.startswith("gap[")}
    panels = ["coordinates", "velocities"] + (["gaps"] if gaps else [])
    panels += ["energy"] if "energy" in extra else []
    fig, axes = new_figure(len(panels), 1, height=1.9 * len(panels) + 0.6, sharex=True)
    axes = np.atleast_1d(axes)
    with style():
        for ax, panel in zip(axes, panels, strict=True):
            if panel == "coordinates":
                for i, name in enumerate(res.coordinates):
                    ax.plot(t, q[:, i], label=name)
                ax.set_ylabel("coordinates")
            elif panel == "velocities":
                for i, name in enumerate(res.velocities):
                    ax.plot(t, v[:, i], label=name)
                ax.set_ylabel("velocities")
            elif panel == "gaps":
                for name, g in gaps.items():
                    ax.plot(t, g, label=name)
                ax.axhline(0.0, color="0.3", linestyle="--", linewidth=0.8)
                ax.set_ylabel("gaps psi")
            else:
                ax.plot(t, extra["energy"], color="0.2", label="T + V")
                ax.set_ylabel("energy T + V")
            _mark_events(ax, res, gaps if panel == "gaps" else None)
            ax.legend(loc="upper right", ncols=min(4, len(ax.get_lines())))
        axes[-1].set_xlabel("t")
        name = res.scene.name if res.scene is not None else "run"
        axes[0].set_title(title or f"{name}: {res.status}, {len(res.events)} events")
    if path is not None:
        save_figure(fig, path)
    return fig


def _mark_events(ax: Any, res: SimulationResult, gaps: dict[str, np.ndarray] | None) -> None:
    """A vertical line per event coloured by kind; on the gaps panel also a marker on the
    struck wall's zero (labelled with the kind, once per kind)."""
    by_kind: dict[str, list[Any]] = {}
    for e in res.events:
        by_kind.setdefault(e.kind, []).append(e)
    for kind, evs in by_kind.items():
        color, marker = EVENT_STYLE.get(kind, ("0.5", "x"))
        times = [float(e.time) for e in evs]
        ax.vlines(
            times,
            0,
            1,
            transform=ax.get_xaxis_transform(),
            colors=color,
            alpha=0.35,
            linewidth=0.8,
            gid=f"events:{kind}",
        )
        if gaps is not None:
            ax.plot(
                times,
                np.zeros(len(times)),
                linestyle="none",
                marker=marker,
                color=color,
                markersize=5,
                label=kind,
                gid=f"events:{kind}",
            )
