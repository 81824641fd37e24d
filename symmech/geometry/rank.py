"""The generic rank of a set of columns (vector fields, frames): the rank off a
measure-zero set of points, by the policy :data:`GENERIC_RANK_POLICY` (see
:mod:`symmech.geometry.distributions` for what it decides and why)."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import mpmath
import sympy as sp
from sympy.polys.matrices import DomainMatrix

from symmech.algebra.budget import BudgetExceeded
from symmech.declaration.sampling import sample_points
from symmech.errors import SceneError
from symmech.geometry.simplification import tidy

__all__ = ["GENERIC_RANK_POLICY", "Point"]

GENERIC_RANK_POLICY = (
    "generic rank: rank off a measure-zero set of points; symbolic rank (exact, after "
    "simplification) cross-checked by the maximal 40-digit numeric rank at random rational "
    "sample points, the numeric rank deciding when available"
)

#: Number of random sample points of the numeric rank check.
_SAMPLES = 3
#: Working precision (digits) and relative singular-value threshold of the numeric rank.
_DPS = 40
_REL_TOL = mpmath.mpf(10) ** -25
#: An evaluated entry with fewer significant bits than this, or smaller in magnitude than
#: ``_ZERO_ABS``, is an exact zero that evalf could not resolve (cancellation).
_MIN_BITS = 20
_ZERO_ABS = sp.Float(10, _DPS) ** -60


Point = Mapping[sp.Symbol, Any]

# ---------------------------------------------------------------------------- generic rank


@dataclass(frozen=True)
class _Rank:
    rank: int
    symbolic: int
    numeric: int | None  # None: entries could not be evaluated to numbers


def _entry(e: sp.Expr, simplify: bool) -> sp.Expr:
    """Entry prepared for the symbolic rank: cancelled if rational, else bounded simplify."""
    if not simplify or e.is_Rational or e.is_polynomial():
        return e  # polynomials: the exact domain arithmetic of the rank needs nothing more
    if e.is_rational_function():
        return sp.cancel(e)
    return tidy(e, "full")


def _symbolic_rank(M: sp.Matrix) -> int:
    if all(e == 0 for e in M):
        return 0
    try:
        return int(DomainMatrix.from_Matrix(M).to_field().rank())
    except BudgetExceeded:  # a deadline of the stage around it
        raise
    except Exception:  # domain construction can fail on exotic expressions
        return int(M.rank(simplify=True))


def _numeric_value(e: sp.Expr, point: Point) -> mpmath.mpc | None:
    exact = e.xreplace(dict(point))
    if exact.is_Rational:  # polynomial / rational entries at rational points: no evalf
        return mpmath.mpf(int(exact.p)) / int(exact.q)
    if exact.free_symbols:
        return None
    v = exact.evalf(_DPS)
    if not v.is_number or v.has(sp.zoo, sp.oo, -sp.oo, sp.nan):
        return None
    try:
        parts = [_mp_part(part) for part in v.as_real_imag()]
    except (TypeError, ValueError):
        return None
    return parts[0] if parts[1] == 0 else mpmath.mpc(*parts)


def _mp_part(x: sp.Expr) -> mpmath.mpf:
    """A real part as an mpf; evalf's "no significant digit" results (``0.e-181``) are 0."""
    if x == 0:
        return mpmath.mpf(0)
    f = sp.Float(x, _DPS)
    if getattr(f, "_prec", _DPS) < _MIN_BITS or abs(f) < _ZERO_ABS:
        return mpmath.mpf(0)
    return mpmath.mpf(f)


def _numeric_rank_at(M: sp.Matrix, point: Point) -> int | None:
    rows, cols = M.shape
    with mpmath.workdps(_DPS):
        A = mpmath.matrix(rows, cols)
        for i in range(rows):
            for j in range(cols):
                v = _numeric_value(M[i, j], point)
                if v is None or not mpmath.isfinite(v):
                    return None
                A[i, j] = v
        # Column scaling does not change the rank and evens out the singular values.
        keep = []
        for j in range(cols):
            norm = mpmath.sqrt(sum(abs(A[i, j]) ** 2 for i in range(rows)))
            if norm != 0:
                keep.append(j)
                for i in range(rows):
                    A[i, j] /= norm
        if not keep:
            return 0
        B = mpmath.matrix(rows, len(keep))
        for i in range(rows):
            for jj, j in enumerate(keep):
                B[i, jj] = A[i, j]
        s = mpmath.svd(B, compute_uv=False)
        smax = max(abs(x) for x in s)
        return sum(1 for x in s if abs(x) > _REL_TOL * smax)


def _generic_rank(
    columns: Sequence[sp.MatrixBase], points: Sequence[Point], simplify: bool
) -> _Rank:
    M = sp.Matrix.hstack(*columns)
    symbolic = _symbolic_rank(M.applyfunc(lambda e: _entry(e, simplify)))
    ranks = [r for r in (_numeric_rank_at(M, p) for p in points) if r is not None]
    numeric = max(ranks) if ranks else None
    return _Rank(symbolic if numeric is None else numeric, symbolic, numeric)


def _sample(columns: Sequence[sp.MatrixBase], points: Sequence[Point] | None) -> list[Point]:
    if points is not None:
        return list(points)
    syms: set[sp.Symbol] = set()
    for col in columns:
        syms |= col.free_symbols
    return list(sample_points(syms, count=_SAMPLES))


def _note(label: str, r: _Rank) -> list[str]:
    if r.numeric is None:
        return [f"{label}: could not evaluate numerically; symbolic rank {r.symbolic} used"]
    if r.numeric != r.symbolic:
        return [
            f"{label}: symbolic rank {r.symbolic} disagrees with numeric rank {r.numeric} "
            "at the sample points; the numeric rank is used"
        ]
    return []


def _points_arg(points: Iterable[Point] | None, where: str) -> list[Point] | None:
    if points is None:
        return None
    pts = list(points)
    if not pts or not all(isinstance(p, Mapping) for p in pts):
        raise SceneError(f"{where}: points must be a non-empty list of {{symbol: value}} mappings")
    return pts
