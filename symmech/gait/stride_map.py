"""The stride map and its Jacobian by the variational equations and saltation matrices.

In mode ``j`` the state flows by ``y' = f_j(y)``; with ``variational=True`` the
sensitivity ``Phi`` flows beside it by ``Phi' = Df_j(y) Phi`` (the variational
equations; one augmented system, one step-size control).  A transition ``k`` fires when
its guard ``g_k`` decreases through 0 where its condition holds; at the event the state
jumps to ``R_k(y-)`` and the sensitivity by the saltation matrix (Aizerman and Gantmacher
1958; Hiskens and Pai, IEEE TCAS-I 47 (2000) 204, eq. 20)

    Xi = DR + (f+ - DR f-) Dg / (Dg f-),

``f-`` the field before the event at ``y-``, ``f+`` the target's field at ``R(y-)``; the
guards are static, so no ``g_t`` term.  The stride map ``P`` takes the state just after
the *section* transition to the state just after its next firing; ``DP`` is the product
of the flows' ``Phi`` and the events' ``Xi`` along it.

Events.  A guard is *armed* once it is positive beyond rounding after the mode began (a
state that starts on a guard, as a walker does just after heel strike, does not fire it
until it has left it).  On each accepted step its value is sampled at both ends and three
interior points of the continuous output; the earliest sign change from > 0 to <= 0 where
the condition is positive is narrowed by :func:`symmech.simulate.events.find_root` on the
continuous output, then the event time is polished by Newton's method on ``g`` along
fresh steps from the step's start (``t <- t - g/(Dg f)``), so the event state has the
integrator's full order, not only the dense output's.

The same code runs on floats (DOP853 over generated C or NumPy functions) and on mpmath
numbers (Gauss-Legendre collocation over mpmath closed forms), with the arithmetic taken
from the :class:`~symmech.gait.evaluation.GaitFunctions` it is given.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import mpmath
import numpy as np

from symmech.errors import SymmechError
from symmech.gait.evaluation import GaitFunctions
from symmech.simulate.events import find_root
from symmech.simulate.precise import GaussLegendre
from symmech.simulate.steppers import Dop853, Stepper

__all__ = ["GaitError", "StrideOptions", "StrideResult", "stride"]

_SAMPLES = (0.25, 0.5, 0.75)


class GaitError(SymmechError, RuntimeError):
    """A stride that cannot be completed (no event before ``t_max``, a step too small, a
    grazing guard), with the mode, the time and the state."""


@dataclass(frozen=True)
class StrideOptions:
    """Tolerances and limits of a stride.  ``rtol``/``atol`` apply to the state and the
    sensitivities alike; ``t_max`` bounds the time in one mode; ``max_events`` the
    transitions of one stride; ``h0`` is the first step."""

    rtol: float = 1e-13
    atol: float = 1e-13
    t_max: float = 100.0
    max_events: int = 20
    h0: float = 1e-3
    max_steps: int = 100_000

    def __post_init__(self) -> None:
        problems = []
        for name in ("rtol", "atol", "t_max", "h0"):
            value = getattr(self, name)
            real = isinstance(value, (int, float)) and not isinstance(value, bool)
            if not (real and math.isfinite(value) and value > 0):
                problems.append(f"{name} = {value!r} must be a finite number > 0")
        for name, top in (("max_events", 10_000), ("max_steps", 10**9)):
            value = getattr(self, name)
            whole = isinstance(value, (int, np.integer)) and not isinstance(value, bool)
            if not (whole and 1 <= value <= top):
                problems.append(f"{name} = {value!r} must be a whole number in 1 .. {top}")
        if problems:
            raise GaitError("StrideOptions: " + "; ".join(problems))


@dataclass
class StrideResult:
    """``x1 = P(x0)`` (and ``DP``, the Jacobian of the return map, when asked), the
    time taken, the transitions fired (by index, with their times and pre-event states),
    and the right-hand side calls."""

    x: np.ndarray
    DP: np.ndarray | None
    period: Any
    events: list[tuple[int, Any, np.ndarray]] = field(default_factory=list)
    nfev: int = 0
    steps: int = 0
    #: ``Xi_k Phi_k ... Xi_1 Phi_1`` (the monodromy matrix: the multipliers and the
    #: trivial 1 of the flow's direction); ``DP`` has 0 in place of that 1
    monodromy: np.ndarray | None = None
    #: with ``record=True``: rows ``(t, mode index, y padded with NaN to the largest
    #: mode's size)`` at the start, every accepted step's end and each event's state
    #: before and after its jump
    trajectory: np.ndarray | None = None


# -- the failures of a stride, in the words both loops use (here and gait.native) --------
def step_small_message(mode: str, t: Any) -> str:
    """A step below the resolution of t in ``mode``."""
    return f"mode {mode!r}: step size too small at t = {float(t):.6g}"


def no_event_message(mode: str, t_max: float, t0: Any, y0: Any = None) -> str:
    """No transition out of ``mode`` within ``t_max`` from ``t0`` (and ``y0``)."""
    state = "" if y0 is None else f" (state {[float(x) for x in y0]})"
    return (
        f"mode {mode!r}: no transition fired within t_max = {t_max} from t = {float(t0):.6g}{state}"
    )


def grazing_message(label: str) -> str:
    """The guard of transition ``label`` reached with ``Dg f = 0``."""
    return f"transition {label!r}: the guard is grazed (Dg f = 0)"


def max_events_message(section: int, max_events: int) -> str:
    """The section transition not reached again within ``max_events`` events."""
    return f"stride: transition {section} did not fire again in {max_events} events"


def _stepper(fns: GaitFunctions) -> Stepper:
    return GaussLegendre(8) if fns.multiprecision else Dop853()


class _Flow:
    """The augmented field ``(f(y), Df(y) Phi)`` of one mode and its counters."""

    def __init__(self, fns: GaitFunctions, mode: str, columns: int):
        self.fns, self.mode, self.columns = fns, mode, columns
        self.N = fns.size(mode)
        self.nfev = 0

    def __call__(self, t: Any, z: np.ndarray) -> np.ndarray:
        self.nfev += 1
        y = z[: self.N]
        fy = self.fns.rhs(self.mode, y)
        if not self.columns:
            return fy
        Phi = z[self.N :].reshape(self.N, self.columns)
        dPhi = self.fns.jac(self.mode, y).dot(Phi)
        return np.concatenate([fy, dPhi.ravel()])


def _controller(h: Any, error: float, order: int, fns: GaitFunctions) -> Any:
    if error == 0:
        factor = 5.0
    elif not np.isfinite(error):
        factor = 0.2
    else:
        factor = min(5.0, max(0.2, 0.9 * error ** (-1.0 / (order + 1))))
    return h * (mpmath.mpf(factor) if fns.multiprecision else factor)


def _guards_at(fns: GaitFunctions, mode: str, y: np.ndarray) -> dict[int, Any]:
    return {k: fns.guard(k, y) for k, tr in enumerate(fns.gait.transitions) if tr.source == mode}


def _polish(fns, flow, stepper, k, t0, z0, f0, h, opts) -> tuple[Any, np.ndarray]:
    """The event state at full order: Newton on ``g(y(t0 + s))`` with fresh steps (at
    most four), the state then taken at the last Newton time."""
    N = flow.N
    s = h
    z = z0
    for _ in range(4):
        z = stepper.step(flow, t0, z0, f0, s, opts.rtol, opts.atol).y
        y = z[:N]
        g = fns.guard(k, y)
        rate = fns.guard_gradient(k, y).dot(fns.rhs(flow.mode, y))
        if rate == 0:
            break
        ds = -g / rate
        s = s + ds
        if abs(ds) <= 4 * fns.eps * max(abs(t0 + s), 1):
            break
    if rate != 0:  # the state at the last Newton time
        z = stepper.step(flow, t0, z0, f0, s, opts.rtol, opts.atol).y
    return t0 + s, z


def _first_crossing(fns, dense, mode, armed, values_start, values_end, y_end):
    """(theta_a, theta_b, k) of the earliest armed sign change on this step, or None."""
    N = fns.size(mode)
    thetas = [0, *_SAMPLES, 1]
    cache: dict[Any, np.ndarray] = {}

    def state(theta: Any) -> np.ndarray:
        if theta == 1:
            return y_end
        if theta not in cache:
            cache[theta] = dense(theta)[:N]
        return cache[theta]

    best = None
    for k, g0 in values_start.items():
        values = [g0]
        for theta in thetas[1:-1]:
            values.append(fns.guard(k, state(theta)))
        values.append(values_end[k])
        on = armed[k]
        for i in range(len(thetas) - 1):
            if values[i] > 0 and not on:
                on = values[i] > _arm_level(fns)
            if on and values[i] > 0 >= values[i + 1]:
                a, b = thetas[i], thetas[i + 1]
                if values[i + 1] != 0:
                    a, b, _, _ = find_root(
                        lambda th, _k=k: fns.guard(_k, dense(th)[:N]),
                        a, b, values[i], values[i + 1], fns.eps,
                    )  # fmt: skip
                if fns.condition(k, state(b) if b == 1 else dense(b)[:N]) > 0 and (
                    best is None or b < best[1]
                ):
                    best = (a, b, k)
                break
    return best


def _arm_level(fns: GaitFunctions) -> Any:
    return 1e3 * fns.eps


def _flow_until_event(fns, mode, t0, z0, columns, opts, stats):
    """Integrate ``mode`` from ``(t0, z0)`` to the first event; ``(k, t, z-)``."""
    stepper = _stepper(fns)
    flow = _Flow(fns, mode, columns)
    N = flow.N
    t, z = t0, z0
    f = flow(t, z)
    h = fns.array([opts.h0])[0]
    values = _guards_at(fns, mode, z[:N])
    armed = {k: g > _arm_level(fns) for k, g in values.items()}
    order = stepper.error_order
    for _ in range(opts.max_steps):
        if t - t0 > opts.t_max:
            break
        step = stepper.step(flow, t, z, f, h, opts.rtol, opts.atol)
        if not step.error <= 1:
            h = _controller(h, step.error, order, fns)
            if abs(h) <= 16 * fns.eps * max(abs(t), 1):
                raise GaitError(step_small_message(mode, t))
            continue
        stats["steps"] += 1
        y_end = step.y[:N]
        values_end = _guards_at(fns, mode, y_end)
        hit = _first_crossing(fns, step.dense, mode, armed, values, values_end, y_end)
        if hit is not None:
            _, b, k = hit
            t_event, z_event = _polish(fns, flow, stepper, k, t, z, f, b * h, opts)
            stats["nfev"] += flow.nfev
            return k, t_event, z_event
        for k, g in values_end.items():
            armed[k] = armed[k] or g > _arm_level(fns)
        _record(fns, stats, t + h, mode, y_end)
        t, z, f, values = t + h, step.y, step.f, values_end
        h = _controller(h, step.error, order, fns)
    stats["nfev"] += flow.nfev
    raise GaitError(no_event_message(mode, opts.t_max, t0, z0[:N]))


def _record(fns: GaitFunctions, stats: dict[str, Any], t: Any, mode: str, y: np.ndarray) -> None:
    """A row ``(t, mode index, y padded with NaN)`` of the record, when there is one."""
    rows = stats.get("rows")
    if rows is not None:
        width = max(fns.size(m) for m in fns.mode_names)
        row = [t, fns.mode_names.index(mode), *y[: fns.size(mode)]]
        rows.append(row + [np.nan] * (width + 2 - len(row)))


def saltation(
    fns: GaitFunctions, k: int, y_minus: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(R(y-), Xi, f+ Dg / (Dg f-))`` of transition ``k`` at the pre-event state (module
    docstring); the last term taken from ``Xi`` gives ``DR (I - f- Dg / (Dg f-))``, the
    derivative of the post-event state on the guard (the event time moves with ``y``)."""
    tr = fns.gait.transitions[k]
    f_minus = fns.rhs(tr.source, y_minus)
    y_plus = fns.reset(k, y_minus)
    f_plus = fns.rhs(tr.target, y_plus)
    DR = fns.reset_jacobian(k, y_minus)
    Dg = fns.guard_gradient(k, y_minus)
    rate = Dg.dot(f_minus)
    if rate == 0:
        raise GaitError(grazing_message(tr.label))
    Xi = DR + np.outer(f_plus - DR.dot(f_minus), Dg) / rate
    return y_plus, Xi, np.outer(f_plus, Dg) / rate


