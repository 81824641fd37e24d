"""Hostile and careless input, round 3 (issue 26), the second half: symbolic budgets that
hold in any thread, metric definiteness, large sparse impact maps, sweep stores, output
paths, ``from_mechanics`` and the command line's refusals.  Each test uses the input that
used to hang, crash or pass silently."""

from __future__ import annotations

import re
import threading
import time
from pathlib import Path

import mpmath
import pytest
import sympy as sp
from test_cli import assert_one_line_error, symmech

import symmech as sm
from symmech import codegen
from symmech.algebra import budget
from symmech.codegen.kinds import forcing_notes
from symmech.simulate import SimulationError

# ---------------------------------------------------------------------------------------
# 1. expansion budgets: a velocity inside a power

#: 145 bytes: ``symmech derive`` never finished (forcing_notes expanded the power: 8
#: operations under NOTE_EXPAND_OPS = 100, C(70, 6) = 131,115,985 terms).
POWER_FORCE = """format = 1
name = "p"
coordinates = ["x", "y", "z"]
metric = ["1", "1", "1"]
potential = "0"
forces = ["(x+y+z+xdot+ydot+zdot+1)**64", "0", "0"]
"""


def _finishes(work, seconds: float) -> object:
    """Run ``work()`` in a daemon thread; fail if it is still running after ``seconds``
    (the hang this guards against never returns), else return its result or raise its
    exception."""
    out: dict[str, object] = {}

    def run() -> None:
        try:
            out["value"] = work()
        except BaseException as exc:  # handed to the test thread
            out["error"] = exc

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(seconds)
    assert not thread.is_alive(), f"still running after {seconds} s"
    if "error" in out:
        raise out["error"]  # type: ignore[misc]
    return out.get("value")


def test_a_power_of_a_sum_is_over_every_expanding_budget_measured_in_operations():
    x, y, zd = sp.symbols("x y zdot")
    power = (x + y + zd + 1) ** 64
    assert sp.count_ops(power) <= budget.LIGHT_SIMPLIFY_OPS  # what the old gates measured
    assert budget.expanded_terms(power)[0] == sp.binomial(64 + 3, 3)  # C(67, 3) = 47,905
    assert not budget.affordable(power, budget.LIGHT_SIMPLIFY_OPS)
    assert budget.expand_affordable(power) is power  # skipped, not expanded
    small = (x + y + zd + 1) ** 3
    assert budget.affordable(small, budget.LIGHT_SIMPLIFY_OPS)
    assert budget.expand_affordable(small) == sp.expand(small)


def test_forcing_notes_do_not_expand_a_power_of_velocities():
    v = sp.symbols("xdot ydot zdot")
    x, y, z = sp.symbols("x y z")
    f = sp.Matrix([(x + y + z + sum(v) + 1) ** 64, 0, v[0] * v[1]])
    notes = _finishes(lambda: forcing_notes(f, v, False), 20)
    # entry 0 counts all 6 pairs (a bound), entry 2 its one pair: 18 - 7 = 11 zeros
    assert notes[0].startswith("forcing: at least 11 of the 18 Christoffel symbols")
    assert "entries [1]" in notes[1]


def test_code_generation_of_a_velocity_inside_a_power_finishes():
    """The generated forcing is the power itself, evaluated right (against mpmath)."""
    scene = sm.reads_scene(POWER_FORCE).scene
    code = _finishes(lambda: codegen.generate(scene, "c"), 60)
    assert any("at least 12 of the 18" in note for note in code.omitted)
    state = [0.1, -0.2, 0.05, 0.01, 0.02, -0.03]
    f = code.load().forcing(state[:3], state[3:], {})
    assert f[0] == pytest.approx(float(mpmath.mpf("1.0") * (1 + mpmath.fsum(state)) ** 64))
    assert list(f[1:]) == [0.0, 0.0]


# ---------------------------------------------------------------------------------------
# 2. a deadline that holds off the main thread

#: A dense trigonometric 3 x 3 metric with two curved walls: its closed forms need about
#: 9 s; the gcds of the adjugate route are single long library calls.
SLOW_CLOSED_FORMS = """coordinates = ["x", "y", "z"]
metric = [["3 + sin(x)", "cos(x - y)", "sin(y*z)/7"], ["cos(x - y)", "4 + cos(z)", "x/9"],
          ["sin(y*z)/7", "x/9", "5 + sin(x + z)"]]
potential = "cos(x) + sin(y)*z"
[[walls]]
psi = "x + sin(y) + z**2 + 2"
[[walls]]
psi = "y - cos(x*z) + 3"
"""


