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
listing all of them (as ``sympy.physics.mechanics``' ``validate`` does).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import sympy as sp

from symmech.declaration.expressions import to_expression
from symmech.declaration.numeric import evaluate_matrix
from symmech.declaration.quadratic import NotQuadraticError, metric_from_kinetic_energy
from symmech.declaration.sampling import sample_points
from symmech.declaration.symbols import t as TIME
from symmech.declaration.symbols import velocity_of
from symmech.declaration.wall import Wall
from symmech.errors import SceneError

__all__ = ["NON_SMOOTH", "Declaration", "ResolvedWall", "declare"]

#: Functions that make an expression non-smooth; refused everywhere in a scene, because
#: Christoffel symbols, gradients and impact maps need derivatives.
NON_SMOOTH = (
    sp.Abs,
    sp.sign,
    sp.Piecewise,
    sp.Heaviside,
    sp.floor,
    sp.ceiling,
    sp.Max,
    sp.Min,
    sp.frac,
    sp.DiracDelta,
    sp.re,
    sp.im,
    sp.arg,
)

# Symbolic checks on expressions above this size are replaced by checks at sampled points.
_SYMBOLIC_CHECK_OPS = 400
_SAMPLES = 5


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


def _non_smooth(expr: sp.Basic | sp.MatrixBase) -> list[str]:
    entries = list(expr) if isinstance(expr, sp.MatrixBase) else [expr]
    applied = set().union(*[e.atoms(sp.Function, sp.Max, sp.Min) for e in entries])
    return sorted({type(f).__name__ for f in applied if isinstance(f, NON_SMOOTH)})


def _is_zero(expr: sp.Expr, points: list[dict]) -> bool | None:
    """Decide expr == 0: symbolically when small, else by exact evaluation at sample points."""
    expr = sp.sympify(expr)
    if expr == 0:
        return True
    if sp.count_ops(expr) <= _SYMBOLIC_CHECK_OPS:
        simplified = sp.simplify(expr)
        if simplified == 0:
            return True
        if simplified.is_number and simplified != 0:
            return False
    for point in points:
        value = sp.N(expr.subs(point), 30)
        if value.is_number and abs(complex(value)) > 1e-20:
            return False
    return True


class _Problems:
    def __init__(self) -> None:
        self.items: list[str] = []

    def add(self, message: str) -> None:
        self.items.append(message)

    def raise_if_any(self) -> None:
        if self.items:
            raise SceneError(self.items)


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

    Raises :class:`~symmech.SceneError` listing every problem found.  See
    :class:`symmech.Scene` for the meaning of the arguments.
    """
    problems = _Problems()

    # -- coordinates -------------------------------------------------------------------
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
    if len(set(q)) != len(q):
        raise SceneError(f"coordinates: repeated coordinates in {list(q)}")
    if TIME in q or any(c.name == "t" for c in q):
        raise SceneError("coordinates: 't' is reserved for time (symmech.t)")
    n = len(q)
    qd = tuple(velocity_of(c) for c in q)
    clash = [c for c in q if c in qd]
    if clash:
        raise SceneError(f"coordinates: {clash} collide with velocity names of other coordinates")

    # -- frame / quasi-velocities ------------------------------------------------------
    S: sp.ImmutableMatrix | None = None
    if (frame is None) != (quasi_velocities is None):
        problems.add("frame: 'frame' and 'quasi_velocities' must be given together")
        problems.raise_if_any()
    if quasi_velocities is not None:
        if isinstance(quasi_velocities, sp.Symbol):
            quasi_velocities = (quasi_velocities,)
        v = tuple(quasi_velocities)
        if len(v) != n or not all(isinstance(s, sp.Symbol) for s in v):
            raise SceneError(
                f"quasi_velocities: expected {n} sympy Symbols (one per coordinate), got {list(v)}"
            )
        if len(set(v)) != n or set(v) & (set(q) | set(qd) | {TIME}):
            raise SceneError(
                f"quasi_velocities: {list(v)} must be distinct and differ from the coordinates,"
                " their velocities and t"
            )
    else:
        v = qd

    # the symbol table for string inputs: coordinates, velocities, t, declared parameters
    table: dict[str, sp.Basic] = {s.name: s for s in (*q, *qd, *v, TIME)}
    if parameters is not None:
        if isinstance(parameters, sp.Symbol):
            parameters = (parameters,)
        parameters = tuple(parameters)
        badp = [p for p in parameters if not isinstance(p, sp.Symbol)]
        if badp:
            raise SceneError(f"parameters: {badp} are not sympy Symbols")
        overlap = set(parameters) & set(table.values())
        if overlap:
            raise SceneError(
                f"parameters: {sorted(map(str, overlap))} are coordinates, velocities or t"
            )
        table.update({p.name: p for p in parameters})
    else:
        # parameters found in sympy-valued inputs may be used by name in string inputs
        for value in (metric, kinetic_energy, potential, frame, *list(constraints or [])):
            for s in getattr(
                sp.sympify(value) if isinstance(value, sp.Basic) else value, "free_symbols", ()
            ):
                table.setdefault(s.name, s)

    def expr(value: object, field: str) -> sp.Expr | None:
        try:
            return to_expression(value, table, field=field)
        except ValueError as exc:
            problems.add(str(exc))
            return None

    if frame is not None:
        S0 = _raw_matrix(frame, "frame")
        shape = (len(S0), len(S0[0]) if S0 else 0)
        if shape != (n, n):
            raise SceneError(f"frame: expected an {n} x {n} matrix (q_dot = S v), got {shape}")
        entries = [expr(S0[i][j], f"frame[{i},{j}]") for i in range(n) for j in range(n)]
        problems.raise_if_any()
        S = sp.ImmutableMatrix(n, n, entries)

    # -- metric / kinetic energy -------------------------------------------------------
    kinetic_given = False
    if (metric is None) == (kinetic_energy is None):
        problems.add("metric: give exactly one of 'metric' and 'kinetic_energy'")
        problems.raise_if_any()
    if metric is not None:
        G0 = _raw_matrix(metric, "metric")
        shape = (len(G0), len(G0[0]) if G0 else 0)
        if shape != (n, n):
            if shape[0] != shape[1]:
                raise SceneError(f"metric: not square, shape {shape}")
            raise SceneError(f"metric: shape {shape} does not match the {n} coordinates")
        entries = [expr(G0[i][j], f"metric[{i},{j}]") for i in range(n) for j in range(n)]
        problems.raise_if_any()
        G = sp.Matrix(n, n, entries)
    else:
        kinetic_given = True
        T = expr(kinetic_energy, "kinetic_energy")
        problems.raise_if_any()
        G = _metric_from_kinetic_energy(T, v, q, problems)
        problems.raise_if_any()

    V = expr(potential if potential is not None else 0, "potential")
    problems.raise_if_any()

    # -- constraints --------------------------------------------------------------------
    rows: list[list[sp.Expr]] = []
    if isinstance(constraints, sp.MatrixBase):
        constraints = [list(constraints.row(i)) for i in range(constraints.rows)]
    elif isinstance(constraints, (str, sp.Basic)):
        constraints = [constraints]
    for a, c in enumerate(constraints or ()):
        row = _constraint_row(c, v, f"constraints[{a}]", expr, problems)
        if row is not None:
            rows.append(row)
    problems.raise_if_any()
    mu = sp.Matrix(len(rows), n, [e for r in rows for e in r]) if rows else sp.zeros(0, n)

    # -- walls ----------------------------------------------------------------------------
    wall_list = list(walls or ())
    resolved: list[tuple[Wall, sp.Expr, sp.Matrix]] = []
    for k, w in enumerate(wall_list):
        label = f"walls[{k}]" + (f" ({w.name!r})" if isinstance(w, Wall) and w.name else "")
        if not isinstance(w, Wall):
            problems.add(f"{label}: expected a symmech.Wall, got {type(w).__name__}")
            continue
        psi = expr(w.psi, f"{label}.psi")
        nu_rows = []
        for A, c in enumerate(w.impulsive_constraints):
            r = _constraint_row(c, v, f"{label}.impulsive_constraints[{A}]", expr, problems)
            if r is not None:
                nu_rows.append(r)
        if psi is None:
            continue
        if not (psi.free_symbols & set(q)):
            problems.add(
                f"{label}.psi = {_short(psi)} does not depend on the coordinates {list(q)}"
            )
        if psi.free_symbols & (set(qd) | set(v)):
            problems.add(
                f"{label}.psi = {_short(psi)} contains velocities; psi is a function of (t, q)"
            )
        nu = (
            sp.Matrix(len(nu_rows), n, [e for r in nu_rows for e in r])
            if nu_rows
            else sp.zeros(0, n)
        )
        resolved.append((w, psi, nu))
    names = [w.name for w in wall_list if isinstance(w, Wall) and w.name]
    dup = sorted({x for x in names if names.count(x) > 1})
    if dup:
        problems.add(f"walls: names {dup} are used by more than one wall")
    problems.raise_if_any()

    # -- symbols -----------------------------------------------------------------------------
    q_set, qd_set, v_set = set(q), set(qd), set(v)
    # symbols and smoothness are checked on what the user wrote (T is smaller than g)
    first = ("metric", G, q_set) if not kinetic_given else ("kinetic_energy", T, q_set | v_set)
    fields: list[tuple[str, sp.Basic, set]] = [first, ("potential", V, q_set | {TIME})]
    if S is not None:
        fields.append(("frame", S, q_set))
    fields.append(("constraints", mu, q_set))
    for k, (w, psi, nu) in enumerate(resolved):
        fields.append((f"walls[{k}].psi", psi, q_set | {TIME}))
        fields.append((f"walls[{k}].impulsive_constraints", nu, q_set | {TIME}))
        # a symbolic restitution alpha is a parameter of the scene like any other
        fields.append((f"walls[{k}].restitution", sp.sympify(w.restitution), set()))
    if parameters is None:
        found: set[sp.Symbol] = set()
        for _, e, allowed in fields:
            found |= {s for s in e.free_symbols if s not in allowed}
        found -= qd_set | v_set | {TIME} | q_set
        params = tuple(sorted(found, key=lambda s: s.name))
    else:
        params = tuple(parameters)
    p_set = set(params)
    for field, e, allowed in fields:
        if e is None:
            continue
        syms = e.free_symbols
        vel = sorted(str(s) for s in (syms & (qd_set | v_set)) - allowed)
        if vel:
            problems.add(
                f"{field}: contains velocity symbols {vel};"
                " only coordinates and parameters may appear"
            )
        if TIME in syms and TIME not in allowed:
            problems.add(f"{field}: depends on time t; only the potential and walls may")
        unknown = sorted(str(s) for s in syms - allowed - p_set - qd_set - v_set - {TIME})
        if unknown:
            problems.add(
                f"{field}: unknown symbols {unknown} (not coordinates or declared parameters)"
            )
        # a symbol that looks like the velocity of a coordinate that does not exist
        ghost = sorted(
            s.name
            for s in syms - allowed - qd_set - v_set
            if s.name.endswith("dot") and s.name[:-3] and s not in q_set
        )
        if ghost and parameters is None:
            problems.add(
                f"{field}: symbols {ghost} look like velocities of coordinates that are not in"
                f" the scene {list(map(str, q))}"
            )
        bad_fn = _non_smooth(e)
        if bad_fn:
            problems.add(
                f"{field}: contains non-smooth functions {bad_fn}; symmech needs smooth expressions"
            )
    problems.raise_if_any()

    # -- metric properties ----------------------------------------------------------------------
    points = sample_points([*q, *params, TIME])
    _check_metric(G, points, problems)
    if S is not None:
        _check_frame(S, points, problems)
    m = mu.rows
    if m:
        if m >= n:
            problems.add(
                f"constraints: {m} constraints for {n} coordinates leave no admissible motion;"
                " a scene needs fewer constraints than coordinates"
            )
        else:
            _check_independent(mu, points, "constraints", problems)
    for k, (w, _, nu) in enumerate(resolved):
        label = f"walls[{k}]" + (f" ({w.name!r})" if w.name else "")
        if nu.rows:
            _check_independent(
                mu.col_join(nu),
                points,
                f"{label}.impulsive_constraints (with the permanent constraints)",
                problems,
            )
    problems.raise_if_any()

    walls_out = tuple(
        ResolvedWall(wall=w, psi=psi, impulsive_matrix=sp.ImmutableMatrix(nu), index=k)
        for k, (w, psi, nu) in enumerate(resolved)
    )
    return Declaration(
        coordinates=q,
        velocities=v,
        coordinate_velocities=qd,
        frame=S,
        metric=sp.ImmutableMatrix(G),
        potential=sp.sympify(V),
        constraint_matrix=sp.ImmutableMatrix(mu),
        walls=walls_out,
        parameters=params,
        name=name or "scene",
        kinetic_energy_given=kinetic_given,
    )


# ---------------------------------------------------------------------------------------
# individual checks


def _metric_from_kinetic_energy(
    T: sp.Expr, v: Sequence[sp.Symbol], q: Sequence[sp.Symbol], problems: _Problems
) -> sp.Matrix:
    """g_ij = d^2 T / dv_i dv_j, checking that T is a quadratic form in the velocities."""
    try:
        return metric_from_kinetic_energy(T, v, q)
    except NotQuadraticError as exc:
        problems.add(
            f"kinetic_energy: T = {_short(T)} is not a quadratic form in the velocities"
            f" ({_short(exc.term)} {exc})"
        )
        return sp.zeros(len(v), len(v))


def _check_metric(G: sp.Matrix, points: list[dict], problems: _Problems) -> None:
    n = G.rows
    asym = [
        (i, j)
        for i in range(n)
        for j in range(i + 1, n)
        if G[i, j] != G[j, i] and not _is_zero(G[i, j] - G[j, i], points)
    ]
    if asym:
        problems.add(f"metric: not symmetric, g[i,j] != g[j,i] at (i,j) in {asym}")
        return
    # symbolic where cheap: a constant or diagonal metric
    if all(e.is_number for e in G):
        _check_numeric_pd(G, [{}], problems)
        return
    if all(G[i, j] == 0 for i in range(n) for j in range(n) if i != j):
        for i in range(n):
            d = G[i, i]
            if d == 0 or d.is_zero:
                problems.add(f"metric: singular, diagonal entry g[{i},{i}] is 0")
            elif d.is_nonpositive:
                problems.add(f"metric: not positive definite, g[{i},{i}] = {d} <= 0")
        if problems.items:
            return
    _check_numeric_pd(G, points, problems)


def _check_numeric_pd(G: sp.Matrix, points: list[dict], problems: _Problems) -> None:
    singular_at = []
    for point in points:
        A = evaluate_matrix(G, point)
        if np.abs(A.imag).max(initial=0) > 1e-12:
            problems.add(f"metric: complex entries at the sampled point {_fmt(point)}")
            return
        A = A.real
        w = np.linalg.eigvalsh(0.5 * (A + A.T))
        scale = max(np.abs(w).max(initial=0), 1e-300)
        if np.abs(w).min() <= 1e-12 * scale:
            singular_at.append(point)
        elif w.min() < 0:
            problems.add(
                f"metric: not positive definite at the sampled point {_fmt(point)}"
                f" (eigenvalues {np.round(w, 6).tolist()})"
            )
            return
    if singular_at and len(singular_at) == len(points):
        problems.add(
            f"metric: singular (determinant 0) at every sampled point, e.g. {_fmt(singular_at[0])}"
        )


def _check_frame(S: sp.Matrix, points: list[dict], problems: _Problems) -> None:
    singular = 0
    for point in points:
        A = evaluate_matrix(S, point).real
        s = np.linalg.svd(A, compute_uv=False)
        if s.min() <= 1e-12 * max(s.max(), 1e-300):
            singular += 1
    if singular == len(points):
        problems.add("frame: the matrix S (q_dot = S v) is singular at every sampled point")


def _check_independent(
    rows: sp.Matrix, points: list[dict], label: str, problems: _Problems
) -> None:
    m = rows.rows
    ranks = []
    for point in points:
        A = evaluate_matrix(rows, point).real
        ranks.append(np.linalg.matrix_rank(A, tol=1e-10 * max(np.abs(A).max(initial=0), 1e-300)))
    if max(ranks) < m:
        problems.add(
            f"{label}: the one-forms are linearly dependent (rank {max(ranks)} < {m})"
            " at every sampled point"
        )


def _raw_matrix(value: object, field: str) -> list[list[object]]:
    """Rows of a matrix input, entries untouched (strings are parsed later, never sympified)."""
    if isinstance(value, sp.MatrixBase):
        return [list(value.row(i)) for i in range(value.rows)]
    if isinstance(value, (str, bytes)) or not hasattr(value, "__iter__"):
        raise SceneError(
            f"{field}: expected a square matrix (sympy Matrix or nested lists), got {value!r}"
        )
    rows = [
        list(r) if hasattr(r, "__iter__") and not isinstance(r, (str, bytes)) else None
        for r in value
    ]
    if any(r is None for r in rows):
        raise SceneError(f"{field}: expected a matrix given as a list of rows, got {value!r}")
    if len({len(r) for r in rows}) > 1:
        raise SceneError(f"{field}: rows of different lengths {[len(r) for r in rows]}")
    return rows


def _fmt(point: Mapping) -> str:
    return (
        "{"
        + ", ".join(f"{k}={v}" for k, v in sorted(point.items(), key=lambda kv: str(kv[0])))
        + "}"
    )


def _constraint_row(c, v, field, expr, problems: _Problems) -> list[sp.Expr] | None:
    """Coefficient row of a constraint given as an expression linear in v or as a row."""
    n = len(v)
    if isinstance(c, (list, tuple)) or (isinstance(c, sp.MatrixBase)):
        entries = list(c)
        if len(entries) != n:
            problems.add(f"{field}: a coefficient row needs {n} entries, got {len(entries)}")
            return None
        out = [expr(e, f"{field}[{j}]") for j in range(n) for e in [entries[j]]]
        return None if any(o is None for o in out) else out
    e = expr(c, field)
    if e is None:
        return None
    zero = dict.fromkeys(v, 0)
    row = [sp.diff(e, vj) for vj in v]
    nonlinear = [str(vj) for vj, r in zip(v, row, strict=True) if r.free_symbols & set(v)]
    if nonlinear:
        problems.add(
            f"{field}: {_short(e)} is not linear in the velocities (nonlinear in {nonlinear});"
            " constraints must be one-forms mu_i(q) q_dot^i"
        )
        return None
    if all(r == 0 for r in row):
        problems.add(
            f"{field}: {_short(e)} does not involve any velocity {list(map(str, v))}; a"
            " holonomic constraint h(q) = 0 is given by its differential dh (h_dot = 0)"
        )
        return None
    offset = e.subs(zero)
    if offset != 0 and sp.simplify(offset) != 0:
        problems.add(
            f"{field}: {_short(e)} has the velocity-free part {_short(offset)}; constraints must be"
            " linear (homogeneous) in the velocities"
        )
        return None
    return row
