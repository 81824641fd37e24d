"""Stage 1 of a declaration's validation (:func:`symmech.declaration.spec.declare`): the
structure of the input.  The coordinates (a scene without valid ones stops here), the
velocity basis, ``parameters=``, the shapes of the fields, and reading one-shot iterables
once."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import sympy as sp

from symmech.algebra.walk import free_symbols
from symmech.declaration.checks import (
    Field,
    Problems,
    Reserved,
    assumptions,
    differs,
)
from symmech.declaration.symbols import t as TIME
from symmech.declaration.symbols import velocity_of
from symmech.declaration.wall import Wall
from symmech.errors import SceneError

__all__: list[str] = []


def _coordinate_symbols(coordinates: object) -> tuple[sp.Symbol, ...]:
    """The coordinates; a problem here stops validation (nothing can be checked without)."""
    if isinstance(coordinates, sp.Symbol):
        coordinates = (coordinates,)
    try:
        q: tuple = tuple(coordinates)  # type: ignore[arg-type]
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
    problems: Problems,
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
        v: tuple = tuple(quasi_velocities)  # type: ignore[arg-type]
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
) -> dict[str, Reserved]:
    out = {TIME.name: Reserved(TIME, "the time t", "symmech.t")}
    for c in q:
        out[c.name] = Reserved(c, f"the coordinate {c}", "the coordinate (symmech.coordinates)")
    for c, d in zip(q, qd, strict=True):
        out[d.name] = Reserved(d, f"the velocity {d} of coordinate {c}", "symmech.velocities")
    for s in v:
        out[s.name] = Reserved(s, f"the quasi-velocity {s}", "the symbol in quasi_velocities")
    return out


def _explicit_parameters(
    parameters: object, reserved: Mapping[str, Reserved], problems: Problems
) -> tuple[sp.Symbol, ...]:
    """The declared parameters that are usable (each problem is recorded)."""
    if isinstance(parameters, sp.Symbol):
        parameters = (parameters,)
    try:
        given: tuple = tuple(parameters)  # type: ignore[arg-type]
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
                    f"parameters: symbol {p} {assumptions(p)} has the same name as {r.role}"
                    f" {assumptions(r.symbol)} but {differs(p)}; a name denotes one"
                    f" symbol (use {r.use})"
                )
            continue
        if p.name in by_name:
            first = by_name[p.name]
            if first == p:
                problems.add(f"parameters: {p} is listed more than once")
            else:
                problems.add(
                    f"parameters: symbols {first} {assumptions(first)} and {p}"
                    f" {assumptions(p)} share the name {p.name!r} with different assumptions;"
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
        return list(constraints)  # type: ignore[call-overload]
    except TypeError:
        return [constraints]


def _listed(value: object) -> object:
    """A one-shot iterable read into a list (so it can be read twice); else unchanged."""
    if value is None or isinstance(value, (str, bytes, sp.Basic, sp.MatrixBase, list, tuple)):
        return value
    try:
        return list(value)  # type: ignore[call-overload]
    except TypeError:
        return value


def _wall_items(walls: object, problems: Problems) -> list[object]:
    if walls is None:
        return []
    if isinstance(walls, Wall):
        return [walls]
    try:
        return list(walls)  # type: ignore[call-overload]
    except TypeError:
        problems.add(f"walls: expected a list of symmech.Wall, got {walls!r}")
        return []


def _sympy_symbols(*values: object) -> set[sp.Symbol]:
    """Free symbols of every sympy object inside ``values`` (nested lists, matrices)."""
    out: set[sp.Symbol] = set()
    memo: dict = {}
    stack = list(values)
    while stack:
        value = stack.pop()
        if isinstance(value, sp.MatrixBase):
            stack.extend(value)
        elif isinstance(value, sp.Basic):
            out |= {s for s in free_symbols(value, memo) if isinstance(s, sp.Symbol)}
        elif isinstance(value, list | tuple):
            stack.extend(value)
    return out


def _raw_matrix(value: object, field: str, n: int, problems: Problems) -> list | None:
    """Rows of an n x n matrix input, entries untouched (strings are parsed later)."""
    if isinstance(value, sp.MatrixBase):
        rows = [list(value.row(i)) for i in range(value.rows)]
    elif isinstance(value, (str, bytes)) or not hasattr(value, "__iter__"):
        problems.add(
            f"{field}: expected a square matrix (sympy Matrix or nested lists), got {value!r}"
        )
        return None
    else:
        maybe = [
            list(r) if hasattr(r, "__iter__") and not isinstance(r, (str, bytes)) else None
            for r in value
        ]
        if any(r is None for r in maybe):
            problems.add(f"{field}: expected a matrix given as a list of rows, got {value!r}")
            return None
        rows = [r for r in maybe if r is not None]
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
    problems: Problems,
    key: str | None = None,
) -> Field | None:
    """A constraint: a coefficient row (n entries) or an expression linear in the velocities
    (``key``: its path in the declaration when not ``label``)."""
    if isinstance(c, (list, tuple, sp.MatrixBase)):
        entries = list(c)
        if len(entries) != n:
            problems.add(f"{label}: a coefficient row needs {n} entries, got {len(entries)}")
            return None
        out = [expr(e, f"{label}[{j}]") for j, e in enumerate(entries)]
        if any(o is None for o in out):
            return None
        return Field(label, sp.Matrix([out]), allowed, key=key)
    e = expr(c, label)
    return None if e is None else Field(label, e, allowed | v_set, True, key=key)
