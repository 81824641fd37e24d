"""One-step integrators of the hybrid simulator: explicit Runge-Kutta pairs and Rodas4.

A stepper advances ``y' = f(t, y)`` by one step ``h`` (negative to integrate backwards) from
``(t0, y0)`` with ``f0 = f(t0, y0)`` given, and returns a :class:`Step`: the new state, its
derivative (for the next step), a scaled error norm (accept when ``<= 1``), the step's
continuous output ``dense(theta) = y(t0 + theta h)`` and the number of right-hand-side
calls.  It keeps no state between steps: step-size control is the caller's, with
:func:`initial_step` for the first step and :class:`Controller` for the next ones.

Methods (coefficients in :mod:`symmech.simulate.tableaux`, sources cited there):

====== ===== ===== ====== =================================================================
name   order error dense  notes
====== ===== ===== ====== =================================================================
dop853 8     7     7      12 stages + 3 lazy dense stages, combined 5th/3rd-order estimate
tsit5  5     4     4      7 stages (FSAL)
rk45   5     4     4      Dormand-Prince, Shampine's dense output, 7 stages (FSAL)
rk4    4     --    3      fixed step, cubic Hermite dense output, ``error = 0``
rodas4 4     3     3      L-stable, stiffly accurate Rosenbrock; needs ``jac`` (:mod:`.rosenbrock`)
====== ===== ===== ====== =================================================================

The error norm is ``sqrt(mean((err_i / scale_i)^2))`` with ``scale_i = atol_i + rtol
max(|y0_i|, |y1_i|)`` (HNW I, eq. II.(4.11); SciPy's convention).  A step whose state,
error or derivative is not finite reports ``error = inf``: the caller rejects it and
shrinks ``h``, it is never raised.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from ..errors import SymmechError
from .tableaux import DOP853, DOP853_EXTRAS, RK4, RK45, TSIT5, ExplicitTableau

__all__ = [
    "FLOAT_LOOP_SIZE",
    "METHODS",
    "Controller",
    "Dense",
    "Step",
    "Stepper",
    "StepperError",
    "all_finite",
    "check_tolerances",
    "initial_step",
    "stepper",
]

Rhs = Callable[[float, np.ndarray], np.ndarray]
Jac = Callable[[float, np.ndarray], np.ndarray]


class StepperError(SymmechError, ValueError):
    """Bad input to a stepper: unknown method, bad step size or tolerances, a right-hand
    side or Jacobian of the wrong shape, an implicit method without its Jacobian."""


class Dense(Protocol):
    """The continuous output of one step: ``dense(theta) = y(t0 + theta h)``.

    Accurate to the method's dense order for ``theta`` in ``[0, 1]``; outside it the
    polynomial is extrapolated.
    """

    t0: float
    h: float

    def __call__(self, theta: float) -> np.ndarray: ...


@dataclass
class Step:
    """The result of one step from ``t0`` to ``t0 + h``."""

    y: np.ndarray  #: solution at t0 + h
    f: np.ndarray  #: f(t0 + h, y), for the next step
    error: float  #: scaled RMS error norm; accept when <= 1 (inf: reject)
    dense: Dense  #: continuous output on the step
    nfev: int  #: rhs calls by this step (lazy dense stages included once made)
    njev: int = 0  #: Jacobian calls by this step
    #: an explicit method's stage derivatives, the last row ``f``, at the times ``t0 +
    #: theta h`` of its :attr:`ExplicitRK.nodes` (None for the other methods)
    stages: np.ndarray | None = None


def _rhs(f: Rhs, t: float, y: np.ndarray) -> np.ndarray:
    """``f(t, y)`` as a float array of the state's shape (else :class:`StepperError`)."""
    out = np.asarray(f(t, y), dtype=float)
    if out.shape != y.shape:
        raise StepperError(
            f"the right-hand side f(t, y) returned shape {out.shape} for a state of shape {y.shape}"
        )
    return out


def _check_h(h: float) -> float:
    h = float(h)
    if not math.isfinite(h) or h == 0.0:
        raise StepperError(f"step size h = {h!r}: it must be finite and non-zero")
    return h


