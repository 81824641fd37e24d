"""Parameters declared without a sign, and the positive definiteness of the metric.

Users of ``sympy.physics.mechanics`` write ``m, l, g = sympy.symbols("m l g")``: real
parameters with no sign.  A metric ``diag(m, m l**2)`` is then positive definite only for
``m > 0``; symmech's sampled check (:func:`~symmech.declaration.checks.check_metric`), which
samples such a parameter with either sign, would refuse it.  :func:`check_metric_signs`
accepts it instead and records what run time must check (see its docstring).
"""

from __future__ import annotations

from collections.abc import Sequence

import sympy as sp

from symmech.algebra.numeric import EvaluationError, classify_symmetric, real_values
from symmech.algebra.sampling import atom_key
from symmech.algebra.walk import free_symbols_of, xreplace
from symmech.declaration.checks import Points, Problems, check_metric
from symmech.declaration.symbols import t as TIME

__all__ = ["check_metric_signs"]


def _definite(G: sp.Matrix, point: dict) -> bool | None:
    """Whether G is real and positive definite at ``point``; None where it has no value."""
    try:
        A, complex_ = real_values(G, point)
    except EvaluationError:
        return None
    return not complex_ and classify_symmetric(A)[0] == "positive definite"


def check_metric_signs(
    G: sp.Matrix,
    label: str,
    points: Points,
    problems: Problems,
    q: Sequence[sp.Symbol],
    params: Sequence[sp.Symbol],
    T: sp.Expr | None = None,
) -> tuple[sp.Symbol, ...] | None:
    """:func:`check_metric`, with parameters declared without a sign (``sp.symbols("m l")``,
    as ``sympy.physics.mechanics`` users write them) taken as real.

    When the metric is not positive definite at a point where such a parameter was sampled
    negative, it is checked again with them all positive; passing that, it is accepted.  It
    is then positive definite only for some parameter values, which generated code checks
    at run time (its Cholesky factorisation of g raises ``NumericalError``).  Returned are
    the parameters whose sign flip alone makes g indefinite at every positive sampled point
    where it was positive definite (masses, principal moments): generated code and the
    simulator require them positive, naming them.  A product of inertia or a length, which
    may take either sign, is not among them.  Returns None when the metric passed (or was
    refused) without assumptions.
    """
    first = Problems()
    check_metric(G, label, points, first, q, T)
    if not first.items:
        return None
    free = free_symbols_of(G)
    unsigned = [
        p
        for p in params
        if p in free and p.is_positive is None and p.is_negative is None and p.is_zero is None
    ]
    refused = not first.items or not all("not positive definite" in m.message for m in first.items)
    if refused or not unsigned:
        for m in first.items:  # (recorded again: in the caller's field)
            problems.add(m.message)
        return None
    proxy = {p: sp.Dummy(p.name, positive=True) for p in unsigned}
    memo: dict = {}
    G_pos = G.applyfunc(lambda e: xreplace(e, proxy, memo))
    T_pos = T.xreplace(proxy) if T is not None else None
    others = [s for s in params if s not in proxy]
    pos_points = Points([*q, *others, *proxy.values(), TIME])
    second = Problems()
    check_metric(G_pos, label, pos_points, second, q, T_pos)
    if second.items:
        for m in first.items:  # (recorded again: in the caller's field)
            problems.add(m.message)
        return None
    definite = [p for p in pos_points.for_(G_pos) if _definite(G_pos, p) is True]
    needed = []
    for p, d in proxy.items():
        # (lazily: the first point where the flip leaves g definite settles it)
        flipped = (_definite(G_pos, {**point, d: -point[d]}) for point in definite)
        if definite and all(f is False for f in flipped):
            needed.append(p)
    return tuple(sorted(needed, key=atom_key))
