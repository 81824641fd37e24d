"""Is an expression identically zero?  The one decision every layer of symmech uses.

"Identically" means as a function of its symbols (coordinates, parameters, time,
velocities) and of the undefined functions ``f(t)`` it holds.  The routes, cheapest
sufficient one first:

1. **structure**: sympy's automatic evaluation already gives 0, or an exact non-zero
   number;
2. **exact normal form** (expressions of at most
   :data:`symmech.algebra.budget.ZERO_TEST_OPS` operations): the Pythagorean normal form
   in the rational-function field of the expression
   (:func:`symmech.algebra.field.field_zero`).  A zero there is a proof; a non-zero is not
   (the field treats ``sin(2x)`` and ``sin(x)``, or a radical and its base, as
   independent), so a non-zero goes on;
3. **randomized exact evaluation** (expressions of at most
   :data:`symmech.algebra.budget.ZERO_EXACT_OPS` operations):
   :func:`symmech.algebra.identity.identically_zero`, rational arithmetic at a random point
   with the circle relations exact.  "Zero" has a stated error bound (below ``1e-13``,
   Schwartz-Zippel); "non-zero" is a proof when the model of the functions is exact;
4. **sampled evaluation**: 50-digit evaluation at the sample points
   (:func:`symmech.algebra.numeric.vanishes`) for what the exact routes cannot evaluate
   (floats, functions the exact model does not know) or judge; a generic statement (zero
   at every random point).  ``None`` when the expression cannot be evaluated at any point.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction

import sympy as sp
from sympy.core.function import AppliedUndef

from symmech.algebra import budget as limits
from symmech.algebra.field import field_zero
from symmech.algebra.identity import Unsupported, identically_zero
from symmech.algebra.numeric import vanishes
from symmech.algebra.opcount import count_ops
from symmech.algebra.sampling import sample_points

__all__ = ["ZeroVerdict", "evidently_nonzero", "is_zero", "zero_verdict"]

#: Sample points of route 4 when the caller gives none.
_SAMPLES = 4
_SEED = 20261126


@dataclass(frozen=True)
class ZeroVerdict:
    """``zero``: True, False, or None (undecided: not evaluable anywhere); ``route``: which
    route of the module docstring decided; ``error_bound``: the probability bound of a
    wrong "zero" (0 for a proof, or for a sampled verdict, which states none)."""

    zero: bool | None
    route: str
    error_bound: Fraction = Fraction(0)


def _atoms(expr: sp.Basic) -> list[sp.Basic]:
    found = set(expr.free_symbols)
    found |= {a for a in expr.atoms(AppliedUndef, sp.Derivative)}
    return sorted(found, key=sp.default_sort_key)


def zero_verdict(expr: sp.Basic, points: Sequence[Mapping] | None = None) -> ZeroVerdict:
    """Whether ``expr`` is identically zero, and how that was decided (module docstring).

    ``points`` are the sample points of route 4 (values for every atom of ``expr``); by
    default a few random rational points are drawn with a fixed seed.
    """
    e = sp.sympify(expr, strict=True)
    if e == 0:
        return ZeroVerdict(True, "structure")
    if e.is_Rational:
        return ZeroVerdict(False, "structure")
    ops = count_ops(e)
    if ops <= limits.ZERO_TEST_OPS and field_zero(e):
        return ZeroVerdict(True, "normal form")
    if ops <= limits.ZERO_EXACT_OPS:
        try:
            verdict = identically_zero(lambda value, const: value(e))
        except (Unsupported, ZeroDivisionError):
            verdict = None
        if verdict is not None and verdict.zero:
            return ZeroVerdict(True, "exact evaluation", verdict.error_bound)
        if verdict is not None and verdict.model_exact:
            return ZeroVerdict(False, "exact evaluation")
    if points is None:
        points = sample_points(_atoms(e), count=_SAMPLES, seed=_SEED)
    return ZeroVerdict(vanishes(e, points), "sampled evaluation")


def is_zero(expr: sp.Basic, points: Sequence[Mapping] | None = None) -> bool | None:
    """True when ``expr`` is identically zero, False when it is not, None when it cannot
    be evaluated (see :func:`zero_verdict`)."""
    return zero_verdict(expr, points).zero


def evidently_nonzero(expr: sp.Basic) -> bool:
    """True when ``expr`` is non-zero at one random rational point (50-digit evaluation,
    :func:`symmech.algebra.numeric.vanishes`): then it is not identically zero.  False
    says nothing; its cost is one walk of the tree, a small part of :func:`is_zero`'s, so
    callers that expect a non-zero try it first."""
    e = sp.sympify(expr, strict=True)
    return vanishes(e, sample_points(_atoms(e), count=1, seed=_SEED)) is False