def _rms(x: np.ndarray) -> float:
    """``sqrt(mean(x^2))`` by the operations of ``numpy.mean`` (its pairwise sum
    ``add.reduce``, then the division by the count; sqrt is correctly rounded either way),
    without its per-call overhead: every step takes one."""
    return math.sqrt(float(_ADD_REDUCE(x * x)) / x.size) if x.size else 0.0


_ADD_REDUCE = np.add.reduce


def _scale(y0: np.ndarray, y1: np.ndarray, rtol: float, atol) -> np.ndarray:
    """``scale_i = atol_i + rtol max(|y0_i|, |y1_i|)``."""
    return atol + rtol * np.maximum(np.abs(y0), np.abs(y1))


def all_finite(a: np.ndarray) -> bool:
    """Whether every entry of ``a`` is finite: a finite sum of the entries is the cheap
    proof (an inf or a NaN makes any sum non-finite); a sum that overflows is settled
    entry by entry."""
    return math.isfinite(a.sum()) or bool(np.isfinite(a).all())


def _finite_or_inf(error: float, *arrays: np.ndarray) -> float:
    """``error``, or inf when it or an entry of ``arrays`` is not finite."""
    if not math.isfinite(error) or not all(all_finite(a) for a in arrays):
        return math.inf
    return error


def check_tolerances(rtol: float, atol, n: int) -> tuple[float, np.ndarray | float]:
    """Validate ``rtol`` and ``atol`` for a state of size ``n``.

    ``rtol`` must lie in ``[100 eps, 1)`` (below it no float64 method can follow it) and
    ``atol`` a finite non-negative scalar or array of shape ``(n,)``.  Returns them as a
    float and a float or float array.  Steppers do not repeat this check on every step:
    the caller validates once.
    """
    try:
        rtol_ = float(rtol)
        atol_ = np.asarray(atol, dtype=float)
    except (TypeError, ValueError) as exc:
        raise StepperError(f"tolerances rtol = {rtol!r}, atol = {atol!r}: not numbers") from exc
    eps = np.finfo(float).eps
    if not (100 * eps <= rtol_ < 1):
        raise StepperError(f"rtol = {rtol_!r}: it must lie in [{100 * eps:.3g}, 1)")
    if atol_.ndim not in (0, 1) or (atol_.ndim == 1 and atol_.shape != (n,)):
        raise StepperError(f"atol of shape {atol_.shape}: it must be a scalar or of shape ({n},)")
    if not np.all(np.isfinite(atol_)) or np.any(atol_ < 0):
        raise StepperError(f"atol = {atol!r}: it must be finite and non-negative")
    return rtol_, (float(atol_) if atol_.ndim == 0 else atol_)


class Stepper(ABC):
    """A one-step method; see the module docstring for the contract of :meth:`step`."""

    name: str
    order: int  #: order of the propagated solution
    error_order: int  #: the controller's exponent is 1 / (error_order + 1)
    dense_order: int  #: order of the dense output (local error O(h^(dense_order + 1)))
    adaptive: bool  #: False: error is 0.0 (fixed step; inf when the step is not finite)
    implicit: bool  #: True: step() needs jac
    #: the times (fractions of the step) of the rows of :attr:`Step.stages` (explicit
    #: methods; empty for the others, whose steps have no stages)
    nodes: tuple[float, ...] = ()

    @abstractmethod
    def step(
        self,
        f: Rhs,
        t0: float,
        y0: np.ndarray,
        f0: np.ndarray,
        h: float,
        rtol: float,
        atol: float | np.ndarray,
        jac: Jac | None = None,
    ) -> Step:
        """One step from ``(t0, y0)`` (with ``f0 = f(t0, y0)``) to ``t0 + h``.

        ``f(t, y)`` must return an array of ``y``'s shape (:class:`StepperError`
        otherwise), ``jac(t, y)`` the ``(n, n)`` matrix ``df/dy`` (implicit methods only);
        ``h`` finite and non-zero, negative to integrate backwards.  ``rtol`` and ``atol``
        are used as given (see :func:`check_tolerances`).
        """

    def __repr__(self) -> str:
        return f"<stepper {self.name}: order {self.order}>"


# --- dense outputs ------------------------------------------------------------------------


