"""Lie brackets of vector fields, Frobenius involutivity, bracket rank, frame coefficients.

Conventions (slides 000):

* "Computing Lie bracket in coordinates": for ``X = X^i d/dq^i`` and ``Y = Y^i d/dq^i``,
  ``[X, Y] = Z^i d/dq^i`` with ``Z^i = X^j dY^i/dq^j - Y^j dX^i/dq^j``
  ("``[X, Y] = nabla_X Y - nabla_Y X``").
* "Example: rolling ball": on a matrix manifold (e.g. ``SO(3)`` inside the 3 x 3 matrices)
  a field is a matrix ``X(R)`` and ``[X, Y] = d_X Y - d_Y X`` with the directional
  derivative ``d_X Y = sum_ab X_ab dY/dR_ab``.  This is the coordinate formula applied to
  the entries of ``R`` as coordinates; fields are flattened row by row internally.
* "Constrained mechanical system" (Frobenius integrability condition): a distribution
  spanned by ``X_1 .. X_k`` is integrable (holonomic) iff it is closed under the bracket.
* "Connection coefficients in a nonholonomic basis": a frame ``u_k`` (the columns of S)
  has commutation coefficients ``[u_k, u_l] = c^m_kl u_m``.

Generic rank policy (:data:`GENERIC_RANK_POLICY`): ranks of fields with non-constant
components are *generic* ranks, the rank at points off a measure-zero set.  Each rank is
computed twice: symbolically (exact linear algebra on the entries, simplified first when
``simplify=True``) and numerically (the largest rank, by a 40-digit SVD, over a few
reproducible random rational sample points, see :mod:`symmech.declaration.sampling`).
The numeric rank at a random point equals the generic rank with probability one, whereas
the symbolic rank is too large when sympy fails to recognise a zero (e.g. an unsimplified
``sin^2 + cos^2 - 1``).  So the numeric rank decides when it is available; disagreements
are reported in the result's ``notes``.  When the entries cannot be evaluated to numbers
(undefined functions), the symbolic rank is used alone and a note says so.  Matrix-valued
fields are sampled at generic points of the ambient matrix space (not of the submanifold).
"""

from __future__ import annotations

import numbers
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, TypeAlias

import mpmath
import sympy as sp
from sympy.polys.matrices import DomainMatrix

from symmech.algebra.budget import BudgetExceeded
from symmech.declaration.sampling import sample_points
from symmech.errors import SceneError
from symmech.geometry.field import common_domain
from symmech.geometry.simplification import Level, check_level, normal_form, polish, tidy

__all__ = [
    "GENERIC_RANK_POLICY",
    "BracketRankResult",
    "InvolutivityResult",
    "bracket_rank",
    "commutation_coefficients",
    "hat",
    "is_involutive",
    "lie_bracket",
]

GENERIC_RANK_POLICY = (
    "generic rank: rank off a measure-zero set of points; symbolic rank (exact, after "
    "simplification) cross-checked by the maximal 40-digit numeric rank at random rational "
    "sample points, the numeric rank deciding when available"
)

#: Number of random sample points of the numeric rank check.
_SAMPLES = 3
#: Working precision (digits) and relative singular-value threshold of the numeric rank.
_DPS = 40
_REL_TOL = mpmath.mpf(10) ** -25
#: An evaluated entry with fewer significant bits than this, or smaller in magnitude than
#: ``_ZERO_ABS``, is an exact zero that evalf could not resolve (cancellation).
_MIN_BITS = 20
_ZERO_ABS = sp.Float(10, _DPS) ** -60

Field: TypeAlias = sp.MatrixBase | Sequence[Any]
Point = Mapping[sp.Symbol, Any]


# --------------------------------------------------------------------------- validation


@dataclass(frozen=True)
class _Coords:
    """Validated coordinates: flat symbols and, for a matrix manifold, the matrix shape."""

    symbols: tuple[sp.Symbol, ...]
    shape: tuple[int, int] | None  # None: vector fields given as columns

    @property
    def n(self) -> int:
        return len(self.symbols)


