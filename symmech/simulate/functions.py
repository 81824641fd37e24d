"""The evaluations the hybrid loop makes, over a compiled :class:`~.system.HybridSystem` at
fixed parameters, in float64 (:class:`symmech.simulate.reference.MpFunctions` is the same
interface in mpmath)."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from symmech.codegen.bound import BoundModule
from symmech.codegen.module import NumericalError, SceneModule
from symmech.declaration.symbols import t as TIME
from symmech.simulate.system import (
    FREE,
    HybridSystem,
    Mode,
    SimulationError,
    simultaneous_walls,
)

__all__ = ["Functions"]

#: How many normal rates :meth:`Functions.normal_rate` keeps (then it starts afresh).
_RATES_KEPT = 64


class Functions:
    """The evaluations the hybrid loop makes, over a :class:`HybridSystem` at fixed
    parameters, in float64.  ``mode`` is a :data:`Mode`: ``()`` (free flight) or the sorted
    indices of the walls held.  Every method takes and returns NumPy arrays of float64
    (scalars as floats).
    (:class:`symmech.simulate.reference.MpFunctions` is the same interface in mpmath.)"""

    #: The arithmetic's unit roundoff, and its array constructor.
    eps = float(np.finfo(float).eps)

    @staticmethod
    def array(y: Any) -> np.ndarray:
        return np.array(y, dtype=float)

    def __init__(self, system: HybridSystem, params: Mapping[str, float]):
        self.system = system
        self.n = system.n
        self.walls = len(system.scene.walls)
        self.constrained = system.scene.is_constrained
        self.moving = system.moving
        self.wall_names = tuple(w.name for w in system.scene.walls)
        #: The flow conserves T + V: the potential does not depend on t (ideal constraints
        #: and contact constraints do no work).
        self.energy_conserved = system.energy_conserved
        self._params = dict(params)
        for w in system.scene.walls:
            if (
                w.velocity is not None
                and TIME not in w.psi.free_symbols
                and w.impulsive_matrix.rows
                and any(e != 0 for e in w.velocity)
            ):
                raise SimulationError(
                    f"wall {w.name!r} is static but has a declared velocity (a conveyor) and"
                    " impulsive constraints: its contact mode would hold nu (v - W) = 0, which"
                    " the simulator does not support; its impact map and generated code do"
                )
        free = system.free
        if free.inputs:
            raise SimulationError(
                f"scene {system.scene.name!r} has arbitrary functions of time {list(free.inputs)}:"
                " give their expressions with definitions={f: expression} (command line:"
                " --define f=EXPR)"
            )
        #: Per wall: its impact has a Newton direction (law "newton", no impulsive
        #: constraints), so it can be resolved with others at once (:mod:`.impulses`).
        self.simultaneous = simultaneous_walls(system.scene)
        #: The mode the flow integrates (``()``: free flight; the walls held).
        self.mode: Mode = FREE
        self._p: dict[Mode, np.ndarray | None] = {}
        #: (mode, function name) -> the function at the bound parameters, and whether it
        #: reads t (the loop calls a few functions thousands of times: bound once, the
        #: parameters are not converted and checked at every call)
        self._bound: dict[tuple[Mode, str], tuple[Callable[..., np.ndarray], bool]] = {}
        self._bound_modules: dict[Mode, BoundModule] = {}
        self._walls: dict[tuple[str, int], str] = {}
        #: mode -> :meth:`augmented` in that mode (:meth:`augmented_in`)
        self._fixed: dict[Mode, Callable[[float, np.ndarray], np.ndarray]] = {}
        self._gaps: dict[int, Callable[[float, Any], float]] = {}
        #: (wall, t, the state's bytes) -> normal rate (:meth:`normal_rate`)
        self._rates: dict[tuple[int, float, bytes], float] = {}

    # -- plumbing -------------------------------------------------------------------------
    def _module(self, mode: Mode) -> SceneModule | None:
        return self.system.contact(mode) if mode else self.system.free

    def _pvec(self, mode: Mode) -> np.ndarray | None:
        if mode not in self._p:
            mod = self._module(mode)
            assert mod is not None
            names = mod.parameters
            self._p[mode] = (
                np.array([self._params[k] for k in names], dtype=np.float64) if names else None
            )
        return self._p[mode]

    def locked(self, mode: Mode) -> bool:
        """Whether ``mode`` is a contact that leaves no motion (the body rests)."""
        return bool(mode) and self.system.contact(mode) is None

    def _call(self, mode: Mode, name: str, t: float, *state: np.ndarray) -> np.ndarray:
        key = (mode, name)
        entry = self._bound.get(key)
        if entry is None:
            mod = self._module(mode)
            assert mod is not None
            bound = self._bound_module(mode)
            spec = {f.name: f for f in mod.code.functions}.get(name)
            if spec is None:  # not generated: the module's call explains
                return mod.call(name, *state, params=self._pvec(mode))
            fn = getattr(bound, name)
            plain = None if spec.takes_time else bound.plain(name)
            if plain is not None:
                sizes = {"y": 2 * self.n, "q": self.n, "v": self.n}
                fn = _point(plain, fn, [sizes[a] for a in spec.state], spec.out_shape)
            entry = self._bound[key] = (fn, spec.takes_time)
        fn, takes_t = entry
        return fn(*state, t=t) if takes_t else fn(*state)

    def _bound_module(self, mode: Mode) -> BoundModule:
        bound = self._bound_modules.get(mode)
        if bound is None:
            mod = self._module(mode)
            assert mod is not None
            bound = self._bound_modules[mode] = mod.bind(self._pvec(mode))
        return bound

    def _direct(self, mode: Mode, name: str) -> tuple[Any, bool] | None:
        """The direct one-state caller of ``name`` in ``mode``: ``(plain, True)`` over lists
        of floats (the NumPy module's, :meth:`BoundModule.plain
        <symmech.codegen.bound.BoundModule.plain>`), ``(bound, False)`` over arrays (the
        compiled one); None for a function of t (the general path passes it)."""
        mod = self._module(mode)
        spec = None if mod is None else {f.name: f for f in mod.code.functions}.get(name)
        if spec is None or spec.takes_time or spec.takes_inputs:
            return None
        bound = self._bound_module(mode)
        plain = bound.plain(name)
        return (plain, True) if plain is not None else (getattr(bound, name), False)

    def _wall_name(self, kind: str, wall: int) -> str:
        key = (kind, wall)
        name = self._walls.get(key)
        if name is None:
            name = self._walls[key] = self.system.free._wall_function(kind, wall)
        return name

    # -- the evaluations --------------------------------------------------------------------
    def rhs(self, mode: Mode, t: float, y: np.ndarray) -> np.ndarray:
        """y_dot = (q_dot, v_dot) in free flight (mode ``()``) or in contact."""
        if self.locked(mode):
            return np.zeros_like(y)
        try:
            return self._call(mode, "rhs", t, y)
        except NumericalError:
            # a trial stage far outside the solution: NaN makes the integrator reject it
            return np.full_like(y, np.nan)

    def flow_rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        """y_dot in the current :attr:`mode` (the flow's right-hand side)."""
        return self.rhs(self.mode, t, y)

    def flow_rates(self, t: float, y: np.ndarray, ydot: np.ndarray) -> np.ndarray:
        """d psi_w/dt of every wall along the flow (for :class:`~.flow.AugmentedFlow`); NaN
        where a generated call fails at a trial stage (the integrator then rejects it)."""
        try:
            return np.array([self.rate(w, t, y, ydot) for w in range(self.walls)])
        except NumericalError:
            return np.full(self.walls, np.nan)

    def gaps(self, t: float, y: np.ndarray) -> np.ndarray:
        """psi_w(t, q) of every wall."""
        return np.array([self.psi(w, t, y[: self.n]) for w in range(self.walls)])

    def augmented(self, t: float, ya: np.ndarray) -> np.ndarray:
        """``(y_dot, d psi_w/dt of every wall)`` in the current :attr:`mode` at ``ya = (y,
        gaps)`` (the right-hand side of :class:`~.flow.AugmentedFlow`): :meth:`flow_rhs`
        and :meth:`flow_rates` concatenated, through the direct caller of the generated
        ``augmented_rhs`` in free flight, else of the rhs and the gradients, where they
        exist (one conversion of the state; a failure or a non-finite value goes the
        general way, which gives NaN)."""
        return self.augmented_in(self.mode)(t, ya)

    def augmented_in(self, mode: Mode) -> Callable[[float, np.ndarray], np.ndarray]:
        """:meth:`augmented` in ``mode``, whatever the current mode becomes: the flow's
        right-hand side from a (re)start on, which a step's continuous output formed
        later (on first read) evaluates too."""
        fixed = self._fixed.get(mode)
        if fixed is None:
            fixed = self._fixed[mode] = self._augmented_in(mode)
        return fixed

    def _augmented_in(self, mode: Mode) -> Callable[[float, np.ndarray], np.ndarray]:
        size = 2 * self.n

        def general(t: float, ya: np.ndarray) -> np.ndarray:
            y = ya[:size]
            ydot = self.rhs(mode, t, y)
            return np.concatenate([ydot, self.flow_rates(t, y, ydot)])

        if self.locked(mode):
            return general
        generated = self._direct(mode, "augmented_rhs") if mode == FREE else None
        if generated is not None:  # the hot path of free flight: one layer, no more
            return _generated_kernel(*generated, size, general)
        kernel = self._augmented_kernel(mode)
        if kernel is None:
            return general

        def fused(t: float, ya: np.ndarray) -> np.ndarray:
            out = kernel(t, ya)
            return general(t, ya) if out is None else out

        return fused

    def _augmented_kernel(self, mode: Mode) -> Any:
        """The fused :meth:`augmented` of ``mode`` from the rhs and the gradients (None:
        the general path only): for static walls, whose rate is ``dpsi q_dot``, when the
        rhs and every gradient have direct callers of the same kind."""
        if any(self.moving):
            return None
        rhs = self._direct(mode, "rhs")
        grads = [self._direct(FREE, self._wall_name("dpsi", w)) for w in range(self.walls)]
        if rhs is None or any(g is None or g[1] != rhs[1] for g in grads):
            return None
        n, size = self.n, 2 * self.n
        f, gs = rhs[0], [g[0] for g in grads]  # type: ignore[index]
        if rhs[1]:  # plain lists of floats

            def plain(t: float, ya: np.ndarray) -> np.ndarray | None:
                y = ya.tolist()[:size]
                out = f(y)
                if out is None:
                    return None
                q = y[:n]
                for g in gs:
                    d = g(q)
                    if d is None:
                        return None
                    r = 0.0
                    for di, qi in zip(d, out, strict=False):
                        r += di * qi
                    out.append(r)
                return np.array(out)

            return plain

        def arrays(t: float, ya: np.ndarray) -> np.ndarray | None:
            y = ya[:size]
            try:
                ydot = f(y)
                out = np.empty(size + len(gs))
                out[:size] = ydot
                q, qdot = y[:n], ydot[:n]
                for k, g in enumerate(gs):
                    out[size + k] = g(q).dot(qdot)
            except NumericalError:
                return None
            return out

        return arrays

    def gap_function(self, wall: int) -> Callable[[float, Any], float]:
        """``(t, q) -> psi`` of ``wall`` (``q`` an array or a list of floats): :meth:`psi`
        through its direct caller where there is one (the event search samples it many
        times a step)."""
        fn = self._gaps.get(wall)
        if fn is None:
            fn = self._gaps[wall] = self._gap_function(wall)
        return fn

    def _gap_function(self, wall: int) -> Callable[[float, Any], float]:
        direct = self._direct(FREE, self._wall_name("psi", wall))
        psi = self.psi
        if direct is None:
            return lambda t, q: psi(wall, t, np.asarray(q, dtype=float))
        fn, plain = direct
        if plain:

            def over_lists(t: float, q: np.ndarray | list[float]) -> float:
                out = fn(q if isinstance(q, list) else q.tolist())
                return out[0] if out is not None else psi(wall, t, np.asarray(q, dtype=float))

            return over_lists

        def over_arrays(t: float, q: np.ndarray) -> float:
            try:
                return float(fn(q))
            except NumericalError:
                return psi(wall, t, q)  # raises as the general path does

        return over_arrays

    def jac(self, mode: Mode, t: float, y: np.ndarray) -> np.ndarray:
        """d(y_dot)/dy in the mode (the generated Jacobian; zero in a locked contact)."""
        if self.locked(mode):
            return np.zeros((len(y), len(y)))
        return self._call(mode, "jacobian", t, y)

    def flow_jac(self, t: float, y: np.ndarray) -> np.ndarray:
        """d(y_dot)/dy in the current :attr:`mode`."""
        return self.jac(self.mode, t, y)

    def psi(self, wall: int, t: float, q: np.ndarray) -> float:
        """The gap of ``wall`` at (t, q)."""
        return float(self._call(FREE, self._wall_name("psi", wall), t, q))

    def rate(self, wall: int, t: float, y: np.ndarray, ydot: np.ndarray) -> float:
        """d psi/dt = dpsi(q) q_dot + psi_t along the flow (q_dot from ``ydot``)."""
        n = self.n
        q = y[:n]
        g = self._call(FREE, self._wall_name("dpsi", wall), t, q)
        r = float(g.dot(ydot[:n]))
        if self.moving[wall]:
            r += float(self._call(FREE, self._wall_name("psi_t", wall), t, q))
        return r

    def normal_rate(self, wall: int, t: float, y: np.ndarray) -> float:
        """d psi/dt at a state (q_dot from the kinematics of the free flow).  The loop asks
        for it at one state several times (an impact's checks before and after it, the
        next step's search): the values at the last few states are kept."""
        if type(y) is not np.ndarray or y.dtype.char != "d":
            return self.rate(wall, t, y, self.rhs(FREE, t, y))
        key = (wall, t, y.tobytes())
        rate = self._rates.get(key)
        if rate is None:
            if len(self._rates) >= _RATES_KEPT:
                self._rates.clear()
            rate = self._rates[key] = self.rate(wall, t, y, self.rhs(FREE, t, y))
        return rate

    def rate_change(self, wall: int, t: float, q: np.ndarray, dv: np.ndarray) -> float:
        """``dpsi S dv``: the change of the wall's normal rate for a velocity change
        ``dv`` (``S dv`` the q-part of the free flow at velocity ``dv``: the kinematics)."""
        if self.system.scene.frame is None:
            qdot = dv
        else:
            qdot = self.rhs(FREE, t, np.concatenate([q, dv]))[: self.n]
        return float(np.dot(self.gradient(wall, t, q), qdot))

    def gradient(self, wall: int, t: float, q: np.ndarray) -> np.ndarray:
        """d psi/d q of ``wall`` (coordinates)."""
        return self._call(FREE, self._wall_name("dpsi", wall), t, q)

    def impact(self, wall: int, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """v+ of the scene's closed-form (or KKT) impact map at ``wall``."""
        return self._call(FREE, self._wall_name("impact", wall), t, q, v)

    def energy(self, t: float, q: np.ndarray, v: np.ndarray) -> float:
        """T + V."""
        return float(self._call(FREE, "energy", t, q, v))

    def project(self, mode: Mode, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """P(q) v: v projected g-orthogonally onto the mode's distribution."""
        if not mode and not self.constrained:
            return v
        if self.locked(mode):
            return np.zeros_like(v)
        P = self._call(mode, "projector_P", t, q)
        return P @ v

    def residual(self, mode: Mode, t: float, q: np.ndarray, v: np.ndarray) -> float:
        """max |mu v| of the mode's constraints (0 for an unconstrained free flight)."""
        if not mode and not self.constrained:
            return 0.0
        if self.locked(mode):
            return float(np.max(np.abs(v), initial=0.0))
        return float(np.max(np.abs(self._call(mode, "constraint_residual", t, q, v))))

    def impact_condition(self, wall: int, t: float, q: np.ndarray) -> float:
        """The 2-norm condition number of the impact's Gram matrix ``C = A g^-1 A^T`` with
        ``A = [mu; dpsi S]`` (Carnot paper section 3: the wall's one-form with the permanent
        constraints), 1 for an unconstrained scene.  It bounds the relative error of the
        impulse: a wall nearly in the constraint span makes C nearly singular."""
        if not self.constrained:
            return 1.0
        n = self.n
        eye = np.eye(n)
        g = self._call(FREE, "mass_matrix", t, q)
        mu = np.column_stack([self._call(FREE, "constraint_residual", t, q, e) for e in eye])
        row = self.gradient(wall, t, q)
        if self.system.scene.frame is not None:
            S = np.column_stack([self.rhs(FREE, t, np.concatenate([q, e]))[:n] for e in eye])
            row = row @ S
        A = np.vstack([mu, row])
        C = A @ np.linalg.solve(g, A.T)
        return float(np.linalg.cond(C))

    def normal_force(
        self, wall: int, t: float, q: np.ndarray, v: np.ndarray, mode: Mode | None = None
    ) -> float:
        """lambda_N of ``wall`` in the contact mode ``mode`` (default: the wall alone) at
        (q, v): positive while the wall pushes."""
        mode = (wall,) if mode is None else mode
        if self.locked(mode):
            p = [self._params[str(s)] for s in self.system.scene.parameters]
            return float(self.system.locked_force(mode)(t, q, p)[mode.index(wall)])
        lam = self._call(mode, "multipliers", t, q, v)
        return float(lam[self.system.normal_index(mode, wall)])


def _generated_kernel(
    fn: Callable, over_lists: bool, size: int, general: Callable[[float, np.ndarray], np.ndarray]
) -> Callable[[float, np.ndarray], np.ndarray]:
    """:meth:`Functions.augmented` through a direct caller of ``augmented_rhs`` (over
    lists of floats, or over arrays); ``general`` where the call fails (it explains, or
    returns NaN for a trial stage far outside the solution)."""
    if over_lists:

        def plain(t: float, ya: np.ndarray) -> np.ndarray:
            out = fn(ya.tolist()[:size])
            return general(t, ya) if out is None else np.array(out)

        return plain

    def arrays(t: float, ya: np.ndarray) -> np.ndarray:
        try:
            return fn(ya[:size])
        except NumericalError:
            return general(t, ya)

    return arrays


def _point(
    plain: Callable[..., list | None],
    general: Callable[..., np.ndarray],
    sizes: list[int],
    shape: tuple[int, ...],
) -> Callable[..., Any]:
    """A generated function of the state at one point: its one-state variant over the
    states as lists of floats (``plain``, :meth:`BoundModule.plain
    <symmech.codegen.bound.BoundModule.plain>`), the same operations and values as the
    bound attribute ``general`` without its layers of argument checks (a scalar output as
    a float); ``general`` for anything but float64 vectors of the state's ``sizes``, or
    where the variant fails (it explains)."""
    shapes = [(k,) for k in sizes]

    def output(out: list) -> Any:
        if not shape:
            return out[0]
        return np.array(out) if len(shape) == 1 else np.array(out).reshape(shape)

    if len(shapes) == 1:  # the common case, unrolled: one state array
        (only,) = shapes

        def call1(a: np.ndarray) -> Any:
            if type(a) is np.ndarray and a.shape == only and a.dtype.char == "d":
                out = plain(a.tolist())
                if out is not None:
                    return output(out)
            return general(a)

        return call1

    if len(shapes) == 2:  # (q, v): unrolled as well
        first, second = shapes

        def call2(a: np.ndarray, b: np.ndarray) -> Any:
            if (
                type(a) is np.ndarray
                and type(b) is np.ndarray
                and a.shape == first
                and b.shape == second
                and a.dtype.char == "d"
                and b.dtype.char == "d"
            ):
                out = plain(a.tolist(), b.tolist())
                if out is not None:
                    return output(out)
            return general(a, b)

        return call2

    def call(*state: np.ndarray) -> Any:
        if len(state) == len(shapes):
            lists = []
            for a, k in zip(state, shapes, strict=True):
                if type(a) is not np.ndarray or a.shape != k or a.dtype.char != "d":
                    return general(*state)
                lists.append(a.tolist())
            out = plain(*lists)
            if out is not None:
                return output(out)
        return general(*state)

    return call
