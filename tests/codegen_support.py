"""Independent references and error bounds for the generated-code tests.

References are computed in mpmath at 50 digits from the scene's symbolic quantities
(metric, forcing, constraint one-forms, walls), *not* from the generated code or the
code-generation plan: the constrained acceleration, the multipliers and the Newton
impact are obtained by an LU solve of the full KKT systems (Carnot paper eqs. 5 and 6,
15, 20), a different algorithm from both the closed forms and the generated Cholesky /
Schur-complement code.

Error bounds (float64 unit roundoff u = 2^-53):

* closed forms: a first-order *running error bound* (Higham, Accuracy and Stability of
  Numerical Algorithms, 2nd ed., section 3.3) computed along the expression tree at the
  point: inputs are exact doubles; a sum of k terms adds ``(k-1) u sum|terms|`` (valid
  for any order of summation, so CSE regrouping is covered); a product of k factors adds
  ``(k-1) u |product|``; a power or libm function adds ``2 u |result|`` and propagates the
  argument's error through its derivative.  The generated code evaluates the same
  expression after CSE and printing rewrites (``x*x``, ``hypot``, ``expm1``), which do
  not increase these bounds.  Tests accept ``2 x bound`` (second-order terms).
* linear solves: the normwise perturbation bound for ``K z = b`` (Higham Thm 7.2) with
  the backward error of Cholesky (Thm 10.3): ``|dz|/|z| <= kappa_2(K) (e_K + e_b +
  (3N + 1) N u)``, where ``e_K, e_b`` are the running bounds of the entries (relative, in
  the 2-norm) and N the order of K.  Tests accept ``2 x bound``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import mpmath as mp
import sympy as sp

U = mp.mpf(2) ** -53
DPS = 50

_DERIVATIVES = {
    sp.sin: lambda a: mp.cos(a),
    sp.cos: lambda a: -mp.sin(a),
    sp.tan: lambda a: 1 / mp.cos(a) ** 2,
    sp.exp: lambda a: mp.exp(a),
    sp.log: lambda a: 1 / a,
    sp.atan: lambda a: 1 / (1 + a**2),
    sp.asin: lambda a: 1 / mp.sqrt(1 - a**2),
    sp.acos: lambda a: -1 / mp.sqrt(1 - a**2),
    sp.sinh: lambda a: mp.cosh(a),
    sp.cosh: lambda a: mp.sinh(a),
    sp.tanh: lambda a: 1 / mp.cosh(a) ** 2,
}


def _mp(value) -> mp.mpf:
    if isinstance(value, sp.Rational):
        return mp.mpf(value.p) / mp.mpf(value.q)
    return mp.mpf(sp.N(value, DPS + 10)) if isinstance(value, sp.Basic) else mp.mpf(value)


def _exact_double(x: mp.mpf) -> bool:
    return float(x) == x


def running_bound(expr: sp.Expr, env: Mapping[sp.Symbol, float]) -> tuple[mp.mpf, mp.mpf]:
    """(value, first-order error bound) of evaluating ``expr`` in float64 at ``env``."""
    memo: dict[sp.Basic, tuple[mp.mpf, mp.mpf]] = {}

    def go(e: sp.Basic) -> tuple[mp.mpf, mp.mpf]:
        if e in memo:
            return memo[e]
        if e.is_Symbol:
            out = (mp.mpf(env[e]), mp.mpf(0))
        elif e.is_Number or e.is_NumberSymbol:
            v = _mp(e)
            out = (v, mp.mpf(0) if _exact_double(v) else U * abs(v))
        elif e.is_Add:
            parts = [go(a) for a in e.args]
            v = mp.fsum(p[0] for p in parts)
            mu = mp.fsum(p[1] for p in parts) + (len(parts) - 1) * U * mp.fsum(
                abs(p[0]) for p in parts
            )
            out = (v, mu)
        elif e.is_Mul:
            parts = [go(a) for a in e.args]
            v = mp.fprod(p[0] for p in parts)
            mu = mp.mpf(0)
            for i, (_, mi) in enumerate(parts):
                others = mp.fprod(abs(p[0]) for j, p in enumerate(parts) if j != i)
                mu += mi * others
            mu += (len(parts) - 1) * U * abs(v)
            out = (v, mu)
        elif e.is_Pow:
            (b, mb) = go(e.base)
            k = e.exp
            if not k.is_number:
                raise ValueError(f"symbolic exponent in {e}")
            kv = _mp(k)
            v = b**kv
            deriv = abs(kv) * abs(b) ** (kv - 1) if b != 0 else mp.mpf(0)
            if k.is_Integer and abs(int(k)) <= 4:
                rounding = (abs(int(k)) - 1 + (1 if k < 0 else 0)) * U * abs(v)
            else:
                rounding = 3 * U * abs(v)
            out = (v, deriv * mb + rounding)
        elif isinstance(e, sp.Function) and len(e.args) == 1 and e.func in _DERIVATIVES:
            (a, ma) = go(e.args[0])
            v = getattr(mp, e.func.__name__)(a)
            out = (v, abs(_DERIVATIVES[e.func](a)) * ma + 2 * U * abs(v))
        elif isinstance(e, sp.atan2):
            (y, my), (x, mx) = go(e.args[0]), go(e.args[1])
            r2 = x**2 + y**2
            v = mp.atan2(y, x)
            out = (v, (abs(x) * my + abs(y) * mx) / r2 + 2 * U * abs(v))
        else:
            raise ValueError(f"running_bound: unsupported node {e.func.__name__} in {e}")
        memo[e] = out
        return out

    with mp.workdps(DPS):
        return go(sp.sympify(expr))


def block_bounds(
    entries: Sequence[sp.Expr], env: Mapping[sp.Symbol, float]
) -> tuple[mp.matrix, mp.mpf]:
    """Values (column) and the 2-norm of the entry-wise running bounds."""
    with mp.workdps(DPS):
        vals, bounds = zip(*(running_bound(e, env) for e in entries), strict=True)
        return mp.matrix(list(vals)), mp.sqrt(mp.fsum(b**2 for b in bounds))


def norm2(x) -> mp.mpf:
    return mp.sqrt(mp.fsum(abs(v) ** 2 for v in x))


def kkt_solution(
    M: mp.matrix, rhs_top: mp.matrix, A: mp.matrix, rhs_bottom: mp.matrix
) -> tuple[mp.matrix, mp.matrix, mp.matrix]:
    """Solve [[M, -A^T], [A, 0]] [x; lam] = [rhs_top; rhs_bottom] by LU at 50 digits.

    Returns (x, lam, K)."""
    n, k = M.rows, A.rows
    with mp.workdps(DPS):
        K = mp.zeros(n + k, n + k)
        b = mp.zeros(n + k, 1)
        for i in range(n):
            for j in range(n):
                K[i, j] = M[i, j]
            for a in range(k):
                K[i, n + a] = -A[a, i]
                K[n + a, i] = A[a, i]
            b[i] = rhs_top[i]
        for a in range(k):
            b[n + a] = rhs_bottom[a]
        z = mp.lu_solve(K, b)
        x = mp.matrix([z[i] for i in range(n)])
        lam = mp.matrix([z[n + a] for a in range(k)])
        return x, lam, K


def ulps(err: mp.mpf, scale: mp.mpf) -> float:
    """``err`` in units of the last place of a double of magnitude ``scale``."""
    if scale == 0:
        return 0.0 if err == 0 else float("inf")
    e = mp.floor(mp.log(abs(scale), 2))
    return float(err / mp.mpf(2) ** (e - 52))
