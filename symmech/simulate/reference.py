"""The high-precision reference: the same hybrid loop in mpmath arithmetic.

:func:`reference_run` runs :mod:`symmech.simulate.hybrid`'s loop unchanged, with

* :class:`MpFunctions`: the scene's closed forms (acceleration, gaps and their gradients,
  impact maps, energy, projectors, contact modes; Carnot paper eqs. 5, 10, 17, 20 and
  section 2.2) evaluated by ``sympy.lambdify`` in mpmath at ``mpmath.mp.dps`` digits, the
  parameters taken as the exact binary values of their float64 inputs;
* :class:`MpFlow`: Gauss-Legendre collocation (:class:`~.precise.GaussLegendre`, order 2s)
  with the standard step-size rule, the walls' gaps in the state, and each step's
  ``refine`` so the loop polishes every event time on a full-order recomputation of the
  state, not only on the collocation polynomial.

so every decision (impact, sequential rule, accumulation, contact, release) is the float
loop's, taken at 30+ digits.  The result holds mpmath numbers (object arrays); compare with
:func:`as_float`.  It is the reference of ``benchmarks/work_precision.py`` and of the
simulator's tests where no closed form exists.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import mpmath
import numpy as np
import sympy as sp

from symmech.declaration.symbols import t as TIME
from symmech.scene import Scene
from symmech.simulate.flow import AugmentedFlow, FlowFailure, FlowStats, Segment
from symmech.simulate.hybrid import Options, run
from symmech.simulate.parameters import check_parameters
from symmech.simulate.precise import GaussLegendre
from symmech.simulate.result import SimulationResult
from symmech.simulate.system import (
    FREE,
    Mode,
    SimulationError,
    contact_rows,
    contact_scene,
    simultaneous_walls,
)

__all__ = ["MpFlow", "MpFunctions", "as_float", "reference_run"]


def _mp_array(values: Any) -> np.ndarray:
    return np.array([mpmath.mpf(v) for v in values], dtype=object)


class MpFunctions:
    """The :class:`~.functions.Functions` interface over lambdified closed forms in mpmath."""

    def __init__(self, scene: Scene, params: Mapping[str, float]):
        self.scene = scene
        decl = scene.declaration
        self.n = scene.n
        self.walls = len(scene.walls)
        self.wall_names = tuple(w.name for w in scene.walls)
        self.constrained = scene.is_constrained
        self.moving = tuple(TIME in w.psi.free_symbols for w in scene.walls)
        self.energy_conserved = scene.conservative
        self.simultaneous = simultaneous_walls(scene)
        self.mode: Mode = FREE
        self.eps = mpmath.eps
        self._values = {
            p: sp.Float(mpmath.mpf(params[str(p)]), mpmath.mp.dps + 5) for p in scene.parameters
        }
        self._q = list(decl.coordinates)
        self._v = list(decl.velocities)
        self._cache: dict[Any, Callable[..., Any]] = {}
        self._contact: dict[Mode, Scene | None] = {}

    @staticmethod
    def array(y: Any) -> np.ndarray:
        return _mp_array(y)

    # -- lambdified closed forms ----------------------------------------------------------
    def _fn(self, key: Any, build: Callable[[], sp.MatrixBase | sp.Expr]) -> Callable[..., Any]:
        if key not in self._cache:
            expr = build()
            expr = expr.xreplace(self._values) if self._values else expr
            self._cache[key] = sp.lambdify(
                [TIME, self._q, self._v], expr, modules="mpmath", cse=True
            )
        return self._cache[key]

    def _eval(self, key: Any, build: Callable[[], Any], t: Any, q: Any, v: Any = None) -> Any:
        f = self._fn(key, build)
        out = f(t, list(q), list(v) if v is not None else [0] * self.n)
        if isinstance(out, (sp.MatrixBase, mpmath.matrix, list, tuple, np.ndarray)):
            return _mp_array(np.asarray(out, dtype=object).ravel())
        return mpmath.mpf(out)

    def contact_scene(self, mode: Mode) -> Scene | None:
        if mode not in self._contact:
            self._contact[mode] = contact_scene(self.scene, mode)
        return self._contact[mode]

    def locked(self, mode: Mode) -> bool:
        return bool(mode) and self.contact_scene(mode) is None

    def _mode_scene(self, mode: Mode) -> Scene:
        scene = self.contact_scene(mode) if mode else self.scene
        assert scene is not None
        return scene

    # -- the interface ----------------------------------------------------------------------
    def rhs(self, mode: Mode, t: Any, y: np.ndarray) -> np.ndarray:
        if self.locked(mode):
            return _mp_array([0] * len(y))
        scene = self._mode_scene(mode)
        n = self.n
        qdot = self._eval(("qdot",), lambda: sp.Matrix(self.scene.kinematics()), t, y[:n], y[n:])
        acc = self._eval(("acc", mode), lambda: sp.Matrix(scene.acceleration()), t, y[:n], y[n:])
        return np.concatenate([qdot, acc])

    def flow_rhs(self, t: Any, y: np.ndarray) -> np.ndarray:
        return self.rhs(self.mode, t, y)

    def psi(self, wall: int, t: Any, q: np.ndarray) -> Any:
        return self._eval(("psi", wall), lambda: self.scene.walls[wall].psi, t, q)

    def gradient(self, wall: int, t: Any, q: np.ndarray) -> np.ndarray:
        psi = self.scene.walls[wall].psi
        return self._eval(("dpsi", wall), lambda: sp.Matrix([psi.diff(x) for x in self._q]), t, q)

    def rate(self, wall: int, t: Any, y: np.ndarray, ydot: np.ndarray) -> Any:
        n = self.n
        r = mpmath.fdot(list(self.gradient(wall, t, y[:n])), list(ydot[:n]))
        if self.moving[wall]:
            psi = self.scene.walls[wall].psi
            r += self._eval(("psi_t", wall), lambda: psi.diff(TIME), t, y[:n])
        return r

    def normal_rate(self, wall: int, t: Any, y: np.ndarray) -> Any:
        return self.rate(wall, t, y, self.rhs(FREE, t, y))

    def rate_change(self, wall: int, t: Any, q: np.ndarray, dv: np.ndarray) -> Any:
        """As :meth:`.functions.Functions.rate_change`, in mpmath."""
        qdot = self._eval(("qdot",), lambda: sp.Matrix(self.scene.kinematics()), t, q, dv)
        return mpmath.fdot(list(self.gradient(wall, t, q)), list(qdot))

    def flow_rates(self, t: Any, y: np.ndarray, ydot: np.ndarray) -> np.ndarray:
        return _mp_array([self.rate(w, t, y, ydot) for w in range(self.walls)])

    def gaps(self, t: Any, y: np.ndarray) -> np.ndarray:
        return _mp_array([self.psi(w, t, y[: self.n]) for w in range(self.walls)])

    def gap_function(self, wall: int) -> Callable[[Any, np.ndarray], Any]:
        """``(t, q) -> psi`` of ``wall`` (as :meth:`Functions.gap_function
        <symmech.simulate.functions.Functions.gap_function>`)."""
        return lambda t, q: self.psi(wall, t, q)

    def impact(self, wall: int, t: Any, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return self._eval(
            ("impact", wall), lambda: sp.Matrix(self.scene.impact_map(wall).post_velocity), t, q, v
        )

    def energy(self, t: Any, q: np.ndarray, v: np.ndarray) -> Any:
        return self._eval(("energy",), self.scene.energy, t, q, v)

    def project(self, mode: Mode, t: Any, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        if not mode and not self.constrained:
            return v
        if self.locked(mode):
            return _mp_array([0] * len(v))
        scene = self._mode_scene(mode)
        P = self._eval(("P", mode), lambda: sp.Matrix(scene.projectors()[0]), t, q)
        n = self.n
        return _mp_array([mpmath.fdot(list(P[i * n : (i + 1) * n]), list(v)) for i in range(n)])

    def residual(self, mode: Mode, t: Any, q: np.ndarray, v: np.ndarray) -> Any:
        if not mode and not self.constrained:
            return mpmath.mpf(0)
        if self.locked(mode):
            return max(abs(x) for x in v)
        scene = self._mode_scene(mode)
        r = self._eval(
            ("res", mode), lambda: sp.Matrix(scene.constraint_matrix) * sp.Matrix(self._v), t, q, v
        )
        return max(abs(x) for x in r)

    def impact_condition(self, wall: int, t: Any, q: np.ndarray) -> float:
        """Not limited at 30+ digits: always 1
        (see :meth:`.functions.Functions.impact_condition`)."""
        return 1.0

    def normal_force(
        self, wall: int, t: Any, q: np.ndarray, v: np.ndarray, mode: Mode | None = None
    ) -> Any:
        mode = (wall,) if mode is None else mode
        m = self.scene.constraint_matrix.rows
        k = mode.index(wall)
        if self.locked(mode):

            def statics() -> sp.Expr:
                A = sp.Matrix(contact_rows(self.scene, mode))
                f0 = sp.Matrix(self.scene.forcing()).xreplace({x: 0 for x in self._v})
                return A.T.LUsolve(-f0)[m + k]

            return self._eval(("locked", mode, wall), statics, t, q)
        scene = self._mode_scene(mode)
        lam = self._eval(("lam", mode), lambda: sp.Matrix(scene.multipliers()), t, q, v)
        return lam[m + k]


class _MpSegment(Segment):
    """A segment whose state can be recomputed to full order at any time."""

    refine: Callable[[Any], np.ndarray]


class MpFlow:
    """Adaptive Gauss-Legendre collocation in mpmath (the rule of :class:`~.flow.RKFlow`)."""

    def __init__(self, f: Callable, rtol: Any, atol: Any, max_step: Any, stages: int = 8):
        self.stepper = GaussLegendre(stages)
        self.f = f
        self.rtol, self.atol, self.max_step = mpmath.mpf(rtol), mpmath.mpf(atol), max_step
        self.stats = FlowStats()
        self.h: Any = None
        self.t: Any = None

    def _rhs(self, t: Any, y: np.ndarray) -> np.ndarray:
        self.stats.nfev += 1
        return self.f(t, y)

    def start(self, t: Any, y: np.ndarray, t_bound: Any) -> None:
        self.t, self.y, self.t_bound = mpmath.mpf(t), _mp_array(y), mpmath.mpf(t_bound)
        self.fy = self._rhs(self.t, self.y)
        if self.h is None:
            scale = max((abs(v) for v in self.y), default=0) + 1
            speed = max((abs(v) for v in self.fy), default=0)
            h = self.rtol ** (mpmath.mpf(1) / (self.stepper.order + 1)) * scale / max(speed, 1)
            self.h = min(h, (self.t_bound - self.t) / 4)
        self.h = min(self.h, self.max_step)

    def advance(self) -> Segment:
        t, y = self.t, self.y
        left = self.t_bound - t
        if left <= 0:
            raise FlowFailure("advance past t_bound")
        k = self.stepper.error_order
        while True:
            h = min(self.h, self.max_step, left)
            if h < left and h <= 64 * mpmath.eps * max(abs(t), 1):  # as flow.RKFlow
                raise FlowFailure(f"step size {mpmath.nstr(h, 5)} too small at t = {t}")
            st = self.stepper.step(self._rhs, t, y, self.fy, h, self.rtol, self.atol)
            err = st.error
            if mpmath.isfinite(err) and err <= 1:
                factor = 10 if err == 0 else min(10, max(0.2, 0.9 * err ** (-1.0 / (k + 1))))
                self.h = h * mpmath.mpf(factor)
                break
            self.stats.rejected += 1
            self.h = h * mpmath.mpf(
                0.25 if not mpmath.isfinite(err) else max(0.2, 0.9 * err ** (-1.0 / (k + 1)))
            )
        self.stats.steps += 1
        t1 = self.t_bound if h == left else t + h
        dense_step = st.dense

        def dense(tt: Any, _d: Any = dense_step, _t0: Any = t, _h: Any = h) -> np.ndarray:
            return _d((tt - _t0) / _h)

        def refine(tt: Any, _d: Any = dense_step, _t0: Any = t, _h: Any = h) -> np.ndarray:
            return _d.refine((tt - _t0) / _h)

        seg = _MpSegment(t, t1, y, st.y, st.f, dense)
        seg.refine = refine
        self.t, self.y, self.fy = t1, st.y, st.f
        return seg

    def limit_step(self, h: Any) -> None:
        """As :meth:`~.flow.RKFlow.limit_step`."""
        if self.h is not None and 0 < h < self.h:
            self.h = h

    def accept_projection(self, y: np.ndarray) -> None:
        self.y = _mp_array(y)
        self.fy = self._rhs(self.t, self.y)


class _MpAugmented(AugmentedFlow):
    """:class:`~.flow.AugmentedFlow` that keeps the inner segment's ``refine``."""

    def advance(self) -> Segment:
        inner_seg = self.inner.advance()
        k = self.size

        def dense(tt: Any, _d: Any = inner_seg.dense) -> np.ndarray:
            return _d(tt)[:k]

        def refine(tt: Any, _r: Any = inner_seg.refine) -> np.ndarray:
            return _r(tt)[:k]

        seg = _MpSegment(
            inner_seg.t0, inner_seg.t1, inner_seg.y0[:k], inner_seg.y1[:k], None, dense
        )
        seg.refine = refine
        return seg


