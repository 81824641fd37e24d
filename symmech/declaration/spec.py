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
   depend on the coordinates.

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

import itertools
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass

import sympy as sp
from sympy.core.function import AppliedUndef

from symmech.declaration.admissible import NON_SMOOTH, expression_problems
from symmech.declaration.definiteness import definiteness
from symmech.declaration.expressions import to_expression
from symmech.declaration.numeric import (
    EvaluationError,
    classify_symmetric,
    proven_real,
    proven_sign,
    rank_at,
    real_values,
    vanishes,
)
from symmech.declaration.quadratic import (
    NotQuadraticError,
    linear_form_row,
    metric_from_kinetic_energy,
)
from symmech.declaration.sampling import atom_key, sample_points
from symmech.declaration.symbols import t as TIME
from symmech.declaration.symbols import velocity_of
from symmech.declaration.wall import Wall
from symmech.declaration.wallpoints import vanishing_gradient
from symmech.errors import SceneError, UndecidedWarning

__all__ = ["NON_SMOOTH", "Declaration", "ResolvedWall", "declare"]

_SAMPLES = 4
#: ... and points away from the origin (angles near +-pi), see sampling.sample_points.
_FAR_SAMPLES = 2
_EXTRA_SEED = 19970521  # seed of the values of velocities and undefined functions


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

    @property
    def name(self) -> str:
        return self.wall.name or f"wall{self.index}"

    @property
    def restitution(self) -> sp.Expr:
        return self.wall.restitution

    @property
    def law(self) -> str:
        return self.wall.law

    @property
    def moving(self) -> bool:
        return TIME in self.psi.free_symbols


@dataclass(frozen=True)
class Declaration:
    """A validated mechanical system in normal form (see the module docstring)."""

    coordinates: tuple[sp.Symbol, ...]
    velocities: tuple[sp.Symbol, ...]  # the velocity basis: q_dot symbols, or quasi-velocities
    coordinate_velocities: tuple[sp.Symbol, ...]
    frame: sp.ImmutableMatrix | None  # q_dot = frame * velocities; None means identity
    metric: sp.ImmutableMatrix
    potential: sp.Expr
    constraint_matrix: sp.ImmutableMatrix  # m x n
    walls: tuple[ResolvedWall, ...]
    parameters: tuple[sp.Symbol, ...]
    name: str
    kinetic_energy_given: bool

    @property
    def n(self) -> int:
        return len(self.coordinates)

    @property
    def m(self) -> int:
        return self.constraint_matrix.rows

    @property
    def has_frame(self) -> bool:
        return self.frame is not None

    def q_dot(self) -> sp.ImmutableMatrix:
        """q_dot as a column in the velocity basis: ``S v`` with a frame, else the q_dot symbols."""
        v = sp.Matrix(self.velocities)
        return sp.ImmutableMatrix(v if self.frame is None else self.frame * v)


# ---------------------------------------------------------------------------------------
# helpers


def _short(expr: object, limit: int = 60) -> str:
    s = str(expr)
    return s if len(s) <= limit else s[: limit - 3] + "..."


def _entries(expr: sp.Basic | sp.MatrixBase) -> list[sp.Basic]:
    return list(expr) if isinstance(expr, sp.MatrixBase) else [expr]


def _non_smooth(expr: sp.Basic | sp.MatrixBase) -> list[str]:
    applied = set().union(*[e.atoms(sp.Function, sp.Max, sp.Min) for e in _entries(expr)])
    return sorted({type(f).__name__ for f in applied if isinstance(f, NON_SMOOTH)})


def _unknown_functions(expr: sp.Basic | sp.MatrixBase) -> set[sp.Basic]:
    """Undefined applied functions g(x) and their derivatives: atoms without a formula."""
    return {a for a in _atoms(expr) if not isinstance(a, sp.Symbol)}


def _atoms(*exprs: sp.Basic | sp.MatrixBase) -> set[sp.Basic]:
    """Free symbols, undefined functions g(x) and derivatives of them, in one walk that
    visits each shared subtree once."""
    out: set[sp.Basic] = set()
    seen: set[sp.Basic] = set()
    stack = [e for x in exprs for e in _entries(x)]
    while stack:
        e = stack.pop()
        if e in seen:
            continue
        seen.add(e)
        if isinstance(e, AppliedUndef | sp.Derivative):
            out.add(e)
            out |= e.free_symbols
        elif isinstance(e, sp.Symbol):
            out.add(e)
        elif e.args:
            stack.extend(e.args)
    return out


