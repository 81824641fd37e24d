"""Running a sweep's chunks: in local threads, or as Dask tasks on a cluster.

Both routes run :func:`~symmech.sweep.chunks.chunk_table` for each chunk (check, run the C
loop, table: the whole life of the chunk where it runs) and hand each finished chunk's
Arrow table to a ``sink`` (which keeps it or writes it to the store) in the order they
finish; at most ``window`` chunks are in flight at any time, so memory stays flat however
long the sweep.

* Local: a pool of threads (the C loop releases the GIL).
* Dask: the plan is scattered once to every worker (it pickles to the scene, the generated
  source and the options; each worker process compiles or loads the code once) and each
  chunk is a task taking its grid rows.  The client only collects tables, so its work does
  not grow with the number of workers.  A task that raises, or whose workers keep dying
  (Dask's ``KilledWorker``), becomes ``"failed"`` rows naming the error; a worker lost
  mid-sweep costs only the chunks it was running (Dask resubmits them), never a finished
  one (the client holds those).
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterable
from concurrent.futures import FIRST_COMPLETED, Future, ThreadPoolExecutor, wait
from typing import Any, TextIO

import numpy as np

from symmech.sweep.chunks import Plan, chunk_table, failed_table

__all__ = ["Progress", "run_dask", "run_local"]

Chunk = tuple[int, int, int]  # (index, lo, hi)
Sink = Callable[[int, Any], None]  # (chunk index, its Arrow table)


class Progress:
    """A progress bar on ``stream`` (stderr): runs done, rate, time left (tqdm, the
    ``sweep`` extra; without tqdm, no bar).

    ``enabled=None`` shows it only when the stream is a terminal and the sweep has run for
    more than ``delay`` seconds (a short sweep prints nothing)."""

    def __init__(
        self, total: int, enabled: bool | None, stream: TextIO | None = None, delay: float = 1.0
    ):
        self.stream = stream if stream is not None else sys.stderr
        tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.enabled = tty if enabled is None else bool(enabled)
        self.total = total
        self._bar: Any = None
        if self.enabled:
            try:
                from tqdm import tqdm
            except ImportError:  # the bar is a convenience: the sweep runs without it
                return
            self._bar = tqdm(
                total=total,
                file=self.stream,
                desc="sweep",
                unit="run",
                delay=0.0 if enabled else delay,
                mininterval=0.2,
                dynamic_ncols=tty,
            )

    def update(self, runs: int) -> None:
        """Count ``runs`` more finished runs (tqdm redraws at most 5 times a second)."""
        if self._bar is not None:
            self._bar.update(runs)

    def close(self) -> None:
        """End the bar's line (if it was drawn)."""
        if self._bar is not None:
            self._bar.close()


def run_local(
    plan: Plan, grid: np.ndarray, chunks: Iterable[Chunk], threads: int, sink: Sink
) -> None:
    """Run ``chunks`` of the ``grid``'s rows in ``threads`` threads, at most ``2 threads``
    in flight."""
    todo = iter(chunks)
    window = 2 * threads
    with ThreadPoolExecutor(max_workers=threads) as pool:
        pending: dict[Future, int] = {}

        def fill() -> None:
            while len(pending) < window:
                nxt = next(todo, None)
                if nxt is None:
                    return
                k, lo, hi = nxt
                pending[pool.submit(chunk_table, plan, k, lo, grid[lo:hi])] = k

        fill()
        while pending:
            finished, _ = wait(pending, return_when=FIRST_COMPLETED)
            # in chunk order: a failed chunk stops the sweep before any later chunk that
            # finished beside it is stored, whatever the threads' timing
            for fut in sorted(finished, key=pending.__getitem__):
                sink(pending.pop(fut), fut.result())
            fill()


def _failure(result: Any) -> BaseException | None:
    """The exception of a failed task as ``as_completed(raise_errors=False)`` yields it
    (an error: (type, exception, traceback); cancelled: the exception), else None."""
    if isinstance(result, BaseException):
        return result
    if isinstance(result, tuple) and len(result) == 3 and isinstance(result[1], BaseException):
        return result[1]
    return None


def run_dask(
    plan: Plan,
    grid: np.ndarray,
    chunks: Iterable[Chunk],
    client: Any,
    window: int,
    sink: Sink,
    tag: str,
) -> None:
    """Run ``chunks`` of the ``grid``'s rows as Dask tasks on ``client``'s cluster, at
    most ``window`` in flight.  ``tag`` makes the task keys of this sweep
    (``symmech-sweep-<tag>-<chunk>``)."""
    from distributed import as_completed

    shared = client.scatter(plan, broadcast=True, hash=False)
    todo = iter(chunks)
    spans: dict[str, Chunk] = {}
    # results are fetched by the client's event loop as they complete (no blocking
    # ``result()`` round trip per chunk from this thread); a failed chunk yields its
    # exception instead of raising
    queue = as_completed(with_results=True, raise_errors=False)

    def submit() -> bool:
        nxt = next(todo, None)
        if nxt is None:
            return False
        k, lo, hi = nxt
        key = f"symmech-sweep-{tag}-{k}"
        fut = client.submit(chunk_table, shared, k, lo, grid[lo:hi], key=key, pure=False)
        spans[fut.key] = nxt
        queue.add(fut)
        return True

    for _ in range(window):
        if not submit():
            break
    for fut, result in queue:
        k, lo, hi = spans.pop(fut.key)
        # what came back decides, not ``fut.status``: a worker that dies after its result
        # was fetched sends the future back to "pending" (Dask would recompute it)
        exc = _failure(result)
        if exc is None:
            table = result
        else:
            error = f"chunk {k} failed on the cluster: {type(exc).__name__}: {exc}"
            table = failed_table(plan, k, lo, grid[lo:hi], error)
        fut.release()
        sink(k, table)
        submit()
