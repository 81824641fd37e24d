"""Validation of a declaration, stages 2 and 3 (see :mod:`symmech.declaration.spec`).

* the bookkeeping shared by every stage: the problems found (:class:`Problems`), a field as
  parsed (:class:`Field`), the reserved names (:class:`Reserved`) and the sample points
  (:class:`Points`);
* stage 2, symbols: which symbols may appear in which field (:class:`SymbolRules`), non-smooth
  and unsupported functions, constants outside float64 (:mod:`symmech.declaration.admissible`);
* stage 3, properties: the metric symmetric and positive definite (at sampled points, then
  over the coordinates: :mod:`symmech.declaration.definiteness`), fields real, walls regular
  (:mod:`symmech.declaration.wallpoints`), frames invertible, constraints independent.
"""

from __future__ import annotations

import itertools
import warnings
from collections.abc import Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import sympy as sp
from sympy.core.function import AppliedUndef

from symmech.algebra.numeric import (
    EvaluationError,
    classify_symmetric,
    proven_real,
    proven_sign,
    real_values,
)
from symmech.algebra.rank import generic_rank
from symmech.algebra.sampling import atom_key, sample_points
from symmech.algebra.walk import atoms, free_symbols_of
from symmech.algebra.zero import is_zero
from symmech.declaration.admissible import NON_SMOOTH, expression_problems
from symmech.declaration.definiteness import Verdict, definiteness
from symmech.declaration.kinetic_metric import (
    NotQuadraticError,
    linear_form_row,
    metric_from_kinetic_energy,
)
from symmech.declaration.symbols import t as TIME
from symmech.declaration.wallpoints import vanishing_gradient
from symmech.errors import Problem, SceneError, UndecidedWarning

__all__ = [
    "Field",
    "Points",
    "Problems",
    "Reserved",
    "SymbolRules",
    "assumptions",
    "check_frame",
    "check_independent",
    "check_metric",
    "check_real",
    "check_wall_gradient",
    "constraint_row",
    "differs",
    "metric_of_kinetic_energy",
    "short",
]

# Arithmetic failures of the numerical searches (never an error of the user's input): they
# leave the property undecided, and the declaration says so.
_NUMERIC_FAILURES = (ArithmeticError, ValueError, TypeError, RecursionError)

_SAMPLES = 4
#: ... and points away from the origin (angles near +-pi), see sampling.sample_points.
_FAR_SAMPLES = 2
_EXTRA_SEED = 19970521  # seed of the values of velocities and undefined functions


# ---------------------------------------------------------------------------------------
# helpers


def short(expr: object, limit: int = 60) -> str:
    s = str(expr)
    return s if len(s) <= limit else s[: limit - 3] + "..."


def _entries(expr: sp.Basic | sp.MatrixBase) -> list[sp.Basic]:
    return list(expr) if isinstance(expr, sp.MatrixBase) else [expr]


def _non_smooth(expr: sp.Basic | sp.MatrixBase) -> list[str]:
    applied = set().union(*[atoms(e, (sp.Function, sp.Max, sp.Min)) for e in _entries(expr)])
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


def assumptions(s: sp.Symbol) -> str:
    if isinstance(s, sp.Dummy):
        return "(a sympy Dummy)"
    orig = getattr(s, "_assumptions_orig", None)
    if orig is None:  # pragma: no cover - sympy < 1.12
        orig = {k: v for k, v in s.assumptions0.items() if k != "commutative"}
    items = [f"{k}={v}" for k, v in sorted(orig.items()) if k != "commutative" or not v]
    return f"({', '.join(items)})" if items else "(no assumptions)"


def differs(s: sp.Symbol) -> str:
    return "is a sympy Dummy" if isinstance(s, sp.Dummy) else "different assumptions"


def _at(point: Mapping, about: sp.Basic | sp.MatrixBase) -> str:
    """`` at the sampled point {x=1/2, y=-3/4}`` for the atoms of ``about`` (empty for a
    constant)."""
    keep = _atoms(about)
    items = sorted((kv for kv in point.items() if kv[0] in keep), key=lambda kv: atom_key(kv[0]))
    if not items:
        return ""
    return " at the sampled point {" + ", ".join(f"{k}={v}" for k, v in items) + "}"


class Problems:
    """The problems of one declaration, each recorded with the field it is about: the
    field of the innermost :meth:`about` block around the check that adds it."""

    def __init__(self) -> None:
        self.items: list[Problem] = []
        self._about: list[tuple[str | None, str | None]] = [(None, None)]

    def add(self, message: str) -> None:
        field, label = self._about[-1]
        self.items.append(Problem(message, field, label))

    @contextmanager
    def about(self, field: str, label: str | None = None) -> Iterator[None]:
        """Problems added inside the block are about ``field`` (a path into the
        declaration), named ``label`` in their messages (default: the path)."""
        self._about.append((field, label))
        try:
            yield
        finally:
            self._about.pop()

    def raise_if_any(self) -> None:
        if self.items:
            raise SceneError(self.items)


