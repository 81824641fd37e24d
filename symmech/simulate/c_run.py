"""One run of the hybrid loop in generated C (``backend="c"``), from Python.

:func:`run_c` hands the loop of :mod:`.csim`'s library a state and its options and turns
what the loop wrote into a :class:`~.result.SimulationResult`.  The loop writes its accepted
steps, dense-output segments and events into buffers given by the caller; when they run
short it pauses at the top of an iteration and :func:`run_c` copies them out and lets it
continue, so a run's length is bounded by memory only.

The buffers, and the option and parameter vectors last used, belong to a
:class:`Workspace` kept per library and per thread (``threading.local``): a run allocates
nothing in Python but its results, and the addresses handed to C (``ndarray.ctypes.data``
costs about a microsecond each) are taken once.  Runs in different threads never share a
workspace.  Events are returned as an :class:`~.result.EventTable` whose
:class:`~.result.Event` records are built on first access.

The continuous output of the C backend is each step's own dense output (tsit5, rk45,
DOP853 where its dense stages were made) or the cubic Hermite interpolant through the
step's ends and their derivatives (rk4, and DOP853 steps with no event function to sample:
a scene without walls).
"""

from __future__ import annotations

import threading
import time as _time
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from symmech.simulate.csim import (
    EVENT_COUNTS,
    CLibrary,
    decode,
    info_entry,
    library,
    missing_mode,
    options_vector,
)
from symmech.simulate.hybrid import Options
from symmech.simulate.protocol import EVENT_KINDS, INFO_HEAD
from symmech.simulate.result import STATUSES, EventTable, SimulationResult
from symmech.simulate.system import HybridSystem, Mode, SimulationError

__all__ = ["Workspace", "run_c"]

#: rows of the step and segment buffers, and of the event buffer per wall, of a workspace
STEP_ROWS = 512
EVENT_ROWS_PER_WALL = 100


class Workspace:
    """The buffers one thread hands one library's C loop, with their addresses."""

    def __init__(self, lib: CLibrary, n: int):
        walls = max(lib.spec.walls, 1)
        ny = 2 * n
        # the loop pauses unless 4 step rows, 2 segments and 100 walls + 8 event rows are free
        room_ev = 100 * walls + 8
        self.rec_cap = max(STEP_ROWS, 8)
        self.ev_cap = max(4 * (EVENT_ROWS_PER_WALL * walls + 8), 2 * room_ev)
        self.rec = np.empty((self.rec_cap, ny + 1))
        self.seg = np.empty((self.rec_cap, 4 + 8 * ny))
        self.ev = np.empty((self.ev_cap, 3 + 3 * n))
        self.evi = np.empty((self.ev_cap, 2), dtype=np.intc)
        self.counts = np.zeros(3, dtype=np.int64)
        self.info = np.zeros(INFO_HEAD + ny)
        self.y0 = np.zeros(ny)
        self.addr = tuple(
            a.ctypes.data
            for a in (self.rec, self.seg, self.ev, self.evi, self.counts, self.info, self.y0)
        )
        # the option and parameter vectors of the last run, kept with their addresses
        self.options_key: tuple | None = None
        self.options: tuple[int, np.ndarray, int] = (0, np.zeros(0), 0)
        self.values: dict[str, float] | None = None
        self.P: tuple[np.ndarray, int] = (np.zeros(0), 0)

    def option_vector(
        self, opts: Options, method: str, max_step: float, t0: float
    ) -> tuple[int, int]:
        """The method index and the address of the options vector (:func:`.csim.options_vector`)."""
        key = (opts, method, max_step, t0)
        if key != self.options_key:
            index, vec = options_vector(opts, method, max_step, t0)
            self.options, self.options_key = (index, vec, vec.ctypes.data), key
        return self.options[0], self.options[2]

    def parameters(self, lib: CLibrary, values: dict[str, float]) -> int:
        """The address of the library's parameter vector for ``values``."""
        if values != self.values:
            P = lib.parameters(values)
            self.P, self.values = (P, P.ctypes.data), dict(values)
        return self.P[1]


def workspace(lib: CLibrary, n: int) -> Workspace:
    """This thread's workspace for ``lib``."""
    local = lib.__dict__.get("_workspaces")
    if local is None:
        local = lib.__dict__.setdefault("_workspaces", threading.local())
    ws = getattr(local, "ws", None)
    if ws is None:
        ws = local.ws = Workspace(lib, n)
    return ws


class _Dense:
    """The continuous output of one C step on ``[t0, t1]`` (absolute time), the step of
    size ``h`` starting at ``t0``: the method's own dense output (type 1: ``y0 + theta (Q0
    + theta (Q1 + theta (Q2 + theta Q3)))``, tsit5 and rk45; type 2: DOP853's
    ``y0 + theta (F0 + (1 - theta)(F1 + theta (F2 + ...)))``, HNW I, II.10), or (type 0:
    rk4, and DOP853 steps whose dense stages were never needed) the cubic Hermite
    interpolant of ``y0, f0, y1, f1``."""

    __slots__ = ("c", "h", "kind", "t0", "t1", "y0")

    def __init__(self, row: np.ndarray, size: int):
        self.t0, self.t1, self.h, self.kind = (
            float(row[0]),
            float(row[1]),
            float(row[2]),
            int(row[3]),
        )
        self.y0 = row[4 : 4 + size]
        self.c = row[4 + size :].reshape(7, size)

    def __call__(self, t: float) -> np.ndarray:
        s = (t - self.t0) / self.h
        s1 = 1 - s
        c = self.c
        if self.kind == 1:
            acc = c[3]
            for r in (2, 1, 0):
                acc = acc * s + c[r]
            return self.y0 + s * acc
        if self.kind == 2:
            acc = c[6]
            for r in range(5, -1, -1):
                acc = c[r] + (s1 if r % 2 == 0 else s) * acc
            return self.y0 + s * acc
        h = self.h
        return (
            (1 + 2 * s) * s1 * s1 * self.y0
            + s * s1 * s1 * h * c[0]
            + s * s * (3 - 2 * s) * c[1]
            + s * s * (s - 1) * h * c[2]
        )


