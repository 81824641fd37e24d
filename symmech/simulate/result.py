"""What a simulation returns: the accepted steps, the events, a status and statistics.

:class:`SimulationResult` holds the accepted step times and states (event times included:
the state just before an event, then the state just after it, at the same time), the list
of :class:`Event` records, the status (``"finished"``, ``"zeno"``, ``"max_events"``,
``"failed"``, ``"max_steps"``) with a message, and ``stats``.  ``res(t)`` (or
``res.sol(t)``) evaluates the continuous output: the integrator's own dense output of the
step containing t, or, where a method has none (rk4, and on the C backend DOP853 steps whose
dense stages were never made), the cubic Hermite interpolant through the step ends.  At an
event time the value after the event is returned.

Out of the result (:mod:`.table`, :mod:`.plotting`, :mod:`.animation`): ``res.sample(ts)``
(the dense output at chosen times, each event's instant twice: before and after),
``res.to_frame()`` / ``res.events_frame()`` (pandas), ``res.save(path)`` (CSV, Parquet or
NPZ; :func:`~symmech.simulate.table.load_result` reads it back), ``res.plot()`` and
``res.animate()`` (matplotlib).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, overload

import numpy as np

from symmech.simulate.protocol import EVENT_KINDS, RUN_STATES

if TYPE_CHECKING:
    from symmech.simulate.table import Samples

__all__ = ["STATUSES", "Event", "EventTable", "SimulationResult"]

#: Final statuses of a run (the run states of the C loop after ``running``).
STATUSES = RUN_STATES[1:]


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


class EventTable(Sequence[Event]):
    """The events of a run kept as the rows the C loop wrote; the :class:`Event` records
    are built on first access (a run whose events are never read never builds them).

    Each row of ``rows`` is ``time, energy change, normal speed, q, v_minus, v_plus``; each
    row of ``ids`` is ``wall, kind`` (an index into :data:`EVENT_KINDS`).  It compares
    equal to a list of the same events.
    """

    __slots__ = ("_built", "_n", "ids", "names", "rows")

    def __init__(self, rows: np.ndarray, ids: np.ndarray, names: Sequence[str], n: int):
        self.rows, self.ids, self.names, self._n = rows, ids, tuple(names), n
        self._built: list[Event] | None = None

    def _events(self) -> list[Event]:
        if self._built is None:
            n, names = self._n, self.names
            self._built = [
                Event(
                    time=float(row[0]),
                    wall=int(w),
                    wall_name=names[int(w)],
                    kind=EVENT_KINDS[int(kind)],
                    q=row[3 : 3 + n].copy(),
                    v_minus=row[3 + n : 3 + 2 * n].copy(),
                    v_plus=row[3 + 2 * n : 3 + 3 * n].copy(),
                    energy_change=float(row[1]),
                    normal_speed=float(row[2]),
                )
                for row, (w, kind) in zip(self.rows, self.ids, strict=True)
            ]
        return self._built

    def __len__(self) -> int:
        return len(self.rows)

    @overload
    def __getitem__(self, k: int) -> Event: ...

    @overload
    def __getitem__(self, k: slice) -> list[Event]: ...

    def __getitem__(self, k: int | slice) -> Event | list[Event]:
        return self._events()[k]

    def __iter__(self) -> Iterator[Event]:
        return iter(self._events())

    def __eq__(self, other: object) -> bool:
        if isinstance(other, EventTable):
            other = other._events()
        return isinstance(other, list) and self._events() == other

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return repr(self._events())


#: The continuous output of one step, a function of the (absolute) time.
Interpolant = Callable[[float], np.ndarray]


@dataclass
class SimulationResult:
    """The outcome of :func:`symmech.simulate.simulate` (see the module docstring)."""

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    events: Sequence[Event]
    status: str
    message: str
    stats: dict[str, Any]
    segments: Sequence[tuple[float, float, Interpolant]] = field(default=(), repr=False)
    n: int = 0
    accumulation_time: float | None = None
    #: The parameter values of the run, by name.
    params: dict[str, float] = field(default_factory=dict)
    #: Names of the coordinates, of the velocities (or quasi-velocities) and of the walls.
    coordinates: tuple[str, ...] = ()
    velocities: tuple[str, ...] = ()
    wall_names: tuple[str, ...] = ()
    #: The scene simulated (None for a result read from a file).
    scene: Any = field(default=None, repr=False, compare=False)
    #: The compiled functions at the run's parameters (energy, gaps), or None.
    functions: Any = field(default=None, repr=False, compare=False)
    #: Columns read from a file beside the states (``energy``, ``gap[wall]``), at ``t``.
    stored: dict[str, np.ndarray] = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self) -> None:
        self._starts: np.ndarray | None = None
        if not self.coordinates:
            self.coordinates = tuple(f"q{i}" for i in range(self.n))
        if not self.velocities:
            self.velocities = tuple(f"{c}_dot" for c in self.coordinates)

    def attach(self, scene: Any, params: Mapping[str, float], functions: Any) -> None:
        """Record what the run was made from (:func:`symmech.simulate.simulate` calls it):
        the scene, its parameter values and the compiled functions (for energy and gaps)."""
        self.scene, self.functions = scene, functions
        self.params = {str(k): float(v) for k, v in params.items()}
        # a Symbol's name is its printed form (the str printer costs microseconds a name)
        self.coordinates = tuple(_name(c) for c in scene.coordinates)
        self.velocities = tuple(_name(v) for v in scene.velocities)
        self.wall_names = tuple(functions.wall_names)

    def sample(self, ts: Sequence[float] | np.ndarray, *, events: bool = True) -> Samples:
        """The states at times ``ts`` from the continuous output, with each event inside
        ``[min(ts), max(ts)]`` at its exact time twice: the state before it and after it
        (:func:`symmech.simulate.table.sample`)."""
        from symmech.simulate.table import sample

        return sample(self, ts, events=events)

    def to_frame(self, ts: Sequence[float] | np.ndarray | None = None) -> Any:
        """The run as a pandas DataFrame, one row per accepted step (or per time of
        :meth:`sample` when ``ts`` is given): ``t``, the coordinates, the velocities,
        ``energy``, a ``gap[wall]`` per wall, and ``event``/``wall`` on the rows at an
        event (:func:`symmech.simulate.table.to_frame`)."""
        from symmech.simulate.table import to_frame

        return to_frame(self, ts)

    def events_frame(self) -> Any:
        """The events as a pandas DataFrame, one row per event
        (:func:`symmech.simulate.table.events_frame`)."""
        from symmech.simulate.table import events_frame

        return events_frame(self)

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the run to ``path``: ``.csv``, ``.parquet`` or ``.npz`` by its suffix, with
        its events, status, message, statistics and parameters
        (:func:`symmech.simulate.table.save`; read back with ``load_result``)."""
        from symmech.simulate.table import save

        return save(self, path)

    def plot(self, **options: Any) -> Any:
        """Coordinates, velocities, gaps and energy against time, events marked by kind
        (:func:`symmech.simulate.plotting.plot`); returns the matplotlib Figure."""
        from symmech.simulate.plotting import plot

        return plot(self, **options)

    def animate(self, **options: Any) -> Any:
        """The run drawn as the scene's drawing says, as a matplotlib animation
        (:func:`symmech.simulate.animation.animate`)."""
        from symmech.simulate.animation import animate

        return animate(self, **options)

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
            raise ValueError(
                "this result holds no continuous output (a result read from a file keeps"
                " only its accepted steps)"
            )
        lo, hi = self.segments[0][0], self.segments[-1][1]
        if not np.all((ts >= lo) & (ts <= hi)):  # NaN included
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


def _name(symbol: Any) -> str:
    """The printed name of a coordinate or velocity (``str`` of anything but a plain
    Symbol)."""
    return symbol.name if type(symbol).__name__ == "Symbol" else str(symbol)
