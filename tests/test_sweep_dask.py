"""sm.sweep on a real Dask LocalCluster (2 worker processes, loopback only): the same table
as the local run bit for bit, the library loaded once per worker, failures as rows, a lost
worker costing no finished chunk, and a resumable store."""

from __future__ import annotations

import os

import numpy as np
import pytest

pd = pytest.importorskip("pandas", reason="sm.sweep needs pandas (the sweep/test extra)")
pytest.importorskip("pyarrow", reason="sm.sweep needs pyarrow (the sweep/test extra)")
distributed = pytest.importorskip(
    "distributed", reason="the cluster route needs dask.distributed (the sweep/test extra)"
)

import symmech as sm  # noqa: E402
from symmech.bench.cases import case  # noqa: E402
from symmech.examples import bouncing_ball  # noqa: E402
from symmech.sweep import runner  # noqa: E402
from symmech.sweep.worker import loaded_libraries  # noqa: E402


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(
        n_workers=2,
        processes=True,
        threads_per_worker=1,
        host="127.0.0.1",
        dashboard_address=None,
    )
    with cluster, distributed.Client(cluster) as c:
        yield c


@pytest.fixture(scope="module")
def ellipse():
    c = case("ellipse_gravity")
    base = {k: v for k, v in c.params().items() if k != "alpha"}
    return c.scene(), {"params": base, "q0": c.q0, "v0": c.v0}


def test_cluster_table_equals_local_table_bit_for_bit(client, ellipse):
    scene, kw = ellipse
    grid = sm.sweep.product(alpha=np.linspace(0.1, 1.0, 5), theta0=np.linspace(0, 3, 8))
    grid["theta0"][3] = np.nan  # an invalid row travels as a row
    local = sm.sweep(scene, grid, 3.0, chunk=7, threads=2, **kw)
    remote = sm.sweep(scene, grid, 3.0, chunk=7, client=client, **kw)
    pd.testing.assert_frame_equal(local, remote, check_exact=True)
    assert local.loc[3, "status"] == "invalid"
    assert (local["status"] != "invalid").sum() == 39
    # another chunking on the cluster: still the same table
    again = sm.sweep(scene, grid, 3.0, chunk=40, client=client, **kw)
    pd.testing.assert_frame_equal(local, again, check_exact=True)
    # a worker process that ran chunks compiled or loaded the library once, however many
    # chunks and sweeps it ran, and holds only it (Dask may give every chunk to one
    # worker while the other is still starting: a worker with none loaded none)
    loaded = client.run(loaded_libraries).values()
    assert set(loaded) <= {0, 1} and 1 in set(loaded)


def test_the_client_only_collects_tables(client, ellipse, monkeypatch):
    """On a cluster the whole life of a chunk (its checks, the C loop, its table) runs on
    the workers: the client's own checks may be broken without changing the table."""
    from symmech.sweep import chunks

    scene, kw = ellipse
    grid = sm.sweep.product(alpha=np.linspace(0.1, 1.0, 3), theta0=np.linspace(0, 3, 5))
    local = sm.sweep(scene, grid, 3.0, chunk=4, threads=1, **kw)

    def not_here(*args, **kwargs):
        raise AssertionError("a chunk was prepared on the client")

    monkeypatch.setattr(chunks, "prepare", not_here)
    remote = sm.sweep(scene, grid, 3.0, chunk=4, client=client, **kw)
    pd.testing.assert_frame_equal(local, remote, check_exact=True)


def test_failures_on_the_cluster_are_rows(client):
    grid = {"y0": [1.0, -1.0, 2.0], "alpha": [0.5, 0.5, 0.5]}
    kw = {"v0": [0.0], "params": {"m": 1, "g": 9.81}, "max_events": 3, "chunk": 1}
    remote = sm.sweep(bouncing_ball(), grid, 5.0, client=client, **kw)
    assert remote["status"].tolist() == ["max_events", "invalid", "max_events"]
    pd.testing.assert_frame_equal(
        remote, sm.sweep(bouncing_ball(), grid, 5.0, **kw), check_exact=True
    )


def test_a_task_that_raises_on_a_worker_is_failed_rows(client, monkeypatch):
    """A worker that cannot run a chunk (here: its library source does not compile)
    reports failed rows naming the error; the sweep returns."""
    from dataclasses import replace

    from symmech.sweep import driver as api

    real = runner.run_dask

    def broken_source(plan, *args):  # a plan whose simulator source cannot compile
        bad = replace(plan.source, files=(("broken.c", "this is not C"),))
        return real(replace(plan, source=bad), *args)

    monkeypatch.setattr(api, "run_dask", broken_source)
    tab = sm.sweep(
        bouncing_ball(), {"y0": [1.0, 2.0]}, 1.0, v0=[0.0],
        params={"m": 1, "g": 9.81, "alpha": 0.5}, client=client, chunk=1,
    )  # fmt: skip
    assert tab["status"].tolist() == ["failed", "failed"]
    assert "failed on the cluster: CompileError" in tab.loc[0, "message"]