def _coords(q: Any, where: str) -> _Coords:
    if isinstance(q, sp.MatrixBase):
        shape = (q.rows, q.cols) if q.rows > 1 and q.cols > 1 else None
        syms = list(q)
    elif isinstance(q, sp.Symbol):
        raise SceneError(f"{where}: q is the single symbol {q}; pass a sequence such as ({q},)")
    elif isinstance(q, (str, bytes)) or not isinstance(q, Iterable):
        raise SceneError(
            f"{where}: q must be a sequence of sympy Symbols or a matrix of Symbols, "
            f"got {type(q).__name__}"
        )
    else:
        shape = None
        syms = list(q)
    if not syms:
        raise SceneError(f"{where}: q is empty; give at least one coordinate")
    for i, s in enumerate(syms):
        if not isinstance(s, sp.Symbol):
            raise SceneError(f"{where}: q[{i}] = {s!r} is not a sympy Symbol")
    seen: set[sp.Symbol] = set()
    for s in syms:
        if s in seen:
            raise SceneError(f"{where}: coordinate {s} appears twice in q")
        seen.add(s)
    return _Coords(tuple(syms), shape)


def _component(c: Any, name: str, where: str) -> sp.Expr:
    if isinstance(c, sp.Expr):
        return c
    if isinstance(c, numbers.Number) and not isinstance(c, bool):
        return sp.sympify(c)
    raise SceneError(
        f"{where}: component {name} = {c!r} ({type(c).__name__}) is not a sympy expression"
    )


def _field(X: Any, cs: _Coords, name: str, where: str) -> sp.ImmutableMatrix:
    """Validate a field and return its components as a flat n x 1 column."""
    n = cs.n
    if cs.shape is not None:
        r, c = cs.shape
        if not isinstance(X, sp.MatrixBase):
            raise SceneError(
                f"{where}: {name} must be a {r}x{c} sympy Matrix (q is a {r}x{c} matrix of "
                f"coordinates), got {type(X).__name__}"
            )
        if X.shape != cs.shape:
            raise SceneError(
                f"{where}: {name} has shape {X.rows}x{X.cols} but q is a {r}x{c} matrix"
            )
        comps = [
            _component(X[i, j], f"{name}[{i}, {j}]", where) for i in range(r) for j in range(c)
        ]
        return sp.ImmutableMatrix(n, 1, comps)
    if isinstance(X, sp.MatrixBase):
        if X.shape != (n, 1):
            hint = (
                "; for matrix-valued fields pass q as a matrix of symbols"
                if X.rows > 1 and X.cols > 1
                else ""
            )
            raise SceneError(
                f"{where}: {name} has shape {X.rows}x{X.cols} but q has {n} coordinates, "
                f"so a {n}x1 column is required{hint}"
            )
        comps = list(X)
    elif isinstance(X, (str, bytes)) or not isinstance(X, Iterable):
        raise SceneError(
            f"{where}: {name} must be a {n}x1 sympy Matrix or a sequence of {n} expressions, "
            f"got {type(X).__name__}"
        )
    else:
        comps = list(X)
        if len(comps) != n:
            raise SceneError(
                f"{where}: {name} has {len(comps)} components but q has {n} coordinates"
            )
    return sp.ImmutableMatrix(
        n, 1, [_component(c, f"{name}[{i}]", where) for i, c in enumerate(comps)]
    )


def _fields(fields: Any, cs: _Coords, where: str) -> list[sp.ImmutableMatrix]:
    if isinstance(fields, (sp.MatrixBase, str, bytes)) or not isinstance(fields, Iterable):
        raise SceneError(
            f"{where}: fields must be a list of vector fields, got {type(fields).__name__}"
        )
    out = [_field(X, cs, f"fields[{i}]", where) for i, X in enumerate(fields)]
    if not out:
        raise SceneError(f"{where}: fields is empty; give at least one vector field")
    return out


def _shaped(Z: sp.MatrixBase, cs: _Coords) -> sp.Matrix:
    """Flat column back to the user's layout (n x 1, or the matrix shape of q)."""
    if cs.shape is None:
        return sp.Matrix(Z)
    return sp.Matrix(*cs.shape, list(Z))


