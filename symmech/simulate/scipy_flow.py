"""SciPy's ``OdeSolver`` classes (``DOP853``, ``RK45``, ``RK23``, ``Radau``, ``BDF``,
``LSODA``) as a flow of the hybrid loop (the interface of :mod:`symmech.simulate.flow`):
one accepted step at a time, each handed over as a :class:`~symmech.simulate.flow.Segment`
with SciPy's own continuous output.

Three things here read a solver's state beyond SciPy's documented attributes, each only
for the classes whose state it knows and each held to SciPy's own results, bit for bit, by
the tests: a step's continuous output is formed from a copy of what ``dense_output`` reads
(:func:`_snapshot`), so that a step whose output is never read skips its extra stages;
DOP853's output is evaluated entry by entry on floats by the operations of its
``_call_impl`` (:func:`_dop853_head`); and an explicit Runge-Kutta solver is restarted in
place after an event (:func:`_restart`) instead of being built again.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from operator import itemgetter
from typing import Any

import numpy as np

from symmech.simulate.flow import _EPS, FlowFailure, FlowStats, Rhs, Segment
from symmech.simulate.steppers import FLOAT_LOOP_SIZE, all_finite

__all__ = ["ScipyFlow"]


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
        #: an explicit Runge-Kutta solver is restarted in place (:func:`_restart`)
        self._restartable = name in ("DOP853", "RK45", "RK23")
        #: the right-hand side the current solver was built with
        self._built_with: Rhs | None = None

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
        reuse = self._restartable and self._built_with is self.f and "first_step" in kwargs
        if not (reuse and _restart(self.solver, t, y, t_bound, kwargs["first_step"])):
            self.solver = self.cls(self.f, t, y, t_bound, **kwargs)
            self._built_with = self.f
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
        many = head = None
        if isinstance(s, self._dop853):  # element by element, as one call

            def many(ts: Sequence[float]) -> np.ndarray:
                return dense()(np.asarray(ts, dtype=float)).T

            head = _scipy_head(dense)
        # a state at one time of a small system: its entries on floats (the same values)
        whole, size = (head, s.n) if head is not None and s.n <= FLOAT_LOOP_SIZE else (None, 0)

        def continuous(tt: float) -> np.ndarray:
            if whole is not None and isinstance(tt, float):
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


#: The instance state of SciPy's explicit Runge-Kutta solvers (``OdeSolver.__init__`` and
#: ``RungeKutta.__init__``; DOP853 adds ``K_extended``): what :func:`_restart` sets, and
#: what it keeps (the function and its wrappers, the tolerances and the step bound, the
#: counters, the stage arrays that every step writes before it reads them).
_RESET = frozenset(
    ("t_old", "t", "y", "t_bound", "direction", "status", "y_old", "f", "h_abs", "h_previous")
)
_KEPT = frozenset(
    {"_fun", "fun", "fun_single", "fun_vectorized", "vectorized", "n", "nfev", "njev", "nlu"}
    | {"max_step", "rtol", "atol", "error_exponent", "K", "K_extended"}
)


def _restart(solver: Any, t: float, y: np.ndarray, t_bound: float, first_step: float) -> bool:
    """Restart SciPy's explicit Runge-Kutta ``solver`` in place at ``(t, y)`` towards
    ``t_bound`` with the first step ``first_step``: the state its constructor gives for
    the same function, tolerances and step bound (``t_old = y_old = h_previous = None``,
    ``direction``, ``status = "running"``, ``h_abs = first_step``, ``f = fun(t, y)``),
    without the checks it made at construction.  False, with nothing changed, for a
    solver holding state this does not know (another SciPy), or a first step that the
    constructor refuses (it then says why)."""
    state = vars(solver).keys()
    if not (_RESET <= state and state <= _RESET | _KEPT):
        return False
    if not 0 < first_step <= abs(t_bound - t):
        return False
    solver.t_old, solver.t, solver.y, solver.t_bound = None, t, y, t_bound
    solver.direction = np.sign(t_bound - t) if t_bound != t else 1
    solver.status = "running"
    solver.y_old = solver.h_previous = None
    solver.h_abs = first_step
    solver.f = solver.fun(t, y)
    return True


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
