"""Walks of an expression that visit each distinct subtree once.

sympy's ``free_symbols``, ``atoms`` and ``xreplace`` walk the expression as a tree: a
subtree shared by many parents (the velocity of a link, reused in the kinetic energy of
every link after it) is walked once per parent.  These walks remember what they have
seen, so their cost is the number of distinct subexpressions; they return what sympy's
return.
"""

from __future__ import annotations

from collections.abc import Iterable

import sympy as sp

__all__ = ["atoms", "free_symbols", "free_symbols_of", "xreplace"]

# sympy's free_symbols of a node that binds no variables: the union over its arguments
_UNION_OF_ARGS = sp.Basic.free_symbols


def free_symbols(expr: sp.Basic, memo: dict[sp.Basic, frozenset] | None = None) -> frozenset:
    """``expr.free_symbols`` as a frozenset; ``memo`` (expression -> its set) may be kept
    by the caller for the next expressions.  Nodes whose class defines its own free
    symbols (symbols, derivatives, integrals, functions) are asked for them."""
    if memo is None:
        memo = {}
    hit = memo.get(expr)
    if hit is None:
        if expr.args and type(expr).free_symbols is _UNION_OF_ARGS:
            hit = frozenset().union(*[free_symbols(a, memo) for a in expr.args])
        else:
            hit = frozenset(expr.free_symbols)
        memo[expr] = hit
    return hit


def free_symbols_of(exprs: Iterable[sp.Basic]) -> set[sp.Basic]:
    """The union of the free symbols of ``exprs`` (the entries of a matrix, say), each
    distinct subtree walked once even when several of them share it."""
    memo: dict[sp.Basic, frozenset] = {}
    return set().union(*[free_symbols(e, memo) for e in exprs])


def atoms(expr: sp.Basic, types: tuple[type, ...]) -> set[sp.Basic]:
    """``expr.atoms(*types)``: the subexpressions of ``expr`` (itself included) that are
    instances of ``types``."""
    out: set[sp.Basic] = set()
    seen: set[sp.Basic] = set()
    stack = [expr]
    while stack:
        e = stack.pop()
        if e in seen:
            continue
        seen.add(e)
        if isinstance(e, types):
            out.add(e)
        stack.extend(e.args)
    return out


def xreplace(expr: sp.Basic, rule: dict, memo: dict | None = None) -> sp.Basic:
    """``expr.xreplace(rule)``, each distinct subtree once: sympy's ``_xreplace`` rebuilds a
    node (``func(*args)``) when a replacement occurred below it, and so does this, from
    the results of its arguments remembered in ``memo`` (subtree -> (result, replaced),
    shareable between expressions with the same rule)."""
    return _xreplace(expr, rule, {} if memo is None else memo)[0]


def _xreplace(e: sp.Basic, rule: dict, memo: dict) -> tuple[sp.Basic, bool]:
    hit = memo.get(e)
    if hit is not None:
        return hit
    if e in rule:
        out = (rule[e], True)
    elif e.args:
        args = []
        changed = False
        for a in e.args:
            if isinstance(a, sp.Basic):
                a_new, a_changed = _xreplace(a, rule, memo)
                args.append(a_new)
                changed |= a_changed
            else:
                args.append(a)
        out = (e.func(*args), True) if changed else (e, False)
    else:
        out = (e, False)
    memo[e] = out
    return out