# ------------------------------------------------------------------------------ brackets


def _bracket_poly(X: sp.MatrixBase, Y: sp.MatrixBase, q: Sequence[sp.Symbol]) -> sp.Matrix | None:
    """The bracket by sparse polynomial arithmetic when all components are polynomial in q.

    Returns None when they are not (the generic path is used).  The result is expanded.
    """
    exprs = [*X, *Y]
    if not all(e.is_polynomial(*q) for e in exprs):
        return None
    try:
        polys, _ = sp.parallel_poly_from_expr(exprs, *q)
    except sp.PolynomialError:
        return None
    n = len(q)
    P, Q = polys[:n], polys[n:]
    out = []
    for i in range(n):
        acc = P[i] * 0
        for j in range(n):
            if not P[j].is_zero:
                acc += P[j] * Q[i].diff(q[j])
            if not Q[j].is_zero:
                acc -= Q[j] * P[i].diff(q[j])
        out.append(acc.as_expr())
    return sp.Matrix(n, 1, out)


def _bracket_flat(X: sp.MatrixBase, Y: sp.MatrixBase, q: Sequence[sp.Symbol]) -> sp.Matrix:
    """``Z = (dY/dq) X - (dX/dq) Y`` on flat columns (slides 000, coordinates formula)."""
    n = len(q)
    out = []
    for i in range(n):
        terms = []
        for j in range(n):
            qj = q[j]
            if X[j] != 0 and qj in Y[i].free_symbols:
                terms.append(X[j] * sp.diff(Y[i], qj))
            if Y[j] != 0 and qj in X[i].free_symbols:
                terms.append(-Y[j] * sp.diff(X[i], qj))
        out.append(sp.Add(*terms))
    return sp.Matrix(n, 1, out)


def _bracket(
    X: sp.MatrixBase, Y: sp.MatrixBase, q: Sequence[sp.Symbol], level: Level
) -> sp.ImmutableMatrix:
    """Flat bracket, simplified at ``level`` (polynomial fields: expanded, canonical)."""
    fast = _bracket_poly(X, Y, q)
    if fast is not None:
        return sp.ImmutableMatrix(fast)
    return _tidy_col(_bracket_flat(X, Y, q), level)


def _tidy_entry(e: sp.Expr, level: Level) -> sp.Expr:
    """Simplify one component: polynomials are expanded (a canonical form), other
    expressions get the exact normal form with the Pythagorean reduction
    (:func:`~symmech.geometry.simplification.normal_form`, bounded in size), then
    :func:`~symmech.geometry.simplification.polish` at ``"full"``."""
    if level == "none":
        return e
    e = sp.expand(e)
    if e.is_polynomial():
        return e
    return polish(normal_form(e), level)


def _tidy_col(Z: sp.MatrixBase, level: Level) -> sp.ImmutableMatrix:
    return sp.ImmutableMatrix(Z.rows, 1, [_tidy_entry(e, level) for e in Z])


