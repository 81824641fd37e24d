"""The event search's stage certificate (``StepSearch._screened_end``): a step whose gaps'
rates at the stages never turn from negative to positive is not sampled where no gap
ends below zero, and is bisected over the samples where one does
(``StepSearch._first_negative``).

Checked three ways: the whole runs are the same, bit for bit, as the search that samples
every step (a monkeypatched ``_screened_end``) on the built-in cases and all four Python
routes; a gap that dips below zero between two positive step ends (rates turning) is
still found; and a certified step never forms its continuous output."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from symmech.bench.cases import CASES
from symmech.simulate import detection
from symmech.simulate.detection import StepSearch, _no_minimum
from symmech.simulate.flow import Segment

ROUTES = [("numpy", "dop853"), ("numpy", "rk45"), ("scipy", "DOP853"), ("scipy", "RK45")]


def _run(name: str, backend: str, method: str, rtol: float) -> tuple:
    res = CASES[name].simulate(backend=backend, method=method, rtol=rtol, atol=rtol / 100)
    dense = res.sol(np.linspace(0.0, res.t[-1], 57))  # the steps' continuous output
    return res.status, res.t, res.y, [(e.time, e.wall, e.kind) for e in res.events], dense


@pytest.mark.parametrize(("backend", "method"), ROUTES)
def test_certified_runs_equal_the_fully_sampled_runs(monkeypatch, backend, method):
    """The ellipse and the disc over their flights, the ellipse coming to rest (a contact
    after certified steps), the falling rod (two walls) and the ladder (two walls, resting
    contact): the same events, states and continuous output, bit for bit."""
    names = (
        "ellipse_gravity_flight",
        "disk_3_7_gravity_flight",
        "ellipse_gravity",
        "falling_rod",
        "ladder",
    )
    certified = {}
    ends, firsts = [], []
    screened_end, first_negative = StepSearch._screened_end, StepSearch._first_negative

    def spy_end(self):
        out = screened_end(self)
        ends.append(out)
        return out

    def spy_first(end, at, last):
        out = first_negative(end, at, last)
        firsts.append(out)
        return out

    monkeypatch.setattr(StepSearch, "_screened_end", spy_end)
    monkeypatch.setattr(StepSearch, "_first_negative", staticmethod(spy_first))
    for name in names:
        for rtol in (1e-3, 1e-8):
            certified[name, rtol] = _run(name, backend, method, rtol)
    # the certificate was used: steps skipped, and steps bisected to a later sample
    assert any(e is not None and min(e) >= 0 for e in ends) and max(firsts) > 1
    monkeypatch.setattr(StepSearch, "_screened_end", lambda self: None)
    for (name, rtol), fast in certified.items():
        slow = _run(name, backend, method, rtol)
        assert fast[0] == slow[0], (name, rtol)
        assert np.array_equal(fast[1], slow[1]) and np.array_equal(fast[2], slow[2]), name
        assert fast[3] == slow[3], (name, rtol)
        assert np.array_equal(fast[4], slow[4]), (name, rtol)


def test_no_minimum():
    assert _no_minimum([1.0, 0.5, -0.2, -1.0])  # a maximum, then falling
    assert _no_minimum([-1.0, -0.5, -0.1])  # falling throughout
    assert _no_minimum([0.3, 0.0, 0.2])  # a zero rate is not a turn
    assert not _no_minimum([-1.0, 0.0, 0.5])  # a minimum
    assert not _no_minimum([1.0, -0.2, 0.1, -1.0])  # a minimum between two maxima
    assert _no_minimum([math.nan, -1.0])


class _Gap:
    """A one-coordinate 'motion' ``q(t)`` with the gap psi = q: its step segment with the
    rates at DOP853-like nodes, and a run that the search reads."""

    NODES = (0.0, 0.05, 0.08, 0.12, 0.25, 0.28, 0.31, 0.33, 0.6, 0.65, 0.86, 1.0, 1.0)

    def __init__(self, q, qdot, t0=0.0, t1=1.0):
        self.q, self.qdot, self.t0, self.t1 = q, qdot, t0, t1
        self.dense_calls = 0

    def segment(self) -> Segment:
        def dense(t):
            self.dense_calls += 1
            return np.array([self.q(t), self.qdot(t)])

        h = self.t1 - self.t0
        rates = [self.qdot(self.t0 + c * h) for c in self.NODES]

        def head(t, m):  # the coordinates alone, sample by sample (as DOP853's)
            return dense(t)[:m].tolist()

        seg = Segment(self.t0, self.t1, dense(self.t0), dense(self.t1), None, dense, head=head)
        self.dense_calls = 0
        seg.gap_rates = (list(self.NODES), [rates])
        return seg

    def run(self) -> SimpleNamespace:
        f = SimpleNamespace(
            gap_function=lambda w: lambda t, q: float(q[0]),
            normal_rate=lambda w, t, y: float(y[1]),
            eps=float(np.finfo(float).eps),
        )
        return SimpleNamespace(
            f=f,
            mode=(),
            walls=1,
            n=1,
            tol_psi=1e-12,
            banded=set(),
            grazing=set(),
            time_scale=1.0,
            o=SimpleNamespace(samples=8),
        )


def test_a_dip_between_positive_ends_is_found():
    """psi = (t - 0.5)^2 - 0.01: positive at both ends, below zero from t = 0.4 to 0.6;
    the rates turn from negative to positive, so the step is sampled and the entry at
    t = 0.4 found."""
    gap = _Gap(lambda t: (t - 0.5) ** 2 - 0.01, lambda t: 2 * (t - 0.5))
    found = StepSearch(gap.run(), gap.segment()).earliest()
    assert found is not None and found[2:] == (0, "wall")
    assert abs(found[0] - 0.4) < 1e-12


def test_a_certified_step_forms_no_continuous_output():
    """A gap that rises then falls and stays positive: no event, no dense call."""
    gap = _Gap(lambda t: 1 + t - t * t, lambda t: 1 - 2 * t)
    assert StepSearch(gap.run(), gap.segment()).earliest() is None
    assert gap.dense_calls == 0


def test_a_single_crossing_is_bisected_to_the_sampled_bracket(monkeypatch):
    """A falling gap that crosses zero at t = 0.7: the certificate bisects to the sample
    bracket the full search finds, so the same event time, with fewer samples."""
    gap = _Gap(lambda t: 0.49 - t * t, lambda t: -2 * t)
    fast = StepSearch(gap.run(), gap.segment()).earliest()
    fast_calls = gap.dense_calls
    monkeypatch.setattr(detection.StepSearch, "_screened_end", lambda self: None)
    slow = StepSearch(gap.run(), gap.segment()).earliest()
    assert fast is not None and slow is not None
    assert fast[0] == slow[0] and abs(fast[0] - 0.7) < 1e-12
    assert fast_calls < gap.dense_calls


@pytest.mark.parametrize("name", ["DOP853", "RK45", "RK23", "Radau"])
def test_scipy_output_formed_late_is_the_output_formed_at_once(name):
    """A SciPy step's continuous output formed after the solver took its next step (from
    the copy ``_snapshot`` keeps) equals the one formed at once, bit for bit; an implicit
    solver is not copied (its output is formed at once)."""
    from scipy import integrate

    from symmech.simulate.scipy_flow import _snapshot

    def f(t, y):
        return np.array([y[1], -np.sin(y[0]), np.cos(t)])

    solver = getattr(integrate, name)(f, 0.0, np.array([1.0, 0.0, 0.0]), 10.0)
    solver.step()
    solver.step()
    copy = _snapshot(solver)
    if name == "Radau":
        assert copy is None
        return
    now = solver.dense_output()
    solver.step()
    ts = np.linspace(now.t_min, now.t_max, 9)
    assert np.array_equal(copy.dense_output()(ts), now(ts))
