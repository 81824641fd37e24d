"""The baseline a user writes today: ``solve_ivp`` + ``lambdify`` + a terminal event.

Exactly the usual recipe: the scene's closed-form right-hand side and impact maps turned
into Python functions by ``sympy.lambdify``, ``scipy.integrate.solve_ivp`` (DOP853 by
default) with one terminal event per wall on psi (``direction = -1``), and a Python loop
that applies the impact map at each terminal event and restarts the integration from
there, up to a cap on the number of impacts.  Nothing else: no sampling inside steps, no
accumulation detection, no contact.  Its failures (a wall crossed between step ends, a
restart that fires again at once, the impact cap hit in an accumulation) are what the
work-precision benchmark shows beside symmech's runs.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import sympy as sp

from symmech.declaration.symbols import t as TIME
from symmech.scene import Scene

__all__ = ["BaselineResult", "baseline_run"]


@dataclass
class BaselineResult:
    """What the baseline produced: final state, impact times, and why it stopped."""

    t: float
    y: np.ndarray
    impact_times: list[float]
    status: str
    wall_time: float
    nfev: int
    min_gap: float
    notes: list[str] = field(default_factory=list)


def _lambdify(scene: Scene, params: Mapping[str, float]) -> tuple[Any, list, list]:
    subs = {p: params[str(p)] for p in scene.parameters}
    q, v = list(scene.coordinates), list(scene.velocities)
    ydot = sp.Matrix(list(scene.kinematics()) + list(scene.acceleration())).xreplace(subs)
    rhs = sp.lambdify([TIME, q + v], list(ydot), modules="numpy")
    psis = [sp.lambdify([TIME, q + v], w.psi.xreplace(subs), modules="numpy") for w in scene.walls]
    maps = [
        sp.lambdify(
            [TIME, q + v], list(scene.impact_map(i).post_velocity.xreplace(subs)), modules="numpy"
        )
        for i in range(len(scene.walls))
    ]
    return rhs, psis, maps


def baseline_run(
    scene: Scene,
    q0: Any,
    v0: Any,
    t_end: float,
    params: Mapping[str, float],
    *,
    rtol: float,
    atol: float,
    method: str = "DOP853",
    max_impacts: int = 500,
    prepared: tuple | None = None,
) -> BaselineResult:
    """Run the baseline (see the module docstring); ``prepared`` reuses the lambdified
    functions of an earlier call (the lambdify cost is not part of a run's time)."""
    from scipy.integrate import solve_ivp

    rhs, psis, maps = prepared if prepared is not None else _lambdify(scene, params)
    n = scene.n

    def fun(t: float, y: np.ndarray) -> list:
        return rhs(t, y)

    events = []
    for psi in psis:

        def ev(t: float, y: np.ndarray, _psi: Any = psi) -> float:
            return float(_psi(t, y))

        ev.terminal = True  # type: ignore[attr-defined]
        ev.direction = -1  # type: ignore[attr-defined]
        events.append(ev)
    clock = time.perf_counter()
    t, y = 0.0, np.concatenate([np.asarray(q0, float), np.asarray(v0, float)])
    impacts: list[float] = []
    nfev = 0
    min_gap = min((float(p(t, y)) for p in psis), default=np.inf)
    status = "finished"
    while t < t_end:
        sol = solve_ivp(fun, (t, t_end), y, method=method, rtol=rtol, atol=atol, events=events)
        nfev += sol.nfev
        if sol.status == -1:
            status = "failed"
            break
        t, y = float(sol.t[-1]), sol.y[:, -1].copy()
        min_gap = min(
            min_gap,
            *(float(p(tt, yy)) for p in psis for tt, yy in zip(sol.t, sol.y.T, strict=True)),
        )
        if sol.status == 1:
            hit = next(i for i, te in enumerate(sol.t_events) if len(te))
            t = float(sol.t_events[hit][0])
            y = sol.y_events[hit][0].copy()
            y[n:] = maps[hit](t, y)
            impacts.append(t)
            if len(impacts) >= max_impacts:
                status = "max_impacts"
                break
    return BaselineResult(
        t=t,
        y=y,
        impact_times=impacts,
        status=status,
        wall_time=time.perf_counter() - clock,
        nfev=nfev,
        min_gap=min_gap,
    )


def prepare(scene: Scene, params: Mapping[str, float]) -> tuple:
    """The lambdified functions of the baseline (done once, outside the timed runs)."""
    return _lambdify(scene, params)