def _assumptions(s: sp.Symbol) -> str:
    if isinstance(s, sp.Dummy):
        return "(a sympy Dummy)"
    orig = getattr(s, "_assumptions_orig", None)
    if orig is None:  # pragma: no cover - sympy < 1.12
        orig = {k: v for k, v in s.assumptions0.items() if k != "commutative"}
    items = [f"{k}={v}" for k, v in sorted(orig.items()) if k != "commutative" or not v]
    return f"({', '.join(items)})" if items else "(no assumptions)"


def _differs(s: sp.Symbol) -> str:
    return "is a sympy Dummy" if isinstance(s, sp.Dummy) else "different assumptions"


def _at(point: Mapping, about: sp.Basic | sp.MatrixBase) -> str:
    """`` at the sampled point {x=1/2, y=-3/4}`` for the atoms of ``about`` (empty for a
    constant)."""
    keep = _atoms(about)
    items = sorted((kv for kv in point.items() if kv[0] in keep), key=lambda kv: atom_key(kv[0]))
    if not items:
        return ""
    return " at the sampled point {" + ", ".join(f"{k}={v}" for k, v in items) + "}"


class _Problems:
    def __init__(self) -> None:
        self.items: list[str] = []

    def add(self, message: str) -> None:
        self.items.append(message)

    def raise_if_any(self) -> None:
        if self.items:
            raise SceneError(self.items)


@dataclass
class _Field:
    """One field of the declaration, as parsed: an expression or a matrix of them."""

    label: str
    value: sp.Basic | sp.MatrixBase
    allowed: frozenset  # symbols it may contain besides the parameters
    in_velocities: bool = False  # written in the velocities (T, a constraint expression)
    ok: bool = True  # no problem with its symbols: its properties can be checked

    @property
    def symbols(self) -> set[sp.Symbol]:
        return set().union(*[e.free_symbols for e in _entries(self.value)])


@dataclass(frozen=True)
class _Reserved:
    symbol: sp.Symbol
    role: str  # "the coordinate r"
    use: str  # what to write instead


class _Points:
    """Sample points: coordinates, parameters and t as in every check of symmech, plus
    values for any other atom an expression contains (velocities, undefined functions)."""

    def __init__(self, base_symbols: Iterable[sp.Symbol]):
        self.base = sample_points(base_symbols, count=_SAMPLES, far=_FAR_SAMPLES)

    def for_(self, *exprs: sp.Basic | sp.MatrixBase) -> list[dict]:
        missing = _atoms(*exprs) - set(self.base[0])
        if not missing:
            return self.base
        extra = sample_points(missing, count=len(self.base), seed=_EXTRA_SEED)
        return [{**b, **x} for b, x in zip(self.base, extra, strict=True)]


# ---------------------------------------------------------------------------------------
# the builder


