"""Exact arithmetic for energy identities: quadratic forms over a rational-function field.

Carnot's theorems compare kinetic energies, quadratic in the velocities with coefficients
that are rational functions of the parameters (and of sin/cos of the coordinates).  Summing
them as sympy expressions and calling :func:`sympy.cancel` on the result is slow (tens of
seconds for Example 3.13).  Here every coefficient matrix is converted once into a common
sympy polynomial domain (the fraction field ``QQ(k, r, alpha, sin(theta), ...)``, built by
:func:`sympy.polys.constructor.construct_domain` after replacing functions and radicals
by dummy generators), where sums and products are canonical, so "is this identically
zero" is exact and cheap (the field itself lives in :mod:`symmech.algebra.field`).
The field keeps ``sin^2 + cos^2 = 1`` (its Pythagorean normal form) but not
``sqrt(u)^2 = u``: a coefficient is therefore tested for zero once more after it is
written back to sympy (where the square of a root becomes its base), and a non-zero one
is passed through :func:`sympy.cancel` / :func:`sympy.simplify` before it is reported.
If no such domain exists (the domain would be ``EX``), plain sympy arithmetic is used.
"""

from __future__ import annotations

import sympy as sp

from symmech.algebra import budget as limits
from symmech.algebra.field import RationalField, field_zero

__all__ = ["Affine", "QuadraticForm"]


class Affine:
    """The affine map ``v -> L v + o`` of the velocity symbols, in a common domain."""

    def __init__(self, ring: RationalField, L, o):
        self.ring, self.L, self.o = ring, L, o

    @classmethod
    def of(cls, ring: RationalField, L: sp.MatrixBase, o: sp.MatrixBase) -> Affine:
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

    def __init__(self, ring: RationalField, A, b, c):
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
        A = r.to_sympy_matrix(r.normal_matrix(self.A))
        b = r.to_sympy_matrix(r.normal_matrix(self.b))
        c = r.to_sympy_matrix(r.normal_matrix(self.c))[0, 0]
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
    """A coefficient cancelled (and simplified when asked and small); returned as it is,
    exact but not normalised, when its expansion is over :data:`symmech.algebra.budget.FIELD_TERMS`
    (the bound the fraction field declines at: ``cancel`` of such a coefficient takes
    minutes, and the callers decide zero by exact evaluation instead)."""
    e = sp.sympify(e, strict=True)
    if e == 0 or e.is_number:
        return e
    if limits.expanded_terms(e, cap=limits.FIELD_TERMS + 1)[0] > limits.FIELD_TERMS:
        return e
    if field_zero(e):  # e.g. sqrt(u)^2 written back as u, with sin^2 + cos^2 = 1 in it
        return sp.S.Zero
    e = sp.cancel(e)
    if (
        simplify
        and e != 0
        and (
            e.has(sp.sin, sp.cos, sp.tan)
            or any(p.exp.is_Rational and not p.exp.is_Integer for p in e.atoms(sp.Pow))
        )
    ):
        if limits.affordable(e, limits.QUADRATIC_SIMPLIFY_OPS):
            e = sp.simplify(e)
    return sp.factor_terms(e)