def lie_bracket(X: Field, Y: Field, q: Any, *, simplify: Level = "light") -> sp.Matrix:
    """The Lie bracket ``[X, Y]`` of two vector fields.

    Slides 000, "Computing Lie bracket in coordinates": with ``X = X^j d/dq^j`` and
    ``Y = Y^j d/dq^j``, ``[X, Y]^i = X^j dY^i/dq^j - Y^j dX^i/dq^j``.  The slides' example:

    >>> x, y, z = sp.symbols("x y z")
    >>> lie_bracket([y, 0, 0], [0, x, 0], (x, y, z)).T
    Matrix([[-x, y, 0]])

    Matrix-valued fields (slides 000, "Example: rolling ball"): when ``q`` is an r x c
    matrix of symbols (e.g. ``R = sp.Matrix(3, 3, sp.symbols("R0:9"))``), ``X`` and ``Y``
    are r x c matrices of functions of those entries and
    ``[X, Y] = d_X Y - d_Y X`` with ``d_X Y = sum_ab X_ab dY/dR_ab``:

    >>> R = sp.Matrix(3, 3, sp.symbols("R0:9"))
    >>> lie_bracket(hat((1, 0, 0)) * R, hat((0, 1, 0)) * R, R) == -hat((0, 0, 1)) * R
    True

    Args:
        X, Y: n x 1 Matrix or sequence of n expressions (``q`` a sequence of n symbols),
            or r x c Matrices (``q`` an r x c Matrix of symbols).
        q: the coordinates.
        simplify: ``"none"``, ``"light"`` or ``"full"``.  Fields polynomial in ``q`` are
            bracketed with sparse polynomial arithmetic and returned expanded (a
            canonical form) whatever the level.  Otherwise ``"none"`` returns the raw
            sum, and other levels expand each component, keep it if it is then a
            polynomial, else put it in the exact normal form of
            :func:`symmech.geometry.simplification.normal_form` (``sin^2 -> 1 - cos^2``
            where both occur; ``"full"`` then tries a bounded ``sympy.simplify``).

    Returns:
        ``[X, Y]`` as an n x 1 Matrix, or an r x c Matrix for matrix-valued fields.

    Raises:
        SceneError: naming the argument, when shapes do not match ``q``, a component is
            not a sympy expression, ``q`` is not a sequence/matrix of distinct Symbols, or
            ``simplify`` is not a level.
    """
    check_level(simplify, "lie_bracket")
    cs = _coords(q, "lie_bracket")
    Xf = _field(X, cs, "X", "lie_bracket")
    Yf = _field(Y, cs, "Y", "lie_bracket")
    Z = _bracket(Xf, Yf, cs.symbols, simplify)
    return _shaped(Z, cs)


def hat(w: Field) -> sp.Matrix:
    """The skew matrix ``[w x]`` with ``[w x] v = w x v`` (slides 000, "Example: rolling ball").

    >>> hat((1, 2, 3))
    Matrix([
    [ 0, -3,  2],
    [ 3,  0, -1],
    [-2,  1,  0]])
    """
    if isinstance(w, sp.MatrixBase):
        comps = list(w) if 1 in w.shape else None
    elif isinstance(w, (str, bytes)) or not isinstance(w, Iterable):
        comps = None
    else:
        comps = list(w)
    if comps is None or len(comps) != 3:
        raise SceneError(f"hat: w must be a 3-vector (3x1 Matrix or 3 expressions), got {w!r}")
    a, b, c = (_component(v, f"w[{i}]", "hat") for i, v in enumerate(comps))
    return sp.Matrix([[0, -c, b], [c, 0, -a], [-b, a, 0]])


# ---------------------------------------------------------------------------- generic rank


@dataclass(frozen=True)
class _Rank:
    rank: int
    symbolic: int
    numeric: int | None  # None: entries could not be evaluated to numbers


def _entry(e: sp.Expr, simplify: bool) -> sp.Expr:
    """Entry prepared for the symbolic rank: cancelled if rational, else bounded simplify."""
    if not simplify or e.is_Rational or e.is_polynomial():
        return e  # polynomials: the exact domain arithmetic of the rank needs nothing more
    if e.is_rational_function():
        return sp.cancel(e)
    return tidy(e, "full")


def _symbolic_rank(M: sp.Matrix) -> int:
    if all(e == 0 for e in M):
        return 0
    try:
        return int(DomainMatrix.from_Matrix(M).to_field().rank())
    except BudgetExceeded:  # a deadline of the stage around it
        raise
    except Exception:  # domain construction can fail on exotic expressions
        return int(M.rank(simplify=True))


def _numeric_value(e: sp.Expr, point: Point) -> mpmath.mpc | None:
    exact = e.xreplace(dict(point))
    if exact.is_Rational:  # polynomial / rational entries at rational points: no evalf
        return mpmath.mpf(int(exact.p)) / int(exact.q)
    if exact.free_symbols:
        return None
    v = exact.evalf(_DPS)
    if not v.is_number or v.has(sp.zoo, sp.oo, -sp.oo, sp.nan):
        return None
    try:
        parts = [_mp_part(part) for part in v.as_real_imag()]
    except (TypeError, ValueError):
        return None
    return parts[0] if parts[1] == 0 else mpmath.mpc(*parts)


