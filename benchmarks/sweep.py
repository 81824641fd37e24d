"""Benchmark: ``sm.sweep`` on one thread, on every local core, and on a Dask LocalCluster.

For the bouncing ball and the text 001 ellipse (their built-in cases, ``contact`` as the
case runs: persistent), ``--runs`` runs over a grid of initial states (one parameter
vector, so the baseline below runs the same thing) go through

* **baseline**: ``sm.simulate_batch(..., threads=1)``: the bare C batch loop, one call,
  no table, no per-run Python (and the same on every core: what the machine allows, so a
  loaded machine shows in this row, not as the sweep's overhead);
* **sweep, 1 thread**: ``sm.sweep(..., threads=1)``;
* **sweep, local**: ``sm.sweep(..., threads=<cores>)``;
* **sweep, Dask**: ``sm.sweep(..., client=Client(LocalCluster(n_workers=<cores>,
  processes=True, threads_per_worker=1)))`` with chunks of ``--dask-chunk`` runs
  (default 10^4); the cluster is started and the library loaded on every worker (one small
  sweep) before the clock starts;
* **floor**: the same sweep's ``run_chunk`` calls alone as Dask tasks, all submitted at
  once and gathered (no checks, no table): the cost of going through Dask at all on this
  machine, where the scheduler and the client share the cores with the workers.

Each timed route runs ``--repeat`` times (default 3) and its shortest time is kept, the
baseline's too (load from elsewhere only slows a run down).  Printed per route: runs per
second; seconds per run; the route's overhead per run over the baseline's CPU time per
run (``(workers x T_route - T_baseline) / N``, as a fraction of the baseline's time per
run); the parallel efficiency ``T_1 thread / (workers x T_route)``; and
``simulate_batch``'s time on as many threads over the route's (the route's cost over the
bare C loop whatever the machine's load).  Targets (issue 15):
local parallel efficiency >= 80% on 2 cores, Dask overhead < 10% of run time at chunks of
10^4 runs.  Memory: the resident set size of each Dask worker after a sweep of N runs and
after one of ``--grow`` x N runs (flat if the results are streamed, not held).  Load
independent: the share of a 1-thread sweep's CPU time spent outside the C loop (Python,
holding the GIL), from CPU clocks, and the Amdahl bound it sets on the local efficiency;
and, per route, the CPU time of every process it uses (on Dask: the client with the
scheduler it hosts, the workers and their nannies) beyond the C loop's, as a share of the
C loop's (the overhead on an otherwise idle machine; on a real cluster the client's and
scheduler's share leaves the workers' cores).
``--big N`` also runs an N-run ellipse sweep locally and on the cluster, reports both
times and whether the tables are identical (bit for bit).

Run from the repository root: ``python3 benchmarks/sweep.py`` (about 8 minutes on 2
cores), ``python3 benchmarks/sweep.py --big 100000``.  Timings on a shared machine are
indicative; nothing here is asserted by the tests.
"""

from __future__ import annotations

import argparse
import os
import time
from functools import partial

import numpy as np

import symmech as sm
from symmech.bench.cases import case


def _grid(name: str, runs: int) -> dict[str, np.ndarray]:
    """Initial states around the case's: the ball's height, the ellipse's angle."""
    if name == "bouncing_ball":
        return {"y0": np.linspace(0.5, 2.0, runs)}
    return {"theta0": np.linspace(0.0, np.pi, runs)}


def _kwargs(name: str) -> dict:
    c = case(name)
    return {"params": c.params(), "q0": list(c.q0), "v0": list(c.v0)}


