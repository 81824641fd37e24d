"""``simulate``: run a scene with walls as a hybrid system.

>>> import symmech as sm
>>> from symmech.examples import bouncing_ball
>>> res = sm.simulate(bouncing_ball(), [1.0], [0.0], 2.0, params={"m": 1, "g": 9.81, "alpha": 0.5},
...                   backend="numpy", contact="stop")
>>> res.status, round(res.accumulation_time, 6)   # sqrt(2/9.81) (1 + 1/2)/(1 - 1/2)
('zeno', 1.354571)

Every input is checked before anything runs (:class:`SimulationError` names the argument):
the state's shape and finiteness, ``psi >= 0`` at every wall (a state on the wrong side is
refused), ``v0`` in the constraint distribution D (a residual ``|mu v0|`` within
``100 (atol + rtol |v0|)`` is projected away with P, a larger one is refused),
``t_end > t0``, tolerances (``0 < rtol < 1``, ``atol > 0``), the parameters (all given,
finite, with their declared signs, restitutions in [0, 1]) and the options.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import sympy as sp

from symmech.scene import Scene
from symmech.simulate.arguments import CONTACT_MODES, check_run, states
from symmech.simulate.flow import AugmentedFlow, RKFlow, ScipyFlow
from symmech.simulate.hybrid import MAX_STEPS, run
from symmech.simulate.result import SimulationResult
from symmech.simulate.system import (
    BACKENDS,
    Functions,
    HybridSystem,
    SimulationError,
    check_parameters,
)

__all__ = ["CONTACT_MODES", "simulate", "system_for"]

#: Implicit methods (they use the generated Jacobian): symmech's Rosenbrock method and
#: SciPy's (lower case).
IMPLICIT_METHODS = ("rodas4", "radau", "bdf", "lsoda")


def _key(x: object) -> str:
    return sp.srepr(x) if isinstance(x, sp.Basic) else repr(x)


def system_for(
    scene: Scene,
    target: str,
    strategy: str = "auto",
    definitions: Mapping | None = None,
    jacobian: bool = False,
) -> HybridSystem:
    """The :class:`HybridSystem` of ``scene`` for ``target``, built once and kept with the
    scene (:meth:`symmech.Scene.attached`: it is freed with the scene)."""
    # srepr, not str: symbols that print alike but differ in assumptions are different
    defs = tuple(sorted((_key(k), _key(v)) for k, v in (definitions or {}).items()))
    return scene.attached(
        ("simulate", target, strategy, defs, jacobian),
        lambda: HybridSystem.build(
            scene, target, strategy=strategy, definitions=definitions, jacobian=jacobian
        ),
    )


def simulate(
    scene: Scene,
    q0: Any,
    v0: Any,
    t_end: float,
    *,
    params: Mapping[str, float] | Any = None,
    t0: float = 0.0,
    backend: str = "c",
    method: str = "dop853",
    rtol: float = 1e-8,
    atol: float = 1e-10,
    max_step: float | None = None,
    max_events: int = 100_000,
    max_steps: int = MAX_STEPS,
    contact: str = "persistent",
    strategy: str = "auto",
    definitions: Mapping | None = None,
    event_samples: int = 8,
) -> SimulationResult:
    """Simulate ``scene`` from ``(q0, v0)`` at ``t0`` to ``t_end`` (see the module and
    :mod:`symmech.simulate.hybrid` docstrings).

    ``backend``: ``"c"`` (the whole loop in generated C), ``"numpy"`` (the loop in Python
    over the generated NumPy module: the reference of the C loop) or ``"scipy"`` (SciPy's
    ``OdeSolver`` classes over the generated C rhs, symmech's events and impacts around
    them).  ``method``: ``"dop853"``, ``"tsit5"``, ``"rk45"``, ``"rk4"`` (fixed step
    ``max_step``) or ``"rodas4"`` (linearly implicit, for stiff scenes); with
    ``backend="scipy"`` SciPy's names (``"DOP853"``, ``"RK45"``, ``"Radau"``, ``"BDF"``,
    ``"LSODA"``).  ``contact``: ``"persistent"`` (an accumulation of impacts becomes a
    resting contact, released when the contact force would turn negative) or ``"stop"``
    (the run ends with status ``"zeno"`` at the estimated accumulation time).
    """
    if not isinstance(scene, Scene):
        raise SimulationError(f"scene: expected a symmech.Scene, got {type(scene).__name__}")
    if backend not in BACKENDS:
        raise SimulationError(f"backend must be one of {BACKENDS}, got {backend!r}")
    if not isinstance(method, str):
        raise SimulationError(f"method must be a name, got {method!r}")
    o = check_run(
        t0=t0,
        t_end=t_end,
        rtol=rtol,
        atol=atol,
        max_step=max_step,
        max_events=max_events,
        event_samples=event_samples,
        contact=contact,
        max_steps=max_steps,
    )
    n = scene.n
    q = states(q0, n, "q0")
    v = states(v0, n, "v0")
    t0f, tend, rtol_f, atol_f, step_cap = o.t0, o.t_end, o.rtol, o.atol, o.max_step
    span = tend - t0f
    values = check_parameters(scene, params)

    target = "numpy" if backend == "numpy" else "c"
    implicit = method.lower() in IMPLICIT_METHODS
    if implicit and backend == "c":
        raise SimulationError(
            f"method {method!r} is implicit: it runs on backend 'numpy' (rodas4) or 'scipy'"
            " (Radau, BDF, LSODA) with the generated Jacobian; the C loop has explicit methods"
        )
    system = system_for(scene, target, strategy, definitions, jacobian=implicit)
    fns = Functions(system, values)
    y0 = np.concatenate([q, v])
    for w in range(fns.walls):
        psi = fns.psi(w, t0f, q)
        if psi < -10 * atol_f:
            raise SimulationError(
                f"q0 is on the wrong side of wall {fns.wall_names[w]!r}: psi = {psi!r} < 0"
            )
    if fns.constrained:
        res = fns.residual(None, t0f, q, v)
        allowed = 100 * (atol_f + rtol_f * float(np.max(np.abs(v), initial=0.0)))
        if res > allowed:
            raise SimulationError(
                f"v0 is not in the constraint distribution D: |mu v0| = {res:.3g} >"
                f" {allowed:.3g}; give a velocity that satisfies the constraints"
            )
        y0[n:] = fns.project(None, t0f, q, v)

    opts = o.loop()
    if backend == "c":
        from symmech.simulate.c_run import run_c

        return run_c(system, values, y0, t0f, opts, method=method, max_step=step_cap)
    make: Any
    if backend == "scipy":

        def make(f: Any, jac: Any = None) -> Any:
            return ScipyFlow(f, method, rtol_f, atol_f, step_cap, jac=jac)
    else:
        fixed = None
        if method == "rk4":  # the C loop's rule (csim.options_vector)
            fixed = step_cap if step_cap < span else span / 1000

        def make(f: Any, jac: Any = None) -> Any:
            return RKFlow(f, method, rtol_f, atol_f, step_cap, jac=jac, fixed_step=fixed)

    jac = fns.flow_jac if implicit else None
    flow = (
        AugmentedFlow(make, fns.flow_rhs, fns.flow_rates, fns.gaps, 2 * n, jac=jac)
        if fns.walls
        else make(fns.flow_rhs, jac)
    )
    return run(fns, flow, t0f, y0, opts)
