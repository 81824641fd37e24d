"""Stress cases with several contacts at once, each against a reference that does not come
from the simulator.

========================  ===============================================================
case                      reference
========================  ===============================================================
ladder                    leaves the frictionless wall when sin theta = (2/3) sin theta0,
                          at the time of the energy integral (theta0 = 1.3, 1.0, 0.6)
rod dropped flat          rebounds straight up: ydot+ = alpha sqrt(2 g h), thetadot+ = 0
                          (alpha = 0, 0.5, 1); with alpha < 1 it ends at rest on both ends
box on a corner           a square dropped corner first, alpha = 0: it rocks down onto a
                          side and rests there (y = a, theta = 0 mod pi/2, v = 0)
stack of two discs        dropped onto the floor one above the other, alpha = 0.5: at rest,
                          y1 = r, y2 = 3 r (a contact between bodies)
cradles                   5 and 10 touching balls, one or two swung in, rtol 1e-4..1e-12:
                          the velocities pass to the far end exactly
touching row at rest      5 touching balls at rest for 100 s: no event at all
========================  ===============================================================
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterator

import mpmath
import numpy as np
import sympy as sp

import symmech.simulate as simulate_pkg
from symmech.bench.stress_support import StressResult, result, sane
from symmech.declaration.symbols import coordinates
from symmech.declaration.wall import Wall
from symmech.examples import newtons_cradle
from symmech.scene import Scene
from symmech.scenefile import load_scene

__all__ = ["CONTACT_CASES", "box", "disc_stack"]

G = 9.81


def _ladder_leave_time(theta0: float) -> float:
    """The ladder (l = 1) leaves the wall at this time (energy integral, theta = theta0 -
    s^2; sin theta0 - sin theta = 2 cos(theta0 - s^2/2) sin(s^2/2))."""
    k = 3 * G / 2
    s1 = mpmath.sqrt(theta0 - mpmath.asin(mpmath.mpf(2) / 3 * mpmath.sin(theta0)))

    def f(s: mpmath.mpf) -> mpmath.mpf:
        gap = 2 * mpmath.cos(theta0 - s * s / 2) * mpmath.sin(s * s / 2)
        return 2 * s / mpmath.sqrt(k * gap)

    return float(mpmath.quad(f, [0, s1]))


def ladder(backend: str) -> Iterator[StressResult]:
    scene = load_scene("ladder")
    p = {"alpha": 0.0, "g": G, "l": 1.0, "m": 1.0}
    for theta0 in (1.3, 1.0, 0.6):
        t0 = time.perf_counter()
        t_leave = _ladder_leave_time(theta0)
        q0 = [math.cos(theta0), math.sin(theta0), theta0]
        res = simulate_pkg.simulate(
            scene, q0, [0.0, 0.0, 0.0], 1.2 * t_leave, params=p, backend=backend,
            rtol=1e-10, atol=1e-12,
        )  # fmt: skip
        gone = [e for e in res.events if e.kind == "release" and e.wall_name == "wall"]
        err = math.inf
        if gone:
            e = gone[0]
            err = max(
                abs(math.sin(e.q[2]) / math.sin(theta0) - 2 / 3) / (2 / 3),
                abs(e.time - t_leave) / t_leave,
            )
        gap = lambda q: np.minimum(q[:, 1] - np.sin(q[:, 2]), q[:, 0] - np.cos(q[:, 2]))  # noqa: E731
        yield result(
            "ladder", f"theta0 = {theta0:g}", err, 1e-6,
            sane(res, gap, 1e-12) or ("" if res.success else res.message), t0,
            f"leaves at t = {gone[0].time:.6f}; relative error of sin theta and t" if gone
            else "never left the wall",
        )  # fmt: skip


def rod_flat(backend: str) -> Iterator[StressResult]:
    scene = load_scene("falling_rod")
    for alpha in (0.0, 0.5, 1.0):
        t0 = time.perf_counter()
        p = {"alpha": alpha, "g": G, "l": 1.0, "m": 1.0}
        res = simulate_pkg.simulate(
            scene, [0.0, 1.0, 0.0], [0.0, 0.0, 0.0], 3.0, params=p, backend=backend
        )
        first = res.impacts()[0].v_plus if res.impacts() else np.full(3, np.nan)
        err = float(np.max(np.abs(first - [0.0, alpha * math.sqrt(2 * G), 0.0])))
        if alpha < 1:  # at rest on both ends
            err = max(err, float(np.max(np.abs(res.q[-1]))), float(np.max(np.abs(res.v[-1]))))
        gap = lambda q: np.minimum(q[:, 1] - np.sin(q[:, 2]), q[:, 1] + np.sin(q[:, 2]))  # noqa: E731
        yield result(
            "rod dropped flat", f"alpha = {alpha:g}", err, 1e-9,
            sane(res, gap, 1e-10) or ("" if res.success else res.message), t0,
            f"{res.stats['impacts']} impacts, {res.stats['contacts']} contacts; error of v+"
            + (" and of the rest state" if alpha < 1 else ""),
        )  # fmt: skip


def box() -> Scene:
    """A square (mass m, half-side a, inertia m (2a)^2 / 6) over the floor y = 0: one wall
    per corner, ``y + cx sin(theta) + cy cos(theta) >= 0`` for the corner (cx, cy)."""
    x, y, th = coordinates(["x", "y", "theta"])
    m, a, g = sp.symbols("m a g", positive=True)
    walls = [
        Wall(y + cx * a * sp.sin(th) + cy * a * sp.cos(th), restitution=0, name=f"c{k}")
        for k, (cx, cy) in enumerate([(1, 1), (-1, 1), (-1, -1), (1, -1)])
    ]
    metric = sp.diag(m, m, sp.Rational(2, 3) * m * a**2)
    return Scene([x, y, th], metric=metric, potential=m * g * y, walls=walls, name="box")


def box_corner(backend: str) -> Iterator[StressResult]:
    scene = box()
    t0 = time.perf_counter()
    p = {"m": 1.0, "a": 0.5, "g": G}
    th0 = math.pi / 4 + 0.1
    h = 0.3 + 0.5 * math.sqrt(2) * math.cos(0.1)  # the lowest corner 0.3 above the floor
    res = simulate_pkg.simulate(
        scene, [0.0, h, th0], [0.0, 0.0, 0.0], 4.0, params=p, backend=backend, max_events=5000
    )
    y, th = res.q[-1, 1], res.q[-1, 2]
    tilt = abs(math.remainder(th, math.pi / 2))
    err = max(abs(y - 0.5), tilt, float(np.max(np.abs(res.v[-1]))))

    def gap(q: np.ndarray) -> np.ndarray:
        s, c = np.sin(q[:, 2]), np.cos(q[:, 2])
        return q[:, 1] - 0.5 * (np.abs(s) + np.abs(c))

    yield result(
        "box on a corner", "alpha = 0", err, 1e-8,
        sane(res, gap, 1e-10) or ("" if res.success else res.message), t0,
        f"{res.stats['impacts']} impacts, {res.stats['contacts']} contacts; error of the rest",
    )  # fmt: skip


def disc_stack() -> Scene:
    """Two discs (mass m, radius r) over the floor: each on the floor, and the contact
    between them ``|c2 - c1| - 2 r >= 0``."""
    x1, y1, x2, y2 = coordinates(["x1", "y1", "x2", "y2"])
    m, r, g, alpha = sp.symbols("m r g alpha", positive=True)
    walls = [
        Wall(y1 - r, restitution=alpha, name="floor1"),
        Wall(y2 - r, restitution=alpha, name="floor2"),
        Wall(sp.sqrt((x2 - x1) ** 2 + (y2 - y1) ** 2) - 2 * r, restitution=alpha, name="discs"),
    ]
    return Scene(
        [x1, y1, x2, y2], metric=sp.eye(4) * m, potential=m * g * (y1 + y2), walls=walls,
        name="disc_stack",
    )  # fmt: skip


def stack(backend: str) -> Iterator[StressResult]:
    scene = disc_stack()
    t0 = time.perf_counter()
    p = {"m": 1.0, "r": 0.25, "g": G, "alpha": 0.5}
    q0 = [0.0, 0.25 + 0.5, 0.0, 0.75 + 0.5 + 0.2]
    res = simulate_pkg.simulate(
        scene, q0, [0.0] * 4, 4.0, params=p, backend=backend, max_events=5000
    )
    err = max(
        float(np.max(np.abs(res.q[-1] - [0.0, 0.25, 0.0, 0.75]))),
        float(np.max(np.abs(res.v[-1]))),
    )

    def gap(q: np.ndarray) -> np.ndarray:
        d = np.hypot(q[:, 2] - q[:, 0], q[:, 3] - q[:, 1]) - 0.5
        return np.minimum(np.minimum(q[:, 1], q[:, 3]) - 0.25, d)

    yield result(
        "stack of two discs", "alpha = 0.5", err, 1e-8,
        sane(res, gap, 1e-10) or ("" if res.success else res.message), t0,
        f"{res.stats['impacts']} impacts, {res.stats['contacts']} contacts; error of the rest",
    )  # fmt: skip


def cradles(backend: str) -> Iterator[StressResult]:
    p = {"m": 1.0, "r": 0.1}
    for balls in (5, 10):
        scene = newtons_cradle(balls)
        for swung in (1, 2):
            t0 = time.perf_counter()
            x = 0.2 * np.arange(balls)
            x[:swung] -= 0.05
            v0 = np.zeros(balls)
            v0[:swung] = 1.0
            vf = np.zeros(balls)
            vf[balls - swung :] = 1.0
            err, problem = 0.0, ""
            for rtol in (1e-4, 1e-8, 1e-12):
                res = simulate_pkg.simulate(
                    scene, x, v0, 1.0, params=p, backend=backend, rtol=rtol, atol=rtol / 100
                )
                err = max(err, float(np.max(np.abs(res.v[-1] - vf))))
                gap = lambda q: np.min(np.diff(q, axis=1) - 0.2, axis=1)  # noqa: E731
                problem = problem or sane(res, gap, 1e-6) or ("" if res.success else res.message)
            yield result(
                "cradle", f"{balls} balls, {swung} swung in", err, 1e-9, problem, t0,
                "rtol 1e-4, 1e-8, 1e-12; velocity error",
            )  # fmt: skip


def touching_rest(backend: str) -> Iterator[StressResult]:
    scene = newtons_cradle(5)
    t0 = time.perf_counter()
    res = simulate_pkg.simulate(
        scene, 0.2 * np.arange(5), np.zeros(5), 100.0, params={"m": 1.0, "r": 0.1},
        backend=backend,
    )  # fmt: skip
    err = float(len(res.events) + np.max(np.abs(res.v[-1])))
    yield result(
        "touching row at rest", "5 balls, 100 s", err, 0.0,
        "" if res.success else res.message, t0, "events + |v|",
    )  # fmt: skip


CONTACT_CASES = {
    "ladder": ladder,
    "rod_flat": rod_flat,
    "box_corner": box_corner,
    "disc_stack": stack,
    "cradles": cradles,
    "touching_rest": touching_rest,
}
