"""Animations of a run: the scene's drawing (:mod:`symmech.declaration.drawing`) moved by
the dense output, as a matplotlib animation.

Frames are taken at real time: ``t_k = t0 + k * speed / fps`` up to the end of the run
(``speed`` 2 plays twice as fast), and every event's instant is a frame of its own (the
configuration at an impact, where the body touches the wall, is always shown); the states
come from :meth:`~symmech.simulate.result.SimulationResult.sample`.  Each shape's
expressions are compiled once by ``sympy.lambdify`` (sympy expressions only: the drawing
was checked by the scene's declaration; no text is evaluated) over ``(t, q, parameters)``.
The view is fixed for the whole animation: the bounding box of every shape at every frame
and of the walls' points, padded, with equal axes.

A scene without a drawing warns (:class:`~symmech.SymmechWarning`, saying how to give one)
and animates a plot of its coordinates against time with a moving time cursor instead.

:func:`animate` returns a :class:`SceneAnimation` (a ``FuncAnimation`` that Jupyter shows
inline as HTML/JavaScript); :func:`save_animation` writes it as a GIF (pillow) or an HTML
page through :func:`symmech.files.write_atomic`.
"""

from __future__ import annotations

import html
import io
import os
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import sympy as sp

from symmech.declaration.drawing import Disc, Drawing, Ellipse, Point, Segment
from symmech.declaration.shapes import Plane
from symmech.declaration.symbols import t as TIME
from symmech.errors import SymmechWarning
from symmech.files import write_atomic, write_text_atomic
from symmech.simulate.plotting import new_figure, style
from symmech.simulate.result import SimulationResult
from symmech.simulate.system import SimulationError

__all__ = [
    "ANIMATION_FORMATS",
    "MAX_FRAMES",
    "animate",
    "frame_times",
    "frames_rgb",
    "save_animation",
]

#: Largest number of frames of an animation (a longer run needs a larger ``speed``).
MAX_FRAMES = 3000
#: File suffixes :func:`save_animation` writes.
ANIMATION_FORMATS = (".gif", ".html")


def frame_times(res: SimulationResult, fps: float, speed: float) -> np.ndarray:
    """The frame times: ``t0 + k speed / fps`` within the run and every event's time
    (module docstring), sorted, each once."""
    if not (np.isfinite(fps) and fps > 0 and np.isfinite(speed) and speed > 0):
        raise SimulationError(f"animate: fps and speed must be positive, got {fps!r}, {speed!r}")
    t0, t1 = float(res.t[0]), float(res.t[-1])
    steps = int(np.floor((t1 - t0) * fps / speed + 1e-9))
    # the last frame may land past t1 by a rounding (0.1 * 3 > 0.3): it is t1's
    grid = np.minimum(t0 + np.arange(steps + 1) * (speed / fps), t1)
    times = np.union1d(grid, [float(e.time) for e in res.events])
    if times.size > MAX_FRAMES:
        raise SimulationError(
            f"animate: {times.size} frames (limit {MAX_FRAMES}); play faster (speed > {speed:g})"
            " or at fewer frames per second"
        )
    return times


def _animation_class() -> type:
    try:
        from matplotlib.animation import FuncAnimation
    except ImportError as exc:
        raise SimulationError(
            f"animations need matplotlib ({exc}): python3 -m pip install 'symmech[plot]'"
        ) from None

    class SceneAnimation(FuncAnimation):
        """A FuncAnimation shown inline by Jupyter (as HTML/JavaScript)."""

        times: np.ndarray
        scene_figure: Any
        render: Callable[[int], list]

        def _repr_html_(self) -> str:
            return str(self.to_jshtml())

    return SceneAnimation


def animate(
    res: SimulationResult,
    *,
    fps: float = 25.0,
    speed: float = 1.0,
    drawing: Drawing | None = None,
    width: float = 4.0,
) -> Any:
    """The run drawn frame by frame (module docstring).  ``drawing`` replaces the scene's
    own.  Returns a ``SceneAnimation``: ``anim.times`` holds the frame times,
    ``anim.render(i)`` draws frame i on ``anim.scene_figure``."""
    if res.scene is None and drawing is None:
        raise SimulationError(
            "animate: this result holds no scene (it was read from a file); pass drawing="
        )
    drawing = drawing if drawing is not None else res.scene.drawing
    times = frame_times(res, fps, speed)
    samples = res.sample(times)
    keep = samples.side >= 0  # the state after each event: the configuration is the same
    t, q = samples.t[keep], samples.q[keep]
    if drawing is None:
        name = res.scene.name
        warnings.warn(
            f"scene {name!r} has no drawing (give Scene(..., drawing=...) or [[drawing]] tables"
            " in its scene file); animating its coordinates against time instead",
            SymmechWarning,
            stacklevel=3,
        )
        fig, update = _coordinate_plot(res, t, q, width)
    else:
        fig, update = _drawn(res, drawing, t, q, width)
    cls = _animation_class()
    anim = cls(fig, update, frames=len(t), interval=1000.0 / fps, blit=False)
    anim.times, anim.scene_figure, anim.render = t, fig, update
    # not a pyplot window whose timer must run: matplotlib's warning for an animation freed
    # before it was drawn (meant for a forgotten plt.show()) does not apply
    anim._draw_was_started = True
    return anim


