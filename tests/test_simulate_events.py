"""Events the usual recipe misses: a fast-oscillating moving wall, and a wall crossed and
left again inside what would be one step.  References: the exact crossing times of the
closed-form motions, found by dense sampling and bisection here, independently of the
simulator."""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

import symmech as sm
from symmech.simulate import simulate

BACKENDS = [("numpy", "dop853"), ("scipy", "DOP853"), ("c", "dop853")]


def first_root(g, t0: float, t1: float, samples: int = 2_000_000) -> float:
    """The first sign change of g on [t0, t1] (g(t0) > 0), by dense sampling then bisection."""
    ts = np.linspace(t0, t1, samples)
    vals = g(ts)
    k = int(np.argmax(vals < 0))
    assert vals[k] < 0 <= vals[k - 1]
    a, b = ts[k - 1], ts[k]
    for _ in range(200):
        m = 0.5 * (a + b)
        if g(np.array([m]))[0] >= 0:
            a = m
        else:
            b = m
    return a


def shaker() -> sm.Scene:
    """A ball (unit mass) under gravity g above a floor shaking as A sin(w t)."""
    (y,) = sm.coordinates("y")
    A, w, g = sp.symbols("A w g", positive=True)
    alpha = sp.Symbol("alpha", nonnegative=True)
    return sm.Scene(
        (y,),
        metric=sp.Matrix([[1]]),
        potential=g * y,
        walls=[sm.Wall(y - A * sp.sin(w * sm.t), restitution=alpha, name="shaker")],
        name="shaker",
    )


@pytest.mark.parametrize("backend,method", BACKENDS)
def test_a_fast_oscillating_wall_is_hit_at_its_first_crossing(backend, method):
    params = {"A": 0.05, "w": 2000.0, "g": 9.81, "alpha": 0.5}
    # the ball falls from 1 m; the floor oscillates 318 times a second: the first crossing
    # is at the first time the ball meets the wall's upper swing
    res = simulate(
        shaker(),
        [1.0],
        [0.0],
        0.47,
        params=params,
        backend=backend,
        method=method,
        rtol=1e-9,
        atol=1e-11,
        contact="stop",
    )
    exact = first_root(lambda t: 1 - 9.81 * t**2 / 2 - 0.05 * np.sin(2000 * t), 0.0, 0.47)
    impacts = res.impacts()
    assert impacts, res.message
    assert impacts[0].time == pytest.approx(exact, abs=1e-9)
    # never below the moving floor at the accepted steps
    gap = res.q[:, 0] - 0.05 * np.sin(2000 * res.t)
    assert gap.min() > -1e-9


def ridge() -> sm.Scene:
    """A free point (x, y) (no forces) and the wall y >= 1 - k (x - c)^2: a ridge whose top
    rises above a horizontal path at height y0 < 1 on |x - c| < sqrt((1 - y0)/k)."""
    x, y = sm.coordinates("x y")
    k, c = sp.symbols("k c", positive=True)
    psi = y - 1 + k * (x - c) ** 2
    return sm.Scene(
        (x, y), metric=sp.eye(2), walls=[sm.Wall(psi, restitution=1, name="ridge")], name="ridge"
    )


@pytest.mark.parametrize("backend,method", BACKENDS)
@pytest.mark.parametrize("k", [1.0, 100.0])
def test_a_wall_entered_and_left_inside_one_step_is_found(backend, method, k):
    # straight-line motion is exact for every Runge-Kutta method, so one step spans the
    # whole run and its samples lie 1.25 apart; the path is inside the ridge only on
    # |x - 5| < 0.1 (k = 1) or 0.01 (k = 100): both crossings fall between two samples
    params = {"k": k, "c": 5.0}
    res = simulate(
        ridge(),
        [0.0, 0.99],
        [1.0, 0.0],
        10.0,
        params=params,
        backend=backend,
        method=method,
        event_samples=8,
    )
    exact = 5.0 - math.sqrt(0.01 / k)
    impacts = res.impacts()
    assert len(impacts) == 1, [e.kind for e in res.events]
    assert impacts[0].time == pytest.approx(exact, abs=1e-9)
    # elastic: the speed is kept (to the impact map's rounding: its denominator
    # 4 k^2 (x - c)^2 + 1 is evaluated expanded) and the point leaves the ridge's flank
    e = impacts[0]
    assert np.linalg.norm(e.v_plus) == pytest.approx(1.0, rel=1e-9)
    normal = np.array([2 * k * (e.q[0] - 5.0), 1.0])
    assert normal @ e.v_plus == pytest.approx(-(normal @ e.v_minus), rel=1e-9)


@pytest.mark.parametrize("backend,method", BACKENDS)
def test_accumulation_on_a_moving_wall_stops_with_status_zeno(backend, method):
    params = {"A": 1e-3, "w": 1.0, "g": 9.81, "alpha": 0.5}
    res = simulate(shaker(), [0.2], [0.0], 5.0, params=params, backend=backend, method=method)
    assert res.status == "zeno"
    assert "moves" in res.message
