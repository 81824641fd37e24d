"""The rank of a matrix of expressions at a point, and its generic rank: the one rank test
of symmech (constraint rows, frames, wall and impulsive one-forms, distributions).

At a point, the entries are evaluated in 50-digit arithmetic
(:func:`symmech.algebra.numeric.evaluate_matrix_mp`: one memoised walk of the trees, no
``evalf``), each row is scaled to unit size (the rank does not change, and the threshold
is then independent of units), and the rank is read off Gaussian elimination with
complete pivoting: the number of pivots above ``10^-25`` (relative to the largest entry).
Exactly dependent rows leave residues near ``10^-50``; rows that are independent but
nearly parallel to ``10^-25`` would count as dependent, far beyond what float64 code could
resolve anyway.

The generic rank is the largest rank at a few random points: the rank off a
measure-zero set (a point where the rank drops is found with probability zero).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import mpmath
import sympy as sp

from symmech.algebra.numeric import MP_DIGITS, EvaluationError, evaluate_matrix_mp

__all__ = ["RANK_TOLERANCE", "generic_rank", "rank_at"]

#: Pivots of the row-scaled matrix at most this (relative to its largest entry) are zero.
RANK_TOLERANCE = mpmath.mpf(10) ** -25


def rank_at(M: sp.MatrixBase, point: Mapping) -> int:
    """The rank of ``M`` at ``point`` (module docstring); raises
    :class:`~symmech.algebra.numeric.EvaluationError` naming an entry that has no finite
    value there."""
    if M.rows == 0 or M.cols == 0:
        return 0
    values = evaluate_matrix_mp(M, point, digits=MP_DIGITS)
    with mpmath.workdps(MP_DIGITS):
        rows = []
        for row in values:
            big = max((abs(x) for x in row), default=mpmath.mpf(0))
            if not mpmath.isfinite(big):
                raise EvaluationError("is infinite or undefined at the point")
            if big:
                rows.append([x / big for x in row])
        return _pivots(rows)


def _pivots(A: list[list[mpmath.mpc]]) -> int:
    """Gaussian elimination with complete pivoting; the number of pivots above
    :data:`RANK_TOLERANCE` (rows already scaled to largest entry 1)."""
    A = [list(r) for r in A]
    rank = 0
    cols = len(A[0]) if A else 0
    while A and rank < cols:
        i, j, pivot = max(
            ((i, j, abs(A[i][j])) for i in range(len(A)) for j in range(cols)),
            key=lambda t: t[2],
        )
        if pivot <= RANK_TOLERANCE:
            break
        p = A.pop(i)
        for r in A:
            factor = r[j] / p[j]
            if factor:
                for c in range(cols):
                    r[c] -= factor * p[c]
        rank += 1
    return rank


def generic_rank(
    M: sp.MatrixBase,
    points: Sequence[Mapping],
    where: Callable[[Mapping], str] | None = None,
) -> tuple[int | None, str]:
    """``(rank, reason)``: the largest :func:`rank_at` over ``points``, or ``(None,
    reason)`` when ``M`` cannot be evaluated at any of them (``reason`` names the first
    entry that failed, why, and ``where(point)`` when given)."""
    ranks: list[int] = []
    reason = ""
    for point in points:
        try:
            ranks.append(rank_at(M, point))
        except EvaluationError as exc:
            at = where(point) if where is not None else ""
            reason = reason or f"entry {list(exc.index or ())} {exc.reason}{at}"
    return (max(ranks) if ranks else None), reason
