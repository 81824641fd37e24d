"""Division-free determinant and adjugate of a polynomial matrix, by Laplace expansion.

``det A`` and ``adj A`` (``A adj A = det A I``) are formed from the minors of A: the
minors of the first k rows on every k-subset of columns (expanding along row k), the
minors of the last rows likewise, and each cofactor as the generalised Laplace expansion
of the complementary minor over a split of its rows.  Every intermediate is a minor of A,
built with ring multiplications and additions only, so it may be reduced modulo an ideal
(``reduce``) after every step: modulo ``sin^2 + cos^2 - 1`` the minors of a trigonometric
metric stay as small as the final determinant (for the 5 x 5 pendulum-on-cart metric the
determinant has 81 terms reduced against 1462 unreduced, which Bareiss or Berkowitz,
whose exact divisions or powers of A cannot be reduced on the way, must carry).

Cost: ``n 2^(n-1)`` products for the minors and as many for the cofactors, so the routine
is meant for n up to about 8; a term budget bounds the work: when the minors formed so far
hold more terms than ``budget``, :class:`symmech.algebra.budget.BudgetExceeded` is raised.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from itertools import combinations
from typing import Any

from symmech.algebra.budget import BudgetExceeded, checkpoint

__all__ = ["adjugate_det"]

Poly = Any  # a sympy PolyElement
Reduce = Callable[[Poly], Poly]


def _expand(
    row: Sequence[Poly],
    previous: dict,
    size: int,
    parity: int,
    zero: Poly,
    cols: tuple,
    keep: Callable[[Poly], Poly],
) -> dict:
    """Minors of one more row: ``M[S] = sum_j (-1)^(pos(j, S) + parity) a_j M[S - j]``,
    each passed through ``keep`` (reduction and budget) as soon as it is formed."""
    out = {}
    for S in combinations(cols, size):
        acc = zero
        for pos, j in enumerate(S):
            a = row[j]
            if not a:
                continue
            sub = previous.get(S[:pos] + S[pos + 1 :])
            if sub is None:
                continue
            acc = acc - a * sub if (pos + parity) % 2 else acc + a * sub
        acc = keep(acc)
        if acc:
            out[S] = acc
    return out


def adjugate_det(
    A: Sequence[Sequence[Poly]],
    one: Poly,
    reduce: Reduce = lambda p: p,
    budget: int | None = None,
) -> tuple[list[list[Poly]], Poly]:
    """``(adj A, det A)`` of a square matrix of ring elements (lists of rows).

    ``one`` is the ring's unit; ``reduce`` maps an element to its normal form modulo an
    ideal (a ring homomorphism onto representatives, applied after every expansion step);
    ``budget`` caps the total number of terms of the stored minors and cofactors.

    >>> from sympy import ZZ
    >>> from sympy.polys.rings import ring
    >>> R, x, y = ring("x y", ZZ)
    >>> adj, det = adjugate_det([[x, y], [y, x]], R.one)
    >>> det, adj
    (x**2 - y**2, [[x, -y], [-y, x]])
    """
    n = len(A)
    zero = one - one
    cols = tuple(range(n))
    held = 0

    def keep(p: Poly) -> Poly:
        nonlocal held
        checkpoint()  # the deadline of a stage around this one (symmech.algebra.budget.time_limit)
        p = reduce(p)
        held += len(p)
        if budget is not None and held > budget:
            raise BudgetExceeded(
                "Laplace expansion (minors and cofactors)",
                "FIELD_MINOR_TERMS",
                "terms",
                budget,
                held,
            )
        return p

    # top[k][S]: minor of rows 0..k-1 on columns S; bottom[r][T]: rows r..n-1 on T.
    top: list[dict] = [{(): one}]
    for k in range(1, n):
        top.append(_expand(A[k - 1], top[k - 1], k, k - 1, zero, cols, keep))
    bottom: list[dict] = [{} for _ in range(n + 1)]  # bottom[0] is never read
    bottom[n] = {(): one}
    for r in range(n - 1, 0, -1):
        bottom[r] = _expand(A[r], bottom[r + 1], n - r, 0, zero, cols, keep)
    last = _expand(A[n - 1], top[n - 1], n, n - 1, zero, cols, reduce)
    det = last.get(cols, zero)

    adj = [[zero] * n for _ in range(n)]
    for r in range(n):
        upper, lower = top[r], bottom[r + 1]
        for j in range(n):
            rest = cols[:j] + cols[j + 1 :]
            acc = zero
            for pos in combinations(range(n - 1), r):
                S = tuple(rest[p] for p in pos)
                a = upper.get(S)
                if a is None:
                    continue
                T = tuple(c for p, c in enumerate(rest) if p not in pos)
                b = lower.get(T)
                if b is None:
                    continue
                sign = (sum(pos) - r * (r - 1) // 2 + r + j) % 2
                acc = acc - a * b if sign else acc + a * b
            adj[j][r] = keep(acc)  # adj = transpose of the cofactor matrix
    return adj, det
