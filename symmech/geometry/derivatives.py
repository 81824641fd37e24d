"""Sparse directional derivatives along coordinate or frame vector fields.

``D_i f`` is the derivative of ``f`` along the i-th basis field of the velocity basis:
``d f / d q^i`` in coordinates, ``u_i(f) = S^a_i d f / d q^a`` in a frame ``q_dot = S v``.
Derivatives with respect to a coordinate an expression does not contain are never formed
(they are zero), which keeps metric derivatives O(number of non-zero entries) instead of
O(n^3) for the large, sparse metrics of multibody systems.

Sums and products are formed by :func:`symmech.algebra.canonical.add` and
:func:`~symmech.algebra.canonical.mul`, which return exactly what ``sympy.Add`` and
``sympy.Mul`` return, faster.  :meth:`Derivative.terms` gives a derivative as the list of
its terms before they are summed, for callers that add it into a larger sum: the sum of
those terms with anything else is the same expression as the sum with the derivative.
"""

from __future__ import annotations

from collections.abc import Sequence

import sympy as sp

from symmech.algebra.canonical import add, mul
from symmech.algebra.walk import free_symbols

__all__ = ["Derivative"]


class Derivative:
    """Memoised directional derivatives ``D_i`` along the basis fields.

    >>> import sympy as sp
    >>> x, y = sp.symbols("x y", real=True)
    >>> D = Derivative((x, y))
    >>> D(x**2 * y, 0)
    2*x*y
    """

    def __init__(self, q: Sequence[sp.Symbol], frame: sp.MatrixBase | None = None):
        self.q = tuple(q)
        self.frame = frame
        self._memo: dict[tuple[sp.Basic, int], sp.Expr] = {}
        self._symbols: dict[sp.Basic, frozenset] = {}
        self._outer: dict[sp.Basic, sp.Expr] = {}  # f'(u) of applied functions f(u)

    def free_symbols(self, expr: sp.Basic) -> frozenset:
        """``expr.free_symbols``, memoised (sympy recomputes it on every access)."""
        return free_symbols(expr, self._symbols)

    def partial(self, expr: sp.Expr, a: int) -> sp.Expr:
        """d expr / d q^a, zero without differentiating when q^a does not occur."""
        qa = self.q[a]
        if expr is qa or expr == qa:
            return sp.S.One
        if qa not in self.free_symbols(expr):
            return sp.S.Zero
        if expr.is_Add or expr.is_Mul:
            return add(*self.partial_terms(expr, a))
        if expr.is_Pow and qa not in self.free_symbols(expr.exp):
            db = self.partial(expr.base, a)
            # exp * base**(exp - 1) * db, each product as the operators build it
            return _times(_times(expr.exp, expr.base ** (expr.exp - 1)), db)
        if (
            isinstance(expr, sp.Function)
            and len(expr.args) == 1
            and not isinstance(expr, sp.core.function.AppliedUndef)
        ):
            # chain rule through the function's own derivative (no Derivative objects)
            outer = self._outer.get(expr)
            if outer is None:
                outer = self._outer[expr] = expr.fdiff(1)
            return _times(outer, self.partial(expr.args[0], a))
        return sp.diff(expr, qa)

    def partial_terms(self, expr: sp.Expr, a: int) -> list[sp.Expr]:
        """Terms whose sum (``sympy.Add``) is d expr / d q^a, none of them a sum: the
        derivatives of the terms of a sum, the product rule over the factors of a
        product that contain q^a."""
        qa = self.q[a]
        if qa not in self.free_symbols(expr) or expr is qa:
            return _summands(self.partial(expr, a))
        if expr.is_Add:
            return [t for arg in expr.args for t in self.partial_terms(arg, a)]
        if expr.is_Mul:
            args = expr.args
            out: list[sp.Expr] = []
            for k, f in enumerate(args):
                if qa in self.free_symbols(f):
                    df = self.partial(f, a)
                    if df is not sp.S.Zero:
                        out += _summands(mul(*args[:k], df, *args[k + 1 :]))
            return out
        return _summands(self.partial(expr, a))

    def __call__(self, expr: sp.Expr, i: int) -> sp.Expr:
        key = (expr, i)
        hit = self._memo.get(key)
        if hit is not None:
            return hit
        if not self.free_symbols(expr):
            out = sp.S.Zero
        elif self.frame is None:
            out = self.partial(expr, i)
        else:
            out = add(
                *[
                    _times(self.frame[a, i], self.partial(expr, a))
                    for a in range(len(self.q))
                    if self.frame[a, i] != 0 and self.q[a] in self.free_symbols(expr)
                ]
            )
        self._memo[key] = out
        return out


def _times(x: sp.Expr, y: sp.Expr) -> sp.Expr:
    """``x * y`` as the operator computes it: number arithmetic for two numbers, else
    ``sympy.Mul(x, y)``."""
    return x * y if x.is_Number and y.is_Number else mul(x, y)


def _summands(expr: sp.Expr) -> list[sp.Expr]:
    """The terms of a sum, else ``[expr]`` (nothing for zero)."""
    if expr.is_Add:
        return list(expr.args)
    return [] if expr is sp.S.Zero else [expr]
