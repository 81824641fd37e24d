"""Exact arithmetic for energy identities: quadratic forms over a rational-function field.

Carnot's theorems compare kinetic energies, quadratic in the velocities with coefficients
that are rational functions of the parameters (and of sin/cos of the coordinates).  Summing
them as sympy expressions and calling :func:`sympy.cancel` on the result is slow (tens of
seconds for Example 3.13).  Here every coefficient matrix is converted once into a common
sympy polynomial domain (the fraction field ``QQ(k, r, alpha, sin(theta), ...)``, built by
:func:`sympy.polys.constructor.construct_domain` after replacing functions and radicals
by dummy generators), where sums and products are canonical, so "is this identically
zero" is exact and cheap.  Relations between generators (``sin^2 + cos^2 = 1``,
``sqrt(u)^2 = u``) are not known to the field, so a non-zero result is passed through
:func:`sympy.cancel` / :func:`sympy.simplify` before it is reported.
If no such domain exists (the domain would be ``EX``), plain sympy arithmetic is used.
"""

from __future__ import annotations

from collections.abc import Sequence

import sympy as sp
from sympy.polys.constructor import construct_domain
from sympy.polys.matrices import DomainMatrix

__all__ = ["Affine", "QuadraticForm", "common_domain"]

_SIMPLIFY_MAX_OPS = 300


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


class _Ring:
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


def common_domain(matrices: Sequence[sp.MatrixBase], scalars: Sequence[sp.Expr] = ()) -> _Ring:
    """A domain holding every entry of ``matrices`` and every scalar."""
    exprs = [sp.sympify(e) for M in matrices for e in M] + [sp.sympify(s) for s in scalars]
    return _Ring(exprs)


class Affine:
    """The affine map ``v -> L v + o`` of the velocity symbols, in a common domain."""

    def __init__(self, ring: _Ring, L, o):
        self.ring, self.L, self.o = ring, L, o

    @classmethod
    def of(cls, ring: _Ring, L: sp.MatrixBase, o: sp.MatrixBase) -> Affine:
        return cls(ring, ring.matrix(L), ring.matrix(o))

    def __add__(self, other: Affine) -> Affine:
        return Affine(self.ring, self.L + other.L, self.o + other.o)

    def __sub__(self, other: Affine) -> Affine:
        return Affine(self.ring, self.L - other.L, self.o - other.o)

    def apply(self, M) -> Affine:
        """``M (L v + o)`` for a domain matrix M."""
        return Affine(self.ring, M * self.L, M * self.o)

    def shift(self, w) -> Affine:
        """``L v + o + w`` for a domain column w."""
        return Affine(self.ring, self.L, self.o + w)

    def to_sympy(self, v: sp.Matrix) -> sp.Matrix:
        r = self.ring
        return r.to_sympy_matrix(self.L) * v + r.to_sympy_matrix(self.o)


class QuadraticForm:
    """``v^T A v + b^T v + c`` with A symmetric, coefficients in a common domain."""

    def __init__(self, ring: _Ring, A, b, c):
        self.ring, self.A, self.b, self.c = ring, A, b, c

    @classmethod
    def energy(cls, g, x: Affine) -> QuadraticForm:
        """``T(x) = 1/2 g(x, x)`` for the affine velocity x and the domain metric g."""
        return cls.bilinear(g, x, x).scale(sp.Rational(1, 2))

    @classmethod
    def bilinear(cls, g, x: Affine, y: Affine) -> QuadraticForm:
        """``g(x, y)`` (symmetrised in v)."""
        r = x.ring
        A = x.L.transpose() * g * y.L
        A = (A + A.transpose()) * r.scalar(sp.Rational(1, 2))
        b = (x.o.transpose() * g * y.L).transpose() + (y.o.transpose() * g * x.L).transpose()
        c = x.o.transpose() * g * y.o
        return cls(r, A, b, c)

    def __add__(self, other: QuadraticForm) -> QuadraticForm:
        return QuadraticForm(self.ring, self.A + other.A, self.b + other.b, self.c + other.c)

    def __sub__(self, other: QuadraticForm) -> QuadraticForm:
        return self + other.scale(-1)

    def scale(self, k: sp.Expr) -> QuadraticForm:
        s = self.ring.scalar(k)
        return QuadraticForm(self.ring, self.A * s, self.b * s, self.c * s)

    def expr(self, v: sp.Matrix, simplify: bool = False) -> sp.Expr:
        """The form as a sympy expression in the velocity symbols v, each coefficient
        cancelled (and, with ``simplify``, simplified when small and non-zero, for
        trigonometric or radical relations)."""
        r = self.ring
        A = r.to_sympy_matrix(self.A)
        b = r.to_sympy_matrix(self.b)
        c = r.to_sympy_matrix(self.c)[0, 0]
        n = A.rows

        def clean(e: sp.Expr) -> sp.Expr:
            return _clean(e, simplify)

        out = clean(c)
        for i in range(n):
            out += clean(A[i, i]) * v[i] ** 2
            for j in range(i + 1, n):
                out += clean(2 * A[i, j]) * v[i] * v[j]
            out += clean(b[i]) * v[i]
        return out


def _clean(e: sp.Expr, simplify: bool) -> sp.Expr:
    e = sp.sympify(e)
    if e == 0 or e.is_number:
        return e
    e = sp.cancel(e)
    if simplify and e != 0 and (e.has(sp.sin, sp.cos, sp.tan) or any(
        p.exp.is_Rational and not p.exp.is_Integer for p in e.atoms(sp.Pow)
    )):
        if sp.count_ops(e) <= _SIMPLIFY_MAX_OPS:
            e = sp.simplify(e)
    return sp.factor_terms(e)
