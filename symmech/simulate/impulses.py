"""Simultaneous impacts on several walls: the generalized Newton law, decided exactly.

At an instant where the walls of a set ``A0`` are closed (``psi_i ~ 0``) and approach
(normal rates ``u_i- < -tol_v``), the frictionless generalized Newton law (Moreau 1988;
Glocker and Pfeiffer 1995; Brogliato, *Nonsmooth Mechanics*, ch. 6) gives each contact an
impulse ``Lambda_i >= 0`` with

    v+ = v- + M_c^-1 G^T Lambda,   u+ = u- + W Lambda,   W = G M_c^-1 G^T,
    0 <= Lambda_i  _|_  u_i+ + alpha_i u_i- >= 0,

``G`` the walls' rows ``dpsi_i S``, ``M_c^-1`` the inverse metric in the constrained
space (Carnot paper section 2.2: the impulse keeps ``mu v+ = 0``), ``W`` the Delassus
matrix.  For one wall this is the scene's closed-form map (Carnot paper eq. 10).

The loop does not rebuild ``M_c^-1`` or ``G``: each wall's own generated impact map
``Phi_i`` already holds them.  ``d_i = Phi_i(v-) - v-`` is the velocity change of wall i
hit alone, along ``M_c^-1 G_i^T``, and it changes the wall's rate by
``g_i = G_i d_i = -(1 + alpha_i) u_i-``.  With ``x_i = d_i / g_i`` (the velocity change
per unit change of ``u_i``) and ``K_ji = G_j x_i`` (so ``K = W D^-1``, ``D = diag W``:
``K_ii = 1``), the law in the rate changes ``m_i = W_ii Lambda_i`` is the linear
complementarity problem

    w = K m - g >= 0,   m >= 0,   w^T m = 0,   v+ = v- + sum_i m_i x_i

(``w_i = u_i+ + alpha_i u_i-``).  ``W`` positive definite makes ``K`` a P-matrix: one
solution, found here exactly by trying the active sets (:func:`active_set_solution`), the
smallest first.  Hit alone, a wall gets ``m_i = g_i`` and ``v+ = Phi_i(v-)``.

Walls whose impact also imposes impulsive constraints (rolling on contact) or follows the
energy law have no such direction; a set that holds one is resolved one wall at a time.

Every function here runs on Python floats and on mpmath numbers alike (the reference loop
of :mod:`symmech.simulate.reference` uses the same law at 50 digits), and the C loop
tries the active sets in the same order, so the three loops take the same decisions.  That
is why the loop does not call :func:`symmech.algebra.lcp.solve_lcp` (NumPy only, Murty's
pivoting beyond 4 contacts), the general solver, which the tests use as an independent
route.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

__all__ = ["MAX_SIMULTANEOUS", "active_set_solution", "solve_small"]

#: The largest set of walls resolved together (2^k active sets are tried); a larger set
#: is resolved one wall at a time.
MAX_SIMULTANEOUS = 8


def solve_small(A: Sequence[Sequence[Any]], b: Sequence[Any]) -> list[Any] | None:
    """``x`` with ``A x = b`` by Gaussian elimination with partial pivoting, or None when
    a pivot is zero (a singular ``A``)."""
    k = len(b)
    if k == 0:
        return []
    M = [[*A[i], b[i]] for i in range(k)]
    for c in range(k):
        piv = max(range(c, k), key=lambda i: abs(M[i][c]))
        if M[piv][c] == 0:
            return None
        M[c], M[piv] = M[piv], M[c]
        for i in range(c + 1, k):
            f = M[i][c] / M[c][c]
            for j in range(c, k + 1):
                M[i][j] = M[i][j] - f * M[c][j]
    x = [M[0][0] * 0] * k
    for c in range(k - 1, -1, -1):
        acc = M[c][k]
        for j in range(c + 1, k):
            acc = acc - M[c][j] * x[j]
        x[c] = acc / M[c][c]
    return x


def active_set_solution(K: Sequence[Sequence[Any]], g: Sequence[Any], tol: Any) -> list[Any] | None:
    """The solution ``m`` of ``w = K m - g >= 0, m >= 0, w^T m = 0`` (see the module
    docstring), or None when no active set is feasible.

    Active sets ``A`` are tried by size (the empty set first), then in the order of their
    bit masks (the C loop tries them in the same order): ``K_AA m_A = g_A``, feasible
    when ``m_A >= -tol`` and ``w_j >= -tol`` off ``A`` (``tol``: the velocity tolerance;
    an approach slower than it is no approach).  Entries of ``m`` below zero by less than
    ``tol`` are set to 0."""
    k = len(g)
    zero = g[0] * 0
    masks = sorted(range(1 << k), key=lambda s: (bin(s).count("1"), s))
    for mask in masks:
        act = [i for i in range(k) if mask >> i & 1]
        sol = solve_small([[K[i][j] for j in act] for i in act], [g[i] for i in act])
        if sol is None or any(x < -tol for x in sol):
            continue
        m = [zero] * k
        for i, x in zip(act, sol, strict=True):
            m[i] = x if x > 0 else zero
        ok = True
        for j in range(k):
            if mask >> j & 1:
                continue
            w = -g[j]
            for i in act:
                w = w + K[j][i] * m[i]
            if w < -tol:
                ok = False
                break
        if ok:
            return m
    return None
