"""Running a sweep's chunks: in local threads, or as Dask tasks on a cluster.

Both routes take the chunks of a :class:`~symmech.sweep.chunks.Plan` and hand each finished
chunk's table to a ``sink`` (which keeps it or writes it to the store) in the order they
finish; at most ``window`` chunks are prepared and not yet finished at any time, so memory
stays flat however long the sweep.

* Local: a pool of threads; each prepares its chunk (Python), runs it through
  :func:`~symmech.sweep.worker.run_chunk` (the C loop, which releases the GIL) and tables
  it.  A chunk that cannot allocate the loop's work arrays becomes ``"failed"`` rows.
* Dask: the client prepares each chunk and submits
  :func:`~symmech.sweep.worker.run_chunk` with the library source, scattered once to every
  worker (each worker process compiles or loads it once).  A task that raises, or whose
  workers keep dying (Dask's ``KilledWorker``), becomes ``"failed"`` rows naming the error;
  a worker lost mid-sweep costs only the chunks it was running (Dask resubmits them), never
  a finished one (the client holds those).
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable, Iterable
from concurrent.futures import FIRST_COMPLETED, Future, ThreadPoolExecutor, wait
from typing import Any, TextIO

from symmech.sweep.chunks import Plan, finish, prepare
from symmech.sweep.worker import run_chunk

__all__ = ["Progress", "run_dask", "run_local"]

Chunk = tuple[int, int, int]  # (index, lo, hi)
Sink = Callable[[int, dict], None]


class Progress:
    """A one-line progress bar on ``stream`` (stderr): runs done, rate, time left.

    ``enabled=None`` shows it only when the stream is a terminal and the sweep has run for
    more than ``delay`` seconds (a short sweep prints nothing)."""

    def __init__(
        self, total: int, enabled: bool | None, stream: TextIO | None = None, delay: float = 1.0
    ):
        self.stream = stream if stream is not None else sys.stderr
        tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.enabled = tty if enabled is None else bool(enabled)
        self.delay = 0.0 if enabled else delay
        self.total = total
        self.done = 0
        self.start = time.perf_counter()
        self._last = -math.inf
        self._shown = False

    def update(self, runs: int) -> None:
        """Count ``runs`` more finished runs and redraw (at most 5 times a second)."""
        self.done += runs
        now = time.perf_counter()
        elapsed = now - self.start
        if not self.enabled or elapsed < self.delay:
            return
        if now - self._last < 0.2 and self.done < self.total:
            return
        self._last = now
        rate = self.done / elapsed if elapsed > 0 else 0.0
        left = (self.total - self.done) / rate if rate > 0 else math.inf
        width = 30
        filled = int(width * self.done / max(self.total, 1))
        bar = "#" * filled + "." * (width - filled)
        eta = f"{left:.0f} s left" if math.isfinite(left) else ""
        self.stream.write(
            f"\rsweep [{bar}] {self.done}/{self.total} runs, {rate:.0f} runs/s {eta}   "
        )
        self.stream.flush()
        self._shown = True

    def close(self) -> None:
        """End the bar's line (if it was drawn)."""
        if self._shown:
            self.stream.write("\n")
            self.stream.flush()


def _local_task(plan: Plan, chunk: Chunk) -> tuple[int, dict]:
    k, lo, hi = chunk
    prep = prepare(plan, k, lo, hi)
    try:
        info, error = run_chunk(plan.source, prep.chunk, plan.loop), None
    except MemoryError as exc:
        info, error = None, f"chunk {k}: {exc}"
    return k, finish(plan, prep, info, error)


def run_local(plan: Plan, chunks: Iterable[Chunk], threads: int, sink: Sink) -> None:
    """Run ``chunks`` in ``threads`` threads, at most ``2 threads`` in flight."""
    todo = iter(chunks)
    window = 2 * threads
    with ThreadPoolExecutor(max_workers=threads) as pool:
        pending: set[Future] = set()

        def fill() -> None:
            while len(pending) < window:
                nxt = next(todo, None)
                if nxt is None:
                    return
                pending.add(pool.submit(_local_task, plan, nxt))

        fill()
        while pending:
            finished, _ = wait(pending, return_when=FIRST_COMPLETED)
            for fut in finished:
                pending.discard(fut)
                k, cols = fut.result()
                sink(k, cols)
            fill()


def run_dask(
    plan: Plan, chunks: Iterable[Chunk], client: Any, window: int, sink: Sink, tag: str
) -> None:
    """Run ``chunks`` as Dask tasks on ``client``'s cluster, at most ``window`` in flight.
    ``tag`` makes the task keys of this sweep (``symmech-sweep-<tag>-<chunk>``)."""
    from distributed import as_completed

    source = client.scatter(plan.source, broadcast=True, hash=False)
    todo = iter(chunks)
    preps: dict[str, Any] = {}
    # results are fetched by the client's event loop as they complete (no blocking
    # ``result()`` round trip per chunk from this thread); a failed chunk yields its
    # exception instead of raising
    queue = as_completed(with_results=True, raise_errors=False)

    def submit() -> bool:
        nxt = next(todo, None)
        if nxt is None:
            return False
        k, lo, hi = nxt
        prep = prepare(plan, k, lo, hi)
        key = f"symmech-sweep-{tag}-{k}"
        fut = client.submit(run_chunk, source, prep.chunk, plan.loop, key=key, pure=False)
        preps[fut.key] = prep
        queue.add(fut)
        return True

    for _ in range(window):
        if not submit():
            break
    for fut, result in queue:
        prep = preps.pop(fut.key)
        if fut.status == "finished":
            info, error = result, None
        else:  # "error": (type, exception, traceback); "cancelled": the exception
            exc = result[1] if isinstance(result, tuple) else result
            info = None
            error = f"chunk {prep.index} failed on the cluster: {type(exc).__name__}: {exc}"
        fut.release()
        sink(prep.index, finish(plan, prep, info, error))
        submit()