def declare(
    coordinates: Sequence[sp.Symbol],
    *,
    metric: object = None,
    kinetic_energy: object = None,
    potential: object = 0,
    constraints: Iterable = (),
    frame: object = None,
    quasi_velocities: Sequence[sp.Symbol] | None = None,
    walls: Iterable[Wall] = (),
    parameters: Sequence[sp.Symbol] | None = None,
    name: str | None = None,
) -> Declaration:
    """Validate a scene's inputs and return its :class:`Declaration`.

    Raises :class:`~symmech.SceneError` listing every problem found (see the module
    docstring for the rules).  See :class:`symmech.Scene` for the meaning of the arguments.
    """
    problems = _Problems()

    # -- stage 1: structure ----------------------------------------------------------------
    q = _coordinate_symbols(coordinates)
    n = len(q)
    qd = tuple(velocity_of(c) for c in q)
    constraint_items = _items(constraints)
    wall_list = _wall_items(walls, problems)
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
                p.name, _Reserved(p, f"the parameter {p}", "the symbol given in parameters=")
            )

    # the symbol table for string inputs: coordinates, velocities, t, parameters (declared,
    # or found in the sympy-valued inputs)
    table: dict[str, sp.Basic] = {name_: r.symbol for name_, r in reserved.items()}
    if explicit is None:
        found = _sympy_symbols(metric, kinetic_energy, potential, frame, constraint_items)
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
    fields: list[_Field] = []
    S = G = T = None
    frame_field = metric_field = None
    if frame is not None:
        S = matrix(frame, "frame")
        if S is not None:
            fields.append(frame_field := _Field("frame", S, q_set))
    if (metric is None) == (kinetic_energy is None):
        problems.add("metric: give exactly one of 'metric' and 'kinetic_energy'")
    elif metric is not None:
        G = matrix(metric, "metric")
        if G is not None:
            fields.append(metric_field := _Field("metric", G, q_set))
    else:
        T = expr(kinetic_energy, "kinetic_energy")
        if T is not None:
            fields.append(metric_field := _Field("kinetic_energy", T, q_set | v_set, True))
    V = expr(potential if potential is not None else 0, "potential")
    potential_field = None
    if V is not None:
        fields.append(potential_field := _Field("potential", V, q_set | t_set))
    constraint_fields = [
        _velocity_form_field(c, f"constraints[{a}]", n, q_set, v_set, expr, problems)
        for a, c in enumerate(constraint_items)
    ]
    fields += [f for f in constraint_fields if f is not None]
    wall_fields = []
    for k, w in enumerate(wall_list):
        label = f"walls[{k}]" + (f" ({w.name!r})" if isinstance(w, Wall) and w.name else "")
        if not isinstance(w, Wall):
            problems.add(f"{label}: expected a symmech.Wall, got {type(w).__name__}")
            continue
        psi = expr(w.psi, f"{label}.psi")
        psi_field = _Field(f"{label}.psi", psi, q_set | t_set) if psi is not None else None
        nu_fields = [
            _velocity_form_field(
                c, f"{label}.impulsive_constraints[{A}]", n, q_set | t_set, v_set, expr, problems
            )
            for A, c in enumerate(w.impulsive_constraints)
        ]
        alpha = _Field(f"{label}.restitution", sp.sympify(w.restitution), frozenset())
        wall_fields.append((k, label, w, psi_field, nu_fields))
        fields += [f for f in (psi_field, *nu_fields, alpha) if f is not None]
    names = [w.name for w in wall_list if isinstance(w, Wall) and w.name]
    dup = sorted({x for x in names if names.count(x) > 1})
    if dup:
        problems.add(f"walls: names {dup} are used by more than one wall")

    # -- stage 2: symbols, field by field ----------------------------------------------------
    rules = _SymbolRules(q, qd, v, has_frame, reserved, explicit)
    for f in fields:
        rules.check(f, problems)
    params = explicit if explicit is not None else rules.default_parameters(problems)

    # -- stage 3: properties -------------------------------------------------------------------
    points = _Points([*q, *params, TIME])
    if frame_field is not None and frame_field.ok:
        _check_frame(S, points, problems)
    if metric_field is not None and metric_field.ok and G is not None:
        _check_metric(G, "metric", points, problems, q)
    elif metric_field is not None and metric_field.ok and T is not None and basis_ok:
        G = _metric_from_kinetic_energy(T, v, q, problems)
        if G is not None:
            _check_metric(
                G, "kinetic_energy (its metric, the Hessian of T)", points, problems, q, T
            )

    if potential_field is not None and potential_field.ok:
        _check_real(V, "potential", points, problems)

    rows = [
        _constraint_row(f, v, points, problems) if f is not None and f.ok and basis_ok else None
        for f in constraint_fields
    ]
    m = len(constraint_items)
    mu = sp.zeros(0, n)
    if m >= n:
        problems.add(
            f"constraints: {m} constraints for {n} coordinates leave no admissible motion;"
            " a scene needs fewer constraints than coordinates"
        )
    if m and all(r is not None for r in rows):
        mu = sp.Matrix(rows)
        if m < n:
            _check_independent(mu, points, "constraints", problems)

    resolved: list[tuple[Wall, sp.Expr, sp.Matrix]] = []
    for _k, label, w, psi_field, nu_fields in wall_fields:
        if psi_field is not None and psi_field.ok and not (psi_field.value.free_symbols & q_set):
            problems.add(
                f"{label}.psi = {_short(psi_field.value)} does not depend on the coordinates"
                f" {list(q)}"
            )
        elif (
            psi_field is not None
            and psi_field.ok
            and _check_real(psi_field.value, f"{label}.psi", points, problems)
        ):
            _check_wall_gradient(psi_field.value, f"{label}.psi", q, points, problems)
        nu_rows = [
            _constraint_row(f, v, points, problems) if f is not None and f.ok and basis_ok else None
            for f in nu_fields
        ]
        if psi_field is None or any(r is None for r in nu_rows):
            continue
        nu = sp.Matrix(nu_rows) if nu_rows else sp.zeros(0, n)
        if nu.rows and mu.rows == m:
            _check_independent(
                mu.col_join(nu),
                points,
                f"{label}.impulsive_constraints (with the permanent constraints)",
                problems,
            )
        resolved.append((w, psi_field.value, nu))
    problems.raise_if_any()

    walls_out = tuple(
        ResolvedWall(wall=w, psi=psi, impulsive_matrix=sp.ImmutableMatrix(nu), index=k)
        for k, (w, psi, nu) in enumerate(resolved)
    )
    return Declaration(
        coordinates=q,
        velocities=v,
        coordinate_velocities=qd,
        frame=sp.ImmutableMatrix(S) if S is not None else None,
        metric=sp.ImmutableMatrix(G),
        potential=sp.sympify(V),
        constraint_matrix=sp.ImmutableMatrix(mu),
        walls=walls_out,
        parameters=tuple(params),
        name=name or "scene",
        kinetic_energy_given=T is not None,
    )


