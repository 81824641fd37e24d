"""Exact arithmetic in a rational-function field: the engine behind symmech's "light"
simplification of inverses, solves and energy identities.

Metric inverses, Gram inverses and projectors are rational functions of the parameters
and of the coordinates (or of sin/cos of them).  Building them with a symbolic LU
decomposition and cancelling afterwards is slow: the nested fractions of LU on a 3 x 3
polynomial metric take minutes to cancel.  Here the entries are converted once into a
sympy polynomial domain, the fraction field ``K = QQ(k, r, sin(theta), ...)`` built by
:func:`sympy.polys.constructor.construct_domain` after replacing functions and radicals by
dummy generators, and the linear algebra is done in K (:class:`DomainMatrix`), where every
element is a cancelled fraction.  The result is the same rational function, in cancelled
form, at a fraction of the cost.

Relations between generators (``sin^2 + cos^2 = 1``) are unknown to K: results are exact
but not trigonometrically simplified.  When no field exists (the domain would be ``EX``),
:func:`field_solve` returns ``None`` and callers use plain sympy arithmetic.
"""

from __future__ import annotations

from collections.abc import Sequence

import sympy as sp
from sympy.polys.constructor import construct_domain
from sympy.polys.matrices import DomainMatrix

__all__ = ["RationalField", "common_domain", "field_inverse", "field_solve"]


def _generators(exprs: Sequence[sp.Expr]) -> dict[sp.Basic, sp.Expr]:
    """Replace every non-rational building block by a dummy symbol.

    ``u**(p/q)`` becomes ``d**p`` with ``d`` standing for ``u**(1/q)`` (so that
    ``sqrt(u) * u**(-1/2) = 1`` survives); functions (sin, cos, f(t), derivatives) become
    dummies.  The energy identities are rational identities in the entries of g, d psi
    and the constraints, so they hold with these blocks treated as independent symbols.
    """
    table: dict[sp.Basic, sp.Expr] = {}
    roots: dict[tuple[sp.Expr, int], sp.Dummy] = {}

    def visit(e: sp.Basic) -> None:
        if e in table or e.is_Atom:
            return
        if isinstance(e, sp.Pow) and e.exp.is_Rational and not e.exp.is_Integer:
            base, p, q = e.base, e.exp.p, e.exp.q
            visit(base)
            d = roots.setdefault((base, q), sp.Dummy("root"))
            table[e] = d**p
            return
        if isinstance(e, (sp.Function, sp.Derivative)) or (
            isinstance(e, sp.Pow) and not e.exp.is_Integer
        ):
            table[e] = sp.Dummy("gen")
            return
        for arg in e.args:
            visit(arg)

    for e in exprs:
        visit(sp.sympify(e))
    return table


class RationalField:
    """A common domain for a set of matrices and scalars (or sympy fallback)."""

    def __init__(self, exprs: Sequence[sp.Expr]):
        self.forward = _generators(exprs)
        self.back = {}
        for key, value in self.forward.items():
            if isinstance(value, sp.Dummy):
                self.back[value] = key
            else:  # d**p for u**(p/q): d = u**(1/q)
                base, q = key.base, key.exp.q
                self.back[value.base if isinstance(value, sp.Pow) else value] = base ** sp.Rational(
                    1, q
                )
        replaced = [sp.sympify(e).xreplace(self.forward) for e in exprs] or [sp.S.One]
        K, _ = construct_domain(replaced, field=True)
        self.K = None if K.is_EX or K.is_EXRAW else K

    def _in(self, e: sp.Expr) -> sp.Expr:
        return sp.sympify(e).xreplace(self.forward)

    def _out(self, e: sp.Expr) -> sp.Expr:
        return sp.sympify(e).xreplace(self.back) if self.back else e

    def matrix(self, M: sp.MatrixBase) -> DomainMatrix | sp.Matrix:
        M = sp.Matrix(M)
        if self.K is None:
            return M
        rows = [[self.K.from_sympy(self._in(e)) for e in M.row(i)] for i in range(M.rows)]
        return DomainMatrix(rows, M.shape, self.K)

    def scalar(self, e: sp.Expr):
        e = sp.sympify(e)
        return e if self.K is None else self.K.from_sympy(self._in(e))

    def to_sympy_matrix(self, M) -> sp.Matrix:
        return M if self.K is None else M.to_Matrix().applyfunc(self._out)

    def to_sympy(self, e) -> sp.Expr:
        return e if self.K is None else self._out(self.K.to_sympy(e))


def common_domain(
    matrices: Sequence[sp.MatrixBase], scalars: Sequence[sp.Expr] = ()
) -> RationalField:
    """A domain holding every entry of ``matrices`` and every scalar."""
    exprs = [sp.sympify(e) for M in matrices for e in M] + [sp.sympify(s) for s in scalars]
    return RationalField(exprs)


def field_solve(A: sp.MatrixBase, B: sp.MatrixBase) -> sp.Matrix | None:
    """``A^{-1} B`` computed exactly in the fraction field of the entries, every entry a
    cancelled fraction; ``None`` if the entries admit no such field.  ``A`` must be
    square and generically regular (a ``ZeroDivisionError`` from sympy means it is not).
    """
    A, B = sp.Matrix(A), sp.Matrix(B)
    ring = common_domain([A, B])
    if ring.K is None:
        return None
    Ad, Bd = ring.matrix(A), ring.matrix(B)
    X = Ad.lu_solve(Bd)
    return ring.to_sympy_matrix(X)


def field_inverse(A: sp.MatrixBase) -> sp.Matrix | None:
    """``A^{-1}`` in the fraction field of its entries (see :func:`field_solve`)."""
    A = sp.Matrix(A)
    return field_solve(A, sp.eye(A.rows))
