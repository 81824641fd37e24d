"""The smooth phases of a hybrid run: adaptive integration between events.

A flow integrates ``y_dot = f(t, y)`` one accepted step at a time and hands each step to
the hybrid loop as a :class:`Segment` with its continuous output, so that the loop can look
for events *inside* the step before accepting it.  After an event the loop restarts the
flow from the new state (``start``), keeping the last accepted step size as a hint.

* :class:`RKFlow` drives symmech's own steppers (:mod:`symmech.simulate.steppers`: DOP853,
  Tsitouras 5(4), Dormand-Prince 5(4), RK4 and the linearly implicit Rodas4) with the
  standard step-size rule (Hairer, Norsett & Wanner, Solving ODEs I, II.4):
  ``h_new = h * min(10, max(0.2, 0.9 err^(-1/(k+1))))`` with k the order of the error
  estimate, no growth right after a rejection, and the initial step of HNW I, II.4.
* :class:`ScipyFlow` drives SciPy's ``OdeSolver`` classes (``DOP853``, ``RK45``,
  ``Radau``, ``BDF``, ``LSODA``) step by step with their own dense output.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from operator import itemgetter
from typing import Any

import numpy as np

from symmech.simulate.steppers import FLOAT_LOOP_SIZE, all_finite

__all__ = ["AugmentedFlow", "FlowFailure", "RKFlow", "ScipyFlow", "Segment"]

Rhs = Callable[[float, np.ndarray], np.ndarray]

#: float64's unit roundoff (looked up once: the step loop reads it every step)
_EPS = float(np.finfo(float).eps)


class FlowFailure(RuntimeError):
    """The integrator cannot continue (step size underflow, non-finite state)."""


@dataclass
class Segment:
    """One accepted step from ``t0`` to ``t1``: end states, the derivative at ``t1``, and
    ``dense(t)`` for t in [t0, t1]; ``many(ts)``, where the flow has it, is ``dense`` at
    the times ``ts`` at once (rows of an array: the same values, element by element), and
    ``head(t, m)`` the first ``m`` entries of ``dense(t)`` as a list of floats (the same
    values).

    ``stages``, where the method has them, is ``(nodes, K)``: the derivatives ``K`` (rows)
    of the explicit step at the times ``t0 + theta h`` of ``nodes``.  A step of an
    :class:`AugmentedFlow` carries instead ``gap_rates = (thetas, rates)``: the nodes in
    increasing order and, for each wall, d psi/dt at them (the walls' columns of ``K``)."""

    t0: float
    t1: float
    y0: np.ndarray
    y1: np.ndarray
    f1: np.ndarray | None
    dense: Callable[[float], np.ndarray]
    many: Callable[[Sequence[float]], np.ndarray] | None = None
    head: Callable[[float, int], list[float]] | None = None
    stages: tuple[Sequence[float], np.ndarray] | None = None
    gap_rates: tuple[list[float], list[list[float]]] | None = None

    def samples(self, times: Sequence[Any]) -> list[np.ndarray]:
        """The states at ``times`` (in [t0, t1]): ``y0`` at t0, ``y1`` at t1, the
        continuous output in between (through :attr:`many` where there is one)."""
        inner = [t for t in times if t != self.t0 and t != self.t1]
        rows: Any = iter(self.many(inner) if inner and self.many is not None else ())
        out = []
        for t in times:
            if t == self.t0:
                out.append(self.y0)
            elif t == self.t1:
                out.append(self.y1)
            else:
                out.append(next(rows) if self.many is not None else self.dense(t))
        return out


@dataclass
class FlowStats:
    steps: int = 0
    rejected: int = 0
    nfev: int = 0
    njev: int = 0


class RKFlow:
    """Adaptive (or fixed-step, for rk4) integration with a :mod:`steppers` method."""

    def __init__(
        self,
        f: Rhs,
        method: str,
        rtol: float,
        atol: float,
        max_step: float,
        jac: Callable[[float, np.ndarray], np.ndarray] | None = None,
        fixed_step: float | None = None,
    ):
        from symmech.simulate.steppers import initial_step, stepper

        self._initial_step = initial_step
        self.stepper = stepper(method)
        self.f, self.jac = f, jac
        self.rtol, self.atol, self.max_step = rtol, atol, max_step
        self.fixed_step = fixed_step
        self.stats = FlowStats()
        self.h: float | None = None
        self._rejected_last = False
        self._rhs: Rhs = self._counted()

    def _counted(self) -> Rhs:
        """``f`` as it is now (the flow's owner may replace it at a restart), its calls
        counted: the right-hand side of the run from a (re)start on, which a step also
        hands its continuous output, formed on first read."""
        f, stats = self.f, self.stats

        def rhs(t: float, y: np.ndarray) -> np.ndarray:
            stats.nfev += 1
            return f(t, y)

        return rhs

    def _jac(self, t: float, y: np.ndarray) -> np.ndarray:
        self.stats.njev += 1
        assert self.jac is not None
        return self.jac(t, y)

    def start(self, t: float, y: np.ndarray, t_bound: float) -> None:
        """(Re)start at (t, y), integrating towards ``t_bound``."""
        self.t, self.y, self.t_bound = t, np.array(y, dtype=float), t_bound
        self._rhs = self._counted()
        self.fy = self._rhs(t, self.y)
        if not all_finite(self.fy):
            raise FlowFailure(f"the right-hand side is not finite at t = {t!r}")
        if self.fixed_step is not None:
            self.h = self.fixed_step
        elif self.h is None:
            self.h = self._initial_step(
                self._rhs,
                t,
                self.y,
                self.fy,
                1.0,
                self.stepper.error_order,
                self.rtol,
                self.atol,
            )
        self.h = min(self.h, self.max_step)
        self._rejected_last = False

    def advance(self) -> Segment:
        """Take one accepted step (rejecting and retrying as the error estimate asks)."""
        t, y = self.t, self.y
        left = self.t_bound - t
        if left <= 0:
            raise FlowFailure("advance past t_bound")
        eps = _EPS
        while True:
            assert self.h is not None
            h = min(self.h, self.max_step, left)
            if left - h < 4 * eps * abs(self.t_bound):  # do not leave a sliver
                h = left
            # a step the controller shrank below the resolution of t is a failure; near
            # t = 0 the floor is eps of the run's time scale min(1, |t_end|) (a run to
            # 1e-9 s, or a first step of 1e-21 s for atol = 1e-30, is resolved); the last
            # step to t_bound is taken however short (an impact a few ulps before t_end
            # leaves such a span)
            scale = eps * min(1.0, abs(self.t_bound))
            if h < left and h <= 8 * eps * max(abs(t), scale):
                raise FlowFailure(f"step size {h:.3g} too small at t = {t!r}")
            jac = self._jac if self.stepper.implicit else None
            st = self.stepper.step(self._rhs, t, y, self.fy, h, self.rtol, self.atol, jac=jac)
            err = st.error
            finite = math.isfinite(err) and all_finite(st.y)
            if not self.stepper.adaptive:
                if not finite:
                    raise FlowFailure(f"non-finite state after a fixed step at t = {t!r}")
                break
            if finite and err <= 1.0:
                k = self.stepper.error_order
                factor = 10.0 if err == 0 else min(10.0, max(0.2, 0.9 * err ** (-1 / (k + 1))))
                if self._rejected_last:
                    factor = min(factor, 1.0)
                self._rejected_last = False
                self.h = h * factor
                break
            self.stats.rejected += 1
            self._rejected_last = True
            if not finite:
                self.h = 0.25 * h
            else:
                k = self.stepper.error_order
                self.h = h * max(0.2, 0.9 * err ** (-1 / (k + 1)))
        self.stats.steps += 1
        t1 = self.t_bound if h == left else t + h
        dense_step = st.dense

        def dense(tt: float, _d: Any = dense_step, _t0: float = t, _h: float = h) -> np.ndarray:
            return _d((tt - _t0) / _h)

        many = head = None
        if hasattr(dense_step, "many"):

            def many(ts: Sequence[float], _d: Any = dense_step, _t0: float = t, _h: float = h):
                return _d.many((np.asarray(ts, dtype=float) - _t0) / _h)

        if hasattr(dense_step, "head"):

            def head(tt: float, m: int, _d: Any = dense_step, _t0: float = t, _h: float = h):
                return _d.head((tt - _t0) / _h, m)

        stages = None if st.stages is None else (self.stepper.nodes, st.stages)
        seg = Segment(t, t1, y, st.y, st.f, dense, many, head, stages)
        self.t, self.y, self.fy = t1, st.y, st.f
        return seg

    def limit_step(self, h: float) -> None:
        """Restart no longer than ``h`` (the step the loop just cut at an event): the next
        event is then located on a step of the motion's own scale, whose dense output
        rounds relative to that scale (a polynomial motion lets the step grow without
        bound otherwise)."""
        if self.h is not None and 0 < h < self.h:
            self.h = h

    def accept_projection(self, y: np.ndarray) -> None:
        """The loop replaced the step's end state (constraint projection): recompute f."""
        self.y = np.array(y, dtype=float)
        self.fy = self._rhs(self.t, self.y)


class ScipyFlow:
    """Integration with one of SciPy's ``OdeSolver`` classes, one step at a time."""

    METHODS = ("DOP853", "RK45", "RK23", "Radau", "BDF", "LSODA")

    def __init__(
        self,
        f: Rhs,
        method: str,
        rtol: float,
        atol: float,
        max_step: float,
        jac: Callable[[float, np.ndarray], np.ndarray] | None = None,
    ):
        from scipy import integrate

        name = {m.lower(): m for m in self.METHODS}.get(method.lower())
        if name is None:
            raise ValueError(f"scipy method must be one of {self.METHODS}, got {method!r}")
        self.cls = getattr(integrate, name)
        self._dop853 = integrate.DOP853
        self.implicit = name in ("Radau", "BDF", "LSODA")
        #: the solver keeps f(t0, y0) as ``f`` (the others compute it inside)
        self._own_f = name in ("DOP853", "RK45", "RK23", "Radau")
        #: the times of an explicit solver's stages (its nodes C, then 1 for f(t1, y1))
        C = getattr(self.cls, "C", None)
        self._nodes = (*C.tolist(), 1.0) if isinstance(C, np.ndarray) else None
        self.f, self.jac = f, jac
        self.rtol, self.atol, self.max_step = rtol, atol, max_step
        self.stats = FlowStats()
        self.h: float | None = None
        self.solver: Any = None

    def start(self, t: float, y: np.ndarray, t_bound: float) -> None:
        kwargs: dict[str, Any] = {"rtol": self.rtol, "atol": self.atol, "max_step": self.max_step}
        if self.h is not None:
            kwargs["first_step"] = min(self.h, t_bound - t)
        if self.implicit and self.jac is not None:
            kwargs["jac"] = self.jac
        if self.solver is not None:
            self._collect()
        # the loops' rule (RKFlow.start): SciPy's first-step heuristic turns an infinite
        # rhs into a step of nan, which its step loop then shrinks forever; with the first
        # step given there is no heuristic, and the solver's own f(t, y) is checked
        y = np.array(y, dtype=float)
        if "first_step" not in kwargs or not self._own_f:
            self.stats.nfev += 1
            if not all_finite(np.asarray(self.f(t, y), dtype=float)):
                raise FlowFailure(f"the right-hand side is not finite at t = {t!r}")
        self.solver = self.cls(self.f, t, y, t_bound, **kwargs)
        self.t_bound = t_bound
        if self._own_f and not all_finite(self.solver.f):
            raise FlowFailure(f"the right-hand side is not finite at t = {t!r}")

    def _collect(self) -> None:
        s = self.solver
        self.stats.nfev += s.nfev
        self.stats.njev += getattr(s, "njev", 0)
        s.nfev = 0
        if hasattr(s, "njev"):
            s.njev = 0

    def advance(self) -> Segment:
        s = self.solver
        t0, y0 = float(s.t), s.y.copy()
        # the loops' rule (RKFlow.advance): a step the controller wants at the resolution
        # of t is a failure (SciPy would step by ulps of t, far from t = 0, and take a
        # wall for a contact it cannot resolve)
        eps = _EPS
        floor = 8 * eps * max(abs(t0), eps * min(1.0, abs(self.t_bound)))
        wanted = getattr(s, "h_abs", None)
        if wanted is not None and wanted < self.t_bound - t0 and wanted <= floor:
            raise FlowFailure(f"step size {wanted:.3g} too small at t = {t0!r}")
        message = s.step()
        if s.status == "failed":
            raise FlowFailure(f"scipy {self.cls.__name__}: {message}")
        h = float(s.t) - t0
        if float(s.t) < self.t_bound and h <= floor:
            raise FlowFailure(f"step size {h:.3g} too small at t = {t0!r}")
        if not all_finite(s.y):
            raise FlowFailure(f"the right-hand side is not finite at t = {t0!r}")
        self.stats.steps += 1
        self._collect()
        # the solver's proposal for its next step (h_abs of SciPy's RK, Radau and BDF
        # solvers), so a restart after a projection keeps growing the step
        # (LSODA exposes none: twice its last step, which it cuts back if need be)
        self.h = getattr(s, "h_abs", None) or 2 * s.step_size or self.h
        dense = _LazyDense(s, self._nodes)

        def continuous(tt: float) -> np.ndarray:
            return dense()(tt)

        many = head = None
        if isinstance(s, self._dop853):  # element by element, as one call

            def many(ts: Sequence[float]) -> np.ndarray:
                return dense()(np.asarray(ts, dtype=float)).T

            head = _scipy_head(dense)
            if head is not None and s.n <= FLOAT_LOOP_SIZE:  # one time: on floats
                whole, size = head, s.n

                def continuous(tt: float) -> np.ndarray:
                    if isinstance(tt, float):
                        return np.array(whole(tt, size))
                    return dense()(tt)

        return Segment(t0, float(s.t), y0, s.y.copy(), None, continuous, many, head, dense.stages)

    def limit_step(self, h: float) -> None:
        """As :meth:`RKFlow.limit_step` (the next solver's first step)."""
        if self.h is not None and 0 < h < self.h:
            self.h = h

    def accept_projection(self, y: np.ndarray) -> None:
        """The loop replaced the end state: restart the solver there, unless the change is
        within the tolerance (a restart costs SciPy's multistep methods their order and
        step size, so BDF and LSODA would crawl if restarted after every projection; the
        drift is then corrected at the first projection that matters)."""
        if self.solver.t >= self.t_bound:
            return
        y = np.asarray(y, dtype=float)
        scale = self.atol + self.rtol * np.abs(y)
        if np.max(np.abs(y - self.solver.y) / scale) < 1:
            return
        self.start(float(self.solver.t), y, self.t_bound)


class _LazyDense:
    """SciPy's continuous output of the step a solver has just taken, formed on the first
    call (``self()``): a step whose output is never read (the event search certifies most)
    skips its extra stages.  ``dense_output`` of an explicit Runge-Kutta solver reads the
    last step (:data:`_DENSE_READS`, the class's tableau) and the stage array that the
    next step overwrites, so it runs on a copy of the solver holding just those, the
    stages copied: the same operations on the same numbers.  Any other solver (Radau,
    BDF, LSODA: state of their own) forms its output at once."""

    def __init__(self, solver: Any, nodes: tuple[float, ...] | None):
        self._dense: Any = None
        self.head: Callable[[float, int], list[float]] | None = None
        #: ``Segment.stages`` of an explicit Runge-Kutta solver: its ``nodes`` (C, then 1)
        #: and the stages ``K`` (the last row ``f(t1, y1)``); else None
        self.stages: tuple[Sequence[float], np.ndarray] | None = None
        self._solver: Any = None if nodes is None else _snapshot(solver)
        if nodes is None or self._solver is None:
            self._dense = solver.dense_output()
        else:
            self.stages = (nodes, self._solver.K)

    def __call__(self) -> Any:
        if self._dense is None:
            self._dense = self._solver.dense_output()
            self._solver = None
        return self._dense


#: what SciPy's ``dense_output`` of an explicit Runge-Kutta solver reads of the instance
#: besides its stages (``OdeSolver.dense_output``, ``RungeKutta._dense_output_impl`` and
#: ``DOP853._dense_output_impl``; the tableau is the class's)
_DENSE_READS = ("t_old", "t", "n", "y", "y_old", "f", "fun", "h_previous")
_DENSE_NAMES = frozenset(_DENSE_READS)
_read_dense = itemgetter(*_DENSE_READS)


def _snapshot(solver: Any) -> Any:
    """A copy of ``solver`` holding what its ``dense_output`` reads, its stage arrays
    copied (the next step overwrites them); None for a solver that is not an explicit
    Runge-Kutta solver with those attributes."""
    K = getattr(solver, "K", None)
    state = solver.__dict__
    if not isinstance(K, np.ndarray):
        return None
    if not state.keys() >= _DENSE_NAMES:
        return None
    snapshot = object.__new__(type(solver))
    snapshot.__dict__.update(zip(_DENSE_READS, _read_dense(state), strict=True))
    extended = state.get("K_extended")
    if extended is not None:  # DOP853: K is the first rows of K_extended
        snapshot.K_extended = extended.copy()
        snapshot.K = snapshot.K_extended[: K.shape[0]]
    else:
        snapshot.K = K.copy()
    return snapshot


def _scipy_head(dense: _LazyDense) -> Callable[[float, int], list[float]]:
    """``head(t, m)`` of a SciPy DOP853 step's continuous output (:attr:`Segment.head`),
    the output formed on the first call: :func:`_dop853_head` (the entries of ``dense(t)``
    where it reproduces them, else taken from ``dense(t)``)."""

    def head(tt: float, m: int) -> list[float]:
        entries = dense.head
        if entries is None:
            formed = dense()
            entries = _dop853_head(formed) or (lambda t, k: formed(t)[:k].tolist())
            dense.head = entries
        return entries(tt, m)

    return head


def _dop853_head(dense: Any) -> Callable[[float, int], list[float]] | None:
    """``head(t, m)`` of SciPy's DOP853 continuous output (:attr:`Segment.head`): the
    operations of its ``_call_impl`` on each entry (``y = 0``; for the rows of ``F`` in
    reverse, ``y += F_k`` then ``y *= x`` or ``y *= 1 - x`` alternately; ``y += y_old``,
    with ``x = (t - t_old) / h``), in float64 as there, so the same values; None if the
    object does not hold what that rule reads."""
    try:
        F, y_old, t_old, h = dense.F, dense.y_old, dense.t_old, dense.h
    except AttributeError:
        return None
    if not (len(F) == 7 and F.dtype.char == "d" and y_old.dtype.char == "d"):
        return None  # only real float64 arithmetic is reproduced
    columns: list[tuple[float, ...]] = []

    def head(tt: float, m: int) -> list[float]:
        if not columns:
            columns.extend(zip(*np.asarray(F).tolist(), np.asarray(y_old).tolist(), strict=True))
        x = (tt - t_old) / h
        x1 = 1 - x
        return [
            (((((((0.0 + f6) * x + f5) * x1 + f4) * x + f3) * x1 + f2) * x + f1) * x1 + f0) * x + y0
            for f0, f1, f2, f3, f4, f5, f6, y0 in columns[:m]
        ]

    return head


class AugmentedFlow:
    """A flow whose state carries the walls' gaps: ``y_aug = (y, z)`` with
    ``z_w' = d psi_w/dt = dpsi_w q_dot + psi_t``.  The integrator's error control then
    resolves every gap's variation as well as the motion, so a step never spans a wall's
    oscillation (a spinning body, a fast moving wall) that a few samples would miss.  The
    loop sees only ``y``; ``z`` is reset to the exact gaps at every (re)start."""

    def __init__(
        self,
        make: Callable[[Rhs, Any], Any],
        rhs: Rhs,
        rates: Callable[[float, np.ndarray, np.ndarray], np.ndarray],
        gaps: Callable[[float, np.ndarray], np.ndarray],
        size: int,
        jac: Callable[[float, np.ndarray], np.ndarray] | None = None,
        bind: Callable[[], Rhs] | None = None,
    ):
        self.size, self._rhs, self._rates, self._gaps = size, rhs, rates, gaps
        #: ``bind()``: the same right-hand side fused (Functions.augmented_in), in the mode
        #: the loop integrates now and fixed to it, given to the inner flow at every
        #: (re)start: a step's continuous output formed on first read, after the mode
        #: changed, evaluates the step's own; without it, built here from rhs and rates
        self._bind = bind
        #: the nodes of a method's stages -> their order in time
        self._orders: dict[Sequence[float], tuple[list[float], Any]] = {}
        self._jac = jac
        f = self._augmented if bind is None else bind()
        self.inner = make(f, None if jac is None else self._augmented_jac)

    @property
    def stats(self) -> Any:
        return self.inner.stats

    def _augmented(self, t: float, ya: np.ndarray) -> np.ndarray:
        y = ya[: self.size]
        ydot = self._rhs(t, y)
        return np.concatenate([ydot, self._rates(t, y, ydot)])

    def _augmented_jac(self, t: float, ya: np.ndarray) -> np.ndarray:
        """``[[J, 0], [dr/dy, 0]]``: the gaps do not feed back into the motion; the rows of
        their rates ``r(y) = dpsi q_dot + psi_t`` are central differences (they only steer
        the step size, so their Jacobian need not be exact)."""
        assert self._jac is not None
        k = self.size
        out = np.zeros((len(ya), len(ya)))
        y = ya[:k]
        out[:k, :k] = self._jac(t, y)
        for j in range(k):
            h = 1e-7 * max(1.0, abs(y[j]))
            e = np.zeros(k)
            e[j] = h
            up, down = y + e, y - e
            out[k:, j] = (
                self._rates(t, up, self._rhs(t, up)) - self._rates(t, down, self._rhs(t, down))
            ) / (2 * h)
        return out

    def _lift(self, t: float, y: np.ndarray) -> np.ndarray:
        return np.concatenate([y, self._gaps(t, y)])

    def start(self, t: float, y: np.ndarray, t_bound: float) -> None:
        if self._bind is not None:
            self.inner.f = self._bind()
        self.inner.start(t, self._lift(t, y), t_bound)

    def advance(self) -> Segment:
        seg = self.inner.advance()
        k = self.size

        def dense(tt: float, _d: Any = seg.dense) -> np.ndarray:
            return _d(tt)[:k]

        many = None
        if seg.many is not None:

            def many(ts: Sequence[float], _m: Any = seg.many) -> np.ndarray:
                return _m(ts)[:, :k]

        f1 = None if seg.f1 is None else seg.f1[:k]
        # the first m <= k entries of the augmented state are those of the loop's
        out = Segment(seg.t0, seg.t1, seg.y0[:k], seg.y1[:k], f1, dense, many, seg.head)
        if seg.stages is not None:
            nodes, K = seg.stages
            order = self._orders.get(nodes)
            if order is None:
                rows = sorted(range(len(nodes)), key=nodes.__getitem__)
                order = self._orders[nodes] = ([nodes[i] for i in rows], itemgetter(*rows))
            thetas, in_time = order
            out.gap_rates = (thetas, [list(in_time(c)) for c in K[:, k:].T.tolist()])
        return out

    def limit_step(self, h: float) -> None:
        self.inner.limit_step(h)

    def accept_projection(self, y: np.ndarray) -> None:
        t = self.inner.t if hasattr(self.inner, "t") else float(self.inner.solver.t)
        self.inner.accept_projection(self._lift(t, y))
