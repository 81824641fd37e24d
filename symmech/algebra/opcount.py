"""``sympy.count_ops(expr)`` as an integer, without its symbolic bookkeeping.

sympy counts an expression's operations by walking it and appending a symbol per
operation (``ADD``, ``MUL``, ``NEG``, ...) to a list that it sums with ``Add`` at the end,
then reads the coefficients back.  The count is the number of operations appended (a
``SUB - ADD`` correction adds none), so :func:`count_ops` adds integers instead, walking
the same nodes with the same rules (the sign of a product taken out, ``fraction`` for
its denominator, negated terms of a sum) and remembering the count of each subtree it
met, which the budgets and the generated files' headers ask for again and again.
Anything that is not a plain expression (a relational, a matrix expression, a lattice
operation, a container) is counted by sympy itself.
"""

from __future__ import annotations

import sympy as sp
from sympy.core.operations import LatticeOp
from sympy.simplify.radsimp import fraction

__all__ = ["count_ops"]

_ONE, _MINUS_ONE, _E = sp.S.One, sp.S.NegativeOne, sp.S.Exp1


class _Unusual(Exception):
    """A node the integer walk does not mirror: sympy counts the whole expression."""


def count_ops(expr: sp.Basic, memo: dict | None = None) -> int:
    """``sympy.count_ops(expr)`` (``visual=False``) for an expression; ``memo`` (subtree
    -> count) may be shared between calls on expressions with common parts."""
    if not isinstance(expr, sp.Expr) or expr.is_Relational:
        return int(sp.count_ops(expr))
    try:
        return _count(expr, {} if memo is None else memo)
    except (_Unusual, RecursionError):
        return int(sp.count_ops(expr))


def _count(a: sp.Expr, memo: dict) -> int:
    hit = memo.get(a)
    if hit is None:
        ops, children = _local(a)
        hit = memo[a] = ops + sum(_count(c, memo) for c in children)
    return hit


def _local(a: sp.Expr) -> tuple[int, list[sp.Expr]]:
    """The operations sympy appends for the node ``a`` and the nodes it then visits."""
    if a.is_MatMul or a.is_MatAdd or isinstance(a, LatticeOp):
        raise _Unusual(a)
    ops = 0
    if a.is_Rational:
        if a is not _ONE:
            return int(a.p < 0) + int(a.q != 1), []
    elif a.is_Mul:
        if _coeff_isneg(a):
            ops += 1
            a = a.as_two_terms()[1] if a.args[0] is _MINUS_ONE else -a
        n, d = fraction(a)
        if n.is_Integer:
            return ops + 1 + int(n.p < 0), [d]
        if d is not _ONE:
            return ops + 1, ([] if d.is_Integer else [d]) + [n]
    elif a.is_Add:
        children = []
        negs = 0
        for term in a.args:
            if _coeff_isneg(term):
                negs += 1
                children.append(-term)
            else:
                children.append(term)
        return len(a.args) - 1 + int(negs == len(a.args)), children
    if a.is_Pow and a.exp is _MINUS_ONE:
        return ops + 1, [a.base]
    if a == _E:
        return ops + 1, []
    if a.is_Pow and a.base == _E:
        return ops + 1, [a.exp]
    if a.is_Mul:
        ops += len(a.args) - 1
    elif a.args and (
        a.is_Pow or a.is_Function or isinstance(a, (sp.Derivative, sp.Integral, sp.Sum))
    ):
        ops += 1
    return ops, [] if a.is_Symbol else list(a.args)


def _coeff_isneg(a: sp.Expr) -> bool:
    """sympy's ``_coeff_isneg``: a negative number, or a product whose leading number is
    negative (a matrix expression's too, which :func:`_local` has refused)."""
    if a.is_Number:
        return bool(a.is_extended_negative)
    if a.is_Mul:
        return a.args[0].is_Number and bool(a.args[0].is_extended_negative)
    return False