def reference_run(
    scene: Scene,
    q0: Any,
    v0: Any,
    t_end: float,
    *,
    params: Mapping[str, float],
    dps: int = 32,
    rtol: float | None = None,
    contact: str = "persistent",
    max_events: int = 100_000,
    stages: int = 8,
) -> SimulationResult:
    """The hybrid run of ``scene`` in mpmath at ``dps`` digits (see the module docstring);
    ``rtol`` defaults to ``10^-(dps - 8)``, ``atol`` is ``rtol / 100``."""
    if not isinstance(scene, Scene):
        raise SimulationError(f"scene: expected a symmech.Scene, got {type(scene).__name__}")
    values = check_parameters(scene, params)
    with mpmath.workdps(dps):
        tol = mpmath.mpf(10) ** (-(dps - 8)) if rtol is None else mpmath.mpf(rtol)
        fns = MpFunctions(scene, values)
        n = scene.n
        y0 = _mp_array(list(np.asarray(q0, dtype=float)) + list(np.asarray(v0, dtype=float)))
        if len(y0) != 2 * n:
            raise SimulationError(f"q0, v0: expected {n} values each")
        if fns.constrained:
            y0[n:] = fns.project(FREE, 0, y0[:n], y0[n:])
        opts = Options(
            t_end=mpmath.mpf(t_end),
            rtol=tol,
            atol=tol / 100,
            max_events=max_events,
            contact=contact,
        )
        t_span = mpmath.mpf(t_end)

        def make(f: Any, jac: Any = None) -> MpFlow:
            return MpFlow(f, tol, tol / 100, t_span, stages=stages)

        flow: Any = (
            _MpAugmented(make, fns.flow_rhs, fns.flow_rates, fns.gaps, 2 * n)
            if fns.walls
            else make(fns.flow_rhs)
        )
        return run(fns, flow, mpmath.mpf(0), y0, opts)


def as_float(x: Any) -> Any:
    """mpmath numbers (scalars or arrays) as float64."""
    if isinstance(x, np.ndarray):
        return np.array([float(v) for v in x.ravel()], dtype=float).reshape(x.shape)
    return float(x)
