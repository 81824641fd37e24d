"""Fast float64 evaluation of sympy expressions at sample points (for validation checks).

Validation evaluates metrics, frames and constraint rows at a few random points.  Rebuilding
a large sympy tree with ``subs``/``evalf`` costs far more than the check itself, so this
module walks the tree once with Python's ``math``/``cmath`` functions, memoising shared
subtrees.  Anything it does not know is handed to ``evalf``.
"""

from __future__ import annotations

import cmath
import math
from collections.abc import Mapping

import numpy as np
import sympy as sp

__all__ = ["evaluate", "evaluate_matrix"]

_FUNCS = {
    sp.sin: cmath.sin,
    sp.cos: cmath.cos,
    sp.tan: cmath.tan,
    sp.exp: cmath.exp,
    sp.log: cmath.log,
    sp.asin: cmath.asin,
    sp.acos: cmath.acos,
    sp.atan: cmath.atan,
    sp.sinh: cmath.sinh,
    sp.cosh: cmath.cosh,
    sp.tanh: cmath.tanh,
    sp.cot: lambda x: 1 / cmath.tan(x),
    sp.sec: lambda x: 1 / cmath.cos(x),
    sp.csc: lambda x: 1 / cmath.sin(x),
}


def _eval(expr: sp.Basic, env: dict, memo: dict) -> complex:
    hit = memo.get(expr)
    if hit is not None:
        return hit
    if expr.is_Symbol:
        val = complex(env[expr])
    elif expr.is_Number or expr.is_NumberSymbol:
        val = complex(expr)
    elif expr.is_Add:
        val = sum((_eval(a, env, memo) for a in expr.args), 0j)
    elif expr.is_Mul:
        val = 1 + 0j
        for a in expr.args:
            val *= _eval(a, env, memo)
    elif expr.is_Pow:
        base = _eval(expr.base, env, memo)
        e = expr.exp
        if e.is_Integer:
            val = base ** int(e)
        else:
            val = base ** _eval(e, env, memo)
    elif type(expr) in _FUNCS:
        val = _FUNCS[type(expr)](_eval(expr.args[0], env, memo))
    elif isinstance(expr, sp.atan2):
        y, x = (_eval(a, env, memo) for a in expr.args)
        val = complex(math.atan2(y.real, x.real))
    else:
        val = complex(sp.N(expr.xreplace({k: sp.Float(v, 20) for k, v in env.items()}), 17))
    memo[expr] = val
    return val


def evaluate(expr: sp.Basic, point: Mapping) -> complex:
    """``expr`` at ``point`` (symbol -> number) as a complex float."""
    return _eval(sp.sympify(expr), dict(point), {})


def evaluate_matrix(M: sp.MatrixBase, point: Mapping) -> np.ndarray:
    """Every entry of ``M`` at ``point``, as a complex numpy array (shared subtrees once)."""
    env, memo = dict(point), {}
    return np.array(
        [[_eval(M[i, j], env, memo) for j in range(M.cols)] for i in range(M.rows)], dtype=complex
    )