def _states(name: str, grid: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    c = case(name)
    N = len(next(iter(grid.values())))
    Q = np.tile(np.array(c.q0, dtype=float), (N, 1))
    V = np.tile(np.array(c.v0, dtype=float), (N, 1))
    column = "y0" if name == "bouncing_ball" else "theta0"
    Q[:, -1 if name == "bouncing_ball" else 2] = grid[column]
    return Q, V


def _timed(fn, *args, **kwargs):
    start = time.perf_counter()
    out = fn(*args, **kwargs)
    return time.perf_counter() - start, out


#: Each timed route runs this many times and reports its shortest time (``--repeat``):
#: other load on the machine only ever slows a run down.
REPEAT = 3


def _best(fn, *args, **kwargs):
    """(shortest time of :data:`REPEAT` runs, the last run's output)."""
    times, out = [], None
    for _ in range(REPEAT):
        elapsed, out = _timed(fn, *args, **kwargs)
        times.append(elapsed)
    return min(times), out


def _rss(client) -> list[float]:
    import psutil

    def rss() -> float:
        return psutil.Process().memory_info().rss / 2**20

    return sorted(client.run(rss).values())


def _serial_share(scene, grid, t_end: float, kw: dict) -> float:
    """The share of a 1-thread sweep's CPU time spent outside the C loop (Python holding
    the GIL: checks, tables), from CPU clocks, so the machine's load does not enter."""
    _install_c_clock()
    cpu, c_loop = _cpu_now()
    sm.sweep(scene, grid, t_end, threads=1, **kw)
    after = _cpu_now()
    total = after[0] - cpu
    return (total - (after[1] - c_loop)) / total


def _dask_floor(client, scene, grid, t_end: float, kw: dict, chunk: int) -> float:
    """Wall time of the sweep's C work alone as Dask tasks: the very ``run_chunk`` calls of
    a sweep in chunks of ``chunk`` (captured from a 1-thread sweep), submitted at once
    with the library scattered, results gathered; no checks, no table.  What any route
    through Dask costs on this machine, whatever the sweep does around it."""
    from symmech.sweep import chunks, worker

    calls = []
    real = worker.run_chunk  # the C loop itself, whatever clock wraps chunks.run_chunk

    def capture(*args):
        calls.append(args)
        return real(*args)

    installed = chunks.run_chunk
    chunks.run_chunk = capture
    try:
        sm.sweep(scene, grid, t_end, threads=1, chunk=chunk, **kw)
    finally:
        chunks.run_chunk = installed
    source = client.scatter(calls[0][0], broadcast=True, hash=False)
    client.gather([client.submit(real, source, c, o, pure=False) for _, c, o in calls[:2]])

    def bare_tasks():
        client.gather([client.submit(real, source, c, o, pure=False) for _, c, o in calls])

    return _best(bare_tasks)[0]


def _install_c_clock() -> None:
    """In this process: count the thread CPU time spent in the C loop (``run_chunk``)
    on the chunks module itself (``_bench_c_seconds``), so a later call can read it."""
    from symmech.sweep import chunks

    if hasattr(chunks, "_bench_c_seconds"):
        return
    real = chunks.run_chunk
    chunks._bench_c_seconds = [0.0]

    def timed(*args):
        start = time.thread_time()
        try:
            return real(*args)
        finally:
            chunks._bench_c_seconds[0] += time.thread_time() - start

    chunks.run_chunk = timed


def _cpu_now() -> tuple[float, float]:
    """(CPU seconds of this process and of its parent if that is a Dask nanny, seconds
    of them in the C loop)."""
    import psutil

    from symmech.sweep import chunks

    me = psutil.Process()
    cpu = sum(me.cpu_times()[:2])
    parent = me.parent()
    if parent is not None and "nanny" in " ".join(parent.cmdline()).lower():
        cpu += sum(parent.cpu_times()[:2])
    return cpu, chunks._bench_c_seconds[0]


def _cpu_overhead(client, run) -> float:
    """The CPU time of every process of the route (the client with the scheduler it
    hosts, the workers and their nannies) beyond the C loop's, as a share of the C
    loop's, over ``run()``: the overhead on a machine with no other load (and the
    client's and scheduler's cost, on a cluster, moves off the workers' cores)."""
    _install_c_clock()
    before = [_cpu_now()]
    if client is not None:
        client.run(_install_c_clock)
        before += list(client.run(_cpu_now).values())
    run()
    after = [_cpu_now()]
    if client is not None:
        after += list(client.run(_cpu_now).values())
    cpu = sum(a[0] - b[0] for a, b in zip(after, before, strict=True))
    c_loop = sum(a[1] - b[1] for a, b in zip(after, before, strict=True))
    return (cpu - c_loop) / c_loop


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=20_000)
    ap.add_argument("--dask-chunk", type=int, default=10_000)
    ap.add_argument("--grow", type=int, default=4, help="memory check: N and grow x N runs")
    ap.add_argument("--cases", default="bouncing_ball,ellipse_gravity")
    ap.add_argument("--big", type=int, default=0, help="also an N-run ellipse sweep, both routes")
    ap.add_argument("--repeat", type=int, default=3, help="runs per timed route (shortest kept)")
    ap.add_argument(
        "--quick",
        action="store_true",
        help="a smoke test: the ellipse, 200 runs, each route once",
    )
    ap.add_argument(
        "--no-profiler",
        action="store_true",
        help="the cluster's workers without Dask's statistical profiler",
    )
    args = ap.parse_args()
    if args.quick:
        args.runs, args.dask_chunk, args.grow = 200, 100, 2
        args.cases, args.repeat = "ellipse_gravity", 1
    global REPEAT
    REPEAT = max(1, args.repeat)

    from distributed import Client, LocalCluster

    if args.no_profiler:
        import dask

        # Dask's statistical profiler samples each worker thread every 10 ms; a documented
        # setting for clusters of many short tasks turns it off
        dask.config.set({"distributed.worker.profile.enabled": False})
    cores = os.cpu_count() or 1
    cluster = LocalCluster(
        n_workers=cores,
        processes=True,
        threads_per_worker=1,
        host="127.0.0.1",
        dashboard_address=None,
    )
    client = Client(cluster)
    rows = []
    memory = []
    try:
        for name in args.cases.split(","):
            c = case(name)
            scene = c.scene()
            kw = _kwargs(name)
            grid = _grid(name, args.runs)
            Q, V = _states(name, grid)
            small = {k: v[:50] for k, v in grid.items()}
            sm.sweep(scene, small, c.t_end, client=client, **kw)  # load on every worker
            sm.sweep(scene, small, c.t_end, threads=1, **kw)  # compile, warm up
            t_base, _ = _best(
                sm.simulate_batch, scene, Q, V, c.t_end, params=kw["params"], threads=1
            )
            t_base2, _ = _best(
                sm.simulate_batch, scene, Q, V, c.t_end, params=kw["params"], threads=cores
            )
            t_one, one = _best(sm.sweep, scene, grid, c.t_end, threads=1, **kw)
            t_loc, loc = _best(sm.sweep, scene, grid, c.t_end, threads=cores, **kw)
            t_dask, dsk = _best(
                sm.sweep, scene, grid, c.t_end, client=client, chunk=args.dask_chunk, **kw
            )
            t_floor = _dask_floor(client, scene, grid, c.t_end, kw, args.dask_chunk)
            same = one.equals(loc) and one.equals(dsk)
            cpu_local = _cpu_overhead(
                None, partial(sm.sweep, scene, grid, c.t_end, threads=cores, **kw)
            )
            cpu_dask = _cpu_overhead(
                client,
                partial(sm.sweep, scene, grid, c.t_end, client=client, chunk=args.dask_chunk, **kw),
            )
            serial = _serial_share(scene, grid, c.t_end, kw)
            amdahl = 1 / (cores * (serial + (1 - serial) / cores))
            N = args.runs
            per = t_base / N
            for route, T, workers in (
                ("baseline: simulate_batch, 1 thread", t_base, 1),
                (f"simulate_batch, {cores} threads", t_base2, cores),
                ("sweep, 1 thread", t_one, 1),
                (f"sweep, local {cores} threads", t_loc, cores),
                (f"sweep, Dask {cores} workers (chunk {args.dask_chunk})", t_dask, cores),
                (f"floor: bare run_chunk tasks on {cores} Dask workers", t_floor, cores),
            ):
                overhead = (workers * T - t_base) / N
                batch = t_base if workers == 1 else t_base2
                rows.append(
                    (
                        name,
                        route,
                        N / T,
                        T / N * 1e6,
                        overhead / per,
                        t_one / (workers * T),
                        batch / T,
                    )
                )
            rows.append((name, f"tables identical across routes: {same}", 0, 0, 0, 0, 0))
            rows.append(
                (
                    name,
                    f"CPU overhead over the C loop (all processes): local {cpu_local:.1%},"
                    f" Dask {cpu_dask:.1%}",
                    0, 0, 0, 0, 0,
                )
            )  # fmt: skip
            rows.append(
                (
                    name,
                    f"CPU share outside the C loop {serial:.1%}: Amdahl bound of the local"
                    f" efficiency on {cores} cores {amdahl:.1%}",
                    0, 0, 0, 0, 0,
                )
            )  # fmt: skip
            if name == "ellipse_gravity":
                before = _rss(client)
                grown = {k: np.linspace(v[0], v[-1], args.grow * N) for k, v in grid.items()}
                sm.sweep(scene, grid, c.t_end, client=client, chunk=args.dask_chunk, **kw)
                after_n = _rss(client)
                t_grow, _ = _timed(
                    sm.sweep, scene, grown, c.t_end, client=client, chunk=args.dask_chunk, **kw
                )
                after_grow = _rss(client)
                memory = [before, after_n, after_grow, t_grow]
        profiler = "off" if args.no_profiler else "on (Dask's default)"
        print(
            f"sweep benchmark: {args.runs} runs per case, {cores} cores, worker profiler {profiler}"
        )
        print(
            f"{'case':16} {'route':44} {'runs/s':>9} {'us/run':>9} {'overhead':>9}"
            f" {'efficiency':>10} {'C batch/T':>9}"
        )
        for name, route, rate, us, over, eff, rel in rows:
            if rate == 0:
                print(f"{name:16} {route}")
                continue
            print(f"{name:16} {route:44} {rate:9.0f} {us:9.1f} {over:9.1%} {eff:10.1%} {rel:9.2f}")
        print(
            "overhead: (workers x T - T_baseline) / N over the baseline's time per run;"
            " efficiency: T_1 thread / (workers x T); C batch/T: simulate_batch's time on as"
            " many threads over the route's (1: no cost over the bare C loop)"
        )
        if memory:
            before, after_n, after_grow, t_grow = memory
            print(
                f"Dask worker RSS (MiB): before {before}, after {args.runs} runs {after_n},"
                f" after {args.grow * args.runs} runs {after_grow} ({t_grow:.1f} s)"
            )
        if args.big:
            c = case("ellipse_gravity")
            scene = c.scene()
            kw = _kwargs("ellipse_gravity")
            grid = sm.sweep.product(
                alpha=np.linspace(0.1, 0.9, args.big // 100), theta0=np.linspace(0, np.pi, 100)
            )
            kw["params"] = {k: v for k, v in kw["params"].items() if k != "alpha"}
            t_l, loc = _timed(sm.sweep, scene, grid, c.t_end, progress=False, **kw)
            t_d, dsk = _timed(
                sm.sweep, scene, grid, c.t_end, client=client, chunk=args.dask_chunk, **kw
            )
            counts = loc["status"].value_counts().to_dict()
            print(
                f"{len(loc)}-run ellipse sweep (alpha x theta0): local {t_l:.1f} s,"
                f" Dask LocalCluster {t_d:.1f} s, identical: {loc.equals(dsk)}; {counts}"
            )
    finally:
        client.close()
        cluster.close()


if __name__ == "__main__":
    main()
