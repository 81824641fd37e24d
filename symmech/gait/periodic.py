"""Periodic gaits: fixed points of the stride map, their multipliers, and continuation.

A period-one gait is a fixed point ``x* = P(x*)`` of the stride map of
:mod:`symmech.gait.stride_map`, found by Newton's method on ``P(x) - x`` with the Jacobian
``DP`` of the variational-saltation route: ``x <- x - (DP - I)^-1 (P(x) - x)``, damped
(the step halved) while the stride from the new point fails or its residual more than
doubles.  Its stability is decided by the eigenvalues of ``DP(x*)``, the multipliers of
the return map (stable when all lie inside the unit circle).  ``DP`` has rank at most
``2n - 1``: the state after a transition lies on the reset's image of the guard, so at
least one multiplier is 0; :func:`multipliers` returns them sorted by decreasing modulus,
the trivial zeros last (the monodromy matrix ``Xi Phi`` has the same spectrum with 1 for
0, the flow's direction).

The Jacobian can also be taken by differences of ``P`` (:func:`difference_jacobian`):
forward differences in float64 give about half the digits (Coleman 2009: 9 at the best
step), central differences at mpmath precision are the independent check of the
variational route.  :func:`continuation` follows a gait in a parameter by natural
continuation (the previous fixed point, extrapolated linearly, starts each Newton
solve) and flags period doubling: a multiplier crossing -1.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import mpmath
import numpy as np

from symmech.gait.evaluation import GaitFunctions
from symmech.gait.stride_map import GaitError, StrideOptions, StrideResult, stride

__all__ = [
    "FixedPoint",
    "continuation",
    "difference_jacobian",
    "fixed_point",
    "multipliers",
]


@dataclass
class FixedPoint:
    """A fixed point of the stride map with ``DP`` there, its multipliers, the stride's
    period, the residual ``|P(x) - x|`` and the Newton iterations."""

    x: np.ndarray
    DP: np.ndarray
    multipliers: list
    period: Any
    residual: Any
    iterations: int
    stride: StrideResult

    @property
    def stable(self) -> bool:
        return all(abs(m) < 1 for m in self.multipliers)


def _is_mp(a: np.ndarray) -> bool:
    return a.dtype == object


def _solve(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    if _is_mp(A):
        x = mpmath.lu_solve(mpmath.matrix(A.tolist()), mpmath.matrix([[v] for v in b]))
        return np.array([x[i] for i in range(len(b))], dtype=object)
    return np.linalg.solve(A, b)


def _norm(x: np.ndarray) -> Any:
    return max(abs(v) for v in x) if len(x) else 0


def multipliers(DP: np.ndarray) -> list:
    """The eigenvalues of ``DP`` sorted by decreasing modulus (then by phase), complex
    numbers (mpmath ``mpc`` for an object array)."""
    if _is_mp(DP):
        values = list(mpmath.eig(mpmath.matrix(DP.tolist()), left=False, right=False))
        values = [mpmath.mpc(v) for v in values]
    else:
        values = [complex(v) for v in np.linalg.eigvals(DP)]
    # conjugate pairs share a modulus up to rounding: compare moduli to 9 digits
    return sorted(
        values,
        key=lambda z: (-float(f"{float(abs(z)):.9g}"), float(mpmath.arg(z)) if z != 0 else 0.0),
    )


def fixed_point(
    fns: GaitFunctions,
    section: int,
    x0: Sequence,
    *,
    tol: float | None = None,
    max_iterations: int = 25,
    options: StrideOptions | None = None,
) -> FixedPoint:
    """The fixed point of the stride map after transition ``section`` near ``x0`` (module
    docstring).  ``tol`` on ``max |P(x) - x|`` (default ``1e3 eps``, from ``fns``'s
    arithmetic); raises :class:`~symmech.gait.stride_map.GaitError` if Newton does not get
    there in ``max_iterations``."""
    x = fns.array(list(x0))
    tol = 1e3 * fns.eps if tol is None else tol
    residual: Any = None
    last: tuple[np.ndarray, np.ndarray, Any] | None = None  # (x, dx, residual) of the last step
    for it in range(1, max_iterations + 1):
        try:
            res = stride(fns, section, x, variational=True, options=options)
            r = res.x - x
            residual = _norm(r)
            worse = last is not None and residual > 2 * last[2]
        except GaitError:
            if last is None:
                raise
            worse = True
        if worse and last is not None:
            # damped Newton: halve the last step while the stride fails or the residual grows
            x_prev, dx, prev_res = last
            dx = dx / 2
            if _norm(dx) <= tol:
                break
            last = (x_prev, dx, prev_res)
            x = x_prev + dx
            continue
        assert res.DP is not None
        if residual <= tol:
            # P(x), within tol of x, lies exactly on the image of the section's reset
            return FixedPoint(res.x, res.DP, multipliers(res.DP), res.period, residual, it, res)
        dx = _solve(res.DP - fns.array(np.eye(len(x))), -r)
        last = (x, dx, residual)
        x = x + dx
    raise GaitError(
        f"fixed_point: Newton did not converge in {max_iterations} iterations"
        f" (residual {float(residual):.3g} > {float(tol):.3g}; last x = {[float(v) for v in x]})"
    )


def difference_jacobian(
    fns: GaitFunctions,
    section: int,
    x: Sequence,
    step: Any,
    *,
    central: bool = True,
    options: StrideOptions | None = None,
) -> np.ndarray:
    """``DP(x)`` by differences of the stride map with step ``step`` (central:
    ``(P(x + h e_i) - P(x - h e_i)) / 2h``, error O(h^2); forward: O(h))."""
    x_ = fns.array(list(x))
    h = fns.array([step])[0]
    base = None if central else stride(fns, section, x_, options=options).x
    columns = []
    for i in range(len(x_)):
        e = fns.array(np.zeros(len(x_)))
        e[i] = h
        plus = stride(fns, section, x_ + e, options=options).x
        if central:
            minus = stride(fns, section, x_ - e, options=options).x
            columns.append((plus - minus) / (2 * h))
        else:
            columns.append((plus - base) / h)
    return np.array(columns, dtype=x_.dtype).T


@dataclass
class ContinuationPoint:
    """One parameter value of a continuation: its fixed point, or why there is none."""

    value: float
    point: FixedPoint | None
    failure: str = ""


def continuation(
    make: Callable[[float], GaitFunctions],
    section: int,
    values: Sequence[float],
    x0: Sequence,
    *,
    options: StrideOptions | None = None,
) -> list[ContinuationPoint]:
    """Fixed points along ``values`` of a parameter (``make(value)`` gives the gait's
    functions there), each Newton solve started from the previous fixed point
    extrapolated linearly; a value where Newton fails is recorded with its reason and
    the next starts from the last success."""
    out: list[ContinuationPoint] = []
    known: list[tuple[float, np.ndarray]] = []
    guess = np.asarray(x0, dtype=float)
    for value in values:
        if len(known) >= 2:
            (v1, x1), (v2, x2) = known[-2], known[-1]
            guess = x2 + (x2 - x1) * (value - v2) / (v2 - v1)
        elif known:
            guess = known[-1][1]
        try:
            fp = fixed_point(make(value), section, list(guess), options=options)
        except GaitError as exc:
            out.append(ContinuationPoint(value, None, str(exc)))
            continue
        known.append((value, np.asarray(fp.x, dtype=float)))
        out.append(ContinuationPoint(value, fp))
    return out


def period_doublings(points: Sequence[ContinuationPoint]) -> list[tuple[float, float]]:
    """Intervals ``(a, b)`` of the parameter where a real multiplier crosses -1."""
    out = []
    ok = [p for p in points if p.point is not None]
    for p, q in itertools.pairwise(ok):
        lo = min((m.real for m in p.point.multipliers if abs(m.imag) < 1e-9), default=0)  # type: ignore[union-attr]
        hi = min((m.real for m in q.point.multipliers if abs(m.imag) < 1e-9), default=0)  # type: ignore[union-attr]
        if (lo + 1) * (hi + 1) < 0:
            out.append((p.value, q.value))
    return out
