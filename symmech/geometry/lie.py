"""Lie brackets of vector fields and the commutation coefficients of a frame.

Conventions (slides 000):

* "Computing Lie bracket in coordinates": for ``X = X^i d/dq^i`` and ``Y = Y^i d/dq^i``,
  ``[X, Y] = Z^i d/dq^i`` with ``Z^i = X^j dY^i/dq^j - Y^j dX^i/dq^j``
  ("``[X, Y] = nabla_X Y - nabla_Y X``").
* "Example: rolling ball": on a matrix manifold (e.g. ``SO(3)`` inside the 3 x 3 matrices)
  a field is a matrix ``X(R)`` and ``[X, Y] = d_X Y - d_Y X`` with the directional
  derivative ``d_X Y = sum_ab X_ab dY/dR_ab``.  This is the coordinate formula applied to
  the entries of ``R`` as coordinates; fields are flattened row by row internally.
* "Connection coefficients in a nonholonomic basis": a frame ``u_k`` (the columns of S)
  has commutation coefficients ``[u_k, u_l] = c^m_kl u_m``.

Involutivity (Frobenius) and the bracket rank of a distribution are in
:mod:`symmech.geometry.distributions`.
"""

from __future__ import annotations

import numbers
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, TypeAlias

import sympy as sp

from symmech.algebra import budget as limits
from symmech.algebra.field import common_domain
from symmech.algebra.simplification import Level, check_level, normal_form, polish
from symmech.errors import SceneError
from symmech.geometry.span_rank import _generic_rank, _sample

__all__ = [
    "Field",
    "commutation_coefficients",
    "hat",
    "lie_bracket",
]

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
        e = c
    elif isinstance(c, numbers.Number) and not isinstance(c, bool):
        e = sp.sympify(c, strict=True)
    else:
        raise SceneError(
            f"{where}: component {name} = {c!r} ({type(c).__name__}) is not a sympy expression"
        )
    if e.has(sp.nan, sp.zoo, sp.oo, -sp.oo) or (e.is_number and e.is_extended_real is False):
        raise SceneError(f"{where}: component {name} = {c!r} is not finite and real")
    return e


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
    (:func:`~symmech.algebra.simplification.normal_form`, bounded in size), then
    :func:`~symmech.algebra.simplification.polish` at ``"full"``."""
    if level == "none":
        return e
    if not limits.affordable(e, limits.ZERO_EXACT_OPS):
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
            :func:`symmech.algebra.simplification.normal_form` (``sin^2 -> 1 - cos^2``
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
    :meth:`symmech.algebra.field.RationalField.solve` over the field of the entries of S
    and the brackets with the Pythagorean reduction (``sin^2 -> 1 - cos^2`` wherever
    both occur), so the coefficients are cancelled fractions with reduced numerators and
    denominators (the rigid body's ``sin^2 psi + cos^2 psi`` comes out as 1), then a
    bounded ``sympy.simplify`` at ``"full"``.  When no exact field exists or the solve
    declines, the LU solution is expanded and put in the bounded normal form of
    :func:`symmech.algebra.simplification.normal_form`; ``"none"`` keeps the raw LU
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
    the parameters, coordinates, sin and cos; :mod:`symmech.algebra.field`).  Otherwise,
    or when no exact field exists or the solve declines: ``Matrix.LUsolve`` with sympy's
    zero testing, to be simplified by the caller.
    """
    if level != "none":
        field = common_domain([S, B])
        if field.exact:
            X = field.solve(field.rows(S), field.rows(B))
            if X is not None:
                return field.to_matrix(X), True
    return S.LUsolve(B), False