class _PolyDense:
    """``y(t0 + theta h) = y0 + sum_k Q_k theta^k`` (``Q = h K^T P``), by Horner's rule;
    ``Q`` is formed on the first call (a step whose continuous output is never read, as
    the event search certifies, does not pay for it)."""

    def __init__(self, t0: float, h: float, y0: np.ndarray, K: np.ndarray, P: np.ndarray):
        self.t0, self.h, self._y0 = t0, h, y0
        self._K, self._P = K, P
        self._Qm: np.ndarray | None = None

    @property
    def _Q(self) -> np.ndarray:
        if self._Qm is None:
            self._Qm = self.h * (self._K.T @ self._P)
        return self._Qm

    def __call__(self, theta: float) -> np.ndarray:
        Q = self._Q
        acc = Q[:, -1].copy()
        for k in range(Q.shape[1] - 2, -1, -1):
            acc = acc * theta + Q[:, k]
        return self._y0 + theta * acc

    def many(self, thetas: np.ndarray) -> np.ndarray:
        """``self(theta)`` for each theta, as the rows of an array (the same operations)."""
        Q, s = self._Q, thetas[:, None]
        acc = np.broadcast_to(Q[:, -1], (len(thetas), Q.shape[0]))
        for k in range(Q.shape[1] - 2, -1, -1):
            acc = acc * s + Q[:, k]
        return self._y0 + s * acc


class _HermiteDense:
    """The cubic Hermite interpolant of ``y0, f0, y1, f1`` (order 3)."""

    def __init__(self, t0, h, y0, y1, f0, f1):
        self.t0, self.h = t0, h
        self._y0, self._y1, self._hf0, self._hf1 = y0, y1, h * f0, h * f1

    def __call__(self, theta: float) -> np.ndarray:
        s = theta
        h00 = (1 + 2 * s) * (1 - s) ** 2
        h10 = s * (1 - s) ** 2
        h01 = s * s * (3 - 2 * s)
        h11 = s * s * (s - 1)
        return h00 * self._y0 + h10 * self._hf0 + h01 * self._y1 + h11 * self._hf1


#: Up to this many entries, a state of a DOP853 continuous output evaluated entry by entry
#: on floats (:meth:`_Dop853Dense.head`, and SciPy's by ``scipy_flow._dop853_head``) is
#: cheaper than the same operations on arrays.
FLOAT_LOOP_SIZE = 32


class _Dop853Dense:
    """DOP853's 7th-order dense output (HNW I, section II.10; the routine CONTD8).

    ``y(t0 + theta h) = y0 + theta (F0 + (1 - theta)(F1 + theta (F2 + (1 - theta)(F3 +
    theta (F4 + (1 - theta)(F5 + theta F6))))))`` with ``F0 = y1 - y0``, ``F1 = h f0 -
    F0``, ``F2 = 2 F0 - h (f0 + f1)`` and ``F(3+r) = h sum_i d_ri K_i`` over the 16 stages;
    the three extra stages are evaluated on the first call.
    """

    def __init__(self, f, t0, h, y0, y1, K, owner: Step | None = None):
        self.t0, self.h = t0, h
        self._f, self._y0, self._y1, self._K = f, y0, y1, K
        self._F: np.ndarray | None = None
        self._columns: list[tuple[float, ...]] | None = None
        self.owner = owner

    def _build(self) -> np.ndarray:
        h, y0 = self.h, self._y0
        s = self._K.shape[0]  # 13: the 12 stages and f(t0 + h, y1)
        K = np.empty((s + 3, y0.size))
        K[:s] = self._K
        for r, (node, row) in enumerate(_DOP853_EXTRA_STAGES):
            i = s + r
            K[i] = _rhs(self._f, self.t0 + node * h, y0 + h * row.dot(K[:i]))
        if self.owner is not None:
            self.owner.nfev += 3
        dy = self._y1 - y0
        F = np.empty((7, y0.size))
        F[0] = dy
        F[1] = h * K[0] - dy
        F[2] = 2 * dy - h * (K[0] + K[s - 1])
        F[3:] = h * _DOP853_ARRAYS["d"].dot(K)
        return F

    def __call__(self, theta: float) -> np.ndarray:
        if isinstance(theta, float) and self._y0.size <= FLOAT_LOOP_SIZE:
            return np.array(self._entries(theta, self._y0.size))  # the same operations
        if self._F is None:
            self._F = self._build()
        F, s, s1 = self._F, theta, 1 - theta
        acc = F[6]
        for k in range(5, -1, -1):
            acc = F[k] + (s1 if k % 2 == 0 else s) * acc
        return self._y0 + s * acc

    def head(self, theta: float, m: int) -> list[float]:
        """The first ``m`` entries of ``self(theta)`` as floats, by the same operations on
        each entry (float64 arithmetic, entry by entry, is the same in Python and NumPy):
        a root search evaluates one gap of the coordinates many times, and for a few
        entries the arrays' per-operation cost is most of the work."""
        if self._columns is None:
            if self._F is None:
                self._F = self._build()
            self._columns = list(zip(*self._F.tolist(), self._y0.tolist(), strict=True))
        s, s1 = theta, 1 - theta
        return [
            y0 + s * (f0 + s1 * (f1 + s * (f2 + s1 * (f3 + s * (f4 + s1 * (f5 + s * f6))))))
            for f0, f1, f2, f3, f4, f5, f6, y0 in self._columns[:m]
        ]

    _entries = head  # what __call__ reads (a test takes ``head`` away from the searches)

    def many(self, thetas: np.ndarray) -> np.ndarray:
        """``self(theta)`` for each theta, as the rows of an array (the same operations)."""
        if self._F is None:
            self._F = self._build()
        F, s = self._F, thetas[:, None]
        s1 = 1 - s
        acc: np.ndarray = F[6]
        for k in range(5, -1, -1):
            acc = F[k] + (s1 if k % 2 == 0 else s) * acc
        return self._y0 + s * acc


