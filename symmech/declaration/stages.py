"""The stages of :func:`symmech.declaration.spec.declare`: structure, fields, symbols,
properties.

:class:`_Inputs` holds the raw arguments (with dynamic symbols translated);
:class:`_Reader` reads them in four stages, collecting every problem in one
:class:`~symmech.declaration.checks.Problems` so the caller raises once with all of them
(the habit of sympy.physics.mechanics' ``System.validate``).  The rules themselves are in
:mod:`.checks`, :mod:`.structure`, :mod:`.forces`, :mod:`.wallvelocity` and
:mod:`.unsigned`; this module only orders them.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import sympy as sp

from symmech.algebra.sampling import atom_key
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

__all__ = ["_Inputs", "_Reader"]


@dataclass
class _Inputs:
    """The raw inputs of :func:`declare` (forces and walls as lists, constraints as items)."""

    coordinates: Sequence[sp.Symbol]
    metric: object
    kinetic_energy: object
    potential: object
    forces: object
    constraints: list
    frame: object
    quasi_velocities: Sequence[sp.Symbol] | None
    walls: object
    parameters: Sequence[sp.Symbol] | None

    def translated(self) -> _Inputs:
        """The inputs with dynamic symbols (``q(t)``, ``q(t).diff(t)``, as in
        sympy.physics.mechanics) replaced by plain coordinates and velocities
        (:func:`~symmech.declaration.dynamic.dynamic_translation`), or unchanged."""
        dyn = dynamic_translation(
            self.coordinates,
            self.quasi_velocities,
            (
                self.metric,
                self.kinetic_energy,
                self.potential,
                self.forces,
                self.frame,
                self.constraints,
                self.walls,
            ),
        )
        if dyn is None:
            return self
        walls = self.walls
        if isinstance(walls, Wall):
            walls = [walls]
        if isinstance(walls, list | tuple):
            walls = [dyn.wall(w, f"walls[{k}]") for k, w in enumerate(walls)]
        return _Inputs(
            dyn.coordinates,
            dyn.expr(self.metric, "metric"),
            dyn.expr(self.kinetic_energy, "kinetic_energy"),
            dyn.expr(self.potential, "potential"),
            dyn.expr(self.forces, "forces"),
            [dyn.expr(c, f"constraints[{a}]") for a, c in enumerate(self.constraints)],
            dyn.expr(self.frame, "frame"),
            dyn.quasi_velocities,
            walls,
            self.parameters,
        )


@dataclass
class _WallFields:
    """A wall's fields as read: its key and label for messages, the Wall, and the fields
    of psi, of its impulsive constraints and of its velocity (None where unreadable)."""

    key: str
    label: str
    wall: Wall
    psi: Field | None
    nu: list[Field | None]
    velocity: Field | None


class _Reader:
    """The stages of :func:`declare`, every problem collected in :attr:`problems`.

    1. structure (:meth:`__init__`): coordinates, velocity basis, reserved names, the
       symbol table for text inputs;
    2. the fields (:meth:`read_fields`): frame, metric or kinetic energy, potential,
       forces, constraints, walls, each parsed into a :class:`Field`;
    3. symbols (:meth:`check_symbols`): each field's symbols against the rules, the
       parameters, the drawing;
    4. properties (:meth:`check_properties`, :meth:`resolve_walls`): the frame invertible,
       the metric positive definite, everything real, the constraint rows independent,
       the walls' gradients, impulsive constraints and velocities, at sampled points.
    """

    def __init__(self, inputs: _Inputs):
        self.inputs = inputs
        self.problems = problems = Problems()
        self.q = q = _coordinate_symbols(inputs.coordinates)
        self.n = len(q)
        self.qd = qd = tuple(velocity_of(c) for c in q)
        self.wall_list = _wall_items(inputs.walls, problems)
        v = _velocity_basis(inputs.frame, inputs.quasi_velocities, q, qd, problems)
        self.basis_ok = v is not None
        self.v = v if v is not None else qd
        self.has_frame = self.basis_ok and self.v != qd
        self.reserved = reserved = _reserved_names(q, qd, self.v if self.has_frame else ())
        self.explicit: tuple[sp.Symbol, ...] | None = None
        if inputs.parameters is not None:
            self.explicit = tuple(_explicit_parameters(inputs.parameters, reserved, problems))
            for p in self.explicit:
                reserved.setdefault(
                    p.name, Reserved(p, f"the parameter {p}", "the symbol given in parameters=")
                )
        # the symbol table for string inputs: coordinates, velocities, t, parameters
        # (declared, or found in the sympy-valued inputs)
        self.table: dict[str, sp.Basic] = {key: r.symbol for key, r in reserved.items()}
        if self.explicit is None:
            i = inputs
            found = _sympy_symbols(
                i.metric, i.kinetic_energy, i.potential, i.frame, i.constraints, i.forces
            )
            for w in self.wall_list:
                if isinstance(w, Wall):
                    found |= _sympy_symbols(w.psi, w.impulsive_constraints, w.restitution)
            for s in sorted(found, key=atom_key):
                self.table.setdefault(s.name, s)
        self.q_set, self.t_set, self.v_set = frozenset(q), frozenset({TIME}), frozenset(self.v)
        self.fields: list[Field] = []
        self.S: sp.Matrix | None = None
        self.G: sp.Matrix | None = None
        self.T: sp.Expr | None = None
        self.V: sp.Expr | None = None
        self.F = sp.zeros(self.n, 1)
        self.mu = sp.zeros(0, self.n)
        self.frame_field: Field | None = None
        self.metric_field: Field | None = None
        self.potential_field: Field | None = None
        self.force_field: Field | None = None
        self.constraint_fields: list[Field | None] = []
        self.wall_fields: list[_WallFields] = []
        self.params: Sequence[sp.Symbol] = ()
        self.drawn: Drawing | None = None
        self._points: Points | None = None
        self.assumed: tuple[sp.Symbol, ...] | None = None

    @property
    def points(self) -> Points:
        """The sampled points of stage 4 (made once the parameters are known)."""
        assert self._points is not None, "check_properties() makes the points"
        return self._points

    # -- reading text and matrices -----------------------------------------------------------
    def expr(self, value: object, label: str) -> sp.Expr | None:
        try:
            return to_expression(value, self.table, field=label)
        except ValueError as exc:
            self.problems.add(str(exc))
            return None

    def matrix(self, value: object, label: str) -> sp.Matrix | None:
        n = self.n
        raw = _raw_matrix(value, label, n, self.problems)
        if raw is None:
            return None
        entries = [self.expr(raw[i][j], f"{label}[{i},{j}]") for i in range(n) for j in range(n)]
        return None if any(e is None for e in entries) else sp.Matrix(n, n, entries)

    # -- stage 2 -------------------------------------------------------------------------------
    def read_fields(self) -> None:
        """Every input parsed into a :class:`Field` (or a problem)."""
        i, about, fields = self.inputs, self.problems.about, self.fields
        q_set, t_set, v_set = self.q_set, self.t_set, self.v_set
        if i.frame is not None:
            with about("frame"):
                self.S = self.matrix(i.frame, "frame")
            if self.S is not None:
                fields.append(frame_field := Field("frame", self.S, q_set))
                self.frame_field = frame_field
        self._read_metric()
        with about("potential"):
            self.V = self.expr(i.potential if i.potential is not None else 0, "potential")
        if self.V is not None:
            self.potential_field = Field("potential", self.V, q_set | t_set)
            fields.append(self.potential_field)
        with about("forces"):
            self.force_field = forces_field(
                i.forces, self.n, q_set | v_set | t_set, self.expr, self.problems
            )
        if self.force_field is not None:
            fields.append(self.force_field)
        for a, c in enumerate(i.constraints):
            with about(f"constraints[{a}]"):
                self.constraint_fields.append(
                    _velocity_form_field(
                        c, f"constraints[{a}]", self.n, q_set, v_set, self.expr, self.problems
                    )
                )
        fields += [f for f in self.constraint_fields if f is not None]
        for k, w in enumerate(self.wall_list):
            self._read_wall(k, w)
        names = [w.name for w in self.wall_list if isinstance(w, Wall) and w.name]
        dup = sorted({x for x in names if names.count(x) > 1})
        if dup:
            with about("walls"):
                self.problems.add(f"walls: names {dup} are used by more than one wall")

    def _read_metric(self) -> None:
        i, about = self.inputs, self.problems.about
        if (i.metric is None) == (i.kinetic_energy is None):
            with about("metric"):
                self.problems.add("metric: give exactly one of 'metric' and 'kinetic_energy'")
        elif i.metric is not None:
            with about("metric"):
                self.G = self.matrix(i.metric, "metric")
            if self.G is not None:
                self.metric_field = Field("metric", self.G, self.q_set)
                self.fields.append(self.metric_field)
        else:
            with about("kinetic_energy"):
                self.T = self.expr(i.kinetic_energy, "kinetic_energy")
            if self.T is not None:
                self.metric_field = Field("kinetic_energy", self.T, self.q_set | self.v_set, True)
                self.fields.append(self.metric_field)

    def _read_wall(self, k: int, w: object) -> None:
        about, problems = self.problems.about, self.problems
        qt = self.q_set | self.t_set
        key = f"walls[{k}]"
        label = key + (f" ({w.name!r})" if isinstance(w, Wall) and w.name else "")
        if not isinstance(w, Wall):
            with about(key, label):
                problems.add(f"{label}: expected a symmech.Wall, got {type(w).__name__}")
            return
        with about(f"{key}.psi", f"{label}.psi"):
            psi = self.expr(w.psi, f"{label}.psi")
        psi_field = Field(f"{label}.psi", psi, qt, key=f"{key}.psi") if psi is not None else None
        nu_fields: list[Field | None] = []
        for A, c in enumerate(w.impulsive_constraints):
            nu_label = f"{label}.impulsive_constraints[{A}]"
            nu_key = f"{key}.impulsive_constraints[{A}]"
            with about(nu_key, nu_label):
                nu_fields.append(
                    _velocity_form_field(
                        c, nu_label, self.n, qt, self.v_set, self.expr, problems, key=nu_key
                    )
                )
        alpha = Field(
            f"{label}.restitution",
            sp.sympify(w.restitution, strict=True),
            frozenset(),
            key=f"{key}.restitution",
        )
        with about(f"{key}.velocity", f"{label}.velocity"):
            w_field = wall_velocity_field(w, label, self.n, qt, self.expr, problems, key)
        self.wall_fields.append(_WallFields(key, label, w, psi_field, nu_fields, w_field))
        self.fields += [f for f in (psi_field, *nu_fields, alpha, w_field) if f is not None]

    # -- stage 3 -------------------------------------------------------------------------------
    def check_symbols(self, drawing: object) -> None:
        """Each field's symbols against the rules; the parameters; the drawing."""
        about = self.problems.about
        rules = SymbolRules(self.q, self.qd, self.v, self.has_frame, self.reserved, self.explicit)
        for f in self.fields:
            with about(f.path, f.label):
                rules.check(f, self.problems)
        with about("parameters"):
            self.params = (
                self.explicit
                if self.explicit is not None
                else rules.default_parameters(self.problems)
            )
        with about("drawing"):
            drawing_problems: list[str] = []
            self.drawn = check_drawing(drawing, [*self.q, *self.params, TIME], drawing_problems)
            for message in drawing_problems:
                self.problems.add(message)

    # -- stage 4 -------------------------------------------------------------------------------
    def check_properties(self) -> None:
        """The frame, the metric, the potential, the forces and the constraints at the
        sampled points."""
        about, problems, q, params = self.problems.about, self.problems, self.q, self.params
        self._points = points = Points([*q, *params, TIME])
        if self.frame_field is not None and self.frame_field.ok:
            with about("frame"):
                check_frame(self.S, points, problems)
        if self.metric_field is not None and self.metric_field.ok and self.G is not None:
            with about("metric"):
                self.assumed = check_metric_signs(self.G, "metric", points, problems, q, params)
        elif self.metric_field is not None and self.metric_field.ok and self.T is not None:
            if self.basis_ok:
                with about("kinetic_energy"):
                    self.G = metric_of_kinetic_energy(self.T, self.v, q, problems)
                    if self.G is not None:
                        label = "kinetic_energy (its metric, the Hessian of T)"
                        self.assumed = check_metric_signs(
                            self.G, label, points, problems, q, params, self.T
                        )
        if self.potential_field is not None and self.potential_field.ok:
            with about("potential"):
                check_real(self.V, "potential", points, problems)
        if self.force_field is not None and self.force_field.ok:
            self.F = self.force_field.value
            for k, e in enumerate(self.F):
                with about(f"forces[{k}]"):
                    check_real(e, f"forces[{k}]", points, problems)
        self._check_constraints()

    def form_rows(self, fields: Sequence[Field | None]) -> list[list[sp.Expr] | None]:
        """The rows of linear velocity forms, each checked in its own field (None where
        the field could not be read)."""
        out: list[list[sp.Expr] | None] = []
        for f in fields:
            if f is not None and f.ok and self.basis_ok:
                with self.problems.about(f.path, f.label):
                    out.append(constraint_row(f, self.v, self.points, self.problems))
            else:
                out.append(None)
        return out

    def _check_constraints(self) -> None:
        rows = self.form_rows(self.constraint_fields)
        m, n = len(self.inputs.constraints), self.n
        with self.problems.about("constraints"):
            if m >= n:
                self.problems.add(
                    f"constraints: {m} constraints for {n} coordinates leave no admissible"
                    " motion; a scene needs fewer constraints than coordinates"
                )
            if m and all(r is not None for r in rows):
                self.mu = sp.Matrix(rows)
                if m < n:
                    check_independent(self.mu, self.points, "constraints", self.problems)

    def resolve_walls(self) -> list[tuple[Wall, sp.Expr, sp.Matrix, sp.ImmutableMatrix | None]]:
        """Each readable wall checked (psi depends on q, is real, has a gradient; the
        impulsive constraints are independent of the permanent ones; the wall velocity
        moves with the wall): ``(wall, psi, impulsive rows, velocity or None)``."""
        about, problems, points = self.problems.about, self.problems, self.points
        m = len(self.inputs.constraints)
        resolved: list[tuple[Wall, sp.Expr, sp.Matrix, sp.ImmutableMatrix | None]] = []
        for wf in self.wall_fields:
            key, label = wf.key, wf.label
            with about(f"{key}.psi", f"{label}.psi"):
                psi_value = wf.psi.value if wf.psi is not None and wf.psi.ok else None
                if psi_value is not None and not (psi_value.free_symbols & self.q_set):
                    problems.add(
                        f"{label}.psi = {short(psi_value)} does not depend on the coordinates"
                        f" {list(self.q)}"
                    )
                elif psi_value is not None and check_real(
                    psi_value, f"{label}.psi", points, problems
                ):
                    check_wall_gradient(psi_value, f"{label}.psi", self.q, points, problems)
            nu_rows = self.form_rows(wf.nu)
            if wf.psi is None or any(r is None for r in nu_rows):
                continue
            nu = sp.Matrix(nu_rows) if nu_rows else sp.zeros(0, self.n)
            if nu.rows and self.mu.rows == m:
                with about(f"{key}.impulsive_constraints", f"{label}.impulsive_constraints"):
                    check_independent(
                        self.mu.col_join(nu),
                        points,
                        f"{label}.impulsive_constraints (with the permanent constraints)",
                        problems,
                    )
            W = None
            if wf.velocity is not None and wf.velocity.ok and wf.psi.ok:
                with about(f"{key}.velocity", f"{label}.velocity"):
                    if check_wall_velocity(
                        wf.velocity.value, wf.psi.value, label, self.q, self.S, points, problems
                    ):
                        W = sp.ImmutableMatrix(wf.velocity.value)
            resolved.append((wf.wall, wf.psi.value, nu, W))
        return resolved