def _mp_part(x: sp.Expr) -> mpmath.mpf:
    """A real part as an mpf; evalf's "no significant digit" results (``0.e-181``) are 0."""
    if x == 0:
        return mpmath.mpf(0)
    f = sp.Float(x, _DPS)
    if getattr(f, "_prec", _DPS) < _MIN_BITS or abs(f) < _ZERO_ABS:
        return mpmath.mpf(0)
    return mpmath.mpf(f)


def _numeric_rank_at(M: sp.Matrix, point: Point) -> int | None:
    rows, cols = M.shape
    with mpmath.workdps(_DPS):
        A = mpmath.matrix(rows, cols)
        for i in range(rows):
            for j in range(cols):
                v = _numeric_value(M[i, j], point)
                if v is None or not mpmath.isfinite(v):
                    return None
                A[i, j] = v
        # Column scaling does not change the rank and evens out the singular values.
        keep = []
        for j in range(cols):
            norm = mpmath.sqrt(sum(abs(A[i, j]) ** 2 for i in range(rows)))
            if norm != 0:
                keep.append(j)
                for i in range(rows):
                    A[i, j] /= norm
        if not keep:
            return 0
        B = mpmath.matrix(rows, len(keep))
        for i in range(rows):
            for jj, j in enumerate(keep):
                B[i, jj] = A[i, j]
        s = mpmath.svd(B, compute_uv=False)
        smax = max(abs(x) for x in s)
        return sum(1 for x in s if abs(x) > _REL_TOL * smax)


def _generic_rank(
    columns: Sequence[sp.MatrixBase], points: Sequence[Point], simplify: bool
) -> _Rank:
    M = sp.Matrix.hstack(*columns)
    symbolic = _symbolic_rank(M.applyfunc(lambda e: _entry(e, simplify)))
    ranks = [r for r in (_numeric_rank_at(M, p) for p in points) if r is not None]
    numeric = max(ranks) if ranks else None
    return _Rank(symbolic if numeric is None else numeric, symbolic, numeric)


def _sample(columns: Sequence[sp.MatrixBase], points: Sequence[Point] | None) -> list[Point]:
    if points is not None:
        return list(points)
    syms: set[sp.Symbol] = set()
    for col in columns:
        syms |= col.free_symbols
    return list(sample_points(syms, count=_SAMPLES))


def _note(label: str, r: _Rank) -> list[str]:
    if r.numeric is None:
        return [f"{label}: could not evaluate numerically; symbolic rank {r.symbolic} used"]
    if r.numeric != r.symbolic:
        return [
            f"{label}: symbolic rank {r.symbolic} disagrees with numeric rank {r.numeric} "
            "at the sample points; the numeric rank is used"
        ]
    return []


def _points_arg(points: Iterable[Point] | None, where: str) -> list[Point] | None:
    if points is None:
        return None
    pts = list(points)
    if not pts or not all(isinstance(p, Mapping) for p in pts):
        raise SceneError(f"{where}: points must be a non-empty list of {{symbol: value}} mappings")
    return pts


# ---------------------------------------------------------------------------- Frobenius


@dataclass(frozen=True)
class InvolutivityResult:
    """Outcome of the Frobenius test (slides 000, "Frobenius integrability condition").

    Truthy iff the distribution is involutive.  When it is not, ``pair = (i, j)`` and
    ``bracket = [X_i, X_j]`` (in the layout of the fields) certify it: the bracket is not in
    the span of the fields at generic points.  ``rank`` is the generic rank of the span.
    """

    involutive: bool
    rank: int
    dimension: int
    pair: tuple[int, int] | None = None
    bracket: sp.ImmutableMatrix | None = None
    notes: tuple[str, ...] = ()
    policy: str = field(default=GENERIC_RANK_POLICY, repr=False)

    def __bool__(self) -> bool:
        return self.involutive

    def _repr_latex_(self) -> str:
        if self.involutive:
            return f"$\\text{{involutive (rank {self.rank} of {self.dimension})}}$"
        i, j = self.pair or (0, 0)
        return (
            f"$\\text{{not involutive: }} [X_{{{i}}}, X_{{{j}}}] = {sp.latex(self.bracket)}"
            f" \\notin \\operatorname{{span}}\\{{X\\}}$"
        )


