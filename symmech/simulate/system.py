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
* per set of static walls held, the **contact mode** (:data:`Mode`): the same system with
  each held wall a permanent holonomic constraint.  A wall's one-form is ``dpsi S`` in the
  velocity basis (S the frame, or the identity) and, for a rough wall, its impulsive
  constraints ``nu`` are kept during contact (the body rolls on the wall).  The contact
  scene is an ordinary :class:`~symmech.Scene` with the constraints
  ``[mu; dpsi_1 S; ...; nu]``, so its acceleration, its multipliers and its projector come
  from the same derivation as every other scene (Carnot paper eq. 5 and section 2.2).  The
  normal multipliers ``lambda_N`` (the entries of the ``dpsi_i S``) are the normal contact
  forces: ``g v_dot = f + mu^T lambda + sum_i lambda_N,i (dpsi_i S)^T`` pushes into the
  admissible side while ``lambda_N,i > 0``; a wall is released when its force would turn
  negative.

A moving wall (psi depends on t) has no contact mode: the contact constraint would be
affine in v (``dpsi v + psi_t = 0``), which scenes do not declare; an accumulation of
impacts on a moving wall ends the run with status ``"zeno"``.

The evaluations the loop makes at fixed parameters are :class:`~.functions.Functions`;
the parameters are checked by :mod:`.parameters`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import sympy as sp

from symmech.codegen import generate
from symmech.codegen.definitions import defined, definition_rules
from symmech.codegen.module import SceneModule
from symmech.codegen.plan import FUNCTIONS
from symmech.declaration.symbols import t as TIME
from symmech.errors import SymmechError
from symmech.scene import Scene
from symmech.simulate.impulses import MAX_SIMULTANEOUS

__all__ = [
    "FREE",
    "HybridSystem",
    "Mode",
    "SimulationError",
    "contact_rows",
    "contact_scene",
    "simultaneous_walls",
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
        system.modules[FREE] = system._load(scene, fused=True)
        return system

    def _load(self, scene: Scene, fused: bool = False) -> SceneModule:
        """Generate and load a mode's module: every function but ``dynamics``, with the
        projectors of a constrained scene, the Jacobian when asked for, and with
        ``fused`` (free flight) ``augmented_rhs``, the Python loops' right-hand side."""
        kinds = [k for k in FUNCTIONS if k not in ("dynamics", "projectors", "jacobian")]
        code = generate(
            scene,
            self.target,
            strategy=self.strategy,
            functions=kinds if fused else None,
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
        if self.contact(mode) is None:
            self.locked_force_expression(mode)  # refuses a statically indeterminate rest
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
