"""SciPy's flow restarted in place (``scipy_flow._restart``): after an event the loop
restarts an explicit Runge-Kutta solver of SciPy at the new state instead of building it
again.  The restarted solver must be the one SciPy's constructor gives, so the steps after
a restart are compared, bit for bit, with those of a new solver; a solver whose state the
restart does not know, or a first step the constructor refuses, is built again."""

from __future__ import annotations

import numpy as np
import pytest

from symmech.simulate import scipy_flow
from symmech.simulate.scipy_flow import ScipyFlow, _restart


def _pendulums(t: float, y: np.ndarray) -> np.ndarray:
    return np.array([y[2], y[3], -np.sin(y[0]) + 0.1 * np.cos(t), -4.0 * np.sin(y[1])])


def _steps(flow: ScipyFlow, count: int) -> list:
    out = []
    for _ in range(count):
        seg = flow.advance()
        mid = 0.5 * (seg.t0 + seg.t1)
        out.append((seg.t0, seg.t1, seg.y0.tolist(), seg.y1.tolist(), seg.dense(mid).tolist()))
    return out


def _run(method: str) -> tuple[list, int]:
    """Three steps, an event-like jump of the state, a restart and five more steps."""
    flow = ScipyFlow(_pendulums, method, 1e-7, 1e-9, np.inf)
    flow.start(0.0, np.array([0.3, -0.2, 0.0, 1.0]), 10.0)
    out = _steps(flow, 3)
    t = 0.5 * (out[-1][0] + out[-1][1])
    y = np.array(out[-1][4]) * np.array([1.0, 1.0, -0.8, 0.5])  # velocities changed
    flow.limit_step(0.5 * (t - out[-1][0]))
    flow.start(t, y, 10.0)
    out += _steps(flow, 5)
    flow.start(out[-1][1], np.array(out[-1][3]), 10.0)  # a restart at a step's end
    out += _steps(flow, 3)
    flow._collect()
    return out, flow.stats.nfev


@pytest.mark.parametrize("method", ["DOP853", "RK45", "RK23"])
def test_a_restarted_solver_steps_as_a_new_one(monkeypatch, method):
    used = []

    def spy(*args):
        out = _restart(*args)
        used.append(out)
        return out

    monkeypatch.setattr(scipy_flow, "_restart", spy)
    restarted, nfev = _run(method)
    assert used == [True, True]
    monkeypatch.setattr(scipy_flow, "_restart", lambda *args: False)
    built, nfev_built = _run(method)
    assert restarted == built
    assert nfev == nfev_built


def test_a_solver_with_state_the_restart_does_not_know_is_left_alone():
    from scipy.integrate import DOP853

    solver = DOP853(_pendulums, 0.0, np.ones(4), 1.0, first_step=0.1)
    solver.step()
    before = dict(vars(solver))
    solver.something_new = 1  # a later SciPy with more state
    assert not _restart(solver, 0.5, np.zeros(4), 1.0, 0.1)
    del solver.something_new
    assert not _restart(solver, 0.5, np.zeros(4), 1.0, 0.6)  # beyond t_bound
    assert not _restart(solver, 0.5, np.zeros(4), 1.0, 0.0)
    assert vars(solver).keys() == before.keys()
    assert all(vars(solver)[k] is v for k, v in before.items())


def test_a_first_step_beyond_the_bound_is_refused_by_scipy_itself():
    flow = ScipyFlow(_pendulums, "DOP853", 1e-7, 1e-9, np.inf)
    flow.start(0.0, np.ones(4), 10.0)
    flow.advance()
    flow.h = -1.0  # no solver takes it: the constructor says why
    with pytest.raises(ValueError, match="first_step"):
        flow.start(1.0, np.ones(4), 10.0)
