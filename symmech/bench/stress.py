"""Stiff and extreme cases: each prints its error against its reference and pass/fail.

Every case runs the simulator on an input chosen to break it and measures one number
against a reference that does not come from the simulator: a closed form, a conserved
quantity, or an exact property of the impact law.  A case also fails on any NaN or Inf
in the result, on a run that does not end (every run has a finite ``max_events``), and on
tunnelling (a gap below ``-10 atol`` at an accepted step).

========================  ===============================================================
case                      reference
========================  ===============================================================
mass/inertia ratio        energy of an elastic run (Carnot paper Thm 3.2: alpha = 1
                          conserves it) of the falling ellipse with I/m = 1e-8 .. 1e8
ellipse aspect ratio      first impact time sqrt(2 (y0 - h)/g) of an ellipse of aspect
                          1e-4 .. 1e4 dropped with theta within 1e-12 of pi/2 (h its
                          support function), then energy of the elastic run
grazing                   two balls closing at 1e-10 (momentum kept, no tunnelling); a
                          pendulum touching its wall with zero speed (energy kept)
nearly dependent wall     a point on a line of slope eps hitting y = 0: v+ = -alpha v-
                          exactly; error against the reported condition number, and a
                          clear failure once it passes the limit (eps = 1e-2 .. 1e-10)
stiff potential           energy of the elastic stiff dumbbell (k = 1e4 .. 1e8)
Zeno                      the ball's accumulation time sqrt(2h/g)(1+alpha)/(1-alpha)
10^4 elastic bounces      energy drift over 10^4 impacts of the elastic ball
Newton's cradle           5 touching balls: the velocity passes to the last, exactly
========================  ===============================================================

The cases with several contacts at once are in :mod:`symmech.bench.stress_contacts`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator

import numpy as np
import sympy as sp

import symmech.simulate as simulate_pkg
from symmech.bench.stress_contacts import CONTACT_CASES
from symmech.bench.stress_support import StressResult, energy, format_table, result, sane
from symmech.declaration.symbols import coordinates, velocities
from symmech.declaration.wall import Wall
from symmech.examples import (
    bouncing_ball,
    ellipse_gravity,
    newtons_cradle,
    pendulum_wall,
    stiff_dumbbell,
)
from symmech.scene import Scene

__all__ = ["CASES", "StressResult", "format_table", "run_all", "sloped_line"]


def _ellipse_gap(a: float, b: float) -> Callable[[np.ndarray], np.ndarray]:
    def gap(q: np.ndarray) -> np.ndarray:
        return q[:, 1] - np.sqrt(a**2 * np.sin(q[:, 2]) ** 2 + b**2 * np.cos(q[:, 2]) ** 2)

    return gap


def mass_ratio(backend: str) -> Iterator[StressResult]:
    scene = ellipse_gravity()
    for ratio in (1e-8, 1e-4, 1.0, 1e4, 1e8):
        t0 = time.perf_counter()
        p = {"m": 1.0, "I": ratio, "a": 1.0, "b": 0.5, "g": 9.81, "alpha": 1.0}
        res = simulate_pkg.simulate(
            scene, [0, 1.5, 0.3], [0, 0, 2.0], 3.0, params=p, backend=backend, max_events=20_000
        )
        e0 = energy(scene, p, np.array([0, 1.5, 0.3]), np.array([0, 0, 2.0]))
        e1 = energy(scene, p, res.q[-1], res.v[-1])
        err = abs(e1 - e0) / abs(e0)
        yield result(
            "mass/inertia ratio",
            f"I/m = {ratio:g}",
            err,
            1e-6,
            sane(res, _ellipse_gap(1.0, 0.5), 1e-10) or ("" if res.success else res.message),
            t0,
            f"{res.stats['impacts']} impacts, relative energy error",
        )


def aspect_ratio(backend: str) -> Iterator[StressResult]:
    scene = ellipse_gravity()
    for aspect in (1e-4, 1e-2, 1e2, 1e4):
        t0 = time.perf_counter()
        a, b = 1.0, 1.0 / aspect
        th = math.pi / 2 - 1e-12
        p = {"m": 1.0, "I": (a * a + b * b) / 4, "a": a, "b": b, "g": 9.81, "alpha": 1.0}
        h = math.sqrt(a**2 * math.sin(th) ** 2 + b**2 * math.cos(th) ** 2)
        y0 = h + 1.0
        res = simulate_pkg.simulate(
            scene, [0, y0, th], [0, 0, 0], 1.0, params=p, backend=backend, max_events=20_000
        )
        impacts = res.impacts()
        exact = math.sqrt(2 * 1.0 / 9.81)
        err = abs(impacts[0].time - exact) if impacts else math.inf
        yield result(
            "ellipse aspect ratio",
            f"b/a = {1 / aspect:g}, theta = pi/2 - 1e-12",
            err,
            1e-9,
            sane(res, _ellipse_gap(a, b), 1e-10) or ("" if res.success else res.message),
            t0,
            "first impact time against sqrt(2 (y0 - h)/g)",
        )


def grazing(backend: str) -> Iterator[StressResult]:
    # two free balls closing a gap of 2e-10 at 1e-10: a touch below the velocity tolerance
    t0 = time.perf_counter()
    res = simulate_pkg.simulate(
        newtons_cradle(2),
        [0.0, 1.0 + 2e-10],
        [1e-10, 0.0],
        5.0,
        params={"m": 1, "r": 0.5},
        backend=backend,
    )

    def gap(q: np.ndarray) -> np.ndarray:
        return q[:, 1] - q[:, 0] - 1.0

    momentum = abs(float(np.sum(res.v[-1])) - 1e-10)
    kinds = ",".join(e.kind for e in res.events) or "none"
    yield result(
        "grazing",
        "normal speed 1e-10",
        momentum,
        1e-24,
        sane(res, gap, 1e-10),
        t0,
        f"events: {kinds}; momentum error",
    )
    # a pendulum released at the mirror angle touches the wall x = d with zero speed
    t0 = time.perf_counter()
    scene = pendulum_wall()
    p = {"alpha": 0.9, "d": 0.5, "g": 9.81, "l": 1.0, "m": 1.0}
    res = simulate_pkg.simulate(
        scene,
        [-math.asin(0.5)],
        [0.0],
        4.0,
        params=p,
        backend=backend,
        rtol=1e-12,
        atol=1e-14,
    )
    e0 = energy(scene, p, np.array([-math.asin(0.5)]), np.array([0.0]))
    e1 = energy(scene, p, res.q[-1], res.v[-1])
    kinds = ",".join(e.kind for e in res.events) or "none"
    yield result(
        "grazing",
        "exactly tangent",
        abs(e1 - e0) / abs(e0),
        1e-10,
        sane(res, lambda q: 0.5 - np.sin(q[:, 0]), 1e-14),
        t0,
        f"events: {kinds}; relative energy error",
    )


def sloped_line() -> Scene:
    """A unit point in the plane on the line of slope ``tan(eps)`` (the constraint
    ``-sin(eps) x_dot + cos(eps) y_dot = 0``) hitting the floor y = 0 with restitution
    alpha: the impact map is ``v+ = -alpha v-`` exactly, and the floor's normal lies at
    angle eps from the constraint's span."""
    x, y = coordinates("x y")
    xd, yd = velocities((x, y))
    eps = sp.Symbol("epsilon", positive=True)
    alpha = sp.Symbol("alpha", nonnegative=True)
    return Scene(
        (x, y),
        metric=sp.eye(2),
        constraints=[-sp.sin(eps) * xd + sp.cos(eps) * yd],
        walls=[Wall(y, restitution=alpha, name="floor")],
        name="sloped_line",
    )


