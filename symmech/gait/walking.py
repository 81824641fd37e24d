"""Walking: strides one after another, the hybrid system simulated over many steps.

:func:`walk` iterates the stride map from a state just after the section transition:
``x_{k+1} = P(x_k)``, with each stride's time and, with ``record=True``, the motion (every
accepted step, each event before and after its jump) on one time axis.  It runs on the
loop the functions offer (:func:`symmech.gait.stride_map.stride`: generated C for a
:class:`~symmech.gait.evaluation.CompiledGait` of target ``"c"``, the Python loop over
NumPy functions for ``"numpy"``, mpmath for :class:`~symmech.gait.evaluation.MpGait`).
Near a stable gait ``x_k - x*`` shrinks like ``|lambda|^k``, ``lambda`` the leading
multiplier (a test checks the ratio).  A walker that falls (no transition fires, a step
too small) ends the walk at that stride, with the reason in :attr:`Walk.stopped`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from symmech.gait.evaluation import GaitFunctions
from symmech.gait.stride_map import GaitError, StrideOptions, stride

__all__ = ["Walk", "walk"]


@dataclass
class Walk:
    """``strides`` strides of ``gait`` from ``sections[0]``: the states just after each
    section event (``sections[k]``, k = 0 .. strides done), the times of those events
    (``times``, ``times[0] = 0``), the events of every stride (transition, time, state
    before the jump), the recorded motion (rows ``(t, mode index, state padded with NaN)``,
    with ``record=True``) and why the walk stopped early (``stopped``, "" when it did
    not)."""

    gait: str
    modes: tuple[str, ...]
    section: int
    sections: np.ndarray
    times: np.ndarray
    events: list[tuple[int, float, np.ndarray]] = field(default_factory=list)
    trajectory: np.ndarray | None = None
    stopped: str = ""

    @property
    def periods(self) -> np.ndarray:
        """The strides' durations."""
        return np.diff(self.times)

    def to_frame(self) -> Any:
        """The strides as a pandas DataFrame: ``stride``, ``t``, ``period`` (of the stride
        that ended there; NaN for the start) and ``x0 ... x<n-1>``."""
        import pandas as pd

        frame = pd.DataFrame(
            self.sections, columns=[f"x{i}" for i in range(self.sections.shape[1])]
        )
        frame.insert(0, "period", np.concatenate([[np.nan], self.periods]))
        frame.insert(0, "t", self.times)
        frame.insert(0, "stride", np.arange(len(self.times)))
        return frame

    def trajectory_frame(self) -> Any:
        """The recorded motion as a pandas DataFrame: ``t``, ``mode`` (its name) and
        ``y0 ...`` (NaN beyond the mode's size)."""
        import pandas as pd

        if self.trajectory is None:
            raise GaitError(f"walk of {self.gait!r}: no motion recorded (walk(..., record=True))")
        rec = self.trajectory
        frame = pd.DataFrame(rec[:, 2:], columns=[f"y{i}" for i in range(rec.shape[1] - 2)])
        frame.insert(0, "mode", [self.modes[int(m)] for m in rec[:, 1]])
        frame.insert(0, "t", rec[:, 0])
        return frame


def walk(
    fns: GaitFunctions,
    section: int,
    x0: Any,
    strides: int,
    *,
    record: bool = False,
    options: StrideOptions | None = None,
    loop: str = "auto",
) -> Walk:
    """``strides`` strides from ``x0`` (module docstring)."""
    if isinstance(strides, bool) or not isinstance(strides, (int, np.integer)) or strides < 0:
        raise GaitError(f"walk: strides must be a whole number >= 0, got {strides!r}")
    x = fns.array(x0)
    sections, times = [x], [0.0]
    events: list[tuple[int, float, np.ndarray]] = []
    pieces: list[np.ndarray] = []
    stopped = ""
    for k in range(int(strides)):
        try:
            out = stride(fns, section, x, options=options, loop=loop, record=record)
        except GaitError as exc:
            stopped = f"stride {k + 1}: {exc}"
            break
        t0 = times[-1]
        events += [(i, t0 + float(t), y) for i, t, y in out.events]
        if out.trajectory is not None:
            rows = np.array(out.trajectory, dtype=float)
            rows[:, 0] += t0
            pieces.append(rows if not pieces else rows[1:])  # the start is the last row
        x = out.x
        sections.append(x)
        times.append(t0 + float(out.period))
    return Walk(
        fns.gait.name,
        tuple(fns.mode_names),
        section,
        np.array([np.asarray(s, dtype=float) for s in sections]),
        np.array(times),
        events,
        np.concatenate(pieces) if pieces else (np.empty((0, 0)) if record else None),
        stopped,
    )
