"""An exact solver for small dense linear complementarity problems (numpy only).

The problem LCP(W, q): find x, w in R^k with

    w = W x + q,    w >= 0,    x >= 0,    w^T x = 0.

A solution is fixed by its *active set* S = {i : x_i may be non-zero}: ``w_S = 0``,
``x_N = 0`` (N the complement), so ``W_SS x_S = -q_S`` and ``w_N = W_NS x_S + q_N``; the set
is admissible when ``x_S >= 0`` and ``w_N >= 0``.  For a P-matrix W (every principal minor
positive: a symmetric positive definite W, such as a Delassus matrix of independent
contacts, is one) the solution exists and is unique for every q (Cottle, Pang and Stone,
"The Linear Complementarity Problem", 1992, Thm 3.3.7).

Methods (both deterministic):

* ``"enumerate"``: the 2^k active sets in a fixed order (by size, then lexicographically),
  one linear solve each; the first admissible one is returned.  Exact up to the linear
  solves; used by default for ``k <= ENUMERATION_MAX_SIZE`` (= 4: at most 16 solves of
  size <= 4).
* ``"murty"``: Murty's least-index principal pivoting method (Murty, "Note on a Bard-type
  scheme for solving the complementarity problem", Opsearch 11, 1974; Cottle-Pang-Stone
  section 4.2): start from S = {}; while the smallest index j with ``x_j < 0`` (j in S) or
  ``w_j < 0`` (j not in S) exists, toggle j in S.  Finite for every P-matrix (at most 2^k
  pivots, usually about k); the default beyond ``ENUMERATION_MAX_SIZE``.

Tolerance policy.  A component counts as non-negative when it is at least ``-rtol`` times
its scale: for ``w_i`` the magnitude of the terms that form it,
``|q_i| + sum_j |W_ij| |x_j|`` (a backward-error scale: rounding in the solve is of that
order); for ``x_j`` the largest ``|x|`` of the candidate (with a floor at the smallest
normal number).  ``rtol`` defaults to :data:`DEFAULT_RTOL` (1e-10), well above the rounding
of a well-conditioned solve and far below any physical rate.  A principal block
``W_SS`` whose reciprocal condition number is below ``rtol`` counts as singular: the
enumeration skips that set, the pivoting method stops with :class:`LCPError`.  The returned
solution has ``x_N = 0`` and ``w_S = 0`` exactly (the defining equations of the active set),
with tiny negative entries (within the tolerance) of ``x_S`` and ``w_N`` set to 0, so no
rounding residue is left where the exact answer is zero.

Refusals (:class:`LCPError`): non-finite or non-real data, a W that is not square, a q of
another length, no admissible active set (the LCP has no solution, or only degenerate
ones), and a pivoting run that cycles or meets a singular block (W not a P-matrix).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from itertools import combinations
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symmech.errors import SymmechError

__all__ = [
    "DEFAULT_RTOL",
    "ENUMERATION_MAX_SIZE",
    "LCPError",
    "LCPSolution",
    "solve_lcp",
]

#: Problems up to this size are solved by enumerating their 2^k active sets.
ENUMERATION_MAX_SIZE = 4
#: Relative tolerance of the sign tests and of the singular-block test (module docstring).
DEFAULT_RTOL = 1e-10

Method = Literal["auto", "enumerate", "murty"]


class LCPError(SymmechError, ValueError):
    """A linear complementarity problem was refused or has no (regular) solution."""


@dataclass(frozen=True)
class LCPSolution:
    """The solution of LCP(W, q): ``x``, ``w = W x + q``, the active set (sorted indices
    i with ``w_i = 0`` imposed, ``x_i`` free) and the method that found it."""

    x: NDArray[np.float64]
    w: NDArray[np.float64]
    active: tuple[int, ...]
    method: str


def _checked(W: ArrayLike, q: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    try:
        Wa = np.array(W, dtype=np.float64)
        qa = np.array(q, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise LCPError(f"LCP: W and q must be real arrays of numbers ({exc})") from None
    if Wa.ndim != 2 or Wa.shape[0] != Wa.shape[1]:
        raise LCPError(f"LCP: W must be a square matrix, got shape {Wa.shape}")
    if qa.ndim == 2 and 1 in qa.shape:
        qa = qa.ravel()
    if qa.ndim != 1 or qa.shape[0] != Wa.shape[0]:
        raise LCPError(f"LCP: q must be a vector of length {Wa.shape[0]}, got shape {qa.shape}")
    if not (np.all(np.isfinite(Wa)) and np.all(np.isfinite(qa))):
        raise LCPError("LCP: W and q must be finite (got inf or nan)")
    return Wa, qa


class _Candidate:
    """The point of the active set S: ``x_S`` from ``W_SS x_S = -q_S``, ``x_N = 0``,
    ``w = W x + q`` with ``w_S = 0``; None when W_SS is (numerically) singular."""

    def __init__(
        self, W: NDArray[np.float64], q: NDArray[np.float64], S: tuple[int, ...], rtol: float
    ):
        k = q.shape[0]
        self.S = S
        self.x = np.zeros(k)
        self.regular = True
        if S:
            idx = list(S)
            block = W[np.ix_(idx, idx)]
            if not np.linalg.cond(block, 1) * rtol <= 1:  # also inf or nan: singular
                self.regular = False
                return
            self.x[idx] = np.linalg.solve(block, -q[idx])
        self.w = W @ self.x + q
        self.w[list(S)] = 0.0
        self.w_scale = np.abs(q) + np.abs(W) @ np.abs(self.x)

    def violations(self, rtol: float) -> list[int]:
        """Indices where the candidate is infeasible: ``x_j < 0`` (j in S) or ``w_j < 0``."""
        x_floor = -rtol * max(float(np.max(np.abs(self.x), initial=0.0)), np.finfo(float).tiny)
        bad_x = {j for j in self.S if self.x[j] < x_floor}
        bad_w = {
            j
            for j in range(self.x.shape[0])
            if j not in self.S and self.w[j] < -rtol * self.w_scale[j]
        }
        return sorted(bad_x | bad_w)

    def solution(self, method: str) -> LCPSolution:
        x = np.where(self.x < 0, 0.0, self.x)  # within the tolerance: exactly 0
        w = np.where(self.w < 0, 0.0, self.w)
        return LCPSolution(x=x, w=w, active=self.S, method=method)


def _subsets(k: int) -> Iterator[tuple[int, ...]]:
    for size in range(k + 1):
        yield from combinations(range(k), size)


def _enumerate(W: NDArray[np.float64], q: NDArray[np.float64], rtol: float) -> LCPSolution:
    for S in _subsets(q.shape[0]):
        cand = _Candidate(W, q, S, rtol)
        if cand.regular and not cand.violations(rtol):
            return cand.solution("enumerate")
    raise LCPError(
        f"LCP (k = {q.shape[0]}): no active set is admissible: the problem has no solution,"
        " or only degenerate ones (W is not a P-matrix: dependent contacts?)"
    )


def _murty(W: NDArray[np.float64], q: NDArray[np.float64], rtol: float) -> LCPSolution:
    k = q.shape[0]
    S: set[int] = set()
    for _ in range(2**k):
        cand = _Candidate(W, q, tuple(sorted(S)), rtol)
        if not cand.regular:
            raise LCPError(
                f"LCP (k = {k}): principal pivoting met a singular block W_SS, S ="
                f" {sorted(S)} (W is not a P-matrix: dependent contacts?)"
            )
        bad = cand.violations(rtol)
        if not bad:
            return cand.solution("murty")
        S ^= {bad[0]}
    raise LCPError(
        f"LCP (k = {k}): principal pivoting did not terminate in 2^k = {2**k} pivots"
        " (W is not a P-matrix)"
    )


def solve_lcp(
    W: ArrayLike,
    q: ArrayLike,
    *,
    method: Method = "auto",
    rtol: float = DEFAULT_RTOL,
) -> LCPSolution:
    """Solve ``w = W x + q, w >= 0, x >= 0, w^T x = 0`` (see the module docstring).

    ``method``: ``"auto"`` (enumeration for ``k <= ENUMERATION_MAX_SIZE``, Murty's
    principal pivoting beyond), ``"enumerate"`` or ``"murty"``.  Raises
    :class:`LCPError` for refused input or when no solution is found.

    >>> solve_lcp([[2.0, 1.0], [1.0, 2.0]], [-1.0, 1.0]).x
    array([0.5, 0. ])
    """
    if method not in ("auto", "enumerate", "murty"):
        raise LCPError(f"LCP: method must be 'auto', 'enumerate' or 'murty', got {method!r}")
    if not (isinstance(rtol, float | int) and 0 < rtol < 1):
        raise LCPError(f"LCP: rtol must be a number in (0, 1), got {rtol!r}")
    Wa, qa = _checked(W, q)
    if method == "enumerate" or (method == "auto" and qa.shape[0] <= ENUMERATION_MAX_SIZE):
        return _enumerate(Wa, qa, float(rtol))
    return _murty(Wa, qa, float(rtol))