def _evaluator(res: SimulationResult, exprs: Sequence[sp.Expr]) -> Callable[..., np.ndarray]:
    """``f(t, q) -> values`` of ``exprs`` at the run's parameters."""
    scene = res.scene
    params = {p: res.params[p.name] for p in scene.parameters if p.name in res.params}
    args = [TIME, *scene.coordinates]
    fixed = [sp.sympify(e, strict=True).subs(params) for e in exprs]
    fn = sp.lambdify(args, fixed, modules="numpy")
    return lambda t, q: np.array(fn(t, *q), dtype=float)


def _drawn(
    res: SimulationResult, drawing: Drawing, t: np.ndarray, q: np.ndarray, width: float
) -> tuple[Any, Callable[[int], list]]:
    from matplotlib.lines import Line2D
    from matplotlib.patches import Circle, Polygon
    from matplotlib.patches import Ellipse as EllipsePatch

    shapes = list(drawing)
    evals = [_evaluator(res, _values(s)) for s in shapes]
    values = [np.array([f(ti, qi) for ti, qi in zip(t, q, strict=True)]) for f in evals]
    lo, hi = _bounds(shapes, values)
    span = max(hi[0] - lo[0], hi[1] - lo[1], 1e-3)
    pad = 0.08 * span
    lo, hi = lo - pad, hi + pad
    aspect = (hi[1] - lo[1]) / (hi[0] - lo[0])
    fig, ax = new_figure(width=width, height=min(max(width * aspect, 2.5), 1.6 * width) + 0.5)
    with style():
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(lo[1], hi[1])
        ax.set_aspect("equal", adjustable="box")
        ax.set_axis_off()  # a picture of the scene; the axes' ticks cost most of a frame
        artists: list[list[Any]] = []
        for k, s in enumerate(shapes):
            color = f"C{k % 10}"
            if isinstance(s, Point):
                artists.append([ax.add_line(Line2D([], [], marker="o", color=color, ms=8))])
            elif isinstance(s, Segment):
                artists.append([ax.add_line(Line2D([], [], color=color, lw=2.5))])
            elif isinstance(s, Disc | Ellipse):
                patch = (
                    Circle((0, 0), 1, fc=color, ec="0.2", alpha=0.6)
                    if isinstance(s, Disc)
                    else EllipsePatch((0, 0), 2, 1, fc=color, ec="0.2", alpha=0.6)
                )
                ax.add_patch(patch)
                artists.append([patch, ax.add_line(Line2D([], [], color="0.15", lw=1.2))])
            else:
                band = Polygon(np.zeros((4, 2)), closed=True, fc="0.75", ec="none", alpha=0.7)
                ax.add_patch(band)
                artists.append([ax.add_line(Line2D([], [], color="0.2", lw=1.5)), band])
        clock = ax.text(0.02, 0.96, "", transform=ax.transAxes, va="top")
        ax.set_title(f"{res.scene.name}")

    def update(i: int) -> list:
        out: list[Any] = [clock]
        for s, vals, arts in zip(shapes, values, artists, strict=True):
            _place(s, vals[i], arts, span)
            out.extend(arts)
        clock.set_text(f"t = {t[i]:.3f}")
        return out

    update(0)
    return fig, update


def _values(shape: Any) -> list[sp.Expr]:
    if isinstance(shape, Plane):
        return [*shape.point, *shape.normal]
    if isinstance(shape, Disc):
        return [*shape.center, shape.radius, shape.angle if shape.angle is not None else 0]
    return list(shape.expressions())


def _bounds(shapes: Sequence[Any], values: Sequence[np.ndarray]) -> tuple[np.ndarray, ...]:
    """The box holding every shape at every frame (walls: their point)."""
    xs, ys = [], []
    for s, v in zip(shapes, values, strict=True):
        if isinstance(s, Point | Plane):
            xs.append(v[:, 0])
            ys.append(v[:, 1])
        elif isinstance(s, Segment):
            xs += [v[:, 0], v[:, 2]]
            ys += [v[:, 1], v[:, 3]]
        else:
            r = np.abs(v[:, 2]) if isinstance(s, Disc) else np.maximum(abs(v[:, 2]), abs(v[:, 3]))
            xs += [v[:, 0] - r, v[:, 0] + r]
            ys += [v[:, 1] - r, v[:, 1] + r]
    x, y = np.concatenate(xs), np.concatenate(ys)
    return np.array([x.min(), y.min()]), np.array([x.max(), y.max()])


