"""What a simulation returns: the accepted steps, the events, a status and statistics.

:class:`SimulationResult` holds the accepted step times and states (event times included:
the state just before an event, then the state just after it, at the same time), the list
of :class:`Event` records, the status (``"finished"``, ``"zeno"``, ``"max_events"``,
``"failed"``) with a message, and ``stats``.  ``res(t)`` (or ``res.sol(t)``) evaluates the
continuous output: the integrator's own dense output of the step containing t (NumPy and
SciPy backends), or the cubic Hermite interpolant through the step ends (C backend, which
returns the step ends and their derivatives).  At an event time the value after the event
is returned.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["STATUSES", "Event", "SimulationResult"]

#: Final statuses of a run.
STATUSES = ("finished", "zeno", "max_events", "failed")

#: Kinds of events.
EVENT_KINDS = ("impact", "grazing", "contact", "release")


@dataclass(frozen=True)
class Event:
    """One event of a run: at ``time``, on ``wall`` (index) named ``wall_name``.

    ``kind`` is ``"impact"`` (the impact map was applied), ``"grazing"`` (the wall was
    reached with a normal speed below the grazing threshold: no impact), ``"contact"`` (the
    wall became an active constraint: resting or sliding contact) or ``"release"`` (the
    normal contact force reached zero and the body left the wall).  ``q`` is the
    configuration, ``v_minus`` and ``v_plus`` the velocities before and after, ``energy_change``
    ``E(v_plus) - E(v_minus)``, ``normal_speed`` the normal rate ``d psi/dt`` before the event.
    """

    time: float
    wall: int
    wall_name: str
    kind: str
    q: np.ndarray
    v_minus: np.ndarray
    v_plus: np.ndarray
    energy_change: float
    normal_speed: float

    def __repr__(self) -> str:
        return (
            f"Event({self.kind} at t={float(self.time)!r} on {self.wall_name!r},"
            f" normal speed {float(self.normal_speed):.3g},"
            f" dE={float(self.energy_change):.3g})"
        )


#: The continuous output of one step, a function of the (absolute) time.
Interpolant = Callable[[float], np.ndarray]


@dataclass
class SimulationResult:
    """The outcome of :func:`symmech.simulate.simulate` (see the module docstring)."""

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    events: list[Event]
    status: str
    message: str
    stats: dict[str, Any]
    segments: Sequence[tuple[float, float, Interpolant]] = field(default=(), repr=False)
    n: int = 0
    accumulation_time: float | None = None

    def __post_init__(self) -> None:
        self._starts: np.ndarray | None = None

    @property
    def y(self) -> np.ndarray:
        """The states (q, v) at the accepted times, shape (len(t), 2n)."""
        return np.hstack([self.q, self.v])

    @property
    def success(self) -> bool:
        """True when the run reached t_end (or stopped at an accumulation on purpose)."""
        return self.status in ("finished", "zeno")

    def impacts(self, wall: int | None = None) -> list[Event]:
        """The impact events (of one wall, if given)."""
        return [e for e in self.events if e.kind == "impact" and (wall is None or e.wall == wall)]

    def sol(self, t: float | Sequence[float] | np.ndarray) -> np.ndarray:
        """The state (q, v) at time(s) t from the continuous output, shape (2n,) or
        (len(t), 2n)."""
        ts = np.asarray(t, dtype=float)
        if not self.segments:
            raise ValueError("this result holds no continuous output")
        lo, hi = self.segments[0][0], self.segments[-1][1]
        if np.any(ts < lo) or np.any(ts > hi):
            raise ValueError(f"t outside the simulated interval [{lo!r}, {hi!r}]")
        if self._starts is None:
            self._starts = np.array([float(s[0]) for s in self.segments], dtype=float)
        flat = np.atleast_1d(ts)
        out = np.empty((flat.size, 2 * self.n))
        for i, ti in enumerate(flat):
            k = int(np.searchsorted(self._starts, ti, side="right")) - 1
            k = max(k, 0)
            while k + 1 < len(self.segments) and self.segments[k][1] < ti:
                k += 1
            t0, t1, dense = self.segments[k]
            out[i] = np.asarray(dense(min(max(ti, t0), t1)), dtype=float)
        return out[0] if ts.ndim == 0 else out

    __call__ = sol

    def __repr__(self) -> str:
        return (
            f"SimulationResult(status={self.status!r}, t_end={float(self.t[-1]):.6g},"
            f" steps={len(self.t)}, events={len(self.events)}, message={self.message!r})"
        )