# ---------------------------------------------------------------------------------------
# stage 1: structure


def _coordinate_symbols(coordinates: object) -> tuple[sp.Symbol, ...]:
    """The coordinates; a problem here stops validation (nothing can be checked without)."""
    if isinstance(coordinates, sp.Symbol):
        coordinates = (coordinates,)
    try:
        q = tuple(coordinates)
    except TypeError:
        raise SceneError(
            f"coordinates: expected a sequence of sympy Symbols, got {coordinates!r}"
        ) from None
    if not q:
        raise SceneError("coordinates: a scene needs at least one coordinate")
    bad = [c for c in q if not isinstance(c, sp.Symbol)]
    if bad:
        raise SceneError(f"coordinates: {bad} are not sympy Symbols (use symmech.coordinates)")
    if len(set(q)) != len(q) or len({c.name for c in q}) != len(q):
        raise SceneError(f"coordinates: repeated coordinates (or names) in {list(q)}")
    if TIME in q or any(c.name == "t" for c in q):
        raise SceneError("coordinates: 't' is reserved for time (symmech.t)")
    velocity_names = {velocity_of(c).name for c in q}
    clash = [c for c in q if c.name in velocity_names]
    if clash:
        raise SceneError(f"coordinates: {clash} collide with velocity names of other coordinates")
    return q


def _velocity_basis(
    frame: object,
    quasi_velocities: object,
    q: tuple[sp.Symbol, ...],
    qd: tuple[sp.Symbol, ...],
    problems: _Problems,
) -> tuple[sp.Symbol, ...] | None:
    """The velocity basis: the quasi-velocities with a frame, else q_dot; None if invalid."""
    n = len(q)
    if (frame is None) != (quasi_velocities is None):
        problems.add("frame: 'frame' and 'quasi_velocities' must be given together")
        return None
    if quasi_velocities is None:
        return qd
    if isinstance(quasi_velocities, sp.Symbol):
        quasi_velocities = (quasi_velocities,)
    try:
        v = tuple(quasi_velocities)
    except TypeError:
        problems.add(f"quasi_velocities: expected {n} sympy Symbols, got {quasi_velocities!r}")
        return None
    if len(v) != n or not all(isinstance(s, sp.Symbol) for s in v):
        problems.add(
            f"quasi_velocities: expected {n} sympy Symbols (one per coordinate), got {list(v)}"
        )
        return None
    taken = {s.name for s in (*q, *qd, TIME)}
    if len({s.name for s in v}) != n or any(s.name in taken for s in v):
        problems.add(
            f"quasi_velocities: {list(v)} must have distinct names, different from the"
            " coordinates, their velocities and t"
        )
        return None
    return v


def _reserved_names(
    q: Sequence[sp.Symbol], qd: Sequence[sp.Symbol], v: Sequence[sp.Symbol]
) -> dict[str, _Reserved]:
    out = {TIME.name: _Reserved(TIME, "the time t", "symmech.t")}
    for c in q:
        out[c.name] = _Reserved(c, f"the coordinate {c}", "the coordinate (symmech.coordinates)")
    for c, d in zip(q, qd, strict=True):
        out[d.name] = _Reserved(d, f"the velocity {d} of coordinate {c}", "symmech.velocities")
    for s in v:
        out[s.name] = _Reserved(s, f"the quasi-velocity {s}", "the symbol in quasi_velocities")
    return out


