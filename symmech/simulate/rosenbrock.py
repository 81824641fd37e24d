"""Rodas4, the linearly implicit stepper of :mod:`symmech.simulate.steppers` (its method
``"rodas4"``, for stiff scenes): a 6-stage, L-stable, stiffly accurate Rosenbrock method
of order 4(3) with its order-3 continuous output (HNW II, section VI.4; coefficients in
:mod:`symmech.simulate.tableaux`).  It keeps the steppers' contract (a :class:`Step` per
call, ``error = inf`` for a step that is not finite or whose matrix is singular).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from .steppers import (
    Step,
    Stepper,
    StepperError,
    _check_h,
    _finite_or_inf,
    _NanDense,
    _rhs,
    _rms,
    _scale,
)
from .tableaux import RODAS4

__all__ = ["Rodas4"]


class _RosenbrockDense:
    """``(1 - theta) y0 + theta (y1 + (1 - theta)(k1 + theta k2))`` (HNW II, VI.(4.8))."""

    def __init__(self, t0, h, y0, y1, k1, k2):
        self.t0, self.h = t0, h
        self._y0, self._y1, self._k1, self._k2 = y0, y1, k1, k2

    def __call__(self, theta: float) -> np.ndarray:
        s1 = 1 - theta
        return s1 * self._y0 + theta * (self._y1 + s1 * (self._k1 + theta * self._k2))


def _lu_solver(W: np.ndarray) -> Callable[[np.ndarray], np.ndarray] | None:
    """A solver for ``W x = r`` (LU once: SciPy's ``lu_factor`` if installed, else NumPy),
    or None when ``W`` is singular or not finite."""
    if not np.all(np.isfinite(W)):
        return None
    try:
        from scipy.linalg import lu_factor, lu_solve
    except ImportError:  # the core needs only NumPy
        try:
            inv = np.linalg.inv(W)
        except np.linalg.LinAlgError:
            return None
        return lambda r: inv @ r
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            lu = lu_factor(W, check_finite=False)
        except (np.linalg.LinAlgError, Warning):
            return None
    return lambda r: lu_solve(lu, r, check_finite=False)


class Rodas4(Stepper):
    """Rodas4: a 6-stage, L-stable, stiffly accurate Rosenbrock method of order 4(3).

    Each step factors ``W = I/(gamma h) - J`` once (``J = jac(t0, y0)``) and solves six
    linear systems (see :class:`symmech.simulate.tableaux.RosenbrockTableau`).  ``df/dt``
    is a forward difference ``(f(t0 + delta, y0) - f0) / delta`` with ``delta =
    sqrt(eps max(1e-5, |t0|))`` as the code RODAS does (one extra call; zero up to rounding
    for autonomous problems).  A singular ``W`` gives ``error = inf``.
    """

    name = "rodas4"
    implicit = True
    adaptive = True

    def __init__(self):
        self.tableau = RODAS4
        self.order, self.error_order = RODAS4.order, RODAS4.error_order
        self.dense_order = RODAS4.dense_order
        self._x = RODAS4.arrays

    def step(self, f, t0, y0, f0, h, rtol, atol, jac=None) -> Step:
        h = _check_h(h)
        if jac is None:
            raise StepperError("rodas4 is implicit: step() needs jac(t, y), the Jacobian df/dy")
        y0 = np.asarray(y0, dtype=float)
        f0 = np.asarray(f0, dtype=float)
        n = y0.size
        J = np.asarray(jac(t0, y0), dtype=float)
        if J.shape != (n, n):
            raise StepperError(f"jac(t, y) returned shape {J.shape} for a state of size {n}")
        x = self._x
        delta = math.sqrt(np.finfo(float).eps * max(1e-5, abs(t0)))
        ft = (_rhs(f, t0 + delta, y0) - f0) / delta
        nfev = 1
        solve = _lu_solver(np.eye(n) / (float(x["gamma"]) * h) - J)
        if solve is None:
            return Step(
                np.full(n, np.nan), np.full(n, np.nan), math.inf, _NanDense(t0, h, n), nfev, 1
            )
        a, C, c, d = x["a"], x["C"], x["c"], x["d"]
        U = np.zeros((6, n))
        for i in range(6):
            fi = f0 if i == 0 else _rhs(f, t0 + c[i] * h, y0 + a[i, :i] @ U[:i])
            nfev += i > 0
            U[i] = solve(fi + (C[i, :i] @ U[:i]) / h + (h * d[i]) * ft)
        y1 = y0 + x["b"] @ U
        f1 = _rhs(f, t0 + h, y1)
        nfev += 1
        error = _rms(((x["b"] - x["bhat"]) @ U) / _scale(y0, y1, rtol, atol))
        error = _finite_or_inf(error, y1, f1)
        dense = _RosenbrockDense(t0, h, y0, y1, x["h"][0] @ U, x["h"][1] @ U)
        return Step(y1, f1, error, dense, nfev, 1)
