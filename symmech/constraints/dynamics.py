"""Constrained dynamics: multipliers and the acceleration that keeps the velocity in D.

Carnot paper (002), section 2.2, eq. 5, in the velocity basis of the scene (coordinate
velocities, or quasi-velocities v with ``q_dot = S v``).  With ``M v_dot = f`` the free
equations (see :func:`symmech.geometry.connection.forcing`) and constraints ``mu(q) v = 0``:

    M v_dot = f + mu^T lambda,        mu v_dot + mu_dot v = 0,

where ``mu_dot = d mu / dt = sum_a (d mu / d q^a) q_dot^a``.  Eliminating v_dot:

    lambda = C^{-1} (-mu_dot v - mu M^{-1} f),   C = mu M^{-1} mu^T,
    v_dot  = M^{-1} (f + mu^T lambda).

The paper prints ``lambda = C_ab((-Gamma q_dot q_dot - grad V) mu^a + q_dot q_dot d mu^a) Z^b``;
with its own sign convention (eq. 5, ``nabla q_dot = -grad V + lambda``) the correct
expression is the negative of the printed one (check: a particle held at constant height by
``y_dot = 0`` under gravity needs an upward force).  Our ``Z C^{-1}``-weighted vector
``M^{-1} mu^T lambda`` is that force; the tests check it against a KKT solve.
"""

from __future__ import annotations

from collections.abc import Sequence

import sympy as sp

from symmech.algebra.field import common_domain
from symmech.algebra.simplification import Level, check_level, polish
from symmech.constraints.projectors import bordered, solve_spd
from symmech.geometry.derivatives import Derivative

__all__ = [
    "constrained_acceleration",
    "constrained_solution",
    "constraint_rate",
    "multipliers",
]


def constraint_rate(
    mu: sp.MatrixBase, q: Sequence[sp.Symbol], q_dot: sp.MatrixBase, v: Sequence[sp.Symbol]
) -> sp.Matrix:
    """``mu_dot v`` with ``mu_dot = sum_a (d mu / d q^a) q_dot^a`` (m x 1).

    ``q_dot`` is the coordinate velocity written in the velocity basis (``S v``).  The
    partial derivatives are those of :class:`~symmech.geometry.derivatives.Derivative`
    (memoised over shared subexpressions, as for the forcing).
    """
    m = mu.rows
    vcol = sp.Matrix(v)
    out = sp.zeros(m, 1)
    D = Derivative(q)
    for a in range(len(q)):
        if q_dot[a] == 0:
            continue
        dmu = mu.applyfunc(lambda e, a=a: D.partial(e, a))
        if all(e == 0 for e in dmu):  # structurally zero: mu does not contain q^a
            continue
        out += q_dot[a] * (dmu * vcol)
    return out


def multipliers(
    M: sp.MatrixBase,
    f: sp.MatrixBase,
    mu: sp.MatrixBase,
    rate: sp.MatrixBase,
    level: Level = "light",
) -> sp.Matrix:
    """lambda = C^{-1} (-mu_dot v - mu M^{-1} f) (see the module docstring).

    With a simplification level the solves are exact and in normal form
    (:func:`~symmech.constraints.projectors.solve_spd`), so intermediate results are
    cancelled (and trigonometrically reduced) as they are formed.
    """
    check_level(level, "multipliers", "level")
    Minv = solve_spd(M, mu.T.row_join(f), level)
    m = mu.rows
    C = mu * Minv[:, :m]
    rhs = -rate - mu * Minv[:, m:]
    return solve_spd(C, rhs, level)


def constrained_acceleration(
    M: sp.MatrixBase,
    f: sp.MatrixBase,
    mu: sp.MatrixBase,
    lam: sp.MatrixBase,
    level: Level = "light",
) -> sp.Matrix:
    """v_dot = M^{-1} (f + mu^T lambda) (Carnot eq. 5 in the velocity basis)."""
    rhs = f + mu.T * lam if mu.rows else f
    return solve_spd(M, rhs, level)


def constrained_solution(
    M: sp.MatrixBase,
    f: sp.MatrixBase,
    mu: sp.MatrixBase,
    rate: sp.MatrixBase,
    level: Level = "light",
) -> tuple[sp.Matrix, sp.Matrix]:
    """``(v_dot, lambda)`` of ``M v_dot = f + mu^T lambda``, ``mu v_dot = -mu_dot v``.

    With a simplification level: one exact fraction-free solve of the bordered system
    ``[[M, mu^T], [mu, 0]] [v_dot; -lambda] = [f; -mu_dot v]`` (see
    :func:`~symmech.constraints.projectors.bordered`; entries cancelled against its
    determinant, in the Pythagorean normal form of :mod:`symmech.algebra.field`), which
    avoids inverting the Gram matrix C whose entries already carry ``det M``.  Otherwise,
    or when that solve declines, :func:`multipliers` and
    :func:`constrained_acceleration` (the formulas of the module docstring).
    """
    check_level(level, "constrained_solution", "level")
    n, m = M.rows, mu.rows
    if level != "none" and m:
        field = common_domain([M, f, mu, rate])
        if field.exact:
            zero = field.K.zero
            B = bordered(field.rows(M), field.rows(mu), zero)
            rhs = field.rows(f) + [[-x] for (x,) in field.rows(rate)]
            X = field.solve(B, rhs)
            if X is not None:
                acc = field.to_matrix(X[:n]).applyfunc(lambda e: polish(e, level))
                lam = field.to_matrix([[-x] for (x,) in X[n:]])
                return acc, lam.applyfunc(lambda e: polish(e, level))
    lam = multipliers(M, f, mu, rate, level) if m else sp.zeros(0, 1)
    return constrained_acceleration(M, f, mu, lam, level), lam
