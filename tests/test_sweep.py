"""sm.sweep on one machine: every row equals its own sm.simulate run bit for bit, the table
does not depend on chunks or threads, failures are rows, a stopped sweep resumes from its
Parquet store, bad grids are refused naming the column."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
import sympy as sp

pd = pytest.importorskip("pandas", reason="sm.sweep needs pandas (the sweep/test extra)")
pytest.importorskip("pyarrow", reason="sm.sweep needs pyarrow (the sweep/test extra)")

import symmech as sm  # noqa: E402
from symmech.bench.cases import case  # noqa: E402
from symmech.examples import bouncing_ball  # noqa: E402
from symmech.simulate import SimulationError  # noqa: E402
from symmech.sweep import chunks, runner  # noqa: E402

BALL = {"m": 1.0, "g": 9.81, "alpha": 0.5}


@pytest.fixture(scope="module")
def ellipse():
    c = case("ellipse_gravity")
    return c.scene(), c.params(), c


@pytest.fixture(scope="module")
def quartic():
    """A 1-D particle in V = k x^4 with a wall at x = -1: the energy overflows for huge x,
    so the C loop stops with status "failed"."""
    (x,) = sm.coordinates("x")
    k = sp.Symbol("k", positive=True)
    wall = sm.Wall(x + 1, restitution=1, name="left")
    return sm.Scene((x,), metric=sp.Matrix([[1]]), potential=k * x**4, walls=[wall], name="q4")


def _ellipse_grid():
    return sm.sweep.product(alpha=[0.3, 0.8, 1.0], theta0=[0.0, 0.7, 1.9])


def test_rows_equal_their_own_simulate_runs_bit_for_bit(ellipse):
    scene, params, c = ellipse
    grid = _ellipse_grid()
    base = {k: v for k, v in params.items() if k != "alpha"}
    for contact in ("persistent", "stop"):
        tab = sm.sweep(
            scene, grid, 2.0, params=base, q0=c.q0, v0=c.v0, contact=contact, threads=2,
            outputs=("energy", "gap"),
        )  # fmt: skip
        assert list(tab.index) == list(range(9))
        for i, row in tab.iterrows():
            p = {**base, "alpha": grid["alpha"][i]}
            q0 = [c.q0[0], c.q0[1], grid["theta0"][i]]
            res = sm.simulate(scene, q0, c.v0, 2.0, params=p, contact=contact)
            assert row["status"] == res.status
            assert (pd.isna(row["message"]) and res.status == "finished") or (
                row["message"] == res.message
            )
            assert row["t_final"] == res.t[-1]
            assert [row["x_final"], row["y_final"], row["theta_final"]] == res.q[-1].tolist()
            final_v = [row["xdot_final"], row["ydot_final"], row["thetadot_final"]]
            assert final_v == res.v[-1].tolist()
            for kind, stat in (("impact", "impacts"), ("contact", "contacts")):
                assert row[f"n_{kind}"] == res.stats[stat]
            if res.accumulation_time is None:
                assert math.isnan(row["time_to_rest"])
            else:
                assert row["time_to_rest"] == res.accumulation_time
            # energy at the end, by hand: T + V of the text's ellipse
            m, inertia, g = p["m"], p["I"], p["g"]
            by_hand = 0.5 * m * (final_v[0] ** 2 + final_v[1] ** 2)
            by_hand += 0.5 * inertia * final_v[2] ** 2 + m * g * row["y_final"]
            assert row["energy"] == pytest.approx(by_hand, rel=1e-13, abs=1e-13)
            th, a, b = row["theta_final"], p["a"], p["b"]
            gap = row["y_final"] - math.hypot(a * math.sin(th), b * math.cos(th))
            assert row["gap"] == pytest.approx(gap, abs=1e-14)
    # contact="stop": at alpha = 0.3 the ellipse comes to rest before t = 2, elastic never
    assert (tab["status"][tab["alpha"] == 0.3] == "zeno").all()
    assert (tab["status"][tab["alpha"] == 1.0] == "finished").all()


def test_table_is_the_same_whatever_the_chunks_and_threads(ellipse):
    scene, params, c = ellipse
    grid = sm.sweep.product(alpha=[0.5, 0.9], theta0=np.linspace(0, 3, 7))
    base = {k: v for k, v in params.items() if k != "alpha"}
    kw = {"params": base, "q0": c.q0, "v0": c.v0, "contact": "stop"}
    one = sm.sweep(scene, grid, 3.0, threads=1, chunk=14, **kw)
    two = sm.sweep(scene, grid, 3.0, threads=2, chunk=3, **kw)
    odd = sm.sweep(scene, grid, 3.0, threads=2, chunk=1, **kw)
    pd.testing.assert_frame_equal(one, two, check_exact=True)
    pd.testing.assert_frame_equal(one, odd, check_exact=True)


def test_grid_as_dataframe_and_as_dict_agree():
    grid = {"q0[0]": [1.0, 1.5, 2.0], "alpha": [0.5, 0.6, 0.7]}
    a = sm.sweep(bouncing_ball(), grid, 1.0, v0=[0.0], params={"m": 1, "g": 9.81})
    b = sm.sweep(bouncing_ball(), pd.DataFrame(grid), 1.0, v0=[0.0], params={"m": 1, "g": 9.81})
    pd.testing.assert_frame_equal(a, b, check_exact=True)
    assert a["q0[0]"].tolist() == grid["q0[0]"]


def test_product_is_every_combination_first_name_slowest():
    g = sm.sweep.product(a=[1, 2], b=[10, 20, 30])
    pairs = list(zip(g["a"].tolist(), g["b"].tolist(), strict=True))
    assert pairs == [(a, b) for a in (1, 2) for b in (10, 20, 30)]


def test_ball_columns_against_the_closed_form():
    """Dropped from h at rest with contact="stop": t* = sqrt(2h/g)(1 + alpha)/(1 - alpha)."""
    h = np.array([0.5, 1.0, 3.0])
    alpha = np.array([0.2, 0.5, 0.7])
    tab = sm.sweep(
        bouncing_ball(), {"y0": h, "alpha": alpha}, 20.0, v0=[0.0],
        params={"m": 2.0, "g": 9.81}, contact="stop", outputs=("energy", "gap", "rhs_calls"),
    )  # fmt: skip
    t_star = np.sqrt(2 * h / 9.81) * (1 + alpha) / (1 - alpha)
    assert np.allclose(tab["time_to_rest"], t_star, rtol=1e-7)
    assert (tab["status"] == "zeno").all() and (tab["n_impact"] > 5).all()
    assert np.allclose(tab["energy"], 2.0 * 9.81 * tab["y_final"] + tab["ydot_final"] ** 2)
    assert (tab["rhs_calls"] > 0).all()
    assert tab["gap"].tolist() == tab["y_final"].tolist()  # the floor's gap is y


def test_failures_are_rows(quartic):
    tab = sm.sweep(
        quartic, {"x0": [0.5, 1e200, -2.0, np.nan], "k": [1.0, 1.0, 1.0, 1.0]}, 1.0, v0=[0.0]
    )
    assert tab["status"].tolist() == ["finished", "failed", "invalid", "invalid"]
    assert "energy failed" in tab.loc[1, "message"]
    assert "wrong side of wall 'left'" in tab.loc[2, "message"]
    assert "finite" in tab.loc[3, "message"]
    assert math.isnan(tab.loc[2, "x_final"]) and tab.loc[2, "n_impact"] == 0
    # the ball bounces more than 3 times before t = 5: status "max_events"
    many = sm.sweep(
        bouncing_ball(), {"y0": [1.0, 2.0], "alpha": [0.5, 1.5]}, 5.0, v0=[0.0],
        params={"m": 1, "g": 9.81}, max_events=3,
    )  # fmt: skip
    assert many["status"].tolist() == ["max_events", "invalid"]
    assert "stopped after 3 events" in many.loc[0, "message"]
    assert "restitution" in many.loc[1, "message"]


def test_a_chunk_that_cannot_run_is_failed_rows(monkeypatch):
    real = chunks.run_chunk

    def flaky(source, chunk, options):
        if chunk.index == 1:
            raise MemoryError("the C simulator could not allocate its work arrays")
        return real(source, chunk, options)

    monkeypatch.setattr(chunks, "run_chunk", flaky)
    tab = sm.sweep(
        bouncing_ball(), {"y0": [1.0, 1.1, 1.2, 1.3]}, 1.0, v0=[0.0], params=BALL,
        chunk=2, threads=1,
    )  # fmt: skip
    assert tab["status"].tolist() == ["finished", "finished", "failed", "failed"]
    assert "could not allocate" in tab.loc[2, "message"]


def test_a_plan_pickles_to_data_and_runs_the_same_after(ellipse):
    """What travels to a worker: a plan without loaded code, which loads it on first use
    and tables a chunk exactly as the original plan does."""
    import pickle

    from symmech.sweep import driver

    scene, params, c = ellipse
    params = {k: v for k, v in params.items() if k != "alpha"}
    kw = {"params": params, "q0": c.q0, "v0": c.v0}
    grid = sm.sweep.product(alpha=[0.3, 0.8], theta0=[0.2, 1.0, 2.5])
    captured = []
    real = driver.run_local

    def capture(plan, table, *rest):
        captured.append((plan, table))
        return real(plan, table, *rest)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(driver, "run_local", capture)
        sm.sweep(scene, grid, 2.0, threads=1, expressions={"r": "x**2 + y**2"}, **kw)
    plan, table = captured[0]
    assert "system" in plan._live
    copy = pickle.loads(pickle.dumps(plan))
    assert copy._live == {} and copy.scene is not plan.scene
    a = chunks.chunk_table(plan, 0, 0, table)
    b = chunks.chunk_table(copy, 0, 0, table)
    assert a.num_rows == 6
    pd.testing.assert_frame_equal(a.to_pandas(), b.to_pandas(), check_exact=True)
    assert copy.system.free is not plan.system.free  # loaded anew from the source


def test_resume_from_a_partial_store(tmp_path, monkeypatch):
    grid = {"y0": np.linspace(0.5, 2.0, 10), "alpha": np.linspace(0.3, 0.9, 10)}
    kw = {"v0": [0.0], "params": {"m": 1, "g": 9.81}, "chunk": 3, "threads": 1}
    full = sm.sweep(bouncing_ball(), grid, 2.0, **kw)
    store = tmp_path / "out.parquet"
    real = runner.chunk_table
    calls: list[int] = []

    def stop_at_third(plan, index, lo, rows):
        calls.append(index)
        if len(calls) == 3:
            raise KeyboardInterrupt  # the sweep is stopped half way
        return real(plan, index, lo, rows)

    monkeypatch.setattr(runner, "chunk_table", stop_at_third)
    with pytest.raises(KeyboardInterrupt):
        sm.sweep(bouncing_ball(), grid, 2.0, store=store, **kw)
    parts = sorted(p.name for p in store.glob("part-*.parquet"))
    assert parts == ["part-00000000.parquet", "part-00000001.parquet"]
    calls.clear()
    monkeypatch.setattr(runner, "chunk_table", lambda *a: (calls.append(a[1]), real(*a))[1])
    resumed = sm.sweep(bouncing_ball(), grid, 2.0, store=store, **kw)
    assert calls == [2, 3]  # only the missing chunks ran
    pd.testing.assert_frame_equal(resumed, full, check_exact=True)
    pd.testing.assert_frame_equal(pd.read_parquet(store).set_index("run"), full, check_exact=True)
    # a store of another sweep is refused, not mixed in
    with pytest.raises(SimulationError, match="holds another sweep"):
        sm.sweep(bouncing_ball(), grid, 3.0, store=store, **kw)


@pytest.mark.parametrize(
    ("grid", "match"),
    [
        ({"beta": [1.0]}, "'beta' is not a parameter nor an initial value"),
        ({"y": [1.0]}, "the initial value of y is the column 'y0'"),
        ({"q0[3]": [1.0]}, "the scene has 1 coordinates"),
        ({"y0": [1.0], "q0[0]": [2.0]}, "'y0' and 'q0\\[0\\]' set the same quantity"),
        ({"y0": [1.0, 2.0], "alpha": [0.5]}, "differ in length"),
        ({"y0": ["a"]}, "str 'a' is not a real number"),
        ({"y0": [[1.0]]}, "1-D array"),
        ({}, "no columns"),
        ([1.0, 2.0], "expected a dict"),
    ],
)
def test_bad_grids_are_refused_naming_the_column(grid, match):
    with pytest.raises(SimulationError, match=match):
        sm.sweep(bouncing_ball(), grid, 1.0, v0=[0.0], params=BALL)


def test_bad_arguments_are_refused():
    ball = bouncing_ball()
    with pytest.raises(SimulationError, match="missing values for \\['alpha'\\]"):
        sm.sweep(ball, {"y0": [1.0]}, 1.0, v0=[0.0], params={"m": 1, "g": 9.81})
    with pytest.raises(SimulationError, match="no column sets \\['ydot'\\]"):
        sm.sweep(ball, {"y0": [1.0]}, 1.0, params=BALL)
    with pytest.raises(SimulationError, match="unknown \\['mass'\\]"):
        sm.sweep(ball, {"y0": [1.0]}, 1.0, v0=[0], params={**BALL, "mass": 1})
    for outputs in (("power",), "energy", None):
        with pytest.raises(SimulationError, match="outputs"):
            sm.sweep(ball, {"y0": [1.0]}, 1.0, v0=[0], params=BALL, outputs=outputs)
    with pytest.raises(SimulationError, match="t_end must be greater"):
        sm.sweep(ball, {"y0": [1.0]}, 0.0, v0=[0], params=BALL)
    with pytest.raises(SimulationError, match="store: expected a folder path"):
        sm.sweep(ball, {"y0": [1.0]}, 1.0, v0=[0], params=BALL, store=3)
    with pytest.raises(SimulationError, match="chunk must be a positive integer"):
        sm.sweep(ball, {"y0": [1.0]}, 1.0, v0=[0], params=BALL, chunk=0)
    with pytest.raises(SimulationError, match=r"expected a dask\.distributed\.Client"):
        sm.sweep(ball, {"y0": [1.0]}, 1.0, v0=[0], params=BALL, client="tcp://x:8786")
    with pytest.raises(SimulationError, match=r"expected a symmech\.Scene"):
        sm.sweep("ball", {"y0": [1.0]}, 1.0)


def test_expressions_are_parsed_safely_and_evaluated_at_the_end():
    tab = sm.sweep(
        bouncing_ball(), {"y0": [1.0, 2.0]}, 0.3, v0=[0.0], params=BALL,
        expressions={"height_cm": "100*y", "momentum": "m*ydot"},
    )  # fmt: skip
    assert tab["height_cm"].tolist() == pytest.approx((100 * tab["y_final"]).tolist())
    # free fall before the first impact: y = h - g t^2/2, ydot = -g t
    assert tab["y_final"].tolist() == pytest.approx([1 - 9.81 * 0.045, 2 - 9.81 * 0.045])
    assert tab["momentum"].tolist() == pytest.approx([-9.81 * 0.3] * 2)
    with pytest.raises(SimulationError, match="expressions\\['x'\\]"):
        sm.sweep(bouncing_ball(), {"y0": [1.0]}, 0.3, v0=[0.0], params=BALL,
                 expressions={"x": "__import__('os').system('true')"})  # fmt: skip
    with pytest.raises(SimulationError, match="uses \\['z'\\]"):
        sm.sweep(bouncing_ball(), {"y0": [1.0]}, 0.3, v0=[0.0], params=BALL,
                 expressions={"x": sp.Symbol("z")})  # fmt: skip


def test_progress_bar_on_request_only(capsys):
    grid = {"y0": [1.0, 2.0, 3.0]}
    sm.sweep(bouncing_ball(), grid, 1.0, v0=[0.0], params=BALL, chunk=1)
    assert capsys.readouterr().err == ""  # not a terminal: no bar
    sm.sweep(bouncing_ball(), grid, 1.0, v0=[0.0], params=BALL, chunk=1, progress=True)
    err = capsys.readouterr().err
    assert "sweep: 100%" in err and "3/3" in err and "run/s" in err and err.endswith("\n")


def test_import_symmech_loads_neither_pandas_nor_dask():
    code = "import sys, symmech\nprint(sorted({m.split('.')[0] for m in sys.modules}))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    for heavy in ("pandas", "pyarrow", "dask", "distributed"):
        assert f"'{heavy}'" not in out.stdout
    code = "import symmech as sm; print(callable(sm.sweep), sm.sweep.product.__name__)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.stdout.split() == ["True", "product"], out.stderr


def _sweep_args(argv: list[str]):
    import argparse

    from symmech.sweep.command import add_command

    parser = argparse.ArgumentParser(prog="symmech")
    common = argparse.ArgumentParser(add_help=False)
    add_command(parser.add_subparsers(dest="command"), common)
    return parser.parse_args(["sweep", *argv])


def test_command_writes_the_table_of_sm_sweep(tmp_path, capsys):
    from symmech.scenefile import read_scene
    from symmech.sweep.command import run_command

    grid = pd.DataFrame({"y0": [1.0, 2.0, -1.0], "alpha": [0.5, 0.7, 0.5]})
    grid.to_csv(tmp_path / "grid.csv", index=False)
    grid.to_parquet(tmp_path / "grid.parquet")
    said: list[str] = []
    expected = sm.sweep(bouncing_ball(), grid, 1.0, v0=[0.0], params={**BALL, "m": 2.0}, threads=1)
    for grid_file, out in (("grid.csv", "out.parquet"), ("grid.parquet", "out.csv")):
        argv = ["bouncing_ball", "--grid", str(tmp_path / grid_file), "--out"]
        argv += [str(tmp_path / out), "--t-end", "1", "--v0", "0", "--param", "m=2"]
        assert run_command(_sweep_args(argv), read_scene, said.append) == 0
        printed = capsys.readouterr().out
        assert "finished: 2" in printed and "invalid: 1" in printed
    assert said and "3 runs" in said[0]
    stored = pd.read_parquet(tmp_path / "out.parquet").set_index("run")
    pd.testing.assert_frame_equal(stored, expected, check_exact=True)
    written = pd.read_csv(tmp_path / "out.csv", index_col="run")
    assert written["status"].tolist() == expected["status"].tolist()
    assert np.allclose(written["y_final"][:2], expected["y_final"][:2], rtol=1e-15, atol=0)
    with pytest.raises(sm.SymmechError, match="--out"):
        run_command(_sweep_args([*argv[:4], "out.txt", "--t-end", "1"]), read_scene, print)
    (tmp_path / "grid.txt").write_text("y0\n1\n")
    bad = ["bouncing_ball", "--grid", str(tmp_path / "grid.txt"), "--out", str(tmp_path / "o.csv")]
    with pytest.raises(sm.SymmechError, match="--grid"):
        run_command(_sweep_args([*bad, "--t-end", "1"]), read_scene, print)


def test_constrained_scene_rows_are_projected_and_checked_as_simulate_does():
    """Carnot 3.13 (rolling sphere, quasi-velocities): a v0 slightly off D is projected
    with P as simulate projects it (same final state bit for bit), one far off D is an
    invalid row carrying simulate's own message."""
    c = case("carnot_3_13")
    scene, params = c.scene(), c.params()
    v = list(c.v0)
    grid = {"v0[0]": [v[0], v[0] + 1e-9, v[0] + 1.0], "omega_z0": [v[5], v[5], v[5]]}
    tab = sm.sweep(scene, grid, 0.5, params=params, q0=list(c.q0), v0=v)
    assert tab["status"].tolist()[:2] == ["finished", "finished"]
    for i in (0, 1):
        v0 = [grid["v0[0]"][i], *v[1:]]
        res = sm.simulate(scene, list(c.q0), v0, 0.5, params=params)
        names = [f"{s}_final" for s in ("x", "y", "z", "phi", "theta", "psi")]
        assert tab.loc[i, names].tolist() == res.q[-1].tolist()
        names = [f"{s}_final" for s in ("v_x", "v_y", "v_z", "omega_x", "omega_y", "omega_z")]
        assert tab.loc[i, names].tolist() == res.v[-1].tolist()
    with pytest.raises(SimulationError) as refused:
        sm.simulate(scene, list(c.q0), [v[0] + 1.0, *v[1:]], 0.5, params=params)
    assert tab.loc[2, "status"] == "invalid"
    assert tab.loc[2, "message"] == str(refused.value)
