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
from sympy.polys.matrices import DomainMatrix

from symmech.geometry.field import common_domain, field_solve
from symmech.geometry.simplification import Level, tidy_matrix

__all__ = ["gradients", "gram", "projectors", "solve_spd"]


def solve_spd(A: sp.MatrixBase, B: sp.MatrixBase, level: Level = "light") -> sp.Matrix:
    """Solve ``A X = B`` for a symmetric positive definite A.

    A diagonal A is divided directly.  With a simplification level other than ``"none"``
    the solve runs in the fraction field of the entries (:func:`symmech.geometry.field.
    field_solve`: cancelled fractions, no nested LU quotients); otherwise, or when no such
    field exists, by symbolic LU.
    """
    if A.is_diagonal():
        X = sp.Matrix(B.rows, B.cols, lambda i, j: B[i, j] / A[i, i])
        return tidy_matrix(X, level)
    X = field_solve(A, B) if level != "none" else None
    if X is None:
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


def _field_projectors(g: sp.MatrixBase, mu: sp.MatrixBase) -> tuple[sp.Matrix, sp.Matrix] | None:
    """(P, Q) computed in the fraction field of the entries of g and mu (every entry a
    cancelled fraction), or ``None`` when the entries admit no such field.

    Forming ``Z C^{-1} mu`` with nested symbolic quotients and cancelling afterwards
    costs seconds and leaves hundreds of thousands of operations for a generic 4 x 4
    polynomial metric; in the field the same projector is a few cancelled fractions.
    """
    field = common_domain([g, mu])
    if field.K is None:
        return None
    gd, mud = field.matrix(g), field.matrix(mu)
    Z = gd.lu_solve(mud.transpose())
    C = mud.matmul(Z)
    Qd = Z.matmul(C.lu_solve(mud))
    Pd = DomainMatrix.eye(g.rows, field.K).to_dense().sub(Qd.to_dense())
    return field.to_sympy_matrix(Pd), field.to_sympy_matrix(Qd)