def test_the_time_budget_stops_a_derivation_in_a_worker_thread(monkeypatch):
    """SIGALRM reaches only the main thread: in a worker thread a derivation with a 2 s
    budget ran 9.9 s (and a 10 s one past 100 s).  The deadline is checked cooperatively
    in the symbolic loops, so the thread stops and falls back to linear_solve.  Measured
    in the thread's own CPU time (a loaded machine gives it less, never more)."""
    monkeypatch.setattr(budget, "CLOSED_FORM_SECONDS", 0.3)
    scene = sm.reads_scene(SLOW_CLOSED_FORMS).scene

    def work() -> tuple[object, float]:
        start = time.thread_time()
        code = codegen.generate(scene, "c")
        return code, time.thread_time() - start

    assert threading.current_thread() is threading.main_thread()
    code, cpu = _finishes(work, 60)  # type: ignore[misc]
    assert any("over its budget CLOSED_FORM_SECONDS" in note for note in code.omitted)
    assert cpu < 3.0, cpu  # 0.3 s of closed forms and the linear_solve route


def test_a_deadline_is_checked_at_every_expanding_gate():
    """The gates of the expanding steps are checkpoints: a stage past its deadline stops
    at the next one, whatever thread it runs in."""
    x = sp.Symbol("x")
    caught: list[BaseException] = []

    def work() -> None:
        with budget.time_limit("gate", 0.01):
            time.sleep(0.05)
            try:
                budget.affordable(x + 1, 10)
            except budget.BudgetExceeded as exc:
                caught.append(exc)
            try:
                budget.expand_affordable(x + 1)
            except budget.BudgetExceeded as exc:
                caught.append(exc)

    _finishes(work, 10)
    assert [exc.stage for exc in caught] == ["gate", "gate"]


# ---------------------------------------------------------------------------------------
# 5. a sweep store with a link, a folder or a corrupt part


def _store_sweep(store: Path):
    from symmech.examples import bouncing_ball

    grid = {"alpha": [0.1, 0.2, 0.3, 0.4, 0.5, 0.6]}
    p = {"m": 1.0, "g": 9.81}
    return sm.sweep(bouncing_ball(), grid, 1.0, q0=[1.0], v0=[0.0], params=p, chunk=2, store=store)


def test_a_corrupt_part_of_a_sweep_store_is_recomputed_with_a_warning(tmp_path: Path):
    """A truncated part gave a raw ArrowInvalid and the sweep could not resume."""
    pytest.importorskip("pyarrow")
    store = tmp_path / "out.parquet"
    first = _store_sweep(store)
    part = store / "part-00000001.parquet"
    part.write_bytes(part.read_bytes()[:100])  # truncated
    (store / "part-00000002.parquet").write_bytes(b"PAR1 not a table PAR1")
    with pytest.warns(sm.SymmechWarning) as caught:
        again = _store_sweep(store)
    said = " ".join(str(w.message) for w in caught)
    assert "part-00000001.parquet cannot be read" in said
    assert "part-00000002.parquet cannot be read" in said
    assert again.equals(first)
    assert not list(store.glob(".*.tmp"))


@pytest.mark.parametrize("kind", ["link", "folder", "manifest link"])
def test_a_link_or_a_folder_in_a_sweep_store_is_refused_by_name(tmp_path: Path, kind: str):
    pytest.importorskip("pyarrow")
    store = tmp_path / "out.parquet"
    _store_sweep(store)
    elsewhere = tmp_path / "elsewhere.parquet"
    name = "_sweep.json" if kind == "manifest link" else "part-00000002.parquet"
    planted = store / name
    if kind == "folder":
        planted.unlink()
        planted.mkdir()
    else:
        elsewhere.write_bytes(planted.read_bytes())
        planted.unlink()
        planted.symlink_to(elsewhere)
    what = "a symbolic link" if "link" in kind else "not a regular file"
    with pytest.raises(SimulationError, match=rf"{name} is {what}; a sweep store holds only"):
        _store_sweep(store)


# ---------------------------------------------------------------------------------------
# 8. every refusal on the command line is one line with exit 2