def is_involutive(
    fields: Sequence[Field],
    q: Any,
    *,
    simplify: bool = True,
    points: Iterable[Point] | None = None,
) -> InvolutivityResult:
    """Whether ``span{X_1 .. X_k}`` is closed under the Lie bracket (Frobenius).

    Slides 000, "Constrained mechanical system": the distribution is (locally) integrable,
    i.e. a holonomic constraint, iff ``[X_i, X_j] in span{X_1 .. X_k}`` for all i < j.
    Membership is tested as ``rank [X_1 .. X_k, [X_i, X_j]] == rank [X_1 .. X_k]`` with
    generic ranks (:data:`GENERIC_RANK_POLICY`).  Matrix-valued fields are flattened.

    Args:
        fields: the vector fields (layout as in :func:`lie_bracket`).
        q: the coordinates (sequence of symbols, or matrix of symbols).
        simplify: simplify entries before the symbolic rank and simplify the certificate.
        points: sample points ``{symbol: value}`` for the numeric check (default: three
            reproducible random rational points over all free symbols).  Pass points on a
            submanifold (e.g. rotations) to test there.

    Returns:
        An :class:`InvolutivityResult` (truthy iff involutive).
    """
    where = "is_involutive"
    cs = _coords(q, where)
    Xs = _fields(fields, cs, where)
    pts = _points_arg(points, where)
    level: Level = "light" if simplify else "none"
    sample = _sample(Xs, pts)
    base = _generic_rank(Xs, sample, simplify)
    notes = _note("rank of the fields", base)
    for i in range(len(Xs)):
        for j in range(i + 1, len(Xs)):
            Z = _bracket(Xs[i], Xs[j], cs.symbols, level)
            if all(e == 0 for e in Z):
                continue
            ext = _generic_rank([*Xs, Z], _sample([*Xs, Z], pts), simplify)
            notes += _note(f"rank with [X_{i}, X_{j}]", ext)
            if ext.rank > base.rank:
                return InvolutivityResult(
                    involutive=False,
                    rank=base.rank,
                    dimension=cs.n,
                    pair=(i, j),
                    bracket=sp.ImmutableMatrix(_shaped(Z, cs)),
                    notes=tuple(notes),
                )
    return InvolutivityResult(True, base.rank, cs.n, notes=tuple(notes))


# ---------------------------------------------------------------------------- bracket rank


@dataclass(frozen=True)
class BracketRankResult:
    """Generic rank of the fields and their iterated brackets up to a depth.

    ``fields`` lists the fields kept (in the layout of the input), ``words`` their brackets:
    the word ``(i,)`` is ``X_i``, ``(i, j)`` is ``[X_i, X_j]``, ``(i, j, k)`` is
    ``[X_i, [X_j, X_k]]`` (left-normed brackets span all iterated brackets).  A bracket is
    kept iff it raises the generic rank, so ``rank == len(fields)``.  ``dimension`` is the
    number of coordinates (matrix entries), ``manifold_dimension`` the ``dim`` compared with
    ``rank`` for ``bracket_generating``.
    """

    rank: int
    fields: tuple[sp.ImmutableMatrix, ...]
    words: tuple[tuple[int, ...], ...]
    depth: int
    dimension: int
    manifold_dimension: int
    bracket_generating: bool
    notes: tuple[str, ...] = ()
    policy: str = field(default=GENERIC_RANK_POLICY, repr=False)

    def _repr_latex_(self) -> str:
        words = ", ".join(_latex_word(w) for w in self.words)
        verdict = "bracket-generating" if self.bracket_generating else "not bracket-generating"
        return (
            f"$\\text{{rank {self.rank} of {self.manifold_dimension} at depth {self.depth}"
            f" ({verdict}): }} {words}$"
        )


def _latex_word(word: tuple[int, ...]) -> str:
    """``(i,) -> X_i``, ``(i, j, k) -> [X_i, [X_j, X_k]]`` (left-normed)."""
    out = f"X_{{{word[-1]}}}"
    for i in reversed(word[:-1]):
        out = f"[X_{{{i}}}, {out}]"
    return out