def _start(fns: GaitFunctions, section: int, x0: Any) -> tuple[str, np.ndarray]:
    """The mode a stride starts in (the section's target) and ``x0`` as an array of its
    size, or a GaitError naming what is wrong."""
    gait = fns.gait
    whole = isinstance(section, (int, np.integer)) and not isinstance(section, bool)
    if not (whole and 0 <= section < len(gait.transitions)):
        raise GaitError(
            f"stride: section {section!r} is not a transition of gait {gait.name!r}"
            f" (0 .. {len(gait.transitions) - 1})"
        )
    mode = gait.transitions[section].target
    try:
        x = fns.array(x0)
    except (TypeError, ValueError) as exc:
        raise GaitError(
            f"stride: the initial state {x0!r} is not an array of numbers ({exc})"
        ) from None
    if x.shape != (fns.size(mode),):
        raise GaitError(
            f"stride: the state after {gait.transitions[section].label!r} has"
            f" {fns.size(mode)} entries (q, v of mode {mode!r}), got shape {x.shape}"
        )
    return mode, x


def stride(
    fns: GaitFunctions,
    section: int,
    x0: Any,
    *,
    variational: bool = False,
    options: StrideOptions | None = None,
    loop: str = "auto",
    record: bool = False,
) -> StrideResult:
    """``P(x0)``: from ``x0`` just after transition ``section`` to just after its next
    firing (and ``DP`` with ``variational=True``); see the module docstring.

    ``loop="auto"`` runs the stride in generated C when ``fns`` has a compiled loop
    (:meth:`~symmech.gait.evaluation.GaitFunctions.native_stride`: a
    :class:`~symmech.gait.evaluation.CompiledGait` of target ``"c"``), else this module's
    loop; ``"python"`` forces this module's loop (the reference of the C loop).
    ``record=True`` keeps the motion (:attr:`StrideResult.trajectory`)."""
    if loop not in ("auto", "python"):
        raise GaitError(f"stride: loop must be 'auto' or 'python', got {loop!r}")
    opts = options or StrideOptions()
    gait = fns.gait
    mode, x0 = _start(fns, section, x0)
    native = fns.native_stride() if loop == "auto" else None
    if native is not None:
        if not np.all(np.isfinite(x0)):
            raise GaitError(f"stride: the initial state {x0.tolist()} is not finite")
        return native.stride(section, x0, variational, opts, record)
    dim = len(x0)
    Phi = fns.array(np.eye(dim)) if variational else None
    t = fns.array([0])[0]
    y = x0
    stats: dict[str, Any] = {"nfev": 0, "steps": 0, "rows": [] if record else None}
    _record(fns, stats, t, mode, y)
    events: list[tuple[int, Any, np.ndarray]] = []
    monodromy = None
    for _ in range(opts.max_events):
        N = fns.size(mode)
        z = y if Phi is None else np.concatenate([y, Phi.ravel()])
        k, t, z = _flow_until_event(fns, mode, t, z, dim if variational else 0, opts, stats)
        y_minus = z[:N]
        _record(fns, stats, t, mode, y_minus)
        events.append((k, t, y_minus))
        if variational:
            Phi_flow = z[N:].reshape(N, dim)
            y, Xi, along = saltation(fns, k, y_minus)
            Phi = Xi.dot(Phi_flow)
            if k == section:
                monodromy = Phi
                Phi = Phi - along.dot(Phi_flow)
        else:
            y = fns.reset(k, y_minus)
        mode = gait.transitions[k].target
        _record(fns, stats, t, mode, y)
        if k == section:
            rows = stats["rows"]
            trajectory = None if rows is None else fns.array(rows)
            return StrideResult(
                y, Phi, t, events, stats["nfev"], stats["steps"], monodromy, trajectory
            )
    raise GaitError(max_events_message(section, opts.max_events))