class _Segments(Sequence):
    """The steps' continuous outputs, built on first access (most runs never ask)."""

    def __init__(self, rows: np.ndarray, size: int):
        self.rows, self.size = rows, size

    def __len__(self) -> int:
        return len(self.rows)

    def __getitem__(self, k: int) -> tuple[float, float, _Dense]:  # type: ignore[override]
        r = self.rows[k]
        return float(r[0]), float(r[1]), _Dense(r, self.size)


def run_c(
    system: HybridSystem,
    values: dict[str, float],
    y0: np.ndarray,
    t0: float,
    opts: Options,
    *,
    method: str = "dop853",
    max_step: float,
) -> SimulationResult:
    """One hybrid run in the compiled C loop (arguments validated by
    :func:`symmech.simulate.simulate`); the result has the form of the NumPy loop's.

    A run that reaches a set of walls whose contact mode the library lacks stops there;
    the mode is built in (:meth:`~symmech.simulate.system.HybridSystem.add_c_mode`) and
    the run starts again (a run is deterministic, so the result is the one a library
    built with every mode gives)."""
    while True:
        result, needed = _run_once(system, values, y0, t0, opts, method, max_step)
        if needed is None:
            return result
        try:
            system.add_c_mode(needed)
        except SimulationError as exc:
            return replace(result, message=str(exc))


def _run_once(
    system: HybridSystem,
    values: dict[str, float],
    y0: np.ndarray,
    t0: float,
    opts: Options,
    method: str,
    max_step: float,
) -> tuple[SimulationResult, Mode | None]:
    """One run with the library of the system's current contact modes, and the mode it
    stopped for (None if none)."""
    clock = _time.perf_counter()
    lib = library(system)
    spec = lib.spec
    n, names = system.n, spec.wall_names
    ny = 2 * n
    ws = workspace(lib, n)
    index, vec_addr = ws.option_vector(opts, method, max_step, t0)
    p_addr = ws.parameters(lib, values)
    rec_a, seg_a, ev_a, evi_a, counts_a, info_a, y0_a = ws.addr
    ws.y0[:] = y0
    handle = lib.new(index, vec_addr, p_addr, 1)
    if not handle:
        raise MemoryError("the C simulator could not allocate its work arrays")
    recs, segs, evs, evis = [], [], [], []
    counts = ws.counts
    try:
        lib.begin(handle, t0, y0_a)
        while True:
            paused = lib.run(
                handle, rec_a, ws.rec_cap, seg_a, ws.rec_cap, ev_a, evi_a, ws.ev_cap, counts_a
            )
            k_rec, k_seg, k_ev = int(counts[0]), int(counts[1]), int(counts[2])
            recs.append(ws.rec[:k_rec].copy())
            segs.append(ws.seg[:k_seg].copy())
            evs.append(ws.ev[:k_ev].copy())
            evis.append(ws.evi[:k_ev].copy())
            if not paused:
                break
            if k_rec == k_seg == k_ev == 0:  # the buffers cannot hold one iteration
                raise RuntimeError("the C simulator paused without progress")
        lib.info(handle, info_a)
    finally:
        lib.free(handle)
    info = ws.info
    needed = missing_mode(info, spec.modes)
    status, message, accumulation = decode(info, names, opts.t_end)
    records = recs[0] if len(recs) == 1 else np.concatenate(recs)
    events = EventTable(
        evs[0] if len(evs) == 1 else np.concatenate(evs),
        evis[0] if len(evis) == 1 else np.concatenate(evis),
        names,
        n,
    )
    segments = _Segments(segs[0] if len(segs) == 1 else np.concatenate(segs), ny)
    by_kind = dict(zip(EVENT_KINDS, (int(x) for x in info[EVENT_COUNTS]), strict=True))
    stats = {
        "steps": int(info_entry(info, "steps")),
        "rejected_steps": int(info_entry(info, "rejected_steps")),
        "rhs_calls": int(info_entry(info, "rhs_calls")),
        "jacobian_calls": 0,
        "wall_time": _time.perf_counter() - clock,
        "constraint_drift": float(info_entry(info, "constraint_drift")),
        "impact_condition": float(info_entry(info, "impact_condition")),
        "energy_drift": float(info_entry(info, "energy_drift")) if spec.energy_conserved else None,
        "impacts": by_kind["impact"],
        "grazing": by_kind["grazing"],
        "contacts": by_kind["contact"],
        "releases": by_kind["release"],
    }
    assert status in STATUSES
    result = SimulationResult(
        t=records[:, 0],
        q=records[:, 1 : 1 + n],
        v=records[:, 1 + n :],
        events=events,
        status=status,
        message=message,
        stats=stats,
        segments=segments,
        n=n,
        accumulation_time=accumulation,
    )
    return result, needed
