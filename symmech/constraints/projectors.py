"""Gradients of constraint one-forms, their Gram matrix, and the g-orthogonal projectors.

Carnot paper (002), section 2.2.  For independent one-forms mu^a (rows of ``mu``, m x n)
and the metric g:

* ``Z^a = g^{-1} mu^a`` (the gradient of mu^a: ``g(Z^a, Y) = mu^a(Y)``), columns of ``Z``;
* ``C^ab = mu^a g^{-1} mu^b = mu^a(Z^b)``, the m x m Gram matrix (symmetric, regular);
* ``Q = C_ab Z^a (x) mu^b`` i.e. ``Q = Z C^{-1} mu``, the g-orthogonal projector onto
  D^perp = span{Z^a};
* ``P = I - Q``, the g-orthogonal projector onto the constraint distribution D = ker mu.

Matrices act on velocity columns (``P v``).  ``P`` is g-self-adjoint: ``g P = P^T g``.
"""

from __future__ import annotations

import sympy as sp

from symmech.algebra.field import common_domain, field_solve
from symmech.algebra.simplification import Level, check_level, polish, tidy_matrix

__all__ = ["gradients", "gram", "projectors", "solve_spd"]


def solve_spd(A: sp.MatrixBase, B: sp.MatrixBase, level: Level = "light") -> sp.Matrix:
    """Solve ``A X = B`` for a symmetric positive definite A.

    With a simplification level other than ``"none"`` the solve is exact, by the strategy
    of :func:`symmech.algebra.field.field_solve` (diagonal blocks divided directly, dense
    blocks by a fraction-free adjugate; every entry a cancelled fraction in the
    Pythagorean normal form, ``sin^2 -> 1 - cos^2``), then :func:`polish` at ``"full"``.
    With ``"none"``, or when that solve declines (no exact field, a normal form over its
    term budget), a diagonal A is divided directly and other matrices are solved by
    symbolic LU, then :func:`tidy` at ``level``.
    """
    check_level(level, "solve_spd", "level")
    X = field_solve(A, B) if level != "none" else None
    if X is not None:
        return X.applyfunc(lambda e: polish(e, level))
    if A.is_diagonal():
        X = sp.Matrix(B.rows, B.cols, lambda i, j: B[i, j] / A[i, i])
    else:
        X = A.LUsolve(B)
    return tidy_matrix(X, level)


def gradients(g: sp.MatrixBase, mu: sp.MatrixBase, level: Level = "light") -> sp.Matrix:
    """Z = g^{-1} mu^T: column a is the gradient Z^a of the one-form mu^a (Carnot §2.2)."""
    return solve_spd(g, mu.T, level)


def gram(g: sp.MatrixBase, mu: sp.MatrixBase, level: Level = "light") -> sp.Matrix:
    """C^ab = mu^a g^{-1} mu^b (Carnot §2.2), symmetric positive definite for independent mu."""
    Z = gradients(g, mu, "none")
    return tidy_matrix(mu * Z, level)


def projectors(
    g: sp.MatrixBase, mu: sp.MatrixBase, level: Level = "light"
) -> tuple[sp.Matrix, sp.Matrix]:
    """(P, Q): g-orthogonal projectors onto D = ker mu and onto D^perp; Q = Z C^{-1} mu.

    Carnot paper (002), section 2.2, ``Q = C_ab Z^a (x) mu^b``, ``P = id - Q``.
    With no constraints, P = I and Q = 0.
    """
    check_level(level, "projectors", "level")
    n = g.rows
    if mu.rows == 0:
        return sp.eye(n), sp.zeros(n, n)
    if level != "none":
        exact = _field_projectors(g, mu)
        if exact is not None:
            return exact
    Z = gradients(g, mu, "none")
    C = mu * Z
    Q = Z * solve_spd(C, mu, "none")
    Q = tidy_matrix(Q, level)
    P = tidy_matrix(sp.eye(n) - Q, level)
    return P, Q


def bordered(G: list[list], MU: list[list], zero: object) -> list[list]:
    """The bordered (KKT) matrix ``[[G, MU^T], [MU, 0]]`` of lists of field elements.

    Its inverse has ``P g^{-1}`` as top-left block (Carnot paper 002, section 2.2:
    ``g^{-1} - Z C^{-1} Z^T = (1 - Q) g^{-1}``), and ``[[G, MU^T], [MU, 0]] [x; -lambda]
    = [f; -mu_dot v]`` is the constrained equation of motion.
    """
    n, m = len(G), len(MU)
    top = [list(G[i]) + [MU[a][i] for a in range(m)] for i in range(n)]
    return top + [list(MU[a]) + [zero] * m for a in range(m)]


def _field_projectors(g: sp.MatrixBase, mu: sp.MatrixBase) -> tuple[sp.Matrix, sp.Matrix] | None:
    """(P, Q) computed exactly in the field of the entries of g and mu, every entry a
    cancelled fraction in the Pythagorean normal form (``sin^2 -> 1 - cos^2``, see
    :mod:`symmech.algebra.field`), or ``None`` when the entries admit no exact field or
    the solves decline.

    ``P = (B^{-1})_11 g`` with the bordered matrix ``B = [[g, mu^T], [mu, 0]]`` (see
    :func:`bordered`): one fraction-free solve whose shared denominator is ``det B``
    (``det g det C`` up to sign), so no Gram matrix with denominators is inverted.  When
    that solve declines, ``Z = g^{-1} mu^T``, ``C = mu Z`` and ``Q = Z C^{-1} mu`` are
    formed and normalised in the field.  Either way the car's ``C`` carries no
    ``sin^2 + cos^2``; forming these with nested symbolic quotients and cancelling
    afterwards costs seconds and leaves hundreds of thousands of operations for a
    generic 4 x 4 polynomial metric.
    """
    field = common_domain([g, mu])
    if not field.exact:
        return None
    n, m = g.rows, mu.rows
    G, MU = field.rows(g), field.rows(mu)
    one, zero = field.K.one, field.K.zero
    eye = [[one if i == j else zero for j in range(n)] for i in range(n)]
    X = field.solve(bordered(G, MU, zero), eye + [[zero] * n for _ in range(m)])
    if X is not None:
        P = field.matmul(X[:n], G)
        Q = [[field.normal(eye[i][j] - P[i][j]) for j in range(n)] for i in range(n)]
        return field.to_matrix(P), field.to_matrix(Q)
    Z = field.solve(G, [list(col) for col in zip(*MU, strict=True)])
    if Z is None:
        return None
    Y = field.solve(field.matmul(MU, Z), MU)
    if Y is None:
        return None
    Q = field.matmul(Z, Y)
    P = [[field.normal(eye[i][j] - Q[i][j]) for j in range(n)] for i in range(n)]
    return field.to_matrix(P), field.to_matrix(Q)
