"""The Scene: a declared mechanical system and everything symmech derives from it.

A :class:`Scene` is immutable.  Each derived quantity is computed lazily, once, when first
asked for, and cached; nothing is derived at construction beyond validation.  The cache
is private (a name-mangled slot) and exposed only as a read-only view, so a derived
result cannot be replaced from outside; a second call returns the identical object.

Layering: ``Scene`` is a facade over the layers to its left (declaration -> geometry ->
constraints -> impacts); those layers work on plain sympy matrices and never import it.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from types import MappingProxyType
from typing import Any, overload

import sympy as sp

from symmech.algebra.budget import expand_affordable
from symmech.algebra.simplification import Level, check_level, tidy_matrix
from symmech.constraints.dynamics import constrained_solution, constraint_rate
from symmech.constraints.projectors import gradients, gram, projectors, solve_spd
from symmech.declaration.drawing import Drawing
from symmech.declaration.latex import latex_text
from symmech.declaration.spec import Declaration, ResolvedWall, declare
from symmech.declaration.wall import Wall
from symmech.errors import ImpactError, SceneError
from symmech.geometry.connection import (
    christoffel_first_kind,
    christoffel_second_kind,
    connection_coefficients,
    forcing,
)
from symmech.geometry.lie import commutation_coefficients
from symmech.impacts import (
    ImpactMap,
    SeveralImpactMap,
    derive_impact_map,
    derive_several_impact_map,
)
from symmech.mechanics import reading, scene_arguments

__all__ = ["Scene"]

#: How a wall is named: its index, its name, or the Wall (or resolved wall) itself.
WallKey = int | str | Wall | ResolvedWall

#: Matrices with more entries than this are shown by their shape in ``_repr_latex_``.
_LATEX_MAX_ENTRIES = 64


def _scene_of_declaration(decl: Declaration) -> Scene:
    """The Scene of an unpickled declaration, validated again like any other declaration
    (a pickle from a file or another process is input): the scene is declared anew from
    the declaration's arguments (:meth:`Scene.__reduce__`)."""
    if not isinstance(decl, Declaration):
        raise SceneError(f"unpickling a Scene: expected a Declaration, got {type(decl).__name__}")
    args = decl.arguments()
    Scene(args.pop("coordinates"), **args)  # the checks of a new declaration; raises
    scene = object.__new__(Scene)  # the declaration as it was pickled, now checked
    object.__setattr__(scene, "_decl", decl)
    object.__setattr__(scene, "_Scene__derived", {})
    return scene


def _latex_matrix(M: sp.MatrixBase) -> str:
    if M.rows * M.cols > _LATEX_MAX_ENTRIES:
        return rf"\text{{({M.rows} x {M.cols} matrix)}}"
    return sp.latex(M)


