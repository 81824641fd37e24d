"""The simplification policy of symmech, in one place.

Symbolic results are simplified according to a named level, so results are predictable
and large systems never pay for a full ``sympy.simplify``:

``"none"``
    Return expressions as built.  Used for the scalable quantities (mass matrix, forcing).
``"light"`` (default for accelerations, projectors, impact maps)
    ``sympy.cancel`` on expressions of at most ``LIGHT_MAX_OPS`` operations (clears nested
    fractions such as those from a Gram inverse), then ``factor_terms``; larger expressions
    are left as built.
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
        return sp.factor_terms(sp.cancel(expr))
    return expr


def tidy_matrix(M: sp.MatrixBase, level: Level = "light") -> sp.Matrix:
    """Apply :func:`tidy` to every entry of ``M``."""
    return sp.Matrix(M.rows, M.cols, [tidy(e, level) for e in M])