class _NanDense:
    """Dense output of a failed step (``error = inf``): NaN everywhere."""

    def __init__(self, t0, h, n):
        self.t0, self.h, self._n = t0, h, n

    def __call__(self, theta: float) -> np.ndarray:
        return np.full(self._n, np.nan)


# --- explicit Runge-Kutta ---------------------------------------------------------------


class ExplicitRK(Stepper):
    """An explicit embedded pair (see :class:`symmech.simulate.tableaux.ExplicitTableau`)."""

    implicit = False
    adaptive = True

    def __init__(self, tableau: ExplicitTableau):
        self.tableau = tableau
        self.name = tableau.name
        self.order = tableau.order
        self.error_order = tableau.error_order
        self.dense_order = tableau.dense_order
        arrays = tableau.arrays
        self._c, self._a, self._b = arrays["c"], arrays["a"], arrays["b"]
        self._e, self._P = arrays["e"], arrays["dense"]
        # the rows of a and the nodes, taken out once (the stage loop runs every step);
        # the stages combine through ndarray.dot, the same BLAS product as ``@`` at half
        # its call overhead on these small arrays
        self._rows = [np.ascontiguousarray(self._a[i, :i]) for i in range(tableau.stages)]
        self._nodes = [float(c) for c in self._c]
        self.nodes = (*self._nodes, 1.0)

    def _stages(self, f, t0, y0, f0, h) -> tuple[np.ndarray, np.ndarray]:
        """Stages ``K_0..K_s`` (``K_s = f(t0 + h, y1)``) and ``y1``."""
        s = self.tableau.stages
        K = np.empty((s + 1, y0.size))
        K[0] = f0
        rows, nodes = self._rows, self._nodes
        for i in range(1, s):
            K[i] = _rhs(f, t0 + nodes[i] * h, y0 + h * rows[i].dot(K[:i]))
        y1 = y0 + h * self._b.dot(K[:s])
        K[s] = _rhs(f, t0 + h, y1)
        return K, y1

    def _error(self, K, h, y0, y1, rtol, atol) -> float:
        return _rms(h * self._e.dot(K) / _scale(y0, y1, rtol, atol))

    def _dense(self, f, t0, h, y0, y1, K) -> Dense:
        return _PolyDense(t0, h, y0, K, self._P)

    def step(self, f, t0, y0, f0, h, rtol, atol, jac=None) -> Step:
        h = _check_h(h)
        y0 = np.asarray(y0, dtype=float)
        K, y1 = self._stages(f, t0, y0, np.asarray(f0, dtype=float), h)
        error = self._error(K, h, y0, y1, rtol, atol) if self.adaptive else 0.0
        error = _finite_or_inf(error, y1, K[-1])
        step = Step(y1, K[-1], error, None, self.tableau.stages, stages=K)  # type: ignore[arg-type]
        step.dense = self._dense(f, t0, h, y0, y1, K)
        if isinstance(step.dense, _Dop853Dense):
            step.dense.owner = step
        return step


