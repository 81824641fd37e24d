"""The generic rank of a set of columns (vector fields, frames): the rank off a
measure-zero set of points, by the policy :data:`GENERIC_RANK_POLICY` (see
:mod:`symmech.geometry.distributions` for what it decides and why)."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import sympy as sp
from sympy.polys.matrices import DomainMatrix

from symmech.algebra.budget import BudgetExceeded
from symmech.algebra.numeric import EvaluationError
from symmech.algebra.rank import rank_at
from symmech.algebra.sampling import sample_points
from symmech.algebra.simplification import tidy
from symmech.errors import SceneError

__all__ = ["GENERIC_RANK_POLICY", "Point"]

GENERIC_RANK_POLICY = (
    "generic rank: rank off a measure-zero set of points; symbolic rank (exact, after "
    "simplification) cross-checked by the maximal 50-digit numeric rank at random rational "
    "sample points (symmech.algebra.rank), the numeric rank deciding when available"
)

#: Number of random sample points of the numeric rank check.
_SAMPLES = 3


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


def _numeric_rank_at(M: sp.Matrix, point: Point) -> int | None:
    """:func:`symmech.algebra.rank.rank_at`, or None where an entry has no finite value."""
    try:
        return rank_at(M, point)
    except EvaluationError:
        return None


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