@dataclass
class Field:
    """One field of the declaration, as parsed: an expression or a matrix of them."""

    label: str
    value: sp.Basic | sp.MatrixBase
    allowed: frozenset  # symbols it may contain besides the parameters
    in_velocities: bool = False  # written in the velocities (T, a constraint expression)
    ok: bool = True  # no problem with its symbols: its properties can be checked
    key: str | None = None  # its path in the declaration when not the label ("walls[0].psi")

    @property
    def path(self) -> str:
        return self.key or self.label

    @property
    def symbols(self) -> set[sp.Symbol]:
        return free_symbols_of(_entries(self.value))


@dataclass(frozen=True)
class Reserved:
    symbol: sp.Symbol
    role: str  # "the coordinate r"
    use: str  # what to write instead


class Points:
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
# stage 2: symbols


class SymbolRules:
    """Which symbols may appear in which field; collects the parameter candidates."""

    def __init__(
        self,
        q: Sequence[sp.Symbol],
        qd: Sequence[sp.Symbol],
        v: Sequence[sp.Symbol],
        has_frame: bool,
        reserved: Mapping[str, Reserved],
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

    def check(self, f: Field, problems: Problems) -> None:
        syms = sorted(f.symbols, key=atom_key)
        bad = False
        # one name, one symbol
        impostors = [
            s for s in syms if s.name in self.reserved and s != self.reserved[s.name].symbol
        ]
        for s in impostors:
            r = self.reserved[s.name]
            problems.add(
                f"{f.label}: symbol {s} {assumptions(s)} has the same name as {r.role}"
                f" {assumptions(r.symbol)} but {differs(s)}, so sympy treats it as"
                f" another symbol; use {r.use}"
            )
            bad = True
        syms = [s for s in syms if s not in impostors]
        sset = set(syms)
        velocities = sset & (self.qd_set | self.v_set) - f.allowed
        if velocities and f.in_velocities and self.has_frame:
            problems.add(
                f"{f.label}: contains the coordinate velocities {_names(velocities)}; in a scene"
                " with a frame the kinetic energy, forces, constraints and impulsive constraints"
                f" are written in the quasi-velocities {_names(self.v)} (q_dot = S v)"
            )
            bad = True
        elif velocities and f.label.endswith(".psi"):
            problems.add(
                f"{f.label} = {short(f.value)} contains velocities {_names(velocities)}; psi is"
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
            problems.add(f"{f.label}: depends on time t; only the potential, forces and walls may")
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

    def default_parameters(self, problems: Problems) -> tuple[sp.Symbol, ...]:
        """Every other free symbol, sorted by name; two symbols sharing a name are refused."""
        params = sorted(self.candidates, key=atom_key)
        for a, b in itertools.pairwise(params):
            if a.name == b.name:
                problems.add(
                    f"{self.candidates[b]}: symbol {b} {assumptions(b)} has the same name as the"
                    f" symbol {a} {assumptions(a)} in {self.candidates[a]} but"
                    f" {differs(a if isinstance(a, sp.Dummy) else b)}, so sympy treats them as"
                    " two symbols; use one symbol per name"
                )
        return tuple(params)


def _names(symbols: Iterable[sp.Basic]) -> list[str]:
    return sorted(str(s) for s in symbols)


# ---------------------------------------------------------------------------------------
# stage 3: properties


def metric_of_kinetic_energy(
    T: sp.Expr, v: Sequence[sp.Symbol], q: Sequence[sp.Symbol], problems: Problems
) -> sp.Matrix | None:
    """g_ij = d^2 T / dv_i dv_j, checking that T is a quadratic form in the velocities."""
    try:
        return metric_from_kinetic_energy(T, v, q)
    except NotQuadraticError as exc:
        problems.add(
            f"kinetic_energy: T = {short(T)} is not a quadratic form in the velocities"
            f" ({short(exc.term)} {exc})"
        )
        return None


def check_metric(
    G: sp.Matrix,
    label: str,
    points: Points,
    problems: Problems,
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
        if G[i, j] != G[j, i] and is_zero(G[i, j] - G[j, i], pts) is False
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
    singular_at: list[tuple[Any, str]] = []
    failure: tuple[Any, Any] | None = None
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
    if not evaluated and failure is not None:
        error, point = failure
        i, j = error.index
        problems.add(
            f"{label}: entry [{i},{j}] = {short(G[i, j])} {error.reason}{_at(point, G)};"
            " positive definiteness cannot be checked (rescale the units, or"
            " write the entry so that it has a finite value)"
        )
    elif evaluated and len(singular_at) == evaluated:
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
    problems: Problems,
    q: Sequence[sp.Symbol],
    T: sp.Expr | None,
) -> None:
    """Positive definiteness away from the sampled points (see :func:`definiteness`)."""
    try:
        verdict = definiteness(G, q, pts, kinetic_energy=T)
    except _NUMERIC_FAILURES as exc:  # a failure of the search is no verdict
        verdict = Verdict("undecided", f"the search failed ({type(exc).__name__})")
    if verdict.status == "refuted":
        where = _at(verdict.point, G).replace(" at the sampled point", " at the point")
        problems.add(f"{label}: not positive definite{where} ({verdict.detail}), {verdict.found}")
    elif verdict.status == "undecided":
        warnings.warn(
            f"{label}: positive definiteness is undecided: {verdict.detail}; symmech"
            " accepts the metric, but it may be indefinite elsewhere",
            UndecidedWarning,
            stacklevel=5,
        )


def check_real(e: sp.Expr, label: str, points: Points, problems: Problems) -> bool:
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
            f"{label} = {short(e)}: not real at any sampled point (e.g."
            f"{_at(complex_at[0], e).replace(' at the sampled point', '')}): a scene's fields"
            " are real functions"
        )
        return False
    if complex_at:
        warnings.warn(
            f"{label} = {short(e)}: not real{_at(complex_at[0], e)} (real at"
            f" {len(flags) - len(complex_at)} of {len(flags)} sampled points): its real"
            " domain is restricted, and symmech does not check that motions stay in it",
            UndecidedWarning,
            stacklevel=4,
        )
    return True


def check_wall_gradient(
    psi: sp.Expr, label: str, q: Sequence[sp.Symbol], points: Points, problems: Problems
) -> None:
    """Refuse a wall whose gradient vanishes on it (``x**2``, ``sin(x)**2``, ``(x - 1)**2*(y
    + 2)``); warn when no point of the wall was found to check (see
    :mod:`symmech.declaration.wallpoints`)."""
    try:
        point, found = vanishing_gradient(psi, q, points.for_(psi))
    except _NUMERIC_FAILURES:  # a failure of the root finding finds no point
        point, found = None, 0
    if point is not None:
        shown = ", ".join(
            f"{k}={sp.N(v, 6) if isinstance(v, sp.Float) else v}"
            for k, v in sorted(point.items(), key=lambda kv: atom_key(kv[0]))
            if psi.has(k)
        )
        problems.add(
            f"{label} = {short(psi)}: its gradient d psi/dq vanishes on the wall, e.g. at"
            f" {{{shown}}} (psi = 0 and d psi = 0 there): an impact there has no normal"
            " direction, so psi = 0 is not a regular wall (Carnot paper section 3.1 assumes"
            " d psi != 0 on the wall); write psi so that it changes sign across the wall"
            " with a nonzero gradient (x, not x**2)"
        )
    elif not found:
        warnings.warn(
            f"{label} = {short(psi)}: no point of the wall psi = 0 was found from the sampled"
            " points, so symmech could not check that d psi != 0 on it (a wall that is never"
            " reached, or one reached only at isolated points such as x**2 + y**2 = 0)",
            UndecidedWarning,
            stacklevel=4,
        )


def _generic_rank(M: sp.Matrix, pts: list[dict]) -> tuple[int | None, str]:
    return generic_rank(M, pts, lambda point: _at(point, M))


def check_frame(S: sp.Matrix, points: Points, problems: Problems) -> None:
    rank, reason = _generic_rank(S, points.for_(S))
    if rank is None:
        problems.add(f"frame: cannot be evaluated at any sampled point ({reason})")
    elif rank < S.rows:
        problems.add("frame: the matrix S (q_dot = S v) is singular at every sampled point")


def check_independent(rows: sp.Matrix, points: Points, label: str, problems: Problems) -> None:
    m = rows.rows
    rank, reason = _generic_rank(rows, points.for_(rows))
    if rank is None:
        problems.add(f"{label}: cannot be evaluated at any sampled point ({reason})")
    elif rank < m:
        problems.add(
            f"{label}: the one-forms are linearly dependent (rank {rank} < {m})"
            " at every sampled point"
        )


def constraint_row(
    f: Field, v: Sequence[sp.Symbol], points: Points, problems: Problems
) -> list[sp.Expr] | None:
    """Coefficient row mu of a constraint ``mu(q) v`` (see :func:`linear_form_row`)."""
    if not f.in_velocities:
        return list(f.value)
    try:
        return linear_form_row(f.value, v, points.for_)
    except NotQuadraticError as exc:
        problems.add(f"{f.label}: {short(f.value)} {exc}")
        return None