def _place(shape: Any, v: np.ndarray, arts: list[Any], span: float) -> None:
    """Move the artists of one shape to the values ``v`` of its expressions."""
    if isinstance(shape, Point):
        arts[0].set_data([v[0]], [v[1]])
    elif isinstance(shape, Segment):
        arts[0].set_data([v[0], v[2]], [v[1], v[3]])
    elif isinstance(shape, Disc):
        arts[0].set_center((v[0], v[1]))
        arts[0].set_radius(v[2])
        c, s = np.cos(v[3]), np.sin(v[3])
        arts[1].set_data([v[0], v[0] + v[2] * c], [v[1], v[1] + v[2] * s])
        arts[1].set_visible(shape.angle is not None)
    elif isinstance(shape, Ellipse):
        arts[0].set_center((v[0], v[1]))
        arts[0].width, arts[0].height = 2 * v[2], 2 * v[3]
        arts[0].set_angle(np.degrees(v[4]))
        c, s = np.cos(v[4]), np.sin(v[4])
        arts[1].set_data([v[0], v[0] + v[2] * c], [v[1], v[1] + v[2] * s])
    else:  # a wall: a long line through p across n, the blocked side (-n) shaded
        p, n = v[:2], v[2:4]
        along = np.array([-n[1], n[0]]) * 3 * span
        arts[0].set_data([p[0] - along[0], p[0] + along[0]], [p[1] - along[1], p[1] + along[1]])
        depth = -n * 0.04 * span
        arts[1].set_xy(np.array([p - along, p + along, p + along + depth, p - along + depth]))


def _coordinate_plot(
    res: SimulationResult, t: np.ndarray, q: np.ndarray, width: float
) -> tuple[Any, Callable[[int], list]]:
    """The fallback: the coordinates against time, a cursor at the frame's time."""
    fig, ax = new_figure(width=width, height=0.7 * width)
    with style():
        for i, name in enumerate(res.coordinates):
            ax.plot(t, q[:, i], label=name)
        ax.set_xlabel("t")
        ax.set_ylabel("coordinates")
        ax.set_title(f"{res.scene.name}: no drawing, its coordinates")
        ax.legend(loc="upper right")
        cursor = ax.axvline(t[0], color="0.2", lw=1)
        dots = ax.plot(np.full(q.shape[1], t[0]), q[0], "o", color="0.2", ms=4)[0]

    def update(i: int) -> list:
        cursor.set_xdata([t[i], t[i]])
        dots.set_data(np.full(q.shape[1], t[i]), q[i])
        return [cursor, dots]

    return fig, update


def frames_rgb(anim: Any, dpi: float = 72.0) -> list[np.ndarray]:
    """Every frame of ``anim`` rendered at ``dpi`` to an RGB array (height, width, 3)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig = anim.scene_figure
    canvas = FigureCanvasAgg(fig)
    out = []
    with style():
        fig.set_dpi(dpi)
        canvas.draw()
        fig.set_layout_engine("none")  # laid out once: the frames keep one layout
        for i in range(len(anim.times)):
            anim.render(i)
            canvas.draw()
            out.append(np.asarray(canvas.buffer_rgba())[:, :, :3].copy())
    return out


def save_animation(
    anim: Any, path: str | os.PathLike[str], fps: float = 25.0, dpi: float = 72.0
) -> Path:
    """Write ``anim`` to ``path``: a looping GIF (pillow; frames rendered at ``dpi``) or a
    self-contained HTML page with the player (``to_jshtml``), by the suffix."""
    suffix = Path(path).suffix.lower()
    if suffix not in ANIMATION_FORMATS:
        raise SimulationError(
            f"{os.fspath(path)!r}: unknown animation type {suffix or '(none)'!r}; expected one"
            f" of {', '.join(ANIMATION_FORMATS)}"
        )
    if suffix == ".html":
        with style():
            player = str(anim.to_jshtml(fps=fps))
        title = html.escape(Path(path).stem)
        page = (
            f'<!DOCTYPE html>\n<html>\n<head>\n<meta charset="utf-8">\n<title>{title}</title>\n'
            f"</head>\n<body>\n{player}\n</body>\n</html>\n"
        )
        return write_text_atomic(path, page)
    try:
        from PIL import Image
    except ImportError as exc:
        raise SimulationError(
            f"GIF animations need pillow ({exc}): python3 -m pip install 'symmech[plot]'"
        ) from None
    # an octree palette per frame: pillow's default (median cut) takes most of the time
    fast = Image.Quantize.FASTOCTREE
    images = [Image.fromarray(a).quantize(colors=128, method=fast) for a in frames_rgb(anim, dpi)]
    duration = max(round(1000.0 / fps), 20)

    def gif(fh: Any) -> None:
        buffer = io.BytesIO()
        images[0].save(
            buffer,
            format="GIF",
            save_all=True,
            append_images=images[1:],
            duration=duration,
            loop=0,
        )
        fh.write(buffer.getvalue())

    return write_atomic(path, gif)
