"""Independent references and error bounds for the generated-code tests.

References are computed in mpmath at 50 digits from the scene's symbolic quantities
(metric, forcing, constraint one-forms, walls), *not* from the generated code or the
code-generation plan: the constrained acceleration, the multipliers and the Newton
impact are obtained by an LU solve of the full KKT systems (Carnot paper eqs. 5 and 6,
15, 20), a different algorithm from both the closed forms and the generated Cholesky /
Schur-complement code.

Error bounds are first order in the float64 unit roundoff u = 2^-53 and are computed for
the code actually emitted: the expressions of the code-generation plan (after the
stable rewrite of :func:`symmech.algebra.stability.stable_coefficient`, which is an
exact identity, so the plan's expressions have the scene's values: the tests check this
at 50 digits) and the linear-algebra algorithm of the templates.  Tests accept
``2 x bound`` (the second-order terms).

* Closed forms: a *running error bound* (Higham, Accuracy and Stability of Numerical
  Algorithms, 2nd ed., section 3.3) along the expression tree at the point: inputs are
  exact doubles; a sum of k terms adds ``(k-1) u sum|terms|`` and a product of k factors
  ``(k-1) u |product|`` (valid for any order and grouping, so CSE regrouping is
  covered; a factor +-2^j does not count, and the difference of two exact doubles within
  a factor 2 of each other is exact, Sterbenz's lemma, Higham Thm 2.5); ``x**k`` printed
  as a product (``|k| <= 8``, repeated squaring) adds ``(|k|-1) u |x^k|`` (+ u for a
  reciprocal), ``x**(p/2)`` printed ``sqrt(x) x^k`` adds ``(k+1) u`` (+ u), any other
  power (``pow``) and a libm function ``2 u |result|`` (one ulp, glibc's documented
  accuracy) and propagates the argument's error through its derivative.  A number that
  is not a double adds ``u |value|``.  Printing rewrites do not increase these bounds:
  ``hypot``, ``expm1``, ``log1p`` are within an ulp where the rewritten expression's
  bound is at least that; a symbol-free subexpression is folded into one literal
  rounded once (error <= u/2 |value|), while the tree's own bound is at least
  ``u |value|`` (its top node rounds).
* Linear solves (:func:`solve_bound`, :func:`constrained_bound`, :func:`impact_bound`):
  a first-order analysis of the emitted algorithm (lower.py).  A Cholesky factorisation
  plus the two triangular solves, as the templates write them (the reciprocal
  ``inv_j = fl(1/fl(sqrt(d_j)))`` stored on the diagonal, products instead of
  divisions), give a computed x with ``(A + dA) x = b``, ``|dA| <= (3N + 4) u |L||L^T|``:
  Higham Thms 10.3 and 8.5 applied to the factor whose diagonal is ``l_jj = 1/inv_j``
  exactly (the solves then multiply by ``1/l_jj``, one rounding as a division would be);
  the factorisation costs ``(N + 3) u`` (``inv_j`` adds four roundings to ``l_jj^2``),
  each solve ``N u``.  A structurally diagonal metric is solved by one division per
  entry (``u |M_jj|``, within the same bound).  Inner products of N terms starting from
  0 add ``N u sum|terms|``, every other operation its one rounding.  The first-order error
  of an output is the sum over all these error sources (input entries with their running
  bounds, each rounding, each solve's backward error) of the source's bound times the
  *exact* sensitivity of the output to it, computed at the point by one reverse (adjoint)
  sweep through the algorithm in mpmath.  This replaces a normwise bound with the
  condition number of the full KKT matrix, which the range-space (Schur complement)
  algorithm does not see: its error depends on M and on the Schur complements
  C = mu M^-1 mu^T and G = A M^-1 A^T, and the adjoints follow exactly those.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence

import mpmath as mp
import pytest
import sympy as sp

from symmech.codegen.build import CompileError, find_compiler
from symmech.codegen.printers import MAX_PRODUCT_POWER

U = mp.mpf(2) ** -53
DPS = 50


def require_c_compiler() -> str:
    """The C compiler, or skip the test with the reason; a failure when CI=true.

    STYLE.md: compile-and-run tests skip with a stated reason when no compiler is
    found, never silently; on CI (the environment variable CI=true) a missing compiler is
    a failure, because there the C backend must be tested."""
    try:
        return find_compiler()
    except CompileError as exc:
        reason = f"no C compiler: {exc}"
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail(f"{reason} (CI=true: a compiler is required)")
        pytest.skip(reason)


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


def _power_of_two(e: sp.Expr) -> bool:
    """A numeric factor +-2^j: multiplying by it is exact (no under- or overflow here)."""
    if not e.is_Rational or e == 0:
        return False
    p, q = abs(int(e.p)), int(e.q)
    return (p & (p - 1)) == 0 and (q & (q - 1)) == 0


def _sterbenz(parts: Sequence[tuple[mp.mpf, mp.mpf]]) -> bool:
    """x - y of two exact doubles with y/2 <= x <= 2y is exact (Sterbenz; Higham Thm 2.5)."""
    if len(parts) != 2 or any(err != 0 for _, err in parts):
        return False
    (a, _), (b, _) = parts
    if not (_exact_double(a) and _exact_double(b)) or a * b >= 0:
        return False
    x, y = abs(a), abs(b)
    return y / 2 <= x <= 2 * y


def _power_rounding(k: sp.Expr) -> int:
    """Roundings (in units of u) of ``x**k`` as the printers write it."""
    if k.is_Integer and 1 <= abs(int(k)) <= MAX_PRODUCT_POWER:
        return abs(int(k)) - 1 + (1 if k < 0 else 0)
    if k.is_Rational and k.q == 2 and abs(int(k.p)) // 2 <= MAX_PRODUCT_POWER:
        j = abs(int(k.p)) // 2
        return (j + 1 if j else 1) + (1 if k < 0 else 0)
    return 2  # pow: one ulp


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
            mu = mp.fsum(p[1] for p in parts)
            if not _sterbenz(parts):
                mu += (len(parts) - 1) * U * mp.fsum(abs(p[0]) for p in parts)
            out = (v, mu)
        elif e.is_Mul:
            parts = [go(a) for a in e.args]
            v = mp.fprod(p[0] for p in parts)
            mu = mp.mpf(0)
            for i, (_, mi) in enumerate(parts):
                others = mp.fprod(abs(p[0]) for j, p in enumerate(parts) if j != i)
                mu += mi * others
            # a factor +-2^j (a sign, 0.5*) scales exactly
            rounded = sum(1 for a in e.args if not _power_of_two(a))
            mu += max(rounded - 1, 0) * U * abs(v)
            out = (v, mu)
        elif e.is_Pow:
            (b, mb) = go(e.base)
            k = e.exp
            if not k.is_number:
                raise ValueError(f"symbolic exponent in {e}")
            kv = _mp(k)
            v = b**kv
            deriv = abs(kv) * abs(b) ** (kv - 1) if b != 0 else mp.mpf(0)
            out = (v, deriv * mb + _power_rounding(k) * U * abs(v))
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


def entries(
    exprs: Sequence[sp.Expr], env: Mapping[sp.Symbol, float], shape: tuple[int, ...]
) -> tuple[mp.matrix, mp.matrix]:
    """Values and running bounds of a block of expressions, as (rows x cols) matrices
    (a vector is a column)."""
    rows, cols = (shape[0], 1) if len(shape) == 1 else (shape if shape else (1, 1))
    with mp.workdps(DPS):
        val, err = mp.matrix(rows, cols), mp.matrix(rows, cols)
        for flat, e in enumerate(exprs):
            i, j = divmod(flat, cols)
            val[i, j], err[i, j] = running_bound(e, env)
        return val, err


def norm2(x) -> mp.mpf:
    return mp.sqrt(mp.fsum(abs(v) ** 2 for v in x))


def kkt_solution(
    M: mp.matrix, rhs_top: mp.matrix, A: mp.matrix, rhs_bottom: mp.matrix
) -> tuple[mp.matrix, mp.matrix]:
    """Solve [[M, -A^T], [A, 0]] [x; lam] = [rhs_top; rhs_bottom] by LU at 50 digits.

    Returns (x, lam)."""
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
        return mp.matrix([z[i] for i in range(n)]), mp.matrix([z[n + a] for a in range(k)])


def ulps(err: mp.mpf, scale: mp.mpf) -> float:
    """``err`` in units of the last place of a double of magnitude ``scale``."""
    if scale == 0:
        return 0.0 if err == 0 else float("inf")
    e = mp.floor(mp.log(abs(scale), 2))
    return float(err / mp.mpf(2) ** (e - 52))


# ------------------------------------------------------------------ linear-solve bounds
#
# First-order error of an algorithm = sum over its error sources (input entries, the
# rounding of each computed quantity, the backward error of each Cholesky solve) of the
# exact sensitivity of the output to that source times the source's bound.  For output
# component k the sensitivities are the adjoints ("bar" quantities) of one reverse sweep
# through the algorithm in exact arithmetic, so cancellations between the stages are
# accounted for, unlike a chain of absolute values.


def _abs(A: mp.matrix) -> mp.matrix:
    return A.apply(abs)


def _dot(a: mp.matrix, b: mp.matrix) -> mp.mpf:
    """sum_ij a_ij b_ij."""
    return mp.fsum(a[i, j] * b[i, j] for i in range(a.rows) for j in range(a.cols))


def _lower_sensitivity(bar: mp.matrix) -> mp.matrix:
    """The code reads only the lower triangle of a symmetric matrix (sm_cholesky), so an
    error in entry (i, j), i > j, perturbs both (i, j) and (j, i)."""
    out = mp.zeros(bar.rows, bar.cols)
    for i in range(bar.rows):
        for j in range(i + 1):
            out[i, j] = bar[i, j] + (bar[j, i] if i != j else 0)
    return out


def _lower(E: mp.matrix) -> mp.matrix:
    """Entry bounds of the lower triangle (the entries the code reads)."""
    out = mp.zeros(E.rows, E.cols)
    for i in range(E.rows):
        for j in range(i + 1):
            out[i, j] = E[i, j]
    return out


def _backward(M: mp.matrix) -> mp.matrix:
    """(3N + 4) u |L||L^T|: the backward error of a Cholesky factorisation and solve as the
    templates write them (module docstring)."""
    L = _abs(mp.cholesky(M))
    return (3 * M.rows + 4) * U * (L * L.T)


def _unit(n: int, k: int) -> mp.matrix:
    e = mp.zeros(n, 1)
    e[k] = 1
    return e


def solve_bound(M, bM, f, bf) -> tuple[mp.matrix, mp.matrix]:
    """``spd_solve``: x = M^-1 f (exact) and the first-order bound of the computed x."""
    n = M.rows
    with mp.workdps(DPS):
        Minv = mp.inverse(M)
        x = Minv * f
        EM = _backward(M)
        bound = mp.zeros(n, 1)
        for k in range(n):
            fbar = Minv * _unit(n, k)  # out_k = e_k^T M^-1 f
            Mbar = -fbar * x.T
            bound[k] = (
                _dot(_abs(_lower_sensitivity(Mbar)), _lower(bM))
                + _dot(_abs(fbar), bf)
                + (_abs(fbar).T * EM * _abs(x))[0]
            )
        return x, bound


def constrained_bound(M, bM, f, bf, mu, bmu, rate, brate):
    """``sm_constrained``: (acc, its bound, lambda, its bound).

    X = M^-1 [mu^T | f]; C = mu X_mu (inner products of n terms from 0: n u); s = -rate -
    mu X_f ((n + 1) u); lambda = C^-1 s (Cholesky of C, order m); acc = X_f + X_mu lambda
    ((m + 1) u)."""
    n, m = M.rows, mu.rows
    with mp.workdps(DPS):
        Minv = mp.inverse(M)
        B = mp.matrix(n, m + 1)
        for i in range(n):
            for a in range(m):
                B[i, a] = mu[a, i]
            B[i, m] = f[i]
        X = Minv * B
        Xmu, Xf = X[:, :m], X[:, m]
        C = mu * Xmu
        Cinv = mp.inverse(C)
        s = -rate - mu * Xf
        lam = Cinv * s
        acc = Xf + Xmu * lam
        EM, EC = _backward(M), _backward(C)
        aX = _abs(X)
        err_C = n * U * (_abs(mu) * _abs(Xmu))
        err_s = (n + 1) * U * (_abs(rate) + _abs(mu) * _abs(Xf))
        err_acc = (m + 1) * U * (_abs(Xf) + _abs(Xmu) * _abs(lam))

        def sweep(acc_bar: mp.matrix, lam_bar: mp.matrix) -> mp.mpf:
            """Bound of the output whose adjoints of acc and lambda are given."""
            Xbar = mp.zeros(n, m + 1)
            for i in range(n):
                Xbar[i, m] = acc_bar[i]
                for a in range(m):
                    Xbar[i, a] = acc_bar[i] * lam[a]
            lbar = lam_bar + Xmu.T * acc_bar
            sbar = Cinv * lbar
            Cbar = -sbar * lam.T
            rate_bar = -sbar
            mubar = -sbar * Xf.T + Cbar * Xmu.T
            xf_bar = -mu.T * sbar
            xmu_bar = mu.T * Cbar
            for i in range(n):
                Xbar[i, m] += xf_bar[i]
                for a in range(m):
                    Xbar[i, a] += xmu_bar[i, a]
            Bbar = Minv * Xbar
            Mbar = -Bbar * X.T
            for a in range(m):
                for i in range(n):
                    mubar[a, i] += Bbar[i, a]
            fbar = Bbar[:, m]
            out = _dot(_abs(_lower_sensitivity(Mbar)), _lower(bM)) + _dot(_abs(fbar), bf)
            out += _dot(_abs(mubar), bmu) + _dot(_abs(rate_bar), brate)
            for c in range(m + 1):  # backward error of the solve of each column of X
                out += (_abs(Bbar[:, c]).T * EM * aX[:, c])[0]
            out += _dot(_abs(_lower_sensitivity(Cbar)), _lower(err_C))
            out += _dot(_abs(sbar), err_s)
            out += (_abs(sbar).T * EC * _abs(lam))[0]  # backward error of the solve with C
            return out + _dot(_abs(acc_bar), err_acc)

        e_acc = mp.matrix([sweep(_unit(n, k), mp.zeros(m, 1)) for k in range(n)])
        e_lam = mp.matrix([sweep(mp.zeros(n, 1), _unit(m, a)) for a in range(m)])
        return acc, e_acc, lam, e_lam


def impact_bound(M, bM, A, bA, s, bs, v, m):
    """``sm_impact_kkt``: (v+, its bound).

    Y = M^-1 A^T; G = A Y and A v (inner products of n terms from 0: n u); r = -A v, then
    r_m = (1 + alpha)(r_m - psi_t) (three roundings) and, for the rows of the impulsive
    constraints, r_a = r_a + (-psi_t G_am) / G_mm (three); lambda = G^-1 r (Cholesky of G,
    order k); v+ = v + Y lambda ((k + 1) u)."""
    n, k = M.rows, A.rows
    with mp.workdps(DPS):
        Minv = mp.inverse(M)
        Y = Minv * A.T
        G = A * Y
        Ginv = mp.inverse(G)
        av = A * v
        alpha, psi_t = s[0], s[1]
        r = -av
        d = r[m] - psi_t
        r[m] = (1 + alpha) * d
        err_r = mp.zeros(k, 1)
        err_r[m] = 3 * U * abs(r[m])
        for a in range(m + 1, k):
            t = -psi_t * G[a, m] / G[m, m]
            r[a] = r[a] + t
            err_r[a] = 2 * U * abs(t) + U * abs(r[a])
        lam = Ginv * r
        out = v + Y * lam
        EM, EG = _backward(M), _backward(G)
        err_G = n * U * (_abs(A) * _abs(Y))
        err_av = n * U * (_abs(A) * _abs(v))
        err_out = (k + 1) * U * (_abs(v) + _abs(Y) * _abs(lam))
        bound = mp.zeros(n, 1)
        for j in range(n):
            e = _unit(n, j)
            Ybar = e * lam.T
            rbar = Ginv * (Y.T * e)
            Gbar = -rbar * lam.T
            av_bar = -rbar
            av_bar[m] = -(1 + alpha) * rbar[m]
            alpha_bar = rbar[m] * d
            psi_bar = -(1 + alpha) * rbar[m]
            for a in range(m + 1, k):
                psi_bar += -rbar[a] * G[a, m] / G[m, m]
                Gbar[a, m] += -rbar[a] * psi_t / G[m, m]
                Gbar[m, m] += rbar[a] * psi_t * G[a, m] / G[m, m] ** 2
            Abar = av_bar * v.T + Gbar * Y.T
            Ybar += A.T * Gbar
            Bbar = Minv * Ybar
            Mbar = -Bbar * Y.T
            Abar += Bbar.T
            b = _dot(_abs(_lower_sensitivity(Mbar)), _lower(bM)) + _dot(_abs(Abar), bA)
            b += abs(alpha_bar) * bs[0] + abs(psi_bar) * bs[1]
            for c in range(k):  # backward error of the solve of each column of Y
                b += (_abs(Bbar[:, c]).T * EM * _abs(Y[:, c]))[0]
            b += _dot(_abs(_lower_sensitivity(Gbar)), _lower(err_G))
            b += _dot(_abs(av_bar), err_av) + _dot(_abs(rbar), err_r)
            b += (_abs(rbar).T * EG * _abs(lam))[0]  # backward error of the solve with G
            bound[j] = b + err_out[j]
        return out, bound