class Dop853(ExplicitRK):
    """DOP853: order 8, the combined error estimate and the 7th-order dense output.

    Error norm (HNW I, section II.10, eq. (10.17)): with ``E5 = h sum e_i K_i / scale`` and
    ``E3 = h sum e3_i K_i / scale``, ``err = |h| ||e5||^2 / sqrt(n (||e5||^2 + 0.01
    ||e3||^2))`` where ``e5, e3`` are the scaled estimates without ``h`` -- it behaves like
    ``h^8``, hence ``error_order = 7``.
    """

    def __init__(self):
        super().__init__(DOP853)
        self._e3 = _DOP853_ARRAYS["e3"]

    def _error(self, K, h, y0, y1, rtol, atol) -> float:
        scale = _scale(y0, y1, rtol, atol)
        e5 = self._e.dot(K) / scale
        e3 = self._e3.dot(K) / scale
        n5, n3 = float(e5.dot(e5)), float(e3.dot(e3))
        if n5 == 0.0 and n3 == 0.0:
            return 0.0
        return abs(h) * n5 / math.sqrt((n5 + 0.01 * n3) * y0.size)

    def _dense(self, f, t0, h, y0, y1, K) -> Dense:
        return _Dop853Dense(f, t0, h, y0, y1, K)


class ClassicalRK4(ExplicitRK):
    """The classical fixed-step RK4 with the cubic Hermite dense output (order 3)."""

    adaptive = False

    def __init__(self):
        super().__init__(RK4)

    def _dense(self, f, t0, h, y0, y1, K) -> Dense:
        return _HermiteDense(t0, h, y0, y1, K[0], K[-1])


_DOP853_ARRAYS = {
    "e3": np.array(DOP853_EXTRAS.e3, dtype=object).astype(float),
    "c_extra": np.array(DOP853_EXTRAS.c_extra, dtype=object).astype(float),
    "a_extra": np.array(DOP853_EXTRAS.a_extra, dtype=object).astype(float),
    "d": np.array(DOP853_EXTRAS.d, dtype=object).astype(float),
}

#: The three extra stages of DOP853's dense output, taken out once (every step builds
#: them): the node as a float and the row of coefficients over the stages before it.
_DOP853_EXTRA_STAGES = [
    (
        float(_DOP853_ARRAYS["c_extra"][r]),
        np.ascontiguousarray(_DOP853_ARRAYS["a_extra"][r, : DOP853.stages + 1 + r]),
    )
    for r in range(3)
]


# --- registry, initial step, controller ------------------------------------------------


def _rodas4() -> Stepper:
    """Rodas4 (:mod:`symmech.simulate.rosenbrock`, which builds on this module)."""
    from symmech.simulate.rosenbrock import Rodas4

    return Rodas4()


_FACTORIES: dict[str, Callable[[], Stepper]] = {
    "dop853": Dop853,
    "tsit5": lambda: ExplicitRK(TSIT5),
    "rk45": lambda: ExplicitRK(RK45),
    "rk4": ClassicalRK4,
    "rodas4": _rodas4,
}
#: every method name :func:`stepper` accepts
METHODS: tuple[str, ...] = tuple(_FACTORIES)


def stepper(name: str) -> Stepper:
    """The stepper called ``name`` (one of :data:`METHODS`)."""
    factory = _FACTORIES.get(name) if isinstance(name, str) else None
    if factory is None:
        raise StepperError(
            f"unknown integration method {name!r}: choose one of {', '.join(METHODS)}"
        )
    return factory()


