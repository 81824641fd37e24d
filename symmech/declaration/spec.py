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

from symmech.algebra.sampling import atom_key
from symmech.declaration.admissible import NON_SMOOTH
from symmech.declaration.checks import (
    Field,
    Points,
    Problems,
    Reserved,
    SymbolRules,
    check_frame,
    check_independent,
    check_real,
    check_wall_gradient,
    constraint_row,
    metric_of_kinetic_energy,
    short,
)
from symmech.declaration.drawing import Drawing, check_drawing
from symmech.declaration.dynamic import dynamic_translation
from symmech.declaration.expressions import to_expression
from symmech.declaration.forces import forces_field
from symmech.declaration.structure import (
    _coordinate_symbols,
    _explicit_parameters,
    _items,
    _listed,
    _raw_matrix,
    _reserved_names,
    _sympy_symbols,
    _velocity_basis,
    _velocity_form_field,
    _wall_items,
)
from symmech.declaration.symbols import t as TIME
from symmech.declaration.symbols import velocity_of
from symmech.declaration.unsigned import check_metric_signs
from symmech.declaration.wall import Wall
from symmech.declaration.wallvelocity import check_wall_velocity, wall_velocity_field

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
    """
    problems = Problems()
    constraint_items = _items(constraints)
    forces = _listed(forces)
    walls_in: object = _listed(walls)
    dyn = dynamic_translation(
        coordinates,
        quasi_velocities,
        (metric, kinetic_energy, potential, forces, frame, constraint_items, walls_in),
    )
    if dyn is not None:
        coordinates, quasi_velocities = dyn.coordinates, dyn.quasi_velocities
        metric = dyn.expr(metric, "metric")
        kinetic_energy = dyn.expr(kinetic_energy, "kinetic_energy")
        potential = dyn.expr(potential, "potential")
        forces = dyn.expr(forces, "forces")
        frame = dyn.expr(frame, "frame")
        constraint_items = [
            dyn.expr(c, f"constraints[{a}]") for a, c in enumerate(constraint_items)
        ]
        if isinstance(walls_in, Wall):
            walls_in = [walls_in]
        if isinstance(walls_in, list | tuple):
            walls_in = [dyn.wall(w, f"walls[{k}]") for k, w in enumerate(walls_in)]

    # -- stage 1: structure ----------------------------------------------------------------
    q = _coordinate_symbols(coordinates)
    n = len(q)
    qd = tuple(velocity_of(c) for c in q)
    wall_list = _wall_items(walls_in, problems)
    v = _velocity_basis(frame, quasi_velocities, q, qd, problems)
    basis_ok = v is not None
    v = v if v is not None else qd
    has_frame = basis_ok and v != qd
    reserved = _reserved_names(q, qd, v if has_frame else ())
    explicit = None
    if parameters is not None:
        explicit = _explicit_parameters(parameters, reserved, problems)
        for p in explicit:
            reserved.setdefault(
                p.name, Reserved(p, f"the parameter {p}", "the symbol given in parameters=")
            )

    # the symbol table for string inputs: coordinates, velocities, t, parameters (declared,
    # or found in the sympy-valued inputs)
    table: dict[str, sp.Basic] = {name_: r.symbol for name_, r in reserved.items()}
    if explicit is None:
        found = _sympy_symbols(metric, kinetic_energy, potential, frame, constraint_items, forces)
        for w in wall_list:
            if isinstance(w, Wall):
                found |= _sympy_symbols(w.psi, w.impulsive_constraints, w.restitution)
        for s in sorted(found, key=atom_key):
            table.setdefault(s.name, s)

    def expr(value: object, label: str) -> sp.Expr | None:
        try:
            return to_expression(value, table, field=label)
        except ValueError as exc:
            problems.add(str(exc))
            return None

    def matrix(value: object, label: str) -> sp.Matrix | None:
        raw = _raw_matrix(value, label, n, problems)
        if raw is None:
            return None
        entries = [expr(raw[i][j], f"{label}[{i},{j}]") for i in range(n) for j in range(n)]
        return None if any(e is None for e in entries) else sp.Matrix(n, n, entries)

    q_set, t_set, v_set = frozenset(q), frozenset({TIME}), frozenset(v)
    fields: list[Field] = []
    S = G = T = None
    frame_field = metric_field = None
    about = problems.about
    if frame is not None:
        with about("frame"):
            S = matrix(frame, "frame")
        if S is not None:
            fields.append(frame_field := Field("frame", S, q_set))
    if (metric is None) == (kinetic_energy is None):
        with about("metric"):
            problems.add("metric: give exactly one of 'metric' and 'kinetic_energy'")
    elif metric is not None:
        with about("metric"):
            G = matrix(metric, "metric")
        if G is not None:
            fields.append(metric_field := Field("metric", G, q_set))
    else:
        with about("kinetic_energy"):
            T = expr(kinetic_energy, "kinetic_energy")
        if T is not None:
            fields.append(metric_field := Field("kinetic_energy", T, q_set | v_set, True))
    with about("potential"):
        V = expr(potential if potential is not None else 0, "potential")
    potential_field = None
    if V is not None:
        fields.append(potential_field := Field("potential", V, q_set | t_set))
    with about("forces"):
        force_field = forces_field(forces, n, q_set | v_set | t_set, expr, problems)
    if force_field is not None:
        fields.append(force_field)
    constraint_fields = []
    for a, c in enumerate(constraint_items):
        with about(f"constraints[{a}]"):
            constraint_fields.append(
                _velocity_form_field(c, f"constraints[{a}]", n, q_set, v_set, expr, problems)
            )
    fields += [f for f in constraint_fields if f is not None]
    wall_fields = []
    for k, w in enumerate(wall_list):
        key = f"walls[{k}]"
        label = key + (f" ({w.name!r})" if isinstance(w, Wall) and w.name else "")
        if not isinstance(w, Wall):
            with about(key, label):
                problems.add(f"{label}: expected a symmech.Wall, got {type(w).__name__}")
            continue
        with about(f"{key}.psi", f"{label}.psi"):
            psi = expr(w.psi, f"{label}.psi")
        psi_field = (
            Field(f"{label}.psi", psi, q_set | t_set, key=f"{key}.psi") if psi is not None else None
        )
        nu_fields = []
        for A, c in enumerate(w.impulsive_constraints):
            nu_label, nu_key = (
                f"{label}.impulsive_constraints[{A}]",
                f"{key}.impulsive_constraints[{A}]",
            )
            with about(nu_key, nu_label):
                nu_fields.append(
                    _velocity_form_field(
                        c, nu_label, n, q_set | t_set, v_set, expr, problems, key=nu_key
                    )
                )
        alpha = Field(
            f"{label}.restitution",
            sp.sympify(w.restitution, strict=True),
            frozenset(),
            key=f"{key}.restitution",
        )
        with about(f"{key}.velocity", f"{label}.velocity"):
            w_field = wall_velocity_field(w, label, n, q_set | t_set, expr, problems, key)
        wall_fields.append((key, label, w, psi_field, nu_fields, w_field))
        fields += [f for f in (psi_field, *nu_fields, alpha, w_field) if f is not None]
    names = [w.name for w in wall_list if isinstance(w, Wall) and w.name]
    dup = sorted({x for x in names if names.count(x) > 1})
    if dup:
        with about("walls"):
            problems.add(f"walls: names {dup} are used by more than one wall")

    # -- stage 2: symbols, field by field ----------------------------------------------------
    rules = SymbolRules(q, qd, v, has_frame, reserved, explicit)
    for f in fields:
        with about(f.path, f.label):
            rules.check(f, problems)
    with about("parameters"):
        params = explicit if explicit is not None else rules.default_parameters(problems)

    with about("drawing"):
        drawing_problems: list[str] = []
        drawn = check_drawing(drawing, [*q, *params, TIME], drawing_problems)
        for message in drawing_problems:
            problems.add(message)

    # -- stage 3: properties -------------------------------------------------------------------
    points = Points([*q, *params, TIME])
    if frame_field is not None and frame_field.ok:
        with about("frame"):
            check_frame(S, points, problems)
    assumed: tuple[sp.Symbol, ...] | None = None
    if metric_field is not None and metric_field.ok and G is not None:
        with about("metric"):
            assumed = check_metric_signs(G, "metric", points, problems, q, params)
    elif metric_field is not None and metric_field.ok and T is not None and basis_ok:
        with about("kinetic_energy"):
            G = metric_of_kinetic_energy(T, v, q, problems)
            if G is not None:
                label = "kinetic_energy (its metric, the Hessian of T)"
                assumed = check_metric_signs(G, label, points, problems, q, params, T)

    if potential_field is not None and potential_field.ok:
        with about("potential"):
            check_real(V, "potential", points, problems)
    F = sp.zeros(n, 1)
    if force_field is not None and force_field.ok:
        F = force_field.value
        for k, e in enumerate(F):
            with about(f"forces[{k}]"):
                check_real(e, f"forces[{k}]", points, problems)

    def form_rows(fields: Sequence[Field | None]) -> list[list[sp.Expr] | None]:
        """The rows of linear velocity forms, each checked in its own field (None where
        the field could not be read)."""
        out: list[list[sp.Expr] | None] = []
        for f in fields:
            if f is not None and f.ok and basis_ok:
                with about(f.path, f.label):
                    out.append(constraint_row(f, v, points, problems))
            else:
                out.append(None)
        return out

    rows = form_rows(constraint_fields)
    m = len(constraint_items)
    mu = sp.zeros(0, n)
    with about("constraints"):
        if m >= n:
            problems.add(
                f"constraints: {m} constraints for {n} coordinates leave no admissible motion;"
                " a scene needs fewer constraints than coordinates"
            )
        if m and all(r is not None for r in rows):
            mu = sp.Matrix(rows)
            if m < n:
                check_independent(mu, points, "constraints", problems)

    resolved: list[tuple[Wall, sp.Expr, sp.Matrix, sp.Matrix | None]] = []
    for key, label, w, psi_field, nu_fields, w_field in wall_fields:
        with about(f"{key}.psi", f"{label}.psi"):
            psi_value = psi_field.value if psi_field is not None and psi_field.ok else None
            if psi_value is not None and not (psi_value.free_symbols & q_set):
                problems.add(
                    f"{label}.psi = {short(psi_value)} does not depend on the coordinates {list(q)}"
                )
            elif psi_value is not None and check_real(psi_value, f"{label}.psi", points, problems):
                check_wall_gradient(psi_value, f"{label}.psi", q, points, problems)
        nu_rows = form_rows(nu_fields)
        if psi_field is None or any(r is None for r in nu_rows):
            continue
        nu = sp.Matrix(nu_rows) if nu_rows else sp.zeros(0, n)
        if nu.rows and mu.rows == m:
            with about(f"{key}.impulsive_constraints", f"{label}.impulsive_constraints"):
                check_independent(
                    mu.col_join(nu),
                    points,
                    f"{label}.impulsive_constraints (with the permanent constraints)",
                    problems,
                )
        W = None
        if w_field is not None and w_field.ok and psi_field.ok:
            with about(f"{key}.velocity", f"{label}.velocity"):
                if check_wall_velocity(
                    w_field.value, psi_field.value, label, q, S, points, problems
                ):
                    W = sp.ImmutableMatrix(w_field.value)
        resolved.append((w, psi_field.value, nu, W))
    problems.raise_if_any()

    walls_out = tuple(
        ResolvedWall(wall=w, psi=psi, impulsive_matrix=sp.ImmutableMatrix(nu), index=k, velocity=W)
        for k, (w, psi, nu, W) in enumerate(resolved)
    )
    return Declaration(
        coordinates=q,
        velocities=v,
        coordinate_velocities=qd,
        frame=sp.ImmutableMatrix(S) if S is not None else None,
        metric=sp.ImmutableMatrix(G),
        potential=sp.sympify(V, strict=True),
        forces=sp.ImmutableMatrix(F),
        constraint_matrix=sp.ImmutableMatrix(mu),
        walls=walls_out,
        parameters=tuple(params),
        name=name or "scene",
        kinetic_energy_given=T is not None,
        assumed_positive=assumed or (),
        metric_checked_at_run_time=assumed is not None,
        drawing=drawn,
    )