@pytest.mark.parametrize(
    ("address", "why"),
    [
        ("not a url", "missing port number"),
        ("tcp://", "missing port number"),
        ("tcp://host:99999", "port 99999 is not in 1..65535"),
        ("inproc://x", "don't know how to extract host and port"),
        ("tls://host:1", "cannot connect \\(TypeError: TLS expects"),
    ],
)
def test_a_scheduler_that_is_not_an_address_is_bad_input(tmp_path: Path, address: str, why):
    """'not a url' ended as "internal error: ValueError", exit 3."""
    pytest.importorskip("distributed")
    (tmp_path / "grid.csv").write_text("q0[0]\n1.0\n")
    proc = symmech(
        "sweep", "bouncing_ball", "--grid", "grid.csv", "--out", "o.parquet", "--t-end", "1",
        "--v0", "0", "--scheduler", address, "--quiet", cwd=tmp_path,
    )  # fmt: skip
    line = assert_one_line_error(proc, f"--scheduler {address!r}")
    assert re.search(why, line), line
    assert not (tmp_path / "o.parquet").exists()


# ---------------------------------------------------------------------------------------
# 9. SciPy with a right-hand side that is not finite at the start


@pytest.mark.parametrize("backend", ["numpy", "scipy"])
def test_a_rhs_not_finite_at_the_start_fails_at_once_on_every_backend(backend):
    """SciPy's first step became nan and its step loop never ended (C and NumPy failed at
    once); now the same check as the loops: status failed, naming t."""
    y = sm.coordinates(["y"])[0]
    scene = sm.Scene(
        [y], metric=[[1]], forces=[1 / y], walls=[sm.Wall(y + 1, restitution=sp.Rational(1, 2))]
    )
    res = _finishes(lambda: sm.simulate(scene, [0.0], [0.0], 1.0, backend=backend), 60)
    assert res.status == "failed"  # type: ignore[union-attr]
    assert res.message == "the right-hand side is not finite at t = 0.0"  # type: ignore[union-attr]


# ---------------------------------------------------------------------------------------
# 7. from_mechanics: each refusal a SceneError with its real reason


def _mechanics_models():
    me = pytest.importorskip("sympy.physics.mechanics")
    q, u = me.dynamicsymbols("q u")
    m, k = sp.symbols("m k")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)

    def point(velocity):
        P = O.locatenew("P", q * N.x)
        P.set_vel(N, velocity * N.x)
        return P

    def no_speeds():
        point(q.diff())
        return me.KanesMethod(N, q_ind=[q], u_ind=[], kd_eqs=[])

    def no_kinematics():
        point(u)
        return me.KanesMethod(N, q_ind=[q], u_ind=[u])

    def never_formed():
        point(u)
        return me.KanesMethod(N, q_ind=[q], u_ind=[u], kd_eqs=[q.diff() - u])

    def force_on_a_point_without_velocity():
        L = me.Lagrangian(N, me.Particle("p", point(q.diff()), m))
        return me.LagrangesMethod(L, [q], forcelist=[(me.Point("Q"), k * N.x)], frame=N)

    def quartic():
        qd = q.diff()
        return me.LagrangesMethod(m * qd**2 / 2 - 5 * qd**4 / 4 - k * q**2 / 2, [q])

    def root_of_velocity():
        qd = q.diff()
        return me.LagrangesMethod(-m * sp.sqrt(1 - qd**2) - k * q**2 / 2, [q])

    return {
        no_speeds: r"the KanesMethod has no generalized speeds \(u_ind=\[\]\)",
        no_kinematics: r"the KanesMethod has no kinematic differential equations \(kd_eqs=\)",
        never_formed: r"its kanes_equations\(bodies, loads\) were never formed",
        force_on_a_point_without_velocity: (
            r"the load on point Q: its velocity in the frame N is not defined"
        ),
        quartic: r"terms of degree 4 in the velocities \(-5\*Derivative\(q\(t\), t\)\*\*4/4\)",
        root_of_velocity: r"terms not polynomial in the velocities",
    }


def test_from_mechanics_refuses_each_model_with_its_reason():
    """Before: AttributeError (no speeds), ValueError (a point without velocity), "metric
    singular" / "no bodies" (never formed), "terms linear in the velocities
    (25*q'**4/4)" (a quartic Lagrangian: the Hessian mixed its terms)."""
    for build, why in _mechanics_models().items():
        with pytest.raises(sm.SceneError, match=why) as info:
            sm.Scene.from_mechanics(build())
        assert "\n" not in str(info.value), build.__name__