def _explicit_parameters(
    parameters: object, reserved: Mapping[str, _Reserved], problems: _Problems
) -> tuple[sp.Symbol, ...]:
    """The declared parameters that are usable (each problem is recorded)."""
    if isinstance(parameters, sp.Symbol):
        parameters = (parameters,)
    try:
        given = tuple(parameters)
    except TypeError:
        problems.add(f"parameters: expected a sequence of sympy Symbols, got {parameters!r}")
        return ()
    bad = [p for p in given if not isinstance(p, sp.Symbol)]
    if bad:
        problems.add(f"parameters: {bad} are not sympy Symbols")
    out: list[sp.Symbol] = []
    by_name: dict[str, sp.Symbol] = {}
    for p in given:
        if not isinstance(p, sp.Symbol):
            continue
        r = reserved.get(p.name)
        if r is not None:
            if r.symbol == p:
                problems.add(f"parameters: {p} is {r.role}, not a parameter")
            else:
                problems.add(
                    f"parameters: symbol {p} {_assumptions(p)} has the same name as {r.role}"
                    f" {_assumptions(r.symbol)} but {_differs(p)}; a name denotes one"
                    f" symbol (use {r.use})"
                )
            continue
        if p.name in by_name:
            first = by_name[p.name]
            if first == p:
                problems.add(f"parameters: {p} is listed more than once")
            else:
                problems.add(
                    f"parameters: symbols {first} {_assumptions(first)} and {p}"
                    f" {_assumptions(p)} share the name {p.name!r} with different assumptions;"
                    " a name denotes one symbol"
                )
            continue
        by_name[p.name] = p
        out.append(p)
    return tuple(out)


def _items(constraints: object) -> list[object]:
    """The constraints as a list (a generator is read once)."""
    if constraints is None:
        return []
    if isinstance(constraints, sp.MatrixBase):
        return [list(constraints.row(i)) for i in range(constraints.rows)]
    if isinstance(constraints, (str, sp.Basic)):
        return [constraints]
    try:
        return list(constraints)
    except TypeError:
        return [constraints]


def _wall_items(walls: object, problems: _Problems) -> list[object]:
    if walls is None:
        return []
    if isinstance(walls, Wall):
        return [walls]
    try:
        return list(walls)
    except TypeError:
        problems.add(f"walls: expected a list of symmech.Wall, got {walls!r}")
        return []


def _sympy_symbols(*values: object) -> set[sp.Symbol]:
    """Free symbols of every sympy object inside ``values`` (nested lists, matrices)."""
    out: set[sp.Symbol] = set()
    stack = list(values)
    while stack:
        value = stack.pop()
        if isinstance(value, sp.Basic | sp.MatrixBase):
            out |= {s for s in value.free_symbols if isinstance(s, sp.Symbol)}
        elif isinstance(value, list | tuple):
            stack.extend(value)
    return out


def _raw_matrix(value: object, field: str, n: int, problems: _Problems) -> list | None:
    """Rows of an n x n matrix input, entries untouched (strings are parsed later)."""
    if isinstance(value, sp.MatrixBase):
        rows = [list(value.row(i)) for i in range(value.rows)]
    elif isinstance(value, (str, bytes)) or not hasattr(value, "__iter__"):
        problems.add(
            f"{field}: expected a square matrix (sympy Matrix or nested lists), got {value!r}"
        )
        return None
    else:
        rows = [
            list(r) if hasattr(r, "__iter__") and not isinstance(r, (str, bytes)) else None
            for r in value
        ]
        if any(r is None for r in rows):
            problems.add(f"{field}: expected a matrix given as a list of rows, got {value!r}")
            return None
        if len({len(r) for r in rows}) > 1:
            problems.add(f"{field}: rows of different lengths {[len(r) for r in rows]}")
            return None
    shape = (len(rows), len(rows[0]) if rows else 0)
    if shape != (n, n):
        if shape[0] != shape[1]:
            problems.add(f"{field}: not square, shape {shape}")
        else:
            what = "q_dot = S v" if field == "frame" else "one row per coordinate"
            problems.add(
                f"{field}: shape {shape} does not match the {n} coordinates (expected {n} x {n},"
                f" {what})"
            )
        return None
    return rows


def _velocity_form_field(
    c: object,
    label: str,
    n: int,
    allowed: frozenset,
    v_set: frozenset,
    expr: Callable[[object, str], sp.Expr | None],
    problems: _Problems,
) -> _Field | None:
    """A constraint: a coefficient row (n entries) or an expression linear in the velocities."""
    if isinstance(c, (list, tuple, sp.MatrixBase)):
        entries = list(c)
        if len(entries) != n:
            problems.add(f"{label}: a coefficient row needs {n} entries, got {len(entries)}")
            return None
        out = [expr(e, f"{label}[{j}]") for j, e in enumerate(entries)]
        if any(o is None for o in out):
            return None
        return _Field(label, sp.Matrix([out]), allowed)
    e = expr(c, label)
    return None if e is None else _Field(label, e, allowed | v_set, True)


