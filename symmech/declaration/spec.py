"""Validated declaration of a mechanical system (the input side of a Scene).

:func:`declare` takes what a user writes (coordinates, a metric or a kinetic energy, a
potential, constraint one-forms, an optional frame of quasi-velocities, walls) and returns
a frozen :class:`Declaration` in a normal form the later layers rely on:

* ``metric``: the kinetic metric as an n x n matrix in the velocity basis (the coordinate
  velocities, or the quasi-velocities v when a frame ``q_dot = S(q) v`` is given);
  ``T = 1/2 v^T metric v``.
* ``constraint_matrix``: the rows mu^a of the constraint one-forms, ``mu v = 0``.
* ``walls``: the walls with psi and impulsive-constraint rows resolved.

Validation collects every problem it finds and raises one :class:`~symmech.SceneError`
listing all of them (as ``sympy.physics.mechanics``' ``validate`` does).  It runs in three
stages, and every field goes through each stage whatever the other fields hold; a check
that needs an earlier result (the positive definiteness of a metric whose symbols are
wrong, the independence of constraints one of which is not linear) is skipped when that
result is missing:

1. structure: coordinates (a scene without valid coordinates stops here), the velocity
   basis, ``parameters=``, the shape of every field and the parsing of strings;
2. symbols, field by field: what may appear where (coordinates everywhere; the velocities
   only in the kinetic energy and the constraints; t only in the potential and the
   walls), names shared by different symbols, non-smooth functions;
3. properties: the metric is symmetric and positive definite, T is a quadratic form,
   constraints are linear and homogeneous in the velocities and independent, walls
   depend on the coordinates and have a nonzero gradient on the wall, the potential and
   walls are real.

Stage 1 lives in :mod:`symmech.declaration.structure`, stages 2 and 3 in
:mod:`symmech.declaration.checks`.

Rules the stages enforce:

* One name, one symbol.  A symbol with the name of a coordinate, a velocity, a
  quasi-velocity, t or a declared parameter must be that symbol: ``Symbol("r")`` next to
  the coordinate ``r`` (real) is refused, not made a parameter.  Two different symbols with
  one name (``Symbol("a", positive=True)`` and ``Symbol("a")``) are refused, and so is a
  parameter listed twice.
* ``parameters=`` omitted: the parameters are every other free symbol, sorted by name
  (names are unique, so the order does not depend on the process).  Given: any other
  symbol is refused as unknown.
* Undefined functions (``sympy.Function("g")(x)``) are allowed in every field, with or
  without ``parameters=``, as unknown smooth real functions of their arguments; their
  arguments obey the field's rules (``g(xdot)`` is refused in a metric).  They are never
  parameters.  Checks at sampled points give ``g(x)`` (and each derivative of it) a random
  real value honouring the function's assumptions (``positive=True``): a metric
  ``diag(1 + g(x)**2, 1)`` is accepted, ``diag(g(x), 1)`` is refused unless ``g`` is
  declared positive.
* Properties are decided symbolically where that is cheap and certain (a diagonal metric
  whose entries are sums and products of positive terms is positive definite) and
  otherwise at a few random points honouring the symbols' assumptions, by exact rational
  inputs and float64 or 50-digit arithmetic.  ``sympy.simplify`` is never applied to user
  input: each check costs a few walks of the expression tree (a constraint of a few hundred
  operations once kept ``simplify`` busy for more than ten minutes).  A metric is refused when it is
  indefinite at a sampled point or singular at every one (its determinant vanishes
  identically); ``diag(1, x**2)``, singular only at x = 0, is accepted.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import sympy as sp

from symmech.declaration.admissible import NON_SMOOTH
from symmech.declaration.drawing import Drawing
from symmech.declaration.stages import _Inputs, _Reader
from symmech.declaration.structure import _items, _listed
from symmech.declaration.symbols import t as TIME
from symmech.declaration.wall import Wall

__all__ = ["NON_SMOOTH", "Declaration", "ResolvedWall", "declare"]


@dataclass(frozen=True)
class ResolvedWall:
    """A wall of a declaration, with its expressions resolved against the scene's symbols.

    ``psi`` is the gap function; ``impulsive_matrix`` the rows nu^A (l x n, in the velocity
    basis) of the constraints imposed at impact; ``wall`` the user's :class:`Wall`.
    """

    wall: Wall
    psi: sp.Expr
    impulsive_matrix: sp.ImmutableMatrix
    index: int
    #: the declared wall velocity W (n x 1, velocity basis), or None for the default
    velocity: sp.ImmutableMatrix | None = None

    @property
    def name(self) -> str:
        return self.wall.name or f"wall{self.index}"

    @property
    def restitution(self) -> sp.Expr:
        return self.wall.restitution

    @property
    def law(self) -> str:
        return self.wall.law

    def as_wall(self, **changes: object) -> Wall:
        """The wall as a :class:`Wall` of its resolved expressions (impulsive constraints as
        coefficient rows), with ``changes`` (``restitution=``, ``law=``, ...) applied."""
        nu = self.impulsive_matrix
        args: dict[str, Any] = {
            "restitution": self.restitution,
            "impulsive_constraints": [list(nu.row(i)) for i in range(nu.rows)],
            "name": self.wall.name or None,
            "law": self.law,
            "velocity": None if self.velocity is None else list(self.velocity),
        }
        return Wall(changes.pop("psi", self.psi), **{**args, **changes})

    @property
    def moving(self) -> bool:
        """psi depends on t, or the wall has a declared velocity that is not zero."""
        if TIME in self.psi.free_symbols:
            return True
        return self.velocity is not None and any(e != 0 for e in self.velocity)


@dataclass(frozen=True)
class Declaration:
    """A validated mechanical system in normal form (see the module docstring)."""

    coordinates: tuple[sp.Symbol, ...]
    velocities: tuple[sp.Symbol, ...]  # the velocity basis: q_dot symbols, or quasi-velocities
    coordinate_velocities: tuple[sp.Symbol, ...]
    frame: sp.ImmutableMatrix | None  # q_dot = frame * velocities; None means identity
    metric: sp.ImmutableMatrix
    potential: sp.Expr
    forces: sp.ImmutableMatrix  # n x 1 applied generalized forces, velocity basis
    constraint_matrix: sp.ImmutableMatrix  # m x n
    walls: tuple[ResolvedWall, ...]
    parameters: tuple[sp.Symbol, ...]
    name: str
    kinetic_energy_given: bool
    #: parameters without a sign assumption that the metric's positive definiteness needs
    #: positive (see :mod:`symmech.declaration.unsigned`); generated code checks them at run time
    assumed_positive: tuple[sp.Symbol, ...] = ()
    #: positive definite only for some values of parameters declared without a sign:
    #: generated code checks it at run time (its Cholesky factorisation of g)
    metric_checked_at_run_time: bool = False
    #: how the scene is drawn (:mod:`symmech.declaration.drawing`), or None
    drawing: Drawing | None = None

    @property
    def n(self) -> int:
        return len(self.coordinates)

    @property
    def m(self) -> int:
        return self.constraint_matrix.rows

    @property
    def has_frame(self) -> bool:
        return self.frame is not None

    def arguments(self) -> dict[str, Any]:
        """The keyword arguments of :class:`symmech.Scene` that declare this system again:
        the metric in the velocity basis, the constraint rows, the walls rebuilt from their
        resolved expressions (:meth:`ResolvedWall.as_wall`), the parameters in order."""
        mu = self.constraint_matrix
        return {
            "coordinates": self.coordinates,
            "metric": self.metric,
            "potential": self.potential,
            "forces": self.forces,
            "constraints": [list(mu.row(a)) for a in range(mu.rows)],
            "frame": self.frame,
            "quasi_velocities": self.velocities if self.frame is not None else None,
            "walls": [w.as_wall() for w in self.walls],
            "parameters": self.parameters,
            "name": self.name,
            "drawing": self.drawing,
        }

    def expressions(self) -> list[sp.Expr]:
        """Every declared expression, entry by entry: the metric, the potential, the
        forces, the constraint rows, the frame, and each wall's gap, impulsive rows and
        declared velocity (where the scene's functions of t and of q can occur)."""
        out = [
            *self.metric,
            self.potential,
            *self.forces,
            *self.constraint_matrix,
            *(self.frame if self.frame is not None else []),
        ]
        for w in self.walls:
            out.extend([w.psi, *w.impulsive_matrix, *(w.velocity or [])])
        return out

    def q_dot(self) -> sp.ImmutableMatrix:
        """q_dot as a column in the velocity basis: ``S v`` with a frame, else the q_dot symbols."""
        v = sp.Matrix(self.velocities)
        return sp.ImmutableMatrix(v if self.frame is None else self.frame * v)


# ---------------------------------------------------------------------------------------
# the builder


def declare(
    coordinates: Sequence[sp.Symbol],
    *,
    metric: object = None,
    kinetic_energy: object = None,
    potential: object = 0,
    forces: object = None,
    constraints: Iterable = (),
    frame: object = None,
    quasi_velocities: Sequence[sp.Symbol] | None = None,
    walls: Iterable[Wall] = (),
    parameters: Sequence[sp.Symbol] | None = None,
    name: str | None = None,
    drawing: object = None,
) -> Declaration:
    """Validate a scene's inputs and return its :class:`Declaration`.

    Raises :class:`~symmech.SceneError` listing every problem found (see the module
    docstring for the rules).  See :class:`symmech.Scene` for the meaning of the arguments.
    The stages are those of :class:`_Reader`: structure, the fields, their symbols, then
    their properties at sampled points.
    """
    inputs = _Inputs(
        coordinates,
        metric,
        kinetic_energy,
        potential,
        _listed(forces),
        _items(constraints),
        frame,
        quasi_velocities,
        _listed(walls),
        parameters,
    ).translated()
    reader = _Reader(inputs)
    reader.read_fields()
    reader.check_symbols(drawing)
    reader.check_properties()
    resolved = reader.resolve_walls()
    reader.problems.raise_if_any()
    walls_out = tuple(
        ResolvedWall(wall=w, psi=psi, impulsive_matrix=sp.ImmutableMatrix(nu), index=k, velocity=W)
        for k, (w, psi, nu, W) in enumerate(resolved)
    )
    return Declaration(
        coordinates=reader.q,
        velocities=reader.v,
        coordinate_velocities=reader.qd,
        frame=sp.ImmutableMatrix(reader.S) if reader.S is not None else None,
        metric=sp.ImmutableMatrix(reader.G),
        potential=sp.sympify(reader.V, strict=True),
        forces=sp.ImmutableMatrix(reader.F),
        constraint_matrix=sp.ImmutableMatrix(reader.mu),
        walls=walls_out,
        parameters=tuple(reader.params),
        name=name or "scene",
        kinetic_energy_given=reader.T is not None,
        assumed_positive=reader.assumed or (),
        metric_checked_at_run_time=reader.assumed is not None,
        drawing=reader.drawn,
    )
