"""Parameters declared without a sign, and the positive definiteness of the metric.

Users of ``sympy.physics.mechanics`` write ``m, l, g = sympy.symbols("m l g")``: real
parameters with no sign.  A metric ``diag(m, m l**2)`` is then positive definite only for
``m > 0``; symmech's sampled check (:func:`~symmech.declaration.checks.check_metric`), which
samples such a parameter with either sign, would refuse it.  :func:`check_metric_signs`
accepts it instead and records what run time must check (see its docstring); so it does
with a metric positive definite only for some values of parameters declared positive.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence

import numpy as np
import sympy as sp

from symmech.algebra.numeric import (
    EvaluationError,
    classify_symmetric,
    evaluate_matrix,
    real_values,
)
from symmech.algebra.sampling import atom_key
from symmech.algebra.walk import free_symbols_of, xreplace
from symmech.declaration.checks import Points, Problems, check_metric
from symmech.declaration.definiteness import _compass
from symmech.declaration.symbols import t as TIME

__all__ = ["check_metric_signs"]


def _definite(G: sp.Matrix, point: dict) -> bool | None:
    """Whether G is real and positive definite at ``point``; None where it has no value."""
    try:
        A, complex_ = real_values(G, point)
    except EvaluationError:
        return None
    return not complex_ and classify_symmetric(A)[0] == "positive definite"


def _min_eigenvalue_over(G: sp.Matrix, coordinate_points: Sequence[dict]):
    """The objective of the parameter search: minus the smallest eigenvalue of g scaled
    to unit diagonal (``D^-1/2 g D^-1/2``, free of units) over the sampled configurations,
    +inf where a parameter declared positive is not, or g has no real value."""

    def objective(theta: dict) -> float:
        if any(bool(p.is_positive) and float(v) <= 0 for p, v in theta.items()):
            return math.inf
        worst = math.inf
        for point in coordinate_points:
            try:
                A = evaluate_matrix(G, {**point, **theta}).real
            except EvaluationError:
                return math.inf
            d = np.diag(A)
            if not np.isfinite(A).all():
                return math.inf
            if (d <= 0).any():  # (a finite penalty, so that the search can leave it)
                worst = min(worst, float(d.min() / max(abs(d).max(), 1e-300)) - 1.0)
                continue
            B = A / np.sqrt(d)[:, None] / np.sqrt(d)[None, :]
            worst = min(worst, float(np.linalg.eigvalsh((B + B.T) / 2)[0]))
        return -worst

    return objective


def _definite_for_some_values(
    G: sp.Matrix, label: str, points: Points, q: Sequence[sp.Symbol], T: sp.Expr | None
) -> bool:
    """Whether some parameter values make ``G`` positive definite at every value of the
    coordinates (:func:`check_metric` with the parameters fixed): the sampled parameter
    values first, then those a compass search
    (:func:`~symmech.declaration.definiteness._compass`) finds from each of them by
    maximising the smallest scaled eigenvalue over the sampled configurations.  A hinge's
    inertia ``I_z`` next to ``m_A a^2`` (``[[m_A + m_C, a m_A cos q], [., I_z]]``) is
    positive definite for physical values only (``I_z >= m_A a^2``), not for every
    positive ``I_z``."""
    params = free_symbols_of(G) - set(q) - {TIME}
    pts = points.for_(G)
    configurations = [{k: v for k, v in p.items() if k not in params} for p in pts]
    thetas = [{k: v for k, v in p.items() if k in params} for p in pts]
    objective = _min_eigenvalue_over(G, configurations)
    for theta in thetas:
        if not theta:
            continue
        start = {k: float(v) for k, v in theta.items()}
        value, found = _compass(objective, start, list(theta))
        if value >= 0:
            continue
        exact = {k: sp.Rational(v).limit_denominator(10**6) for k, v in found.items()}
        probe = Problems()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # undecided for one value: still definite there
            check_metric(
                G.xreplace(exact),
                label,
                Points([*q, TIME]),
                probe,
                q,
                None if T is None else T.xreplace(exact),
            )
        if not probe.items:
            return True
    return False


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
    may take either sign, is not among them.

    A metric still not positive definite at every sampled point (its parameters declared
    positive, or taken so) is accepted, with the same run-time check and no parameter
    named, when some parameter values make it positive definite at every value of the
    coordinates (:func:`_definite_for_some_values`; an inertia about a hinge, whose
    physical values exceed the mass times the squared distance, is such a parameter).
    Returns None when the metric passed (or was refused) without assumptions.
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
    refused = not all("not positive definite" in m.message for m in first.items)
    if refused:
        for m in first.items:  # (recorded again: in the caller's field)
            problems.add(m.message)
        return None
    if not unsigned:
        if _definite_for_some_values(G, label, points, q, T):
            return ()
        for m in first.items:
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
        # judged again with the parameters positive: the messages name positive values
        if _definite_for_some_values(G_pos, label, pos_points, q, T_pos):
            return ()
        for m in second.items:
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