# ---------------------------------------------------------------------------------------
# stage 2: symbols


class _SymbolRules:
    """Which symbols may appear in which field; collects the parameter candidates."""

    def __init__(
        self,
        q: Sequence[sp.Symbol],
        qd: Sequence[sp.Symbol],
        v: Sequence[sp.Symbol],
        has_frame: bool,
        reserved: Mapping[str, _Reserved],
        explicit: Sequence[sp.Symbol] | None,
    ):
        self.q, self.q_set = q, set(q)
        self.qd_set, self.v_set = set(qd), set(v)
        self.v = v
        self.has_frame = has_frame
        self.reserved = reserved
        self.explicit = None if explicit is None else set(explicit)
        self.q_names = {c.name for c in q}
        # candidate parameters (default mode): symbol -> first field it appears in
        self.candidates: dict[sp.Symbol, str] = {}

    def check(self, f: _Field, problems: _Problems) -> None:
        syms = sorted(f.symbols, key=atom_key)
        bad = False
        # one name, one symbol
        impostors = [
            s for s in syms if s.name in self.reserved and s != self.reserved[s.name].symbol
        ]
        for s in impostors:
            r = self.reserved[s.name]
            problems.add(
                f"{f.label}: symbol {s} {_assumptions(s)} has the same name as {r.role}"
                f" {_assumptions(r.symbol)} but {_differs(s)}, so sympy treats it as"
                f" another symbol; use {r.use}"
            )
            bad = True
        syms = [s for s in syms if s not in impostors]
        sset = set(syms)
        velocities = sset & (self.qd_set | self.v_set) - f.allowed
        if velocities and f.in_velocities and self.has_frame:
            problems.add(
                f"{f.label}: contains the coordinate velocities {_names(velocities)}; in a scene"
                " with a frame the kinetic energy, constraints and impulsive constraints are"
                f" written in the quasi-velocities {_names(self.v)} (q_dot = S v)"
            )
            bad = True
        elif velocities and f.label.endswith(".psi"):
            problems.add(
                f"{f.label} = {_short(f.value)} contains velocities {_names(velocities)}; psi is"
                " a function of (t, q)"
            )
            bad = True
        elif velocities:
            problems.add(
                f"{f.label}: contains velocity symbols {_names(velocities)};"
                " only coordinates and parameters may appear"
            )
            bad = True
        if TIME in sset and TIME not in f.allowed:
            problems.add(f"{f.label}: depends on time t; only the potential and walls may")
            bad = True
        coords = sset & self.q_set - f.allowed
        if coords:
            problems.add(
                f"{f.label}: depends on the coordinates {_names(coords)}; it must be a number"
                " or a parameter"
            )
            bad = True
        others = [s for s in syms if s.name not in self.reserved]
        if self.explicit is not None:
            unknown = [s for s in others if s not in self.explicit]
            if unknown:
                problems.add(
                    f"{f.label}: unknown symbols {_names(unknown)} (not coordinates or declared"
                    " parameters)"
                )
                bad = True
        else:
            ghost = [
                s.name
                for s in others
                if s.name.endswith("dot") and s.name[:-3] and s.name[:-3] not in self.q_names
            ]
            if ghost:
                problems.add(
                    f"{f.label}: symbols {ghost} look like velocities of coordinates that are"
                    f" not in the scene {list(map(str, self.q))}"
                )
            for s in others:
                self.candidates.setdefault(s, f.label)
        bad_fn = _non_smooth(f.value)
        if bad_fn:
            problems.add(
                f"{f.label}: contains non-smooth functions {bad_fn}; symmech needs smooth"
                " expressions"
            )
        found = expression_problems(f.value, skip=NON_SMOOTH)
        for p in found:
            problems.add(f"{f.label}: {p}")
        f.ok = not (bad or bad_fn or found)

    def default_parameters(self, problems: _Problems) -> tuple[sp.Symbol, ...]:
        """Every other free symbol, sorted by name; two symbols sharing a name are refused."""
        params = sorted(self.candidates, key=atom_key)
        for a, b in itertools.pairwise(params):
            if a.name == b.name:
                problems.add(
                    f"{self.candidates[b]}: symbol {b} {_assumptions(b)} has the same name as the"
                    f" symbol {a} {_assumptions(a)} in {self.candidates[a]} but"
                    f" {_differs(a if isinstance(a, sp.Dummy) else b)}, so sympy treats them as"
                    " two symbols; use one symbol per name"
                )
        return tuple(params)


