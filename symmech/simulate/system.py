"""The compiled functions of a hybrid system: free flight, walls, impacts and contact modes.

A :class:`HybridSystem` is built once per scene, backend and parameter set and holds what
the hybrid loop (:mod:`symmech.simulate.hybrid`) evaluates at a state:

* the flow ``y_dot = rhs(t, y)`` with ``y = (q, v)`` (Carnot paper eq. 5: the constrained
  acceleration when the scene has constraints), and for constrained scenes the projector
  ``P(q)`` onto the distribution D (Carnot paper section 2.2) that removes the drift of
  ``mu v`` after each step;
* per wall: the gap ``psi(t, q)``, its rate ``d psi/dt = dpsi(q) q_dot + psi_t`` and the
  closed-form impact map ``v+ = Phi(q, v-)`` of the scene (Carnot paper eqs. 10, 17, 20;
  text 001 Theorem 2.12);
* per static wall, the **contact mode**: the same system with the wall held as a permanent
  holonomic constraint.  Its one-form is ``dpsi S`` in the velocity basis (S the frame, or
  the identity) and, for a rough wall, the wall's impulsive constraints ``nu`` are kept
  during contact (the body rolls on the wall).  The contact scene is an ordinary
  :class:`~symmech.Scene` with the constraints ``[mu; dpsi S; nu]``, so its acceleration,
  its multipliers and its projector come from the same derivation as every other scene
  (Carnot paper eq. 5 and section 2.2).  The normal multiplier ``lambda_N`` (the entry of
  ``dpsi S``) is the normal contact force: ``g v_dot = f + mu^T lambda + lambda_N (dpsi S)^T``
  pushes into the admissible side while ``lambda_N > 0``; the contact is released when it
  would turn negative.

A moving wall (psi depends on t) has no contact mode: the contact constraint would be
affine in v (``dpsi v + psi_t = 0``), which scenes do not declare; an accumulation of
impacts on a moving wall ends the run with status ``"zeno"``.

Parameters are checked once here (every parameter given, finite, and the signs and ranges
the declaration states: positive symbols, restitution in [0, 1]), so that the loop's
evaluations never fail on a bad parameter half way through a run.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import sympy as sp

from symmech.codegen import CodegenError, generate
from symmech.codegen.module import NumericalError, SceneModule
from symmech.codegen.plan import defined, definition_rules
from symmech.codegen.runtime_checks import real_array
from symmech.declaration.symbols import t as TIME
from symmech.errors import SymmechError
from symmech.scene import Scene
from symmech.simulate.impulses import MAX_SIMULTANEOUS

__all__ = [
    "FREE",
    "HybridSystem",
    "Mode",
    "SimulationError",
    "contact_scene",
    "real_number",
    "real_scalar",
    "real_values",
]


class SimulationError(SymmechError, ValueError):
    """A simulation cannot start: bad state, parameters, options or scene."""


#: A contact mode: the walls held, as sorted indices; ``()`` is free flight.
Mode = tuple[int, ...]
FREE: Mode = ()


def contact_rows(scene: Scene, walls: Mode) -> list[list[sp.Expr]]:
    """The constraint rows ``[mu; dpsi_1 S; ...; dpsi_k S; nu_1; ...; nu_k]`` of the
    contact mode of ``walls`` (velocity basis): the scene's constraints, the walls'
    gradients, their impulsive constraints."""
    decl = scene.declaration
    rows = [list(decl.constraint_matrix.row(i)) for i in range(decl.m)]
    extra: list[list[sp.Expr]] = []
    for wall in walls:
        w = scene.walls[wall]
        if TIME in w.psi.free_symbols:
            raise SimulationError(
                f"wall {w.name!r} moves (psi depends on t): its contact constraint"
                " dpsi v + psi_t = 0 is affine in v and has no contact mode"
            )
        grad = sp.Matrix([[sp.diff(w.psi, qi) for qi in decl.coordinates]])
        rows.append(list(grad * decl.frame if decl.frame is not None else grad))
        extra.extend(list(w.impulsive_matrix.row(i)) for i in range(w.impulsive_matrix.rows))
    return rows + extra


def contact_scene(scene: Scene, walls: Mode) -> Scene | None:
    """The scene of ``scene`` in contact with the static walls ``walls``: the constraints
    :func:`contact_rows`, everything else unchanged; the normal multipliers are entries
    ``m .. m + k - 1`` (after the scene's own ``m`` multipliers).  None when the contact
    leaves no motion (as many constraints as coordinates: the body is locked)."""
    decl = scene.declaration
    rows = contact_rows(scene, walls)
    if len(rows) >= decl.n:
        return None
    tag = "_".join(str(w) for w in walls)
    return scene.replace(constraints=rows, walls=(), name=f"{scene.name}_contact_{tag}")


def simultaneous_walls(scene: Scene) -> tuple[bool, ...]:
    """Per wall: its impact map has a Newton direction (the Newton law without
    impulsive constraints), so it can take part in a simultaneous impact."""
    return tuple(w.law == "newton" and w.impulsive_matrix.rows == 0 for w in scene.walls)


def real_values(value: object, what: str) -> np.ndarray:
    """``value`` as float64 by the rule of the generated code's arguments
    (:func:`symmech.codegen.runtime_checks.real_array`: real numbers of any NumPy or Python
    type, sympy numbers included; booleans, strings, bytes, complex and masked values
    refused), or a :class:`SimulationError` naming ``what``."""
    try:
        return real_array(value, what)
    except CodegenError as exc:
        raise SimulationError(str(exc)) from None


def real_scalar(value: object, what: str) -> float:
    """One real number (by :func:`real_values`' rule) as a float, finite or not."""
    if type(value) is float:  # the common case, exactly this type
        return value
    a = real_values(value, what)
    if a.ndim != 0:
        raise SimulationError(f"{what}: expected a real number, got {value!r}")
    return float(a)


def real_number(value: object, what: str) -> float:
    """One finite real number (by :func:`real_values`' rule) as a float."""
    x = real_scalar(value, what)
    if not math.isfinite(x):
        raise SimulationError(f"{what}: expected a finite real number, got {value!r}")
    return x


@dataclass(frozen=True)
class _ParameterRules:
    """What :func:`check_parameters` checks, prepared once per scene."""

    names: tuple[str, ...]
    positive: tuple[bool, ...]
    nonnegative: tuple[bool, ...]
    #: (wall name, restitution as printed, its value as a function of the parameters)
    restitutions: tuple[tuple[str, str, Any], ...]
    #: the last plain ``{name: float}`` that passed, and its checked values (a run repeated
    #: with the same parameters is not checked again); one slot, replaced whole
    last: list[tuple[dict[str, float], dict[str, float]]] = field(
        default_factory=list, compare=False
    )


_RULES: weakref.WeakKeyDictionary[Scene, _ParameterRules] = weakref.WeakKeyDictionary()


def _rules(scene: Scene) -> _ParameterRules:
    rules = _RULES.get(scene)
    if rules is None:
        params = list(scene.parameters)
        restitutions = []
        for w in scene.walls:
            alpha = sp.sympify(w.restitution, strict=True)
            fn = sp.lambdify(params, alpha, modules="math")
            restitutions.append((w.name, str(w.restitution), fn))
        rules = _ParameterRules(
            tuple(str(p) for p in params),
            tuple(bool(p.is_positive) or p in scene.declaration.assumed_positive for p in params),
            tuple(bool(p.is_nonnegative) for p in params),
            tuple(restitutions),
        )
        _RULES[scene] = rules
    return rules


def check_parameters(scene: Scene, params: object) -> dict[str, float]:
    """``params`` as ``{name: value}``, every scene parameter given, finite, and with the
    sign its symbol declares (positive, nonnegative) and restitutions in [0, 1]."""
    rules = _rules(scene)
    plain = None
    if type(params) is dict and all(type(x) is float for x in params.values()):
        plain = params
    if plain is not None and rules.last and rules.last[0][0] == plain:
        return dict(rules.last[0][1])
    out = _checked_parameters(rules, params)
    if plain is not None:
        rules.last[:] = [(dict(plain), dict(out))]
    return out


def _checked_parameters(rules: _ParameterRules, params: object) -> dict[str, float]:
    names = list(rules.names)
    if params is None:
        params = {}
    if isinstance(params, Mapping):
        given = {str(k): v for k, v in params.items()}
    else:
        values = list(np.atleast_1d(np.asarray(params, dtype=object)))
        if len(values) != len(names):
            raise SimulationError(
                f"params: expected {len(names)} values for {names}, got {len(values)}"
            )
        given = dict(zip(names, values, strict=True))
    missing = [n for n in names if n not in given]
    unknown = sorted(set(given) - set(names))
    if missing or unknown:
        raise SimulationError(
            f"params: missing {missing}, unknown {unknown}; the scene's parameters are {names}"
        )
    out = {n: real_number(given[n], f"params[{n!r}]") for n in names}
    for name, pos, nonneg in zip(names, rules.positive, rules.nonnegative, strict=True):
        x = out[name]
        if pos and not x > 0:
            raise SimulationError(
                f"params[{name!r}] is declared positive (or, declared without a sign, the"
                f" metric needs it positive), got {x!r}"
            )
        if nonneg and not x >= 0:
            raise SimulationError(f"params[{name!r}] is declared non-negative, got {x!r}")
    values = [out[n] for n in names]
    for wall, printed, fn in rules.restitutions:
        alpha = float(fn(*values))
        if not (0 <= alpha <= 1):
            raise SimulationError(
                f"wall {wall!r}: restitution {printed} = {alpha!r} at these"
                " parameters is outside [0, 1]"
            )
    return out


@dataclass
class HybridSystem:
    """The generated functions of ``scene`` for the hybrid loop (see the module docstring).

    Build with :meth:`build`; ``modules`` maps each :data:`Mode` (``()``: free flight; the
    sorted indices of the static walls held) to a loaded
    :class:`~symmech.codegen.module.SceneModule`.
    """

    scene: Scene
    target: str
    strategy: str
    definitions: Mapping[Any, Any]
    modules: dict[Mode, SceneModule] = field(default_factory=dict)
    #: the modules carry the Jacobian d(rhs)/dy (for implicit integrators)
    jacobian: bool = False
    _locked: dict[tuple[str, Mode], Any] = field(default_factory=dict, repr=False)
    _moving: tuple[bool, ...] | None = field(default=None, repr=False)
    _conserved: bool | None = field(default=None, repr=False)
    _extra_modes: list[Mode] = field(default_factory=list, repr=False)

    @classmethod
    def build(
        cls,
        scene: Scene,
        target: str = "c",
        *,
        strategy: str = "auto",
        definitions: Mapping[Any, Any] | None = None,
        jacobian: bool = False,
    ) -> HybridSystem:
        """Generate and load the free-flight module of ``scene`` for ``target``
        (``"c"`` or ``"numpy"``); contact modes are generated on first use.  With
        ``jacobian`` every module also emits d(rhs)/dy."""
        if target not in ("c", "numpy"):
            raise SimulationError(f"target must be 'c' or 'numpy', got {target!r}")
        system = cls(scene, target, strategy, dict(definitions or {}), jacobian=jacobian)
        system.modules[FREE] = system._load(scene)
        return system

    def _load(self, scene: Scene) -> SceneModule:
        code = generate(
            scene,
            self.target,
            strategy=self.strategy,
            definitions=self.definitions or None,
            projectors=scene.is_constrained,
            jacobian=self.jacobian,
        )
        if self.jacobian and "jacobian" not in [f.name for f in code.functions]:
            why = [o for o in code.omitted if o.startswith("jacobian")]
            raise SimulationError(
                f"scene {scene.name!r}: no Jacobian for an implicit method"
                + (f" ({why[0]})" if why else "")
                + "; use an explicit method"
            )
        return code.load()

    @property
    def n(self) -> int:
        return self.scene.n

    @property
    def free(self) -> SceneModule:
        return self.modules[FREE]

    @property
    def moving(self) -> tuple[bool, ...]:
        """Per wall: psi depends on t (no contact mode)."""
        if self._moving is None:
            self._moving = tuple(TIME in w.psi.free_symbols for w in self.scene.walls)
        return self._moving

    @property
    def energy_conserved(self) -> bool:
        """The flow conserves T + V: no applied forces, the potential does not depend on t."""
        if self._conserved is None:
            self._conserved = self.scene.conservative
        return self._conserved

    def has_contact_mode(self, wall: int) -> bool:
        """Whether ``wall`` is static (a moving wall has no contact mode)."""
        return TIME not in self.scene.walls[wall].psi.free_symbols

    @property
    def c_modes(self) -> tuple[Mode, ...]:
        """The contact modes the C simulator library holds: each static wall alone, then
        every set the loop has asked for (:meth:`add_c_mode`), in the order added."""
        singles = tuple((w,) for w in range(len(self.scene.walls)) if self.has_contact_mode(w))
        return singles + tuple(self._extra_modes)

    def add_c_mode(self, mode: Mode) -> None:
        """Build the contact mode ``mode`` into the C library from now on (the library is
        rebuilt on its next use: :func:`symmech.simulate.csim.library`)."""
        mode = tuple(sorted(mode))
        if mode in self.c_modes:
            return
        if len(mode) > MAX_SIMULTANEOUS:
            names = [self.scene.walls[w].name for w in mode]
            raise SimulationError(
                f"contact with {len(mode)} walls at once {names}: the C loop holds at most"
                f" {MAX_SIMULTANEOUS} (backend='numpy' has no such limit)"
            )
        self._extra_modes.append(mode)

    def contact(self, mode: Mode) -> SceneModule | None:
        """The loaded module of the contact mode ``mode`` (generated on first use); None
        when the contact locks the body (:func:`contact_scene`)."""
        if mode not in self.modules:
            cs = contact_scene(self.scene, mode)
            self.modules[mode] = None if cs is None else self._load(cs)  # type: ignore[assignment]
        return self.modules[mode]

    def locked_force_expression(self, mode: Mode) -> list[sp.Expr]:
        """``lambda_N(t, q)`` of each wall of a contact that locks the body: entries ``m ..
        m + k - 1`` of the statics ``A^T lambda = -f(q, 0)`` (Carnot paper eq. 5 at rest;
        A the contact rows, square), with the run's definitions of the functions of time
        substituted.  More rows than coordinates (a statically indeterminate rest) is
        refused."""
        decl = self.scene.declaration
        A = sp.Matrix(contact_rows(self.scene, mode))
        if A.rows != A.cols:
            names = [self.scene.walls[w].name for w in mode]
            raise SimulationError(
                f"the body rests on walls {names} with {A.rows} contact constraints for"
                f" {A.cols} coordinates: the contact forces are statically indeterminate"
            )
        f0 = sp.Matrix(self.scene.forcing()).xreplace({v: 0 for v in decl.velocities})
        f0 = defined(f0, definition_rules(self.scene, self.definitions))
        lam = A.T.LUsolve(-f0)
        return [lam[decl.m + k] for k in range(len(mode))]

    def locked_force(self, mode: Mode) -> Any:
        """:meth:`locked_force_expression` as a NumPy function of (t, q, p) (p in the
        order of the scene's parameters) returning the list of the walls' forces."""
        key = ("locked", mode)
        if key not in self._locked:
            decl = self.scene.declaration
            expr = self.locked_force_expression(mode)
            args = [TIME, sp.Matrix(decl.coordinates), sp.Matrix(decl.parameters)]
            self._locked[key] = sp.lambdify(args, expr, modules="numpy", cse=True)
        return self._locked[key]

    def normal_index(self, mode: Mode, wall: int) -> int:
        """Index of ``wall``'s normal multiplier lambda_N in the contact mode's
        multipliers."""
        return self.scene.constraint_matrix.rows + mode.index(wall)


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
        self._takes_t: dict[tuple[Mode, str], bool] = {}

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
            for f in mod.code.functions:
                self._takes_t[(mode, f.name)] = f.takes_time
        return self._p[mode]

    def locked(self, mode: Mode) -> bool:
        """Whether ``mode`` is a contact that leaves no motion (the body rests)."""
        return bool(mode) and self.system.contact(mode) is None

    def _call(self, mode: Mode, name: str, t: float, *state: np.ndarray) -> np.ndarray:
        p = self._pvec(mode)
        mod = self._module(mode)
        assert mod is not None
        tt = t if self._takes_t.get((mode, name), False) else None
        return mod.call(name, *state, params=p, t=tt)

    def _wall_name(self, kind: str, wall: int) -> str:
        return self.system.free._wall_function(kind, wall)

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
        r = float(np.dot(g, ydot[:n]))
        if self.moving[wall]:
            r += float(self._call(FREE, self._wall_name("psi_t", wall), t, q))
        return r

    def normal_rate(self, wall: int, t: float, y: np.ndarray) -> float:
        """d psi/dt at a state (q_dot from the kinematics of the free flow)."""
        return self.rate(wall, t, y, self.rhs(FREE, t, y))

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
