"""The simplification policy of symmech, in one place.

Symbolic results are simplified according to a named level, so results are predictable
and large systems never pay for a full ``sympy.simplify``:

``"none"``
    Return expressions as built.  Used for the scalable quantities (mass matrix, forcing).
``"light"`` (default for accelerations, projectors, impact maps)
    ``sympy.cancel`` on rational expressions (no function applications such as sin, sqrt
    of a non-symbol) of at most ``LIGHT_MAX_OPS`` operations, clearing nested fractions
    such as those from a Gram inverse, then ``factor_terms``.  Expressions with functions
    get ``factor_terms`` only: ``cancel`` treats every trigonometric term as a new
    generator and can take minutes on a 3 x 3 trigonometric mass matrix.
``"full"`` (default for Christoffel symbols)
    ``sympy.simplify`` (which includes trigsimp) on expressions of at most
    ``FULL_MAX_OPS`` operations, else the light policy.

The thresholds keep the cost bounded: simplification is skipped, never approximated.
"""

from __future__ import annotations

from typing import Literal

import sympy as sp

__all__ = ["FULL_MAX_OPS", "LIGHT_MAX_OPS", "Level", "tidy", "tidy_matrix"]

Level = Literal["none", "light", "full"]
LIGHT_MAX_OPS = 400
FULL_MAX_OPS = 150


def tidy(expr: sp.Expr, level: Level = "light") -> sp.Expr:
    """Simplify ``expr`` according to ``level`` (see the module docstring)."""
    if level not in ("none", "light", "full"):
        raise ValueError(f"simplify level must be 'none', 'light' or 'full', got {level!r}")
    expr = sp.sympify(expr)
    if level == "none" or expr.is_number or expr.is_Symbol:
        return expr
    ops = sp.count_ops(expr)
    if level == "full" and ops <= FULL_MAX_OPS:
        return sp.simplify(expr)
    if ops <= LIGHT_MAX_OPS:
        if _is_rational_function(expr):
            return sp.factor_terms(sp.cancel(expr))
        return sp.factor_terms(expr)
    return expr


def _is_rational_function(expr: sp.Expr) -> bool:
    """True when expr is built from symbols and numbers by + - * / and integer powers."""
    for node in sp.preorder_traversal(expr):
        if isinstance(node, (sp.Function, sp.Derivative)):
            return False
        if node.is_Pow and not node.exp.is_Integer:
            return False
    return True


def tidy_matrix(M: sp.MatrixBase, level: Level = "light") -> sp.Matrix:
    """Apply :func:`tidy` to every entry of ``M``."""
    return sp.Matrix(M.rows, M.cols, [tidy(e, level) for e in M])
