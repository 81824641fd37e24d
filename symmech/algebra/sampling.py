"""Sample numeric values for symbols, respecting their sympy assumptions.

Used where a symbolic check would be too expensive or undecidable: positive definiteness
of a metric, independence of constraints.  A check "at sampled points" evaluates at a few
random points drawn here; it is a generic statement (it holds off a measure-zero set).

Besides symbols, an "atom" may be an undefined applied function ``g(x)`` or a derivative
``Derivative(g(x), x)``: such an atom stands for an unknown smooth real function, and gets
a random real value of its own (honouring ``positive=`` etc. given to ``sympy.Function``).

The order in which values are drawn is fixed by the atoms' names and their full
``srepr`` (which includes the assumptions), never by hashes, so the points are the same in
every process whatever ``PYTHONHASHSEED`` is.
"""

from __future__ import annotations

import random
from collections.abc import Iterable
from functools import lru_cache

import sympy as sp

__all__ = ["atom_key", "sample_point", "sample_points"]


@lru_cache(maxsize=4096, typed=True)  # atoms: their == is cheap, kept across runs
def atom_key(atom: sp.Basic) -> tuple[str, str]:
    """A total, process-independent order on symbols and other atoms: (name, srepr)
    (a function of the atom alone, remembered: printing is slow)."""
    return (str(atom), sp.srepr(atom))


def _sample(sym: sp.Basic, rng: random.Random, far: bool = False) -> sp.Rational:
    # Rationals keep the downstream evaluation exact when sympy can do it.
    def rat(lo: float, hi: float) -> sp.Rational:
        return sp.Rational(rng.randint(int(lo * 1000), int(hi * 1000)), 1000)

    if sym.is_integer:
        if sym.is_positive:
            return sp.Integer(rng.randint(1, 5))
        if sym.is_nonnegative:
            return sp.Integer(rng.randint(0, 5))
        if sym.is_negative:
            return sp.Integer(-rng.randint(1, 5))
        return sp.Integer(rng.randint(-5, 5))
    if sym.is_positive:
        return rat(0.3, 2.0)
    if sym.is_nonnegative:
        return rat(0.0, 2.0)
    if sym.is_negative:
        return -rat(0.3, 2.0)
    if sym.is_nonpositive:
        return -rat(0.0, 2.0)
    if far:
        return rng.choice((-1, 1)) * rat(2.5, 3.5)
    return rat(-1.5, 1.5)


def sample_point(
    symbols: Iterable[sp.Basic], rng: random.Random, far: bool = False
) -> dict[sp.Basic, sp.Rational]:
    """One random rational value per symbol, honouring positive/negative/integer assumptions;
    ``far``: a real symbol without a sign gets a value of magnitude in [2.5, 3.5] (an angle
    near +-pi, a displacement of a few units) instead of one in [-1.5, 1.5]."""
    return {s: _sample(s, rng, far) for s in symbols}


def sample_points(
    symbols: Iterable[sp.Basic], count: int = 4, seed: int = 20010101, far: int = 0
) -> list[dict[sp.Basic, sp.Rational]]:
    """``count`` reproducible random points (fixed seed, so a failing check is repeatable),
    then ``far`` points away from the origin (see :func:`sample_point`): a metric such as
    ``diag(1, 1 + 2 cos(theta))``, positive for |theta| < 2 pi / 3 only, is found
    indefinite there.  The first ``count`` points do not depend on ``far``."""
    syms = sorted(set(symbols), key=atom_key)
    rng = random.Random(seed)
    near = [sample_point(syms, rng) for _ in range(count)]
    return near + [sample_point(syms, rng, far=True) for _ in range(far)]
