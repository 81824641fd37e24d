"""Christoffel symbols, connection coefficients in a frame, and the forcing term.

Conventions (slides 000, "Geodesics in coordinates" and "Connection coefficients in a
nonholonomic basis"; Carnot paper 002, eq. 2):

* Coordinates: ``Gamma_kij = 1/2 (d_i g_jk + d_j g_ik - d_k g_ij)`` (first kind) and
  ``Gamma^k_ij = g^kl Gamma_lij`` (second kind); the geodesic equation with a potential is
  ``q_ddot^k + Gamma^k_ij q_dot^i q_dot^j = -g^kl dV/dq^l``.
* A frame ``u_k`` (columns of S, ``q_dot = S v``) with commutation coefficients
  ``[u_k, u_l] = c^m_kl u_m``: ``nabla_{u_i} u_j = omega^m_ij u_m`` with, by the Koszul
  formula, ``omega_mij = g(nabla_{u_i} u_j, u_m) =
  1/2 (u_i(g_jm) + u_j(g_im) - u_m(g_ij) + c_ijm - c_imj - c_jmi)``, ``c_abm = g_mp c^p_ab``.
  The slides print ``... + c_mkl + c_mlk - c_klm`` which agrees with this in the part
  symmetric in (k, l) (all that enters the equations of motion) but has the opposite sign
  on ``c_klm``; with the printed sign the connection would not be torsion-free
  (``omega^m_kl - omega^m_lk`` must equal ``c^m_kl``).  The tests check torsion-freeness
  and metric compatibility, so the Koszul form is used.
* Simplification: the raised symbols (Christoffel symbols of the second kind, connection
  coefficients) follow the policy of :func:`_raise_index`: exact normal forms computed
  fraction-free with one shared determinant and the Pythagorean reduction, symbols
  formed for i <= j only in coordinates and mirrored; the lowered ones and the forcing
  are cheap and follow :func:`~symmech.algebra.simplification.simplify_all`.
* Equations of motion in the velocity basis (Kane / Hamel form, slides "Kane's method of
  quasi-velocities"): ``M v_dot = f`` with
  ``f_k = -omega_kij v^i v^j - u_k(V)``; in coordinates ``omega = Gamma`` and
  ``f_k = -Gamma_kij q_dot^i q_dot^j - dV/dq^k`` (first kind: no inverse is needed).
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence

import sympy as sp

from symmech.algebra.canonical import add, keep_coeff, mul
from symmech.algebra.field import field_solve
from symmech.algebra.memo import expression_cache
from symmech.algebra.simplification import Level, check_level, polish, simplify_all, tidy
from symmech.geometry.derivatives import Derivative

__all__ = [
    "christoffel_first_kind",
    "christoffel_second_kind",
    "connection_coefficients",
    "connection_first_kind",
    "forcing",
]


_Sparse = dict[tuple[int, int], list[tuple[int, sp.Expr]]]


def _sparse(c: sp.Array | None, n: int) -> _Sparse | None:
    """The non-zero commutation coefficients by lower pair: ``(a, b) -> [(p, c^p_ab)]``,
    p ascending (read once: indexing a sympy Array costs more than the product it feeds)."""
    if c is None:
        return None
    out: _Sparse = {}
    for a in range(n):
        for b in range(n):
            nz = [(p, c[p, a, b]) for p in range(n) if c[p, a, b] != 0]
            if nz:
                out[(a, b)] = nz
    return out


def _lowered(
    G: sp.MatrixBase,
    D: Derivative,
    c: _Sparse | None,
    k: int,
    i: int,
    j: int,
) -> sp.Expr:
    """omega_kij = g(nabla_{u_i} u_j, u_k) (Koszul formula; c = None for coordinates, else
    the commutation coefficients as :func:`_sparse` gives them)."""
    out = (D(G[j, k], i) + D(G[i, k], j) - D(G[i, j], k)) / 2
    if c is not None:

        def low(a: int, b: int, m: int) -> sp.Expr:  # c_abm = g_mp c^p_ab
            return sp.Add(*[G[m, p] * cp for p, cp in c.get((a, b), ())])

        out += (low(i, j, k) - low(i, k, j) - low(j, k, i)) / 2
    return out


def christoffel_first_kind(
    g: sp.MatrixBase, q: Sequence[sp.Symbol], level: Level = "light"
) -> sp.ImmutableDenseNDimArray:
    """Gamma_kij = 1/2 (d_i g_jk + d_j g_ik - d_k g_ij) as an Array ``[k, i, j]``.

    Slides 000, "Geodesics in coordinates" (the bracketed sum before raising the index).
    Computed for i <= j only and mirrored; derivatives of entries that do not contain a
    coordinate are never formed.  Simplification: :func:`~symmech.geometry.
    simplification.simplify_all` (``"light"``: exact normal form with the Pythagorean
    reduction; ``"full"``: then a bounded ``sympy.simplify``).
    """
    check_level(level, "christoffel_first_kind")
    D = Derivative(q)
    n = len(q)
    index = [(k, i, j) for k in range(n) for i in range(n) for j in range(i, n)]
    values = simplify_all([_lowered(g, D, None, k, i, j) for k, i, j in index], level)
    out = [[[sp.S.Zero] * n for _ in range(n)] for _ in range(n)]
    for (k, i, j), val in zip(index, values, strict=True):
        out[k][i][j] = out[k][j][i] = val
    return sp.ImmutableDenseNDimArray(out)


def _raise_index(
    g: sp.MatrixBase, columns: Sequence[Sequence[sp.Expr]], level: Level
) -> list[list[sp.Expr]]:
    """``X = g^{-1} F`` for the columns of F (each a list of n lowered components).

    Simplification policy of the raised symbols (the "documented policy"; see also
    :mod:`symmech.algebra.simplification`):

    * ``"none"``: a diagonal g is divided directly, otherwise a symbolic LU solve, as built;
    * ``"light"`` (default): a diagonal g is divided directly and each entry put in the
      normal form of :func:`~symmech.algebra.simplification.normal_form`.  Otherwise the
      exact solve of :func:`symmech.algebra.field.field_solve`, which chooses its route
      by cost: a fraction-free adjugate and determinant formed once, every minor reduced
      by ``sin^2 -> 1 - cos^2`` (where both occur), ``X = (adj g) F / det g`` with the
      determinant shared by all entries and cancelled against each numerator (by a gcd
      while it has at most 400 terms, else by its monomial and integer content).  When it
      declines (no exact field, a dense block larger than 8 x 8, or minors over the term
      budget, as for the pendulum on a cart with 6 or more links) the LU solution is
      returned with :func:`tidy` applied, which skips large entries, so the cost stays
      bounded and the result exact;
    * ``"full"``: ``"light"``, then ``sympy.simplify`` on each entry of at most
      :data:`symmech.algebra.budget.FULL_SIMPLIFY_OPS` operations, kept only when it is not
      longer (:func:`polish`).
    """
    n = g.rows
    F = sp.Matrix(n, len(columns), lambda k, c: columns[c][k])
    if g.is_diagonal():
        return [simplify_all([col[k] / g[k, k] for k in range(n)], level) for col in columns]
    X = field_solve(g, F) if level != "none" else None
    if X is None:
        X = g.LUsolve(F)
        return [[tidy(X[k, c], level) for k in range(n)] for c in range(F.cols)]
    return [[polish(X[k, c], level) for k in range(n)] for c in range(F.cols)]


def christoffel_second_kind(
    g: sp.MatrixBase, q: Sequence[sp.Symbol], level: Level = "light"
) -> sp.ImmutableDenseNDimArray:
    """Gamma^k_ij = g^kl Gamma_lij as an Array ``[k, i, j]`` (slides 000, Christoffel symbol).

    Formed for i <= j only (``Gamma^k_ij = Gamma^k_ji``) and mirrored: one solve
    ``g X = F`` with the n (n + 1) / 2 columns ``F_(ij) = Gamma_.ij``.  Simplification
    policy: :func:`_raise_index`.  For the equations of motion of large systems use
    :func:`forcing` (first kind, no inverse).
    """
    check_level(level, "christoffel_second_kind")
    n = len(q)
    first = christoffel_first_kind(g, q, level="none")
    pairs = [(i, j) for i in range(n) for j in range(i, n)]
    cols = [[first[k, i, j] for k in range(n)] for i, j in pairs]
    raised = _raise_index(sp.Matrix(g), cols, level)
    out = [[[sp.S.Zero] * n for _ in range(n)] for _ in range(n)]
    for (i, j), col in zip(pairs, raised, strict=True):
        for k in range(n):
            out[k][i][j] = out[k][j][i] = col[k]
    return sp.ImmutableDenseNDimArray(out)


def connection_first_kind(
    G: sp.MatrixBase,
    q: Sequence[sp.Symbol],
    frame: sp.MatrixBase | None,
    commutation: sp.Array | None,
    level: Level = "light",
) -> sp.ImmutableDenseNDimArray:
    """omega_kij = g(nabla_{u_i} u_j, u_k) as an Array ``[k, i, j]`` (Koszul formula).

    ``G`` is the metric in the frame, ``frame`` the matrix S whose columns are the u_i in
    coordinates q (None: coordinate frame) and ``commutation[m, k, l] = c^m_kl``.
    """
    check_level(level, "connection_first_kind")
    n = len(q)
    D = Derivative(q, frame)
    c = None if frame is None else _sparse(commutation, n)
    index = [(k, i, j) for k in range(n) for i in range(n) for j in range(n)]
    values = simplify_all([_lowered(G, D, c, k, i, j) for k, i, j in index], level)
    return sp.ImmutableDenseNDimArray(values, (n, n, n))


def connection_coefficients(
    G: sp.MatrixBase,
    q: Sequence[sp.Symbol],
    frame: sp.MatrixBase | None,
    commutation: sp.Array | None,
    level: Level = "light",
) -> sp.ImmutableDenseNDimArray:
    """omega^m_ij with ``nabla_{u_i} u_j = omega^m_ij u_m``, an Array ``[m, i, j]``.

    Slides 000, "Connection coefficients in a nonholonomic basis" (sign of the c_klm term
    re-derived, see the module docstring).  Equals Gamma^m_ij in a coordinate frame.
    """
    check_level(level, "connection_coefficients")
    if frame is None:
        return christoffel_second_kind(G, q, level)
    n = len(q)
    low = connection_first_kind(G, q, frame, commutation, level="none")
    pairs = [(i, j) for i in range(n) for j in range(n)]
    raised = _raise_index(sp.Matrix(G), [[low[k, i, j] for k in range(n)] for i, j in pairs], level)
    out = [[[sp.S.Zero] * n for _ in range(n)] for _ in range(n)]
    for (i, j), col in zip(pairs, raised, strict=True):
        for k in range(n):
            out[k][i][j] = col[k]
    return sp.ImmutableDenseNDimArray(out)


def forcing(
    G: sp.MatrixBase,
    V: sp.Expr,
    q: Sequence[sp.Symbol],
    v: Sequence[sp.Symbol],
    frame: sp.MatrixBase | None = None,
    commutation: sp.Array | None = None,
    level: Level = "none",
) -> sp.Matrix:
    """f with ``G v_dot = f``: ``f_k = -omega_kij v^i v^j - u_k(V)`` (first kind, no inverse).

    In coordinates this is ``f_k = -Gamma_kij q_dot^i q_dot^j - dV/dq^k`` (slides 000,
    geodesic equation; Carnot paper eq. 2 multiplied by g).  Only the part of omega
    symmetric in (i, j) contributes; it is formed for i <= j, with zero metric derivatives
    skipped, so the cost grows with the number of non-zero terms, not n^3.  The
    velocity-quadratic part is memoised (:func:`_quadratic`): a scene imported from a
    mechanics model forms it once for the comparison with Kane's inertia forces and
    once as its forcing.
    """
    check_level(level, "forcing")
    D = Derivative(q, frame)
    quadratic = _quadratic(
        sp.ImmutableMatrix(G),
        tuple(q),
        tuple(v),
        None if frame is None else sp.ImmutableMatrix(frame),
        None if commutation is None else sp.ImmutableDenseNDimArray(commutation),
    )
    V = sp.sympify(V, strict=True)
    if frame is None:
        rows = [_minus(f, D(V, k)) for k, f in enumerate(quadratic)]
    else:
        rows = [f - D(V, k) for k, f in enumerate(quadratic)]
    return sp.Matrix([tidy(r, level) for r in rows])


@expression_cache(maxsize=64)
def _quadratic(
    G: sp.ImmutableMatrix,
    q: tuple[sp.Symbol, ...],
    v: tuple[sp.Symbol, ...],
    frame: sp.ImmutableMatrix | None,
    commutation: sp.Array | None,
) -> tuple[sp.Expr, ...]:
    """``-omega_kij v^i v^j`` for each k, as :func:`forcing` sums it (in coordinates
    :func:`_quadratic_coordinates`), memoised until sympy's cache is cleared."""
    n = len(q)
    D = Derivative(q, frame)
    if frame is None:
        return _quadratic_coordinates(G, q, v, D)
    c = _sparse(commutation, n)
    rows = []
    for k in range(n):
        terms = []
        for i in range(n):
            for j in range(i, n):
                w = _lowered(G, D, c, k, i, j)
                if c is not None:
                    # the symmetric part only: drop the antisymmetric c_ijk contribution
                    w = (w + _lowered(G, D, c, k, j, i)) / 2
                if w == 0:
                    continue
                terms.append(w * v[i] ** 2 if i == j else 2 * w * v[i] * v[j])
        rows.append(-sp.Add(*terms))
    return tuple(rows)


