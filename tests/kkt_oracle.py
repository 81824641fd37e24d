"""The tests' oracle, route (B): the impulse-momentum (KKT) system, solved as one linear system.

An independent derivation of the Newton-law impact map, used to cross-check the
projector formulas of :mod:`symmech.impacts.impact_projectors` / :mod:`symmech.impacts.newton`.
It shares no code with them.  Unknowns: v+ (n), the impulsive multipliers lambda (m, the
permanent constraints), mu_0 (the wall) and mu_1 (l, the impulsive constraints).
Equations (Carnot paper 002, eq. 6 and eqs. 9, 15, 19, 20):

    g (v+ - v-) = mu^T lambda + dpsi^T mu_0 + nu^T mu_1      (n equations)
    mu v+ = 0                                                 (m)
    dpsi(v+) + psi_t = -alpha (dpsi(v-) + psi_t)              (1)
    nu (v+ - V) = 0                                           (l)

i.e. ``[[g, -A^T], [A, 0]] [v+; lam] = [g v-; r]`` with ``A = [mu; dpsi; nu]``.  It has a
unique solution whenever ``{mu^a, dpsi, nu^A}`` are independent.  For v- in D it agrees
with Prop. 3.4 / eq. 17 / Prop. 4.2; for v- outside D it also removes the D^perp part of
v- (the permanent constraints act impulsively too), which the projector map does not.
"""

from __future__ import annotations

import sympy as sp

__all__ = ["kkt_post_velocity"]


def kkt_post_velocity(
    g: sp.MatrixBase,
    mu: sp.MatrixBase,
    dpsi: sp.MatrixBase,
    nu: sp.MatrixBase,
    v_minus: sp.MatrixBase,
    alpha: sp.Expr,
    psi_t: sp.Expr = 0,
    V: sp.MatrixBase | None = None,
) -> sp.Matrix:
    """Solve the impulse-momentum system above for v+ (n x 1).

    ``V`` (n x 1) is the wall velocity used in ``nu (v+ - V) = 0``; by default the normal
    velocity ``-psi_t grad psi / g(grad psi, grad psi)``, computed here from scratch.
    """
    g = sp.Matrix(g)
    n = g.rows
    mu = sp.Matrix(mu) if mu.rows else sp.zeros(0, n)
    nu = sp.Matrix(nu) if nu.rows else sp.zeros(0, n)
    dpsi = sp.Matrix(dpsi)
    v_minus = sp.Matrix(v_minus)
    alpha, psi_t = sp.sympify(alpha), sp.sympify(psi_t)
    m, l = mu.rows, nu.rows
    if V is None:
        grad = g.LUsolve(dpsi.T)
        V = -psi_t * grad / (dpsi * grad)[0, 0] if psi_t != 0 else sp.zeros(n, 1)
    V = sp.Matrix(V)
    A = mu.col_join(dpsi).col_join(nu)
    k = A.rows
    big = sp.zeros(n + k, n + k)
    big[:n, :n] = g
    big[:n, n:] = -A.T
    big[n:, :n] = A
    rhs = sp.zeros(n + k, 1)
    rhs[:n, 0] = g * v_minus
    rhs[n + m, 0] = -alpha * ((dpsi * v_minus)[0, 0] + psi_t) - psi_t
    if l:
        rhs[n + m + 1 :, 0] = nu * V
    unknowns = sp.symbols(f"_kkt0:{n + k}")
    (solution,) = sp.linsolve((big, rhs), unknowns)
    return sp.Matrix(n, 1, [sp.cancel(e) for e in list(solution)[:n]])
