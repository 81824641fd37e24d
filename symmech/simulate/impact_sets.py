"""Impacts at one instant, for the hybrid loop (:mod:`.hybrid`): one wall's closed-form map,
or several walls resolved together by the generalized Newton law (:mod:`.impulses`), and
the check of each impact's conditioning.

Each function takes the loop's run state ``run`` (its functions ``f``, time ``t``, state
``y``, contact ``mode``, options ``o``; it records through ``run.event`` and releases
through ``run.release``) and updates its state in place.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from symmech.simulate.impulses import MAX_SIMULTANEOUS, active_set_solution

__all__ = [
    "COND_LIMIT",
    "Stop",
    "check_condition",
    "impact_alone",
    "impact_together",
    "simultaneous_group",
]

#: Largest condition number of an impact's Gram matrix the loop accepts: the impulse's
#: relative error is about cond * eps, so 1e-2 / eps keeps it below 1e-2.
COND_LIMIT = 1e-2 / 2.220446049250313e-16


class Stop(Exception):
    """The run ends here: ``status``, ``message`` and, for an accumulation, its time."""

    def __init__(self, status: str, message: str, accumulation: float | None = None):
        super().__init__(message)
        self.status, self.message, self.accumulation = status, message, accumulation


def check_condition(run: Any, wall: int, q: np.ndarray) -> None:
    """Stop the run when the impact's Gram matrix is ill-conditioned (COND_LIMIT)."""
    cond = run.f.impact_condition(wall, run.t, q)
    run.condition = max(run.condition, cond)
    if cond > COND_LIMIT:
        raise Stop(
            "failed",
            f"wall {run.names[wall]!r} is nearly dependent on the constraints at"
            f" t = {float(run.t)!r}: the impact's Gram matrix has condition number"
            f" {cond:.3g} > {COND_LIMIT:.3g} (relative error bound 1e-2)",
        )


def impact_alone(run: Any, wall: int, r: float) -> None:
    """The scene's closed-form impact map of ``wall`` alone."""
    y = run.y
    q, v = run.q(y), run.v(y)
    check_condition(run, wall, q)
    v_plus = run.f.impact(wall, run.t, q, v)
    y_plus = np.concatenate([q, v_plus])
    if run.mode:  # keep the active contact
        y_plus[run.n :] = run.f.project(run.mode, run.t, q, v_plus)
    run.event("impact", wall, y, y_plus, r)
    run.y = y_plus


def simultaneous_group(run: Any) -> list[tuple[int, float]]:
    """The walls closed and approaching now (``run.approaching_walls()``) when the law
    resolves them together: two or more (or one, while walls are held: it is resolved
    with them), each with a Newton direction, the held walls too, at most
    MAX_SIMULTANEOUS in all; else empty (one wall at a time)."""
    if run.o.impact_law != "simultaneous" or run.walls < 2:  # a group needs two walls
        return []
    group = run.approaching_walls()
    size = len(group) + len(run.mode)
    if not group or size < 2 or size > MAX_SIMULTANEOUS:
        return []
    if not all(run.f.simultaneous[w] for w in [*(w for w, _ in group), *run.mode]):
        return []
    return group


def impact_together(run: Any, group: list[tuple[int, float]]) -> list[int] | None:
    """Resolve the walls of ``group`` together with the held walls (:mod:`.impulses`:
    a held wall ``j`` takes an impulse only to keep ``u_j+ >= 0``, its target rate
    change ``g_j = -u_j-``; its Newton direction is taken from its map at the first
    approaching wall's direction, the map being linear); the walls of ``group`` that
    took an impulse, or None when no active set is feasible (then one wall at a
    time).  Held walls that end up leaving are released."""
    y = run.y
    q, v = run.q(y), run.v(y)
    walls = [w for w, _ in group]
    for w in walls:
        check_condition(run, w, q)
    x, g = [], []
    for w in walls:
        d = run.f.impact(w, run.t, q, v) - v
        gw = run.f.rate_change(w, run.t, q, d)
        g.append(gw)
        x.append(d / gw)
    held = []
    for j in run.mode:
        probe = next((xi for xi in x if run.f.rate_change(j, run.t, q, xi) != 0), None)
        if probe is None:
            continue  # no approaching wall moves it: it needs no impulse
        d = run.f.impact(j, run.t, q, probe) - probe
        held.append(j)
        x.append(d / run.f.rate_change(j, run.t, q, d))
        g.append(-run.f.normal_rate(j, run.t, y))
    K = [[run.f.rate_change(j, run.t, q, xi) for xi in x] for j in walls + held]
    m = active_set_solution(K, g, run.tol_v(y))
    if m is None or all(mi == 0 for mi in m[: len(walls)]):
        return None
    v_plus = v.copy()
    for mi, xi in zip(m, x, strict=True):
        if mi != 0:
            v_plus = v_plus + mi * xi
    y_plus = np.concatenate([q, v_plus])
    if run.mode:
        y_plus[run.n :] = run.f.project(run.mode, run.t, q, v_plus)
    struck = [w for w, mi in zip(walls, m[: len(walls)], strict=True) if mi != 0]
    rates = dict(group)
    for k, w in enumerate(struck):  # the energy change is carried by the first
        run.event("impact", w, y, y_plus, rates[w], count_energy=k == 0)
    run.y = y_plus
    for j, mj in zip(held, m[len(walls) :], strict=True):
        if mj == 0 and run.f.normal_rate(j, run.t, run.y) > run.tol_v(run.y):
            run.release(j)
    return struck