def bracket_rank(
    fields: Sequence[Field],
    q: Any,
    depth: int = 3,
    *,
    dim: int | None = None,
    simplify: bool = True,
    points: Iterable[Point] | None = None,
) -> BracketRankResult:
    """Generic rank of ``X_1 .. X_k`` and their iterated Lie brackets of length <= depth.

    The distribution is bracket-generating (Chow-Rashevskii: every nearby configuration is
    reachable, the non-holonomic situation of the slides 000 "car" and "rolling ball") when
    this rank equals the manifold dimension.  Brackets are built left-normed:
    level 1 is the fields, level d+1 is ``[X_i, W]`` for the fields ``X_i`` and the kept
    brackets ``W`` of level d.  A bracket that does not raise the generic rank is dropped;
    this loses nothing, since ``W = sum f_a W_a`` gives
    ``[X, W] = sum X(f_a) W_a + f_a [X, W_a]``.  Stops early once the rank reaches ``dim``.

    Args:
        fields: the vector fields (layout as in :func:`lie_bracket`).
        q: the coordinates.
        depth: maximal bracket length (1: the fields only).
        dim: manifold dimension (default: number of coordinates; for ``SO(3)`` in 3 x 3
            matrices pass ``dim=3``).
        simplify, points: as in :func:`is_involutive`.
    """
    where = "bracket_rank"
    cs = _coords(q, where)
    Xs = _fields(fields, cs, where)
    pts = _points_arg(points, where)
    if isinstance(depth, bool) or not isinstance(depth, int) or depth < 1:
        raise SceneError(f"{where}: depth must be an integer >= 1, got {depth!r}")
    if dim is None:
        dim = cs.n
    elif isinstance(dim, bool) or not isinstance(dim, int) or not 1 <= dim <= cs.n:
        raise SceneError(f"{where}: dim must be an integer in 1..{cs.n}, got {dim!r}")
    level: Level = "light" if simplify else "none"

    kept: list[sp.ImmutableMatrix] = []
    words: list[tuple[int, ...]] = []
    notes: list[str] = []
    rank = 0

    def offer(Z: sp.ImmutableMatrix, word: tuple[int, ...]) -> bool:
        nonlocal rank
        if all(e == 0 for e in Z):
            return False
        r = _generic_rank([*kept, Z], _sample([*kept, Z], pts), simplify)
        notes.extend(_note(f"rank with word {word}", r))
        if r.rank > rank:
            rank = r.rank
            kept.append(Z)
            words.append(word)
            return True
        return False

    frontier: list[tuple[sp.ImmutableMatrix, tuple[int, ...]]] = []
    for i, X in enumerate(Xs):
        if offer(X, (i,)):
            frontier.append((X, (i,)))
    for _ in range(2, depth + 1):
        if rank >= dim:
            break
        nxt = []
        for W, word in frontier:
            for i, X in enumerate(Xs):
                if word == (i,):
                    continue  # [X_i, X_i] = 0
                Z = _bracket(X, W, cs.symbols, level)
                if offer(Z, (i, *word)):
                    nxt.append((Z, (i, *word)))
                if rank >= dim:
                    break
            if rank >= dim:
                break
        frontier = nxt

    return BracketRankResult(
        rank=rank,
        fields=tuple(sp.ImmutableMatrix(_shaped(Z, cs)) for Z in kept),
        words=tuple(words),
        depth=depth,
        dimension=cs.n,
        manifold_dimension=dim,
        bracket_generating=rank >= dim,
        notes=tuple(notes),
    )


# -------------------------------------------------------------------------------- frames