def nearly_dependent(backend: str) -> Iterator[StressResult]:
    scene = sloped_line()
    for eps in (1e-2, 1e-4, 1e-6, 1e-8, 1e-10):
        t0 = time.perf_counter()
        # along the line at speed 1/sin(eps): normal speed 1, reaching the floor at t = 1
        speed = 1 / math.sin(eps)
        v = np.array([-math.cos(eps), -math.sin(eps)]) * speed
        q = np.array([math.cos(eps) * speed, 1.0])
        res = simulate_pkg.simulate(
            scene,
            q,
            v,
            1.5,
            params={"epsilon": eps, "alpha": 0.5},
            backend=backend,
            strategy="linear_solve",
            rtol=1e-13,
            atol=1e-15,
        )
        if res.status == "failed":
            ok = "nearly dependent" in res.message
            yield StressResult(
                "nearly dependent wall",
                f"eps = {eps:g}",
                math.nan,
                math.nan,
                ok,
                "refused: " + res.message[:110],
                time.perf_counter() - t0,
            )
            continue
        imp = res.impacts()
        err = (
            float(np.max(np.abs(imp[0].v_plus + 0.5 * imp[0].v_minus)) / speed) if imp else math.inf
        )
        cond = res.stats["impact_condition"]
        yield result(
            "nearly dependent wall",
            f"eps = {eps:g}",
            err,
            100 * cond * 2.2e-16 + 1e-15,
            "",
            t0,
            f"condition number {cond:.2g}; relative error, tolerance 100 cond eps",
        )