def test_a_lost_worker_loses_no_finished_chunk(client, ellipse, monkeypatch):
    scene, kw = ellipse
    grid = sm.sweep.product(alpha=np.linspace(0.2, 0.9, 8), theta0=np.linspace(0, 3, 40))
    local = sm.sweep(scene, grid, 4.0, chunk=16, threads=2, **kw)
    from symmech.sweep import driver as api

    real = runner.run_dask
    killed: list[str] = []

    def kill_one_worker_after_the_first_chunk(plan, grid, chunks, client, window, sink, tag):
        def sink_then_kill(k, table):
            sink(k, table)
            if not killed:
                victim = sorted(client.scheduler_info()["workers"])[0]
                killed.append(victim)
                try:
                    client.run(os._exit, 1, workers=[victim])
                except Exception:  # the worker dies before it can answer
                    pass

        return real(plan, grid, chunks, client, window, sink_then_kill, tag)

    monkeypatch.setattr(api, "run_dask", kill_one_worker_after_the_first_chunk)
    remote = sm.sweep(scene, grid, 4.0, chunk=16, client=client, **kw)
    assert killed and killed[0] not in client.scheduler_info()["workers"]  # it did die
    assert remote["message"].isna().all(), remote["message"].dropna().unique()
    pd.testing.assert_frame_equal(local, remote, check_exact=True)
    client.wait_for_workers(2, timeout=60)  # the nanny restarts it for the next tests


def test_cluster_store_resumes(client, tmp_path, monkeypatch):
    grid = {"y0": np.linspace(0.5, 2.0, 12), "alpha": np.linspace(0.3, 0.9, 12)}
    kw = {"v0": [0.0], "params": {"m": 1, "g": 9.81}, "chunk": 4}
    store = tmp_path / "ball.parquet"
    first = sm.sweep(bouncing_ball(), grid, 2.0, client=client, store=store, **kw)
    (store / "part-00000001.parquet").unlink()
    from symmech.sweep import driver as api

    calls: list[int] = []
    real = runner.run_dask

    def counting(plan, grid, chunks, *rest):
        chunks = list(chunks)
        calls.extend(k for k, _, _ in chunks)
        return real(plan, grid, chunks, *rest)

    monkeypatch.setattr(api, "run_dask", counting)
    resumed = sm.sweep(bouncing_ball(), grid, 2.0, client=client, store=store, **kw)
    assert calls == [1]
    pd.testing.assert_frame_equal(first, resumed, check_exact=True)
    pd.testing.assert_frame_equal(
        first, sm.sweep(bouncing_ball(), grid, 2.0, **kw), check_exact=True
    )


def test_constrained_and_time_dependent_scenes_on_the_cluster(client):
    """What a worker loads from the plan serves every kind of scene: the rolling sphere
    (its v0 projected onto D by the worker's own free-flight code, a run off D refused)
    and a floor shaken by an arbitrary function of time given by ``definitions``."""
    import sympy as sp

    c = case("carnot_3_13")
    v = list(c.v0)
    grid = {"v0[0]": [v[0], v[0] + 1e-9, v[0] + 1.0]}
    kw = {"params": c.params(), "q0": list(c.q0), "v0": v, "chunk": 2}
    local = sm.sweep(c.scene(), grid, 0.5, threads=1, **kw)
    remote = sm.sweep(c.scene(), grid, 0.5, client=client, **kw)
    pd.testing.assert_frame_equal(local, remote, check_exact=True)
    assert remote["status"].tolist() == ["finished", "finished", "invalid"]

    (y,) = sm.coordinates("y")
    m, g = sp.symbols("m g", positive=True)
    f = sp.Function("f")
    wall = sm.Wall(y - f(sm.t), restitution=sp.Rational(1, 2), name="shaker")
    shaker = sm.Scene((y,), metric=sp.Matrix([[m]]), potential=m * g * y, walls=[wall])
    kw = {
        "params": {"m": 1.0, "g": 9.81},
        "v0": [0.0],
        "definitions": {f(sm.t): sp.sin(3 * sm.t) / 10},
        "chunk": 2,
    }
    grid = {"y0": [0.5, 1.0, 1.5]}
    local = sm.sweep(shaker, grid, 3.0, threads=1, **kw)
    remote = sm.sweep(shaker, grid, 3.0, client=client, **kw)
    pd.testing.assert_frame_equal(local, remote, check_exact=True)
    one = sm.simulate(shaker, [1.0], [0.0], 3.0, params=kw["params"], definitions=kw["definitions"])
    assert remote.loc[1, "y_final"] == one.q[-1][0]
    assert remote.loc[1, "n_impact"] == sum(e.kind == "impact" for e in one.events)