class Scene:
    r"""A mechanical system: coordinates q, kinetic metric g(q), potential V(q), linear
    constraints mu(q) q_dot = 0, an optional frame of quasi-velocities, and walls.

    The equations of motion it derives are (Carnot paper, eqs. 2 and 5; slides 000)

    .. math::  g(q)\,\ddot q = f(q,\dot q,t) + \mu^T\lambda,\qquad \mu(q)\,\dot q = 0,

    with ``f_k = -Gamma_kij q_dot^i q_dot^j - dV/dq^k``.  With a frame ``q_dot = S(q) v``
    the metric, constraints and impulsive constraints are written in the quasi-velocities
    v and the same equations hold with v in place of q_dot and the connection coefficients
    of the frame in place of Gamma (Kane / Hamel form).

    Parameters
    ----------
    coordinates:
        The coordinates, sympy Symbols (see :func:`symmech.coordinates`).
    metric, kinetic_energy:
        Exactly one: the n x n kinetic metric, or the kinetic energy T as a quadratic form in
        the velocities (:func:`symmech.velocities`, or the quasi-velocities).
    potential:
        V(q) (may depend on :data:`symmech.t`); default 0.
    forces:
        Applied generalized forces F (n entries, one per velocity of the basis), the
        non-potential loads: damping, friction, motors, inputs ``tau(t)``.  They may depend on
        q, the velocities, t and undefined functions of t; with a frame they are Kane's
        generalized active forces ``F = S^T Q`` (see :mod:`symmech.declaration.forces`).
        Default: none.
    constraints:
        Linear velocity constraints: expressions linear in the velocities, or coefficient
        rows.
    frame, quasi_velocities:
        Optional frame S(q) (n x n, invertible) and the quasi-velocity symbols v with
        ``q_dot = S v``.
    walls:
        :class:`symmech.Wall` objects.
    parameters:
        The parameter symbols, in order.  Default: every other free symbol, sorted by name.
    name:
        A name for messages and generated code.
    drawing:
        How the scene is drawn in animations, or None: a drawing
        (:class:`~symmech.declaration.drawing.Drawing`) of shapes placed by expressions in
        q, t and the parameters.

    Examples
    --------
    A disk rolling on a line (Carnot paper example 3.7 with a permanent constraint):

    >>> import sympy as sp, symmech as sm
    >>> x, y, th = sm.coordinates("x y theta")
    >>> xd, yd, thd = sm.velocities((x, y, th))
    >>> m, k, R = sp.symbols("m k R", positive=True)
    >>> scene = sm.Scene((x, y, th), metric=sp.diag(m, m, m*k**2), constraints=[xd - R*thd])
    >>> scene.projectors()[0]
    Matrix([
    [R**2/(R**2 + k**2), 0, R*k**2/(R**2 + k**2)],
    [                 0, 1,                    0],
    [   R/(R**2 + k**2), 0,   k**2/(R**2 + k**2)]])
    """

    __slots__ = ("__derived", "__weakref__", "_decl")
    _decl: Declaration
    __derived: dict[tuple, Any]

    def __init__(
        self,
        coordinates: Sequence[sp.Symbol],
        *,
        metric: Any = None,
        kinetic_energy: Any = None,
        potential: Any = 0,
        forces: Any = None,
        constraints: Iterable = (),
        frame: Any = None,
        quasi_velocities: Sequence[sp.Symbol] | None = None,
        walls: Iterable[Wall] = (),
        parameters: Sequence[sp.Symbol] | None = None,
        name: str | None = None,
        drawing: Any = None,
    ):
        decl = declare(
            coordinates,
            metric=metric,
            kinetic_energy=kinetic_energy,
            potential=potential,
            forces=forces,
            constraints=constraints,
            frame=frame,
            quasi_velocities=quasi_velocities,
            walls=walls,
            parameters=parameters,
            name=name,
            drawing=drawing,
        )
        object.__setattr__(self, "_decl", decl)
        object.__setattr__(self, "_Scene__derived", {})

    @classmethod
    def from_mechanics(
        cls, model: object, *, walls: Iterable[Wall] = (), name: str | None = None
    ) -> Scene:
        """The Scene of a ``sympy.physics.mechanics`` model: a ``KanesMethod``,
        ``LagrangesMethod`` or ``System`` with its bodies and loads (see
        :mod:`symmech.mechanics.convert` for how each part is read).  ``walls`` may be
        written in the model's dynamic symbols.

        Kane's generalized speeds become the quasi-velocities (``q_dot = S(q) u`` from the
        kinematic differential equations), velocity constraints and differentiated
        holonomic constraints the constraints, constant forces the potential (when they
        derive from one), every other load (a System's actuators included) an applied
        force; Lagrange models are read from their Lagrangian.  What cannot be imported
        (auxiliary speeds, non-smooth loads, a singular mass matrix, ...) raises a
        :class:`~symmech.SceneError` naming the model's part.
        """
        arguments = scene_arguments(model, walls=list(walls), name=name)
        with reading(type(model).__name__, "the scene its parts declare"):
            return cls(**arguments)

    def replace(self, **changes: Any) -> Scene:
        """A new Scene declaring the same system with ``changes`` to the arguments of
        :class:`Scene` (``walls=``, ``constraints=``, ``name=``, ...; ``parameters=None``
        lets a new symbol in and orders them by name).  The rest is taken from the
        declaration as resolved (:meth:`~symmech.declaration.spec.Declaration.arguments`)."""
        args = {**self._decl.arguments(), **changes}
        return type(self)(args.pop("coordinates"), **args)

    # -- pickling -----------------------------------------------------------------------
    def __reduce__(self) -> tuple[Callable[[Declaration], Scene], tuple[Declaration]]:
        """Pickle the declaration only: the copy is declared and validated again from it
        (a pickle is input: a crafted one is refused as its declaration would be) and
        derives what it is asked for afresh (the cache of derived quantities, which may
        hold loaded code, does not travel).  A sweep's Dask workers receive scenes so."""
        return _scene_of_declaration, (self._decl,)

    # -- immutability -----------------------------------------------------------------
    def __setattr__(self, key: str, value: object) -> None:
        raise AttributeError(f"Scene is immutable; cannot set {key!r} (build a new Scene)")

    def __delattr__(self, key: str) -> None:
        raise AttributeError(f"Scene is immutable; cannot delete {key!r}")

    @property
    def _cache(self) -> Mapping[tuple, Any]:
        """The derived quantities computed so far, as a read-only view (for inspection)."""
        return MappingProxyType(self.__derived)

    def _cached(self, key: tuple, build: Callable[[], Any]) -> Any:
        cache = self.__derived
        if key not in cache:
            cache[key] = build()
        return cache[key]

    def attached(self, key: tuple, build: Callable[[], Any]) -> Any:
        """An object a later layer derives from this scene (the simulator's compiled
        systems), built by ``build()`` once per ``key`` and kept with the scene: it lives
        exactly as long as the scene does (a module-level cache would keep both alive).
        ``key`` is a tuple whose first entry names the layer (``("simulate", ...)``)."""
        if not isinstance(key, tuple) or not key or not isinstance(key[0], str):
            raise SceneError(f"attached: key must be a tuple naming its layer first, got {key!r}")
        return self._cached(("attached", *key), build)

    # -- declaration -----------------------------------------------------------------------
    @property
    def declaration(self) -> Declaration:
        """The validated declaration in normal form."""
        return self._decl

    @property
    def name(self) -> str:
        return self._decl.name

    @property
    def coordinates(self) -> tuple[sp.Symbol, ...]:
        return self._decl.coordinates

    @property
    def velocities(self) -> tuple[sp.Symbol, ...]:
        """The velocity basis: the coordinate velocities, or the quasi-velocities."""
        return self._decl.velocities

    @property
    def coordinate_velocities(self) -> tuple[sp.Symbol, ...]:
        return self._decl.coordinate_velocities

    @property
    def parameters(self) -> tuple[sp.Symbol, ...]:
        return self._decl.parameters

    @property
    def frame(self) -> sp.ImmutableMatrix | None:
        return self._decl.frame

    @property
    def walls(self) -> tuple[ResolvedWall, ...]:
        return self._decl.walls

    @property
    def drawing(self) -> Drawing | None:
        """How the scene is drawn (:mod:`symmech.declaration.drawing`), or None."""
        return self._decl.drawing

    @property
    def n(self) -> int:
        return self._decl.n

    @property
    def potential(self) -> sp.Expr:
        return self._decl.potential

    @property
    def forces(self) -> sp.ImmutableMatrix:
        """The applied generalized forces F (n x 1, velocity basis; zero when none)."""
        return self._decl.forces

    @property
    def conservative(self) -> bool:
        """True when the flow conserves T + V: no applied forces, V independent of t."""
        from symmech.declaration.symbols import t

        return t not in self.potential.free_symbols and all(e == 0 for e in self._decl.forces)

    @property
    def constraint_matrix(self) -> sp.ImmutableMatrix:
        """Rows mu^a of the constraint one-forms (m x n, velocity basis): ``mu v = 0``."""
        return self._decl.constraint_matrix

    @property
    def is_constrained(self) -> bool:
        return self._decl.m > 0

    @property
    def time_dependent(self) -> bool:
        """True when the potential, the forces or a wall depend on :data:`symmech.t`."""
        from symmech.declaration.symbols import t

        return (
            t in self.potential.free_symbols
            or t in self._decl.forces.free_symbols
            or any(t in w.psi.free_symbols for w in self.walls)
            or any(w.velocity is not None and t in w.velocity.free_symbols for w in self.walls)
        )

    def __repr__(self) -> str:
        parts = [f"Scene({self.name!r}: q={list(self.coordinates)}"]
        if self.frame is not None:
            parts.append(f"quasi-velocities {list(self.velocities)}")
        if any(e != 0 for e in self._decl.forces):
            parts.append("applied forces")
        if self.is_constrained:
            parts.append(f"{self._decl.m} constraints")
        if self.walls:
            parts.append(f"{len(self.walls)} walls")
        if self._decl.metric_checked_at_run_time:
            names = ", ".join(p.name for p in self._decl.assumed_positive)
            parts.append(
                "metric positive definite for some parameter values only (checked at run"
                " time" + (f"; {names} > 0" if names else "") + ")"
            )
        return ", ".join(parts) + ")"

    def _repr_latex_(self) -> str:
        r"""A compact LaTeX summary for Jupyter: coordinates, metric, potential,
        constraints and walls, one per line (``$\begin{array}{l} ... \end{array}$``).
        Matrices with more than ``_LATEX_MAX_ENTRIES`` entries are summarised by their
        shape."""
        lx = sp.latex
        q = ", ".join(lx(c) for c in self.coordinates)
        lines = [rf"\text{{Scene {latex_text(self.name)}: }} q = ({q})"]
        if self.frame is not None:
            v = ", ".join(lx(c) for c in self.velocities)
            lines.append(rf"\dot q = S\,v,\quad v = ({v}),\quad S = {_latex_matrix(self.frame)}")
            lines.append(rf"M = {_latex_matrix(self.mass_matrix())}")
        else:
            lines.append(rf"g = {_latex_matrix(self.mass_matrix())}")
        lines.append(rf"V = {lx(self.potential)}")
        if any(e != 0 for e in self._decl.forces):
            lines.append(rf"F = {_latex_matrix(self._decl.forces.T)}^T")
        if self.is_constrained:
            lines.append(rf"\mu = {_latex_matrix(self.constraint_matrix)},\quad \mu\,v = 0")
        for w in self.walls:
            parts = [rf"\psi_{{\text{{{latex_text(w.name)}}}}} = {lx(w.psi)} \geq 0"]
            parts.append(rf"e = {lx(w.restitution)}")
            if w.impulsive_matrix.rows:
                parts.append(rf"\nu = {_latex_matrix(w.impulsive_matrix)}")
            parts.append(rf"\text{{{w.law} law}}")
            lines.append(r",\quad ".join(parts))
        return "$\\begin{array}{l}" + " \\\\ ".join(lines) + "\\end{array}$"

    # -- metric and energy ------------------------------------------------------------------
    def mass_matrix(self) -> sp.ImmutableMatrix:
        """The n x n metric in the velocity basis (g, or S^T g S in a frame): T = 1/2 v^T M v."""
        return self._decl.metric

    def coordinate_metric(self) -> sp.ImmutableMatrix:
        """The metric in coordinates: g, or ``S^-T M S^-1`` for a scene declared in a frame."""

        def build() -> sp.ImmutableMatrix:
            if self.frame is None:
                return self._decl.metric
            Sinv = tidy_matrix(sp.Matrix(self.frame).inv(method="LU"), "full")
            return sp.ImmutableMatrix(tidy_matrix(Sinv.T * self._decl.metric * Sinv, "full"))

        return self._cached(("coordinate_metric",), build)

    def kinetic_energy(self) -> sp.Expr:
        """T = 1/2 v^T M v in the velocity basis."""
        v = sp.Matrix(self.velocities)
        return self._cached(
            ("T",), lambda: expand_affordable((v.T * self._decl.metric * v)[0, 0] / 2)
        )

    def energy(self) -> sp.Expr:
        """Total energy T + V."""
        return self.kinetic_energy() + self.potential

    # -- geometry ---------------------------------------------------------------------------------
    def christoffel(
        self, kind: int = 2, *, simplify: Level = "light"
    ) -> sp.ImmutableDenseNDimArray:
        """Christoffel symbols of the coordinate metric, an Array of shape (n, n, n).

        ``kind=2``: ``[k, i, j] = Gamma^k_ij``; ``kind=1``: ``[k, i, j] = Gamma_kij``
        (slides 000).  Formed for i <= j and mirrored.  ``simplify`` follows
        :mod:`symmech.algebra.simplification`: ``"light"`` (default) gives exact
        normal forms (for kind 2 with one shared determinant, see
        :func:`symmech.geometry.connection.christoffel_second_kind`), falling back to the
        symbols as built when that normal form exceeds its term budget (dense metrics
        beyond about 6 x 6 with trigonometric entries); ``"full"`` adds a bounded
        ``sympy.simplify`` per entry (seconds per entry); ``"none"`` is the raw LU solve.
        """
        if isinstance(kind, bool) or kind not in (1, 2):
            raise SceneError(f"christoffel: kind must be 1 or 2, got {kind!r}")
        check_level(simplify, "christoffel")
        fn = christoffel_first_kind if kind == 1 else christoffel_second_kind
        return self._cached(
            ("christoffel", kind, simplify),
            lambda: fn(self.coordinate_metric(), self.coordinates, simplify),
        )

    def commutation_coefficients(self) -> sp.ImmutableDenseNDimArray:
        """c^m_kl of the frame, [u_k, u_l] = c^m_kl u_m, an Array [m, k, l] (0 in coordinates)."""

        def build() -> sp.ImmutableDenseNDimArray:
            n = self.n
            if self.frame is None:
                return sp.ImmutableDenseNDimArray.zeros(n, n, n)
            return sp.ImmutableDenseNDimArray(
                commutation_coefficients(self.frame, self.coordinates)
            )

        return self._cached(("commutation",), build)

    def connection_coefficients(self, *, simplify: Level = "light") -> sp.ImmutableDenseNDimArray:
        """omega^m_ij with nabla_{u_i} u_j = omega^m_ij u_m, an Array [m, i, j] (slides 000).

        ``simplify`` as in :meth:`christoffel`.
        """
        check_level(simplify, "connection_coefficients")
        return self._cached(
            ("connection", simplify),
            lambda: connection_coefficients(
                self._decl.metric,
                self.coordinates,
                self.frame,
                self.commutation_coefficients() if self.frame is not None else None,
                simplify,
            ),
        )

    def forcing(self) -> sp.ImmutableMatrix:
        """f(q, v, t) with ``M v_dot = f`` unconstrained:
        ``f_k = -omega_kij v^i v^j - u_k(V) + F_k``.

        In coordinates ``f = -Gamma_kij q_dot^i q_dot^j - dV/dq^k + F_k`` (first kind, no
        inverse; F the applied :attr:`forces`); see
        :func:`symmech.geometry.connection.forcing`.
        """

        def build() -> sp.ImmutableMatrix:
            f = forcing(
                self._decl.metric,
                self.potential,
                self.coordinates,
                self.velocities,
                self.frame,
                self.commutation_coefficients() if self.frame is not None else None,
            )
            F = self._decl.forces
            if any(e != 0 for e in F):
                f = sp.Matrix([a + b for a, b in zip(f, F, strict=True)])
            return sp.ImmutableMatrix(f)

        return self._cached(("forcing",), build)

    # -- constraints ---------------------------------------------------------------------------
    def gradients(self) -> sp.ImmutableMatrix:
        """Z = g^-1 mu^T: column a is the gradient Z^a of mu^a (Carnot §2.2)."""
        return self._cached(
            ("Z",), lambda: sp.ImmutableMatrix(gradients(self._decl.metric, self.constraint_matrix))
        )

    def gram(self) -> sp.ImmutableMatrix:
        """C^ab = mu^a g^-1 mu^b (Carnot §2.2)."""
        return self._cached(
            ("C",), lambda: sp.ImmutableMatrix(gram(self._decl.metric, self.constraint_matrix))
        )

    def projectors(self) -> tuple[sp.ImmutableMatrix, sp.ImmutableMatrix]:
        """(P, Q): g-orthogonal projectors onto D and D^perp; Q = C_ab Z^a (x) mu^b (Carnot 2.2)."""

        def build() -> tuple[sp.ImmutableMatrix, sp.ImmutableMatrix]:
            P, Q = projectors(self._decl.metric, self.constraint_matrix)
            return sp.ImmutableMatrix(P), sp.ImmutableMatrix(Q)

        return self._cached(("projectors",), build)

    def constraint_rate(self) -> sp.ImmutableMatrix:
        """mu_dot v, the velocity-quadratic term of the differentiated constraints."""
        return self._cached(
            ("rate",),
            lambda: sp.ImmutableMatrix(
                constraint_rate(
                    self.constraint_matrix, self.coordinates, self._decl.q_dot(), self.velocities
                )
            ),
        )

    def multipliers(self, *, simplify: Level = "light") -> sp.ImmutableMatrix:
        """Lagrange multipliers lambda (m x 1) with ``M v_dot = f + mu^T lambda``.

        ``lambda = C^-1 (-mu_dot v - mu M^-1 f)`` (Carnot §2.2, sign re-derived; see
        :mod:`symmech.constraints.dynamics`).
        """
        check_level(simplify, "multipliers")
        if not self.is_constrained:
            raise SceneError(f"scene {self.name!r}: multipliers() needs constraints; it has none")
        return self._cached(("lambda", simplify), lambda: self._constrained(simplify)[1])

    def _constrained(self, simplify: Level) -> tuple[sp.ImmutableMatrix, sp.ImmutableMatrix]:
        """(v_dot, lambda) of the constrained system, solved once per level."""

        def build() -> tuple[sp.ImmutableMatrix, sp.ImmutableMatrix]:
            acc, lam = constrained_solution(
                self._decl.metric,
                self.forcing(),
                self.constraint_matrix,
                self.constraint_rate(),
                simplify,
            )
            return sp.ImmutableMatrix(acc), sp.ImmutableMatrix(lam)

        return self._cached(("constrained", simplify), build)

    def acceleration(self, *, simplify: Level = "light") -> sp.ImmutableMatrix:
        """The acceleration as an n x 1 Matrix in q, the velocities, t and the parameters.

        Unconstrained: ``q_ddot = -Gamma(q_dot, q_dot) - g^-1 dV`` (geodesic equation with a
        potential).  Constrained: ``v_dot = M^-1 (f + mu^T lambda)``, which keeps v in D.
        With a frame it is v_dot, the rate of the quasi-velocities.  ``simplify="light"``
        solves exactly with the strategy of :mod:`symmech.algebra.field` (normal forms
        with the Pythagorean reduction, a shared determinant for dense trigonometric
        metrics; with constraints one solve of the bordered system
        ``[[M, mu^T], [mu, 0]]``, see :func:`symmech.constraints.dynamics.
        constrained_solution`, which also gives :meth:`multipliers`); ``"none"`` is a
        symbolic LU solve.  For large systems use
        :meth:`mass_matrix` and :meth:`forcing` instead.
        """
        check_level(simplify, "acceleration")

        def build() -> sp.ImmutableMatrix:
            if self.is_constrained:
                return self._constrained(simplify)[0]
            return sp.ImmutableMatrix(solve_spd(self._decl.metric, self.forcing(), simplify))

        return self._cached(("acceleration", simplify), build)

    # -- impacts ---------------------------------------------------------------------------
    def wall(self, wall: int | str | Wall | ResolvedWall) -> ResolvedWall:
        """Look a wall up by index, name, or the :class:`Wall` object given at construction."""
        walls = self.walls
        if isinstance(wall, ResolvedWall):
            if wall in walls:
                return wall
        elif isinstance(wall, bool):
            pass
        elif isinstance(wall, int):
            if -len(walls) <= wall < len(walls):
                return walls[wall]
            raise SceneError(f"scene {self.name!r}: no wall with index {wall} ({len(walls)} walls)")
        elif isinstance(wall, str):
            for w in walls:
                if w.name == wall:
                    return w
            names = [w.name for w in walls]
            raise SceneError(f"scene {self.name!r}: no wall named {wall!r}; walls are {names}")
        elif isinstance(wall, Wall):
            for w in walls:
                if w.wall is wall or w.wall == wall:
                    return w
        raise SceneError(f"scene {self.name!r}: {wall!r} is not one of its walls")

    @overload
    def impact_map(
        self,
        wall: WallKey = 0,
        *,
        law: str | None = None,
        wall_velocity: Sequence | sp.MatrixBase | None = None,
    ) -> ImpactMap: ...

    @overload
    def impact_map(
        self,
        wall: list[WallKey] | tuple[WallKey, ...],
        *,
        law: str | None = None,
        wall_velocity: Sequence | sp.MatrixBase | None = None,
    ) -> ImpactMap | SeveralImpactMap: ...

    def impact_map(
        self,
        wall: WallKey | list[WallKey] | tuple[WallKey, ...] = 0,
        *,
        law: str | None = None,
        wall_velocity: Sequence | sp.MatrixBase | None = None,
    ) -> ImpactMap | SeveralImpactMap:
        """The closed-form impact map of ``wall`` (index, name or Wall); see :class:`ImpactMap`.

        ``v+ = matrix v- + offset`` with the Newton law (Carnot paper eq. 10, Prop. 3.4,
        eq. 17, Prop. 4.2), or the energy-conserving rebound of text 001 section 3.2 with
        ``law="energy"``.  Cached per wall and law (unless ``wall_velocity`` is given).

        A list or tuple of walls gives the map of that set all active at once, the
        generalized Newton law per wall (:class:`~symmech.impacts.several.SeveralImpactMap`,
        with the normal impulses and the energy identity), cached per ordered set; a set
        of one wall is that wall's map (the same cached object).  ``wall_velocity`` is
        for one wall only (in a set, each wall moves with its declared velocity).
        """
        if isinstance(wall, list | tuple):
            if len(wall) != 1:
                if wall_velocity is not None:
                    raise ImpactError(
                        "impact map: wall_velocity is given for one wall; the walls of a set"
                        " move with their declared velocities"
                    )
                resolved_set = tuple(self.wall(w) for w in wall)
                return self._cached(
                    ("impacts", tuple(w.index for w in resolved_set), law),
                    lambda: derive_several_impact_map(
                        self._decl, resolved_set, law=law, projectors=self.projectors()
                    ),
                )
            (wall,) = wall
        resolved = self.wall(wall)
        if wall_velocity is not None:
            return derive_impact_map(
                self._decl,
                resolved,
                law,
                wall_velocity=wall_velocity,
                projectors=self.projectors(),
            )
        return self._cached(
            ("impact", resolved.index, law),
            lambda: derive_impact_map(self._decl, resolved, law, projectors=self.projectors()),
        )

    def kinematics(self) -> sp.ImmutableMatrix:
        """q_dot in the velocity basis: ``S v`` with a frame, else the velocity symbols."""
        return self._decl.q_dot()