def _names(symbols: Iterable[sp.Basic]) -> list[str]:
    return sorted(str(s) for s in symbols)


# ---------------------------------------------------------------------------------------
# stage 3: properties


def _metric_from_kinetic_energy(
    T: sp.Expr, v: Sequence[sp.Symbol], q: Sequence[sp.Symbol], problems: _Problems
) -> sp.Matrix | None:
    """g_ij = d^2 T / dv_i dv_j, checking that T is a quadratic form in the velocities."""
    try:
        return metric_from_kinetic_energy(T, v, q)
    except NotQuadraticError as exc:
        problems.add(
            f"kinetic_energy: T = {_short(T)} is not a quadratic form in the velocities"
            f" ({_short(exc.term)} {exc})"
        )
        return None


def _check_metric(
    G: sp.Matrix,
    label: str,
    points: _Points,
    problems: _Problems,
    q: Sequence[sp.Symbol],
    T: sp.Expr | None = None,
) -> None:
    """Symmetric, and positive definite: proven symbolically for a diagonal metric of
    positive terms, else at sampled points (indefinite at one, or singular at all, refuses),
    then over every value of the coordinates (:mod:`symmech.declaration.definiteness`:
    indefinite somewhere refuses, undecided warns)."""
    n = G.rows
    pts = points.for_(G)
    asym = [
        (i, j)
        for i in range(n)
        for j in range(i + 1, n)
        if G[i, j] != G[j, i] and vanishes(G[i, j] - G[j, i], pts) is False
    ]
    if asym:
        problems.add(f"{label}: not symmetric, g[i,j] != g[j,i] at (i,j) in {asym}")
        return
    diagonal = all(G[i, j] == 0 for i in range(n) for j in range(n) if i != j)
    try:
        if diagonal and all(proven_sign(G[i, i]) == "pos" for i in range(n)):
            return
    except RecursionError:  # an absurdly deep expression: judge it at sampled points
        pass
    singular_at, failure = [], None
    evaluated = 0
    for point in pts:
        try:
            A, complex_ = real_values(G, point)
        except EvaluationError as exc:
            failure = failure or (exc, point)
            continue
        evaluated += 1
        if complex_:
            problems.add(f"{label}: complex entries{_at(point, G)}")
            return
        verdict, evidence = classify_symmetric(A)
        if verdict == "indefinite":
            problems.add(f"{label}: not positive definite{_at(point, G)} ({evidence})")
            return
        if verdict == "singular":
            singular_at.append((point, evidence))
    if not evaluated:
        exc, point = failure
        i, j = exc.index
        problems.add(
            f"{label}: entry [{i},{j}] = {_short(G[i, j])} {exc.reason}{_at(point, G)};"
            " positive definiteness cannot be checked (rescale the units, or"
            " write the entry so that it has a finite value)"
        )
    elif len(singular_at) == evaluated:
        point, evidence = singular_at[0]
        problems.add(
            f"{label}: singular (determinant identically 0): singular at every sampled point"
            f"{_at(point, G).replace(' at the sampled point', ', e.g.')} ({evidence})"
        )
    else:
        _check_everywhere(G, label, pts, problems, q, T)


def _check_everywhere(
    G: sp.Matrix,
    label: str,
    pts: list[dict],
    problems: _Problems,
    q: Sequence[sp.Symbol],
    T: sp.Expr | None,
) -> None:
    """Positive definiteness away from the sampled points (see :func:`definiteness`)."""
    verdict = definiteness(G, q, pts, kinetic_energy=T)
    if verdict.status == "refuted":
        where = _at(verdict.point, G).replace(" at the sampled point", " at the point")
        problems.add(
            f"{label}: not positive definite{where} ({verdict.detail}), a point found by"
            " searching from the sampled points"
        )
    elif verdict.status == "undecided":
        warnings.warn(
            f"{label}: positive definiteness is undecided: {verdict.detail}; symmech"
            " accepts the metric, but it may be indefinite elsewhere",
            UndecidedWarning,
            stacklevel=5,
        )


