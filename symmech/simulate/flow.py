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
* :class:`~symmech.simulate.scipy_flow.ScipyFlow` (its own module) drives SciPy's
  ``OdeSolver`` classes step by step with their own dense output.
* :class:`AugmentedFlow` wraps either and carries the walls' gaps in its state.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from operator import itemgetter
from typing import Any

import numpy as np

from symmech.simulate.steppers import all_finite

__all__ = ["AugmentedFlow", "FlowFailure", "RKFlow", "Segment"]

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
