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
from symmech.simulate.arguments import states
from symmech.simulate.backend import BACKENDS, backend_named
from symmech.simulate.functions import Functions
from symmech.simulate.options import CONTACT_MODES, RunOptions
from symmech.simulate.parameters import check_parameters
from symmech.simulate.result import SimulationResult
from symmech.simulate.system import FREE, HybridSystem, SimulationError

__all__ = ["BACKENDS", "CONTACT_MODES", "simulate", "system_for"]


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
    if definitions is not None and not isinstance(definitions, Mapping):
        raise SimulationError(
            "definitions: expected a mapping {function of t: expression in t and the"
            f" parameters}}, got {type(definitions).__name__}"
        )
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
    backend: str = "c",
    options: RunOptions | None = None,
    strategy: str = "auto",
    definitions: Mapping | None = None,
    **run_options: Any,
) -> SimulationResult:
    """Simulate ``scene`` from ``(q0, v0)`` at ``t0`` to ``t_end`` (see the module and
    :mod:`symmech.simulate.hybrid` docstrings).

    The run options (``method``, ``rtol``, ``atol``, ``max_step``, ``max_events``,
    ``max_steps``, ``contact``, ``event_samples``, ``t0``) are those of
    :class:`~symmech.simulate.options.RunOptions`, given as keywords or as ``options``
    (keywords beside it replace its fields).  ``backend``: ``"c"`` (the whole loop in
    generated C), ``"numpy"`` (the loop in Python over the generated NumPy module: the
    reference of the C loop) or ``"scipy"`` (SciPy's ``OdeSolver`` classes over the
    generated C rhs, symmech's events and impacts around them); see
    :mod:`symmech.simulate.backend`.  ``method``: ``"dop853"``, ``"tsit5"``, ``"rk45"``,
    ``"rk4"`` (fixed step ``max_step``) or ``"rodas4"`` (linearly implicit, for stiff
    scenes); with ``backend="scipy"`` SciPy's names (``"DOP853"``, ``"RK45"``, ``"Radau"``,
    ``"BDF"``, ``"LSODA"``).  ``contact``: ``"persistent"`` (an accumulation of impacts
    becomes a resting contact, released when the contact force would turn negative) or
    ``"stop"`` (the run ends with status ``"zeno"`` at the estimated accumulation time).
    """
    if not isinstance(scene, Scene):
        raise SimulationError(f"scene: expected a symmech.Scene, got {type(scene).__name__}")
    engine = backend_named(backend)
    opts = RunOptions.build(options, run_options)
    tend = opts.end(t_end)
    method = engine.method(opts.method)
    opts = opts.with_changes(method=method) if method != opts.method else opts
    n = scene.n
    q = states(q0, n, "q0")
    v = states(v0, n, "v0")
    values = check_parameters(scene, params)
    implicit = engine.is_implicit(method)
    system = system_for(scene, engine.target, strategy, definitions, jacobian=implicit)
    fns = Functions(system, values)
    y0 = initial_state(fns, opts, q, v)
    result = engine.run(system, fns, values, y0, tend, opts)
    result.attach(scene, values, fns)
    return result


def initial_state(fns: Functions, opts: RunOptions, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``(q, v)`` checked against the walls (``psi >= -10 atol``) and the constraints (a
    residual ``|mu v|`` within ``100 (atol + rtol |v|)`` is projected away with P, a
    larger one is refused)."""
    t0 = opts.t0
    for w in range(fns.walls):
        psi = fns.psi(w, t0, q)
        if psi < -10 * opts.atol:
            raise SimulationError(
                f"q0 is on the wrong side of wall {fns.wall_names[w]!r}: psi = {psi!r} < 0"
            )
    return np.concatenate([q, velocity_in_D(fns, t0, q, v, opts.rtol, opts.atol, "v0")])


def velocity_in_D(
    fns: Functions, t0: float, q: np.ndarray, v: np.ndarray, rtol: float, atol: float, what: str
) -> np.ndarray:
    """``v`` in the constraint distribution D: a residual ``|mu v|`` within
    ``100 (atol + rtol |v|)`` is projected away with P (Carnot paper section 2.2), a larger
    one is refused naming ``what``; ``v`` itself for an unconstrained scene.  The one rule
    of ``simulate`` and of each row of ``simulate_batch``."""
    if not fns.constrained:
        return v
    res = fns.residual(FREE, t0, q, v)
    allowed = 100 * (atol + rtol * float(np.max(np.abs(v), initial=0.0)))
    if res > allowed:
        raise SimulationError(
            f"{what} is not in the constraint distribution D: |mu v0| = {res:.3g} >"
            f" {allowed:.3g}; give a velocity that satisfies the constraints"
        )
    return fns.project(FREE, t0, q, v)
