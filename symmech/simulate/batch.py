"""``simulate_batch``: many initial states through the compiled C loop, no Python per run.

>>> import numpy as np, symmech as sm
>>> from symmech.examples import bouncing_ball
>>> res = sm.simulate_batch(bouncing_ball(), [[1.0], [2.0]], [[0.0], [0.0]], 10.0,
...                         params={"m": 1, "g": 9.81, "alpha": 0.5}, contact="stop")
>>> res.statuses.tolist()
['zeno', 'zeno']
>>> np.round(res.accumulation_time, 6).tolist()   # sqrt(2h/g) (1 + 1/2)/(1 - 1/2)
[1.354571, 1.915653]

The N rows of ``Q0`` and ``V0`` are checked as :func:`symmech.simulate.simulate` checks
one state (the message names the argument and the row), then run in chunks: one call of
the C loop per chunk (:mod:`.csim`, the same code as ``simulate(..., backend="c")``, so a
row's result equals that run's bit for bit), the chunks in Python threads (ctypes
releases the GIL).  Each run is independent of the others, so the results do not depend
on the number of threads.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from symmech.scene import Scene
from symmech.simulate.arguments import count, states
from symmech.simulate.backend import backend_named
from symmech.simulate.csim import (
    EVENT_COUNTS,
    FINISHED_CODE,
    REACHED_END_CODE,
    CLibrary,
    decode,
    info_entry,
    library,
    missing_mode,
    options_vector,
)
from symmech.simulate.functions import Functions
from symmech.simulate.options import RunOptions
from symmech.simulate.parameters import check_parameters
from symmech.simulate.protocol import INFO, INFO_HEAD, slot
from symmech.simulate.result import EVENT_KINDS, STATUSES
from symmech.simulate.run import system_for, velocity_in_D
from symmech.simulate.system import SimulationError

__all__ = ["BatchResult", "simulate_batch"]

#: the head of the info row of a run that reached t_end (status finished, reason t_end)
_REACHED_ROW = np.zeros(INFO_HEAD)
_REACHED_ROW[slot(INFO, "status")] = FINISHED_CODE
_REACHED_ROW[slot(INFO, "reason")] = REACHED_END_CODE
_STATUS, _REASON = slot(INFO, "status"), slot(INFO, "reason")


@dataclass(frozen=True)
class BatchResult:
    """Final states and counts of N runs (row i: the run from ``Q0[i], V0[i]``).

    ``t``, ``q``, ``v`` are each run's last output sample (``res.t[-1]``, ``res.q[-1]``,
    ``res.v[-1]`` of the single run: at a stop inside an event, the state before it).

    ``status`` holds indices into :data:`~symmech.simulate.result.STATUSES`
    (``statuses`` gives the names); ``events[:, k]`` counts the events of kind
    ``EVENT_KINDS[k]`` (impact, grazing, contact, release); ``accumulation_time`` is NaN
    where a run did not stop at an accumulation of impacts."""

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    status: np.ndarray
    events: np.ndarray
    accumulation_time: np.ndarray
    steps: np.ndarray
    messages: tuple[str, ...]
    status_names: tuple[str, ...] = STATUSES
    event_kinds: tuple[str, ...] = EVENT_KINDS

    @property
    def statuses(self) -> np.ndarray:
        """The status names, shape (N,)."""
        return np.array(self.status_names, dtype=object)[self.status]

    @property
    def impacts(self) -> np.ndarray:
        """Impacts per run, shape (N,)."""
        return self.events[:, 0]

    def to_frame(
        self, coordinates: Sequence[str] | None = None, velocities: Sequence[str] | None = None
    ) -> Any:
        """One row per run as a pandas DataFrame (:func:`symmech.simulate.table.batch_frame`)."""
        from symmech.simulate.table import batch_frame

        return batch_frame(self, coordinates, velocities)

    def save(self, path: str | os.PathLike[str], **names: Any) -> Path:
        """Write :meth:`to_frame` (``names``: its arguments) as CSV or Parquet by the suffix
        (:func:`symmech.simulate.table.save_frame`)."""
        from symmech.simulate.table import save_frame

        return save_frame(self.to_frame(**names), path)


def simulate_batch(
    scene: Scene,
    Q0: Any,
    V0: Any,
    t_end: float,
    *,
    params: Mapping[str, float] | Any = None,
    options: RunOptions | None = None,
    threads: int | None = None,
    strategy: str = "auto",
    definitions: Mapping | None = None,
    **run_options: Any,
) -> BatchResult:
    """Run ``simulate(scene, Q0[i], V0[i], t_end, backend="c", ...)`` for every row i in
    the compiled C loop and return the final states, statuses and event counts (see the
    module docstring).  The run options are :func:`symmech.simulate.simulate`'s
    (:class:`~symmech.simulate.options.RunOptions`, as keywords or ``options``).
    ``threads``: the number of Python threads running chunks of rows (default: every
    core); the results do not depend on it."""
    if not isinstance(scene, Scene):
        raise SimulationError(f"scene: expected a symmech.Scene, got {type(scene).__name__}")
    engine = backend_named("c", "batch")
    o = RunOptions.build(options, run_options)
    tend = o.end(t_end)
    method = engine.method(o.method)
    n = scene.n
    Q = states(Q0, n, "Q0", rows=True)
    V = states(V0, n, "V0", rows=True)
    if Q.shape[0] != V.shape[0]:
        raise SimulationError(f"Q0 and V0: {Q.shape[0]} rows against {V.shape[0]} rows")
    t0f, rtol_f, atol_f = o.t0, o.rtol, o.atol
    if threads is None:
        threads = os.cpu_count() or 1
    threads = count(threads, "threads")
    values = check_parameters(scene, params)
    system = system_for(scene, "c", strategy, definitions)
    fns = Functions(system, values)
    index, vec = options_vector(o.loop(tend), method, o.step_cap(tend), t0f)
    _check_rows(fns, values, Q, V, t0f, rtol_f, atol_f)
    N = Q.shape[0]
    Y = np.ascontiguousarray(np.hstack([Q, V]))
    info = np.zeros((N, INFO_HEAD + 2 * n))
    rows = np.arange(N)
    while rows.size:  # runs that stopped for a contact mode run again with it built in
        lib = library(system)
        run = partial(_run_rows, lib, lib.parameters(values), t0f, index, vec)
        info[rows] = run(np.ascontiguousarray(Y[rows]), threads)
        wanted = [missing_mode(info[k], lib.spec.modes) for k in rows]
        try:
            for mode in sorted({m for m in wanted if m is not None}):
                system.add_c_mode(mode)
        except SimulationError:
            break  # those rows stay stopped, with the loop's message
        rows = rows[[m is not None for m in wanted]]
    # a run that reached t_end decodes to ("finished", "reached t_end = ...", None): only
    # the others are decoded one by one (a per-row decode would cost more than a short run)
    finished, reached = decode(_REACHED_ROW, fns.wall_names, tend)[:2]
    status = np.full(N, STATUSES.index(finished), dtype=np.int64)
    messages = [reached] * N
    acc = np.full(N, np.nan)
    unusual = (info[:, _STATUS] != FINISHED_CODE) | (info[:, _REASON] != REACHED_END_CODE)
    for k in np.flatnonzero(unusual):
        st, msg, a = decode(info[k], fns.wall_names, tend)
        status[k], messages[k] = STATUSES.index(st), msg
        acc[k] = np.nan if a is None else a
    return BatchResult(
        t=info_entry(info, "last_t").copy(),
        q=info[:, INFO_HEAD : INFO_HEAD + n].copy(),
        v=info[:, INFO_HEAD + n :].copy(),
        status=status,
        events=info[:, EVENT_COUNTS].astype(np.int64),
        accumulation_time=acc,
        steps=info_entry(info, "steps").astype(np.int64),
        messages=tuple(messages),
    )


def _run_rows(
    lib: CLibrary, P: np.ndarray, t0: float, index: int, vec: np.ndarray, Y: np.ndarray,
    threads: int,
) -> np.ndarray:  # fmt: skip
    """The info rows of runs from the rows of ``Y``, in chunks on ``threads`` threads (more
    chunks than threads, taken in turn: runs of unequal length balance out)."""
    N = Y.shape[0]
    info = np.zeros((N, lib.spec.info_size))
    pieces = min(N, threads if threads == 1 else 8 * threads)
    bounds = np.linspace(0, N, pieces + 1).astype(int)

    def chunk(k: int) -> int:
        lo, hi = int(bounds[k]), int(bounds[k + 1])
        if hi <= lo:
            return 0
        block = np.zeros((hi - lo, info.shape[1]))
        status = lib.batch(hi - lo, Y[lo:hi].ctypes.data, t0, index, vec.ctypes.data,
                           P.ctypes.data, block.ctypes.data)  # fmt: skip
        info[lo:hi] = block
        return int(status)

    with ThreadPoolExecutor(max_workers=min(threads, pieces)) as pool:
        codes = list(pool.map(chunk, range(len(bounds) - 1)))
    if any(codes):
        raise MemoryError("the C simulator could not allocate its work arrays")
    return info


def _check_rows(
    fns: Functions,
    values: Mapping[str, float],
    Q: np.ndarray,
    V: np.ndarray,
    t0: float,
    rtol: float,
    atol: float,
) -> None:
    """psi >= 0 at every wall and v in D for every row (as :func:`simulate` checks one
    state); a small residual of v is projected away with P, in place, by the same call
    :func:`simulate` makes, so that a row runs exactly as the single run would."""
    mod = fns.system.free
    p = {k: values[k] for k in mod.parameters}
    for w in range(fns.walls):
        psi = np.asarray(mod.psi(Q, p, wall=w, t=np.full(Q.shape[0], t0)), dtype=float)
        bad = psi.reshape(-1) < -10 * atol
        if bad.any():
            row = int(np.argmax(bad))
            raise SimulationError(
                f"Q0 row {row} is on the wrong side of wall {fns.wall_names[w]!r}:"
                f" psi = {float(psi.reshape(-1)[row])!r} < 0"
            )
    if fns.constrained:
        for i in range(Q.shape[0]):
            V[i] = velocity_in_D(fns, t0, Q[i], V[i], rtol, atol, f"V0 row {i}")