def commutation_coefficients(
    S: sp.MatrixBase, q: Sequence[sp.Symbol], *, simplify: Level = "light"
) -> sp.ImmutableDenseNDimArray:
    """Commutation coefficients ``c^m_kl`` of the frame whose fields are the columns of S.

    Slides 000, "Connection coefficients in a nonholonomic basis":
    ``[u_k, u_l] = c^m_kl u_m``, so the column ``c^._kl`` solves ``S c = [u_k, u_l]``
    (``c^._kl = S^{-1} [u_k, u_l]``, by LU; the bracket as in :func:`lie_bracket`).
    ``c^m_kl = -c^m_lk`` is built in (only k < l is solved).

    Simplification policy: with a level other than ``"none"`` the solve is exact, by
    :meth:`symmech.geometry.field.RationalField.solve` over the field of the entries of S
    and the brackets with the Pythagorean reduction (``sin^2 -> 1 - cos^2`` wherever
    both occur), so the coefficients are cancelled fractions with reduced numerators and
    denominators (the rigid body's ``sin^2 psi + cos^2 psi`` comes out as 1), then a
    bounded ``sympy.simplify`` at ``"full"``.  When no exact field exists or the solve
    declines, the LU solution is expanded and put in the bounded normal form of
    :func:`symmech.geometry.simplification.normal_form`; ``"none"`` keeps the raw LU
    solution.

    Returns:
        Array of shape (n, n, n) with ``c[m, k, l] = c^m_kl``.

    Raises:
        SceneError: if S is not an n x n Matrix for the n coordinates, has non-expression
            entries, or is degenerate (generic rank < n).
    """
    where = "commutation_coefficients"
    check_level(simplify, where)
    cs = _coords(q, where)
    if cs.shape is not None:
        raise SceneError(f"{where}: q must be a sequence of coordinate symbols, not a matrix")
    n = cs.n
    if not isinstance(S, sp.MatrixBase):
        raise SceneError(f"{where}: S must be a {n}x{n} sympy Matrix, got {type(S).__name__}")
    if S.shape != (n, n):
        raise SceneError(
            f"{where}: S has shape {S.rows}x{S.cols} but q has {n} coordinates; "
            f"S must be {n}x{n} (one column per frame field)"
        )
    entries = [[_component(S[i, k], f"S[{i}, {k}]", where) for i in range(n)] for k in range(n)]
    cols = [sp.ImmutableMatrix(n, 1, col) for col in entries]
    r = _generic_rank(cols, _sample(cols, None), simplify=True)
    if r.rank < n:
        raise SceneError(f"{where}: S is degenerate: its columns have generic rank {r.rank} < {n}")
    Sm = sp.Matrix.hstack(*cols)
    pairs, rhs = [], []
    for k in range(n):
        for l in range(k + 1, n):
            B = _bracket(cols[k], cols[l], cs.symbols, simplify)
            if any(e != 0 for e in B):
                pairs.append((k, l))
                rhs.append(B)
    c = sp.MutableDenseNDimArray.zeros(n, n, n)
    if not pairs:
        return sp.ImmutableDenseNDimArray(c)
    try:
        sol, canonical = _lu_solve(Sm, sp.Matrix.hstack(*rhs), simplify)
    except (ValueError, ZeroDivisionError) as exc:
        raise SceneError(f"{where}: cannot solve S c = [u_k, u_l]: {exc}") from exc
    for p, (k, l) in enumerate(pairs):
        for m in range(n):
            v = polish(sol[m, p], simplify) if canonical else _tidy_entry(sol[m, p], simplify)
            c[m, k, l] = v
            c[m, l, k] = -v
    return sp.ImmutableDenseNDimArray(c)


def _lu_solve(S: sp.Matrix, B: sp.Matrix, level: Level) -> tuple[sp.Matrix, bool]:
    """Solve ``S C = B``; the flag tells whether the solution is in normal form.

    With a level other than ``"none"``: the exact solve in the field of the entries with
    the Pythagorean reduction (every entry a cancelled fraction of reduced polynomials in
    the parameters, coordinates, sin and cos; :mod:`symmech.geometry.field`).  Otherwise,
    or when no exact field exists or the solve declines: ``Matrix.LUsolve`` with sympy's
    zero testing, to be simplified by the caller.
    """
    if level != "none":
        field = common_domain([S, B], trig=True)
        if field.exact:
            X = field.solve(field.rows(S), field.rows(B))
            if X is not None:
                return field.to_matrix(X), True
    return S.LUsolve(B), False