def stiff(backend: str) -> Iterator[StressResult]:
    scene = stiff_dumbbell()
    for k in (1e4, 1e6, 1e8):
        t0 = time.perf_counter()
        p = {"L": 1.0, "alpha": 1.0, "g": 9.81, "k": k, "m": 1.0}
        q0, v0 = np.array([0.5, 1.5]), np.array([0.0, 0.0])
        res = simulate_pkg.simulate(
            scene, q0, v0, 0.5, params=p, backend=backend, rtol=1e-9, atol=1e-11
        )
        e0, e1 = energy(scene, p, q0, v0), energy(scene, p, res.q[-1], res.v[-1])
        yield result(
            "stiff potential",
            f"k = {k:g}",
            abs(e1 - e0) / abs(e0),
            1e-6,
            sane(res, lambda q: q[:, 0], 1e-11),
            t0,
            f"{res.stats['steps']} steps, {res.stats['impacts']} impacts; relative energy error",
        )


def zeno(backend: str) -> Iterator[StressResult]:
    scene = bouncing_ball()
    for alpha in (0.5, 0.9, 0.99):
        t0 = time.perf_counter()
        p = {"m": 1.0, "g": 9.81, "alpha": alpha}
        res = simulate_pkg.simulate(
            scene,
            [1.0],
            [0.0],
            1000.0,
            params=p,
            backend=backend,
            contact="stop",
            rtol=1e-10,
            atol=1e-12,
        )
        exact = math.sqrt(2 / 9.81) * (1 + alpha) / (1 - alpha)
        got = res.accumulation_time if res.accumulation_time is not None else math.inf
        yield result(
            "Zeno",
            f"alpha = {alpha:g}",
            abs(got - exact) / exact,
            1e-7,
            sane(res, lambda q: q[:, 0], 1e-12) or ("" if res.status == "zeno" else res.message),
            t0,
            f"{res.stats['impacts']} impacts; relative error of t*",
        )


def elastic_bounces(backend: str) -> Iterator[StressResult]:
    scene = bouncing_ball()
    t0 = time.perf_counter()
    p = {"m": 1.0, "g": 9.81, "alpha": 1.0}
    period = 2 * math.sqrt(2 / 9.81)
    res = simulate_pkg.simulate(
        scene, [1.0], [0.0], 1e4 * period, params=p, backend=backend, max_events=20_000
    )
    e1 = energy(scene, p, res.q[-1], res.v[-1])
    yield result(
        "10^4 elastic bounces",
        f"{res.stats['impacts']} impacts",
        abs(e1 - 9.81) / 9.81,
        1e-9,
        sane(res, lambda q: q[:, 0], 1e-10) or ("" if res.success else res.message),
        t0,
        "relative energy drift",
    )


def cradle(backend: str) -> Iterator[StressResult]:
    t0 = time.perf_counter()
    scene = newtons_cradle(5)
    res = simulate_pkg.simulate(
        scene,
        [0.0, 1.0, 2.0, 3.0, 4.0],
        [1.0, 0, 0, 0, 0],
        1.0,
        params={"m": 1, "r": 0.5},
        backend=backend,
    )
    err = float(np.max(np.abs(res.v[-1] - [0, 0, 0, 0, 1.0])))

    def gap(q: np.ndarray) -> np.ndarray:
        return np.min(np.diff(q, axis=1) - 1.0, axis=1)

    yield result(
        "Newton's cradle",
        "5 balls, zero gaps",
        err,
        1e-15,
        sane(res, gap, 1e-10),
        t0,
        f"{res.stats['impacts']} impacts; velocity error",
    )


CASES: dict[str, Callable[[str], Iterator[StressResult]]] = {
    "mass_ratio": mass_ratio,
    "aspect_ratio": aspect_ratio,
    "grazing": grazing,
    "nearly_dependent": nearly_dependent,
    "stiff": stiff,
    "zeno": zeno,
    "elastic_bounces": elastic_bounces,
    "cradle": cradle,
    **CONTACT_CASES,
}


def run_all(backend: str = "c", only: list[str] | None = None) -> list[StressResult]:
    """Every stress case (or those named in ``only``) on ``backend``."""
    out: list[StressResult] = []
    for name, case in CASES.items():
        if only and name not in only:
            continue
        out.extend(case(backend))
    return out