def _check_real(e: sp.Expr, label: str, points: _Points, problems: _Problems) -> bool:
    """Whether ``e`` is real at the sampled points: complex at every one where it has a
    value refuses it (``sqrt(-x**2 - 1)``, ``log(-1 - x**2)``), complex at some warns (its
    real domain is restricted, and symmech does not check that motions stay in it)."""
    if not e.free_symbols or proven_real(e):
        return True
    M = sp.Matrix([[e]])
    flags = []
    for point in points.for_(e):
        try:
            _, complex_ = real_values(M, point)
        except EvaluationError:
            continue
        flags.append((complex_, point))
    complex_at = [point for complex_, point in flags if complex_]
    if flags and len(complex_at) == len(flags):
        problems.add(
            f"{label} = {_short(e)}: not real at any sampled point (e.g."
            f"{_at(complex_at[0], e).replace(' at the sampled point', '')}): a scene's fields"
            " are real functions"
        )
        return False
    if complex_at:
        warnings.warn(
            f"{label} = {_short(e)}: not real{_at(complex_at[0], e)} (real at"
            f" {len(flags) - len(complex_at)} of {len(flags)} sampled points): its real"
            " domain is restricted, and symmech does not check that motions stay in it",
            UndecidedWarning,
            stacklevel=4,
        )
    return True


def _check_wall_gradient(
    psi: sp.Expr, label: str, q: Sequence[sp.Symbol], points: _Points, problems: _Problems
) -> None:
    """Refuse a wall whose gradient vanishes on it (``x**2``, ``sin(x)**2``, ``(x - 1)**2*(y
    + 2)``); warn when no point of the wall was found to check (see
    :mod:`symmech.declaration.wallpoints`)."""
    point, found = vanishing_gradient(psi, q, points.for_(psi))
    if point is not None:
        shown = ", ".join(
            f"{k}={sp.N(v, 6) if isinstance(v, sp.Float) else v}"
            for k, v in sorted(point.items(), key=lambda kv: atom_key(kv[0]))
            if psi.has(k)
        )
        problems.add(
            f"{label} = {_short(psi)}: its gradient d psi/dq vanishes on the wall, e.g. at"
            f" {{{shown}}} (psi = 0 and d psi = 0 there): an impact there has no normal"
            " direction, so psi = 0 is not a regular wall (Carnot paper section 3.1 assumes"
            " d psi != 0 on the wall); write psi so that it changes sign across the wall"
            " with a nonzero gradient (x, not x**2)"
        )
    elif not found:
        warnings.warn(
            f"{label} = {_short(psi)}: no point of the wall psi = 0 was found from the sampled"
            " points, so symmech could not check that d psi != 0 on it (a wall that is never"
            " reached, or one reached only at isolated points such as x**2 + y**2 = 0)",
            UndecidedWarning,
            stacklevel=4,
        )


def _generic_rank(M: sp.Matrix, pts: list[dict]) -> tuple[int | None, str]:
    ranks, reason = [], ""
    for point in pts:
        try:
            ranks.append(rank_at(M, point))
        except EvaluationError as exc:
            reason = reason or f"entry {list(exc.index or ())} {exc.reason}{_at(point, M)}"
    return (max(ranks) if ranks else None), reason


def _check_frame(S: sp.Matrix, points: _Points, problems: _Problems) -> None:
    rank, reason = _generic_rank(S, points.for_(S))
    if rank is None:
        problems.add(f"frame: cannot be evaluated at any sampled point ({reason})")
    elif rank < S.rows:
        problems.add("frame: the matrix S (q_dot = S v) is singular at every sampled point")


def _check_independent(rows: sp.Matrix, points: _Points, label: str, problems: _Problems) -> None:
    m = rows.rows
    rank, reason = _generic_rank(rows, points.for_(rows))
    if rank is None:
        problems.add(f"{label}: cannot be evaluated at any sampled point ({reason})")
    elif rank < m:
        problems.add(
            f"{label}: the one-forms are linearly dependent (rank {rank} < {m})"
            " at every sampled point"
        )


def _constraint_row(
    f: _Field, v: Sequence[sp.Symbol], points: _Points, problems: _Problems
) -> list[sp.Expr] | None:
    """Coefficient row mu of a constraint ``mu(q) v`` (see :func:`linear_form_row`)."""
    if not f.in_velocities:
        return list(f.value)
    try:
        return linear_form_row(f.value, v, points.for_)
    except NotQuadraticError as exc:
        problems.add(f"{f.label}: {_short(f.value)} {exc}")
        return None