def initial_step(
    f: Rhs, t0: float, y0, f0, direction: float, order: int, rtol: float, atol
) -> float:
    """A first step size ``|h|`` by Hairer's algorithm (HNW I, section II.4, p. 169).

    With ``sc_i = atol_i + rtol |y0_i|`` and ``||.||`` the RMS norm scaled by ``sc``:
    ``d0 = ||y0||``, ``d1 = ||f0||``, ``h0 = 0.01 d0/d1`` (``1e-6`` if either is below
    ``1e-5``), one explicit Euler step gives ``d2 = ||f(t0 + h0, y0 + h0 f0) - f0|| / h0``,
    ``h1 = (0.01 / max(d1, d2))^(1/(order+1))`` (``max(1e-6, 1e-3 h0)`` if both are below
    ``1e-15``) and the result is ``min(100 h0, h1)``, or 0 when ``d1`` overflows (``h0 = 0``).
    ``order`` is the error estimator's (:attr:`Stepper.error_order`); the caller clamps the
    result to its interval and maximum step, as SciPy's ``select_initial_step`` does inside.
    """
    y0 = np.asarray(y0, dtype=float)
    f0 = np.asarray(f0, dtype=float)
    if y0.size == 0:
        return math.inf
    rtol, atol = check_tolerances(rtol, atol, y0.size)
    if direction not in (1, -1, 1.0, -1.0):
        raise StepperError(f"direction = {direction!r}: it must be +1 or -1")
    scale = atol + np.abs(y0) * rtol
    with np.errstate(over="ignore"):  # an overflow gives d1 = inf: the step 0 below
        d0, d1 = _rms(y0 / scale), _rms(f0 / scale)
    h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
    if h0 == 0.0:  # f0 overflows the scale: no step can be taken (the C loop returns 0 too)
        return 0.0
    f1 = _rhs(f, t0 + direction * h0, y0 + direction * h0 * f0)
    d2 = _rms((f1 - f0) / scale) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1 / (order + 1))
    return min(100 * h0, h1)


class Controller:
    """Step-size controller: from a step's error norm, accept or reject and a factor
    ``h_new = factor h``.

    With ``k = 1/(error_order + 1)``, a step is accepted when ``error <= 1``; then
    ``factor = safety error^-(k - 0.75 beta) previous^beta`` (Gustafsson's PI control, HNW
    II, section IV.2, eq. (2.43c), as DOPRI5 uses it; ``beta = 0``, the default, is the
    standard controller ``safety error^-k`` of HNW I, eq. II.(4.13) and of SciPy), with
    ``previous = max(error of the last accepted step, 1e-4)``; ``factor = max_factor``
    when ``error == 0``.  A rejected step gets ``max(min_factor, safety error^-k)`` (NaN
    counts as ``inf``: ``min_factor``).  Every factor lies in ``[min_factor, max_factor]``
    and the step after a rejection never grows (``factor <= 1``).  :meth:`reset` forgets the
    history (after an impact, a restart).
    """

    def __init__(
        self,
        error_order: int,
        *,
        safety: float = 0.9,
        min_factor: float = 0.2,
        max_factor: float = 10.0,
        beta: float = 0.0,
    ):
        if not (0 < min_factor <= 1 <= max_factor) or not (0 < safety <= 1) or error_order < 1:
            raise StepperError(
                f"Controller(error_order={error_order!r}, safety={safety!r}, min_factor="
                f"{min_factor!r}, max_factor={max_factor!r}): need error_order >= 1, 0 <"
                " safety <= 1 and 0 < min_factor <= 1 <= max_factor"
            )
        if not (0 <= beta < 1 / (error_order + 1) / 0.75):
            raise StepperError(f"Controller beta = {beta!r}: need 0 <= beta < 4/(3 (q + 1))")
        self.k = 1.0 / (error_order + 1)
        self.safety, self.min_factor, self.max_factor, self.beta = (
            safety,
            min_factor,
            max_factor,
            beta,
        )
        self.reset()

    def reset(self) -> None:
        """Forget the previous error and any rejection."""
        self.previous = 1e-4
        self.rejected = False

    def __call__(self, error: float) -> tuple[bool, float]:
        """``(accepted, factor)`` for a step with this error norm."""
        error = math.inf if math.isnan(error) else float(error)
        if error <= 1.0:
            if error == 0.0:
                factor = self.max_factor
            else:
                factor = (
                    self.safety * error ** (-(self.k - 0.75 * self.beta)) * self.previous**self.beta
                )
            factor = min(self.max_factor, max(self.min_factor, factor))
            if self.rejected:
                factor = min(1.0, factor)
            self.previous = max(error, 1e-4)
            self.rejected = False
            return True, factor
        factor = self.min_factor if math.isinf(error) else self.safety * error ** (-self.k)
        self.rejected = True
        return False, min(1.0, max(self.min_factor, factor))