def _quadratic_coordinates(
    G: sp.MatrixBase,
    q: Sequence[sp.Symbol],
    v: Sequence[sp.Symbol],
    D: Derivative,
) -> tuple[sp.Expr, ...]:
    """Sparse assembly of ``-Gamma_kij v^i v^j`` from the metric derivatives.

    With ``Gamma_kij v^i v^j = sum_ij (d_i g_jk - 1/2 d_k g_ij) v^i v^j``, every non-zero
    derivative ``d = d g_ij / d q^a`` (i <= j) is visited once and scattered:
    ``+1/2 d v^i v^j`` (counted for (i, j) and (j, i)) into f_a, and ``-d v^a v^j`` into f_i,
    ``-d v^a v^i`` into f_j.  Terms are grouped by velocity monomial, so each f_k reads
    ``sum (-Gamma_kij) v^i v^j`` with one coefficient per monomial.  Cost: the number of
    non-zero metric derivatives, not n^3.  The derivatives are scattered as their terms
    (:meth:`Derivative.partial_terms`), each scaled as sympy scales a sum, and summed
    once per coefficient: the same expressions as summing the scaled derivatives.
    """
    n = len(q)
    acc: list[dict[tuple[int, int], list[sp.Expr]]] = [defaultdict(list) for _ in range(n)]
    half, minus = sp.S.Half, sp.S.NegativeOne

    def scatter(k: int, i: int, j: int, c: sp.Rational, terms: list[sp.Expr]) -> None:
        # c * d, as sympy distributes a rational over the terms of d, summed later
        acc[k][(i, j) if i <= j else (j, i)].extend(keep_coeff(c, t) for t in terms)

    for i in range(n):
        for j in range(i, n):
            gij = G[i, j]
            fs = D.free_symbols(gij)
            if not fs:
                continue
            for a in range(n):
                if q[a] not in fs:
                    continue
                d = D.partial_terms(gij, a)  # d g_ij / d q^a, as its terms
                if not d:
                    continue
                if i == j:
                    scatter(a, i, i, half, d)
                    scatter(i, a, i, minus, d)
                else:
                    scatter(a, i, j, sp.S.One, d)
                    scatter(i, a, j, minus, d)
                    scatter(j, a, i, minus, d)
    return tuple(
        add(*[mul(add(*coefs), v[i], v[j]) for (i, j), coefs in acc[k].items()]) for k in range(n)
    )


def _minus(x: sp.Expr, y: sp.Expr) -> sp.Expr:
    """``x - y`` as the operator computes it (``sympy.Add(x, -y)``; numbers by number
    arithmetic)."""
    if x.is_Number and y.is_Number:
        return x - y
    return add(x, mul(sp.S.NegativeOne, y) if y.is_Add else -y)
