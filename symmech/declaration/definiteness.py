"""Positive definiteness of a metric on the whole configuration space, not only at samples.

The declaration first judges the metric g(q) at a few sampled points
(:func:`symmech.declaration.checks.check_metric`): indefinite at one of them refuses it.
A metric indefinite on a narrow part of the domain passes that test (``diag(1, 1 +
101/100 sin x)`` is indefinite only for ``|x + pi/2| < 0.14``, ``diag(1, x**2 - 1/100)``
only for ``|x| < 0.1``).  :func:`definiteness` then decides, for the parameter values of
each sampled point, over every value of the coordinates:

1. **proven** positive semidefinite everywhere (singular points are allowed, as in
   ``diag(1, r**2)``; a metric singular everywhere was refused before), by

   * the kinetic energy: ``T`` a sum of nonnegative terms (``m/2 (x_dot + l cos q
     q_dot)**2 + ...``, :func:`~symmech.algebra.numeric.proven_sign` with the
     velocities real) makes g positive semidefinite at every q;
   * the kinetic energy with the parameters at their sampled values: a sum of squares with
     positive weights (``m1/2 (x_dot + l cos q q_dot)**2`` with m1 unsigned but 0.4 at
     the sample) proves g positive semidefinite for those values;
   * interval arithmetic (:mod:`mpmath.iv`, outward rounding) over the whole range of
     each coordinate (from its assumptions; ``sin`` and ``cos`` in [-1, 1], even powers
     nonnegative): for a diagonal metric each diagonal entry has a lower bound >= 0; for
     n <= 3 the leading principal minors ``D_1, ..., D_{n-1}`` have lower bounds > 0 and
     ``det g`` >= 0 (Sylvester's criterion, with the limit case det g = 0), each minor
     bounded as formed and, when that proves nothing, linearised (products of sin and
     cos written as sums of sin and cos of combined angles, so that ``cos q1 cos q2 +
     sin q1 sin q2`` is one term ``cos(q1 - q2)`` and the bound keeps its correlation:
     the 2-link pendulum on a cart imported from sympy.physics.mechanics); for any n, the
     pivots of an LDL^T factorisation in interval arithmetic have lower bounds > 0 (the
     last >= 0);
   * exact real roots (:func:`sympy.real_roots`) of a diagonal entry or leading minor that
     is a polynomial in one coordinate: it is nonnegative iff it is between and beyond its
     roots;

2. **refuted**: a point where g is indefinite, found first by the exact real roots of a
   diagonal entry or leading minor in one coordinate (a polynomial's, above, or those
   ``sympy.solveset`` gives of any other, within the budgets
   :data:`symmech.algebra.budget.ROOTS_OPS` and ``ROOTS_SECONDS``: ``1 - exp(x - 1000)``
   has the root x = 1000, far beyond any sample, and is negative past it), then by a
   compass search from each sampled point, minimising a diagonal entry or the smallest
   eigenvalue of g scaled to unit diagonal (``D^-1/2 g D^-1/2``, free of units); the
   point is confirmed by :func:`~symmech.algebra.numeric.classify_symmetric` at a
   rational point near it;

3. **undecided** otherwise: the searches found g positive definite everywhere they went,
   but nothing proves it elsewhere.  The caller warns (:class:`~symmech.UndecidedWarning`).

Everything is evaluated in float64 tree walks (:mod:`symmech.algebra.numeric`) and
interval arithmetic; nothing calls ``sympy.simplify``.  The search is bounded by
:data:`SEARCH_EVALUATIONS` evaluations per sampled point and :data:`SEARCH_WORK` tree nodes
evaluated per metric.
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import mpmath
import numpy as np
import sympy as sp
from sympy.core.function import AppliedUndef

from symmech.algebra import budget as limits
from symmech.algebra.numeric import (
    EvaluationError,
    classify_symmetric,
    evaluate,
    evaluate_matrix,
    proven_sign,
    real_values,
)
from symmech.algebra.walk import free_symbols_of

__all__ = ["SEARCH_EVALUATIONS", "Verdict", "definiteness", "lower_bound"]

#: Evaluations of the objective allowed to the compass search from one sampled point.
SEARCH_EVALUATIONS = 120
#: Work of all the searches of one metric, in tree nodes evaluated: a large metric gets
#: fewer evaluations (``SEARCH_WORK // nodes`` in all), so the search costs at most about
#: a second whatever its size.
SEARCH_WORK = 100_000
#: Leading principal minors are formed symbolically (Berkowitz, no simplification) up to
#: this size of metric, and when the metric has at most MINORS_MAX_NODES distinct nodes.
MINORS_MAX_N = 3
MINORS_MAX_NODES = 120
#: Polynomials up to this degree have their real roots isolated exactly.
ROOTS_MAX_DEGREE = 12

_IV = mpmath.iv
_INF = mpmath.inf


@dataclass(frozen=True)
class Verdict:
    """``status``: "proven", "refuted" or "undecided"; ``detail``: how (for messages);
    ``point``: the sampled point with the coordinates where g is indefinite (refuted);
    ``found``: how that point was found (for messages)."""

    status: Literal["proven", "refuted", "undecided"]
    detail: str
    point: Mapping = field(default_factory=dict)
    found: str = "a point found by searching from the sampled points"


# -- interval arithmetic -------------------------------------------------------------------


def _assumed_range(atom: sp.Basic) -> mpmath.ctx_iv.ivmpf:
    if atom.is_positive:
        return _IV.mpf([0, _INF])
    if atom.is_nonnegative:
        return _IV.mpf([0, _INF])
    if atom.is_negative or atom.is_nonpositive:
        return _IV.mpf([-_INF, 0])
    return _IV.mpf([-_INF, _INF])


def _lo(x: mpmath.ctx_iv.ivmpf) -> mpmath.mpf:
    return mpmath.mpf(x._mpi_[0])


def _hi(x: mpmath.ctx_iv.ivmpf) -> mpmath.mpf:
    return mpmath.mpf(x._mpi_[1])


def _interval(e: sp.Basic, fixed: Mapping, memo: dict) -> mpmath.ctx_iv.ivmpf | None:
    """An enclosure of ``e`` over the ranges (atoms in ``fixed`` are points); None when
    unknown (an unbounded or complex part, a function without an interval rule)."""
    if e in memo:
        return memo[e]
    out = None
    if e in fixed:
        v = sp.Rational(fixed[e]) if not isinstance(fixed[e], sp.Basic) else fixed[e]
        out = _interval(v, {}, {}) if v.is_number else None
    elif e.is_Rational:
        out = _IV.mpf(int(e.p)) / int(e.q)
    elif e.is_Float:
        out = _IV.mpf(mpmath.mpf(e._mpf_))
    elif e is sp.pi:
        out = _IV.pi
    elif e is sp.E:
        out = _IV.e
    elif isinstance(e, sp.Symbol | AppliedUndef | sp.Derivative):
        out = _assumed_range(e)
    elif e.is_Add or e.is_Mul:
        parts = [_interval(a, fixed, memo) for a in e.args]
        known = [p for p in parts if p is not None]
        if len(known) == len(parts):
            out = known[0]
            for p in known[1:]:
                out = out + p if e.is_Add else out * p
    elif e.is_Pow:
        out = _power(e, fixed, memo)
    elif e.args:
        out = _function(e, fixed, memo)
    memo[e] = out
    return out


def _power(e: sp.Pow, fixed: Mapping, memo: dict) -> mpmath.ctx_iv.ivmpf | None:
    base = _interval(e.base, fixed, memo)
    if base is None:
        return None
    if e.exp.is_Integer:
        k = int(e.exp)
        if k < 0 and _lo(base) <= 0 <= _hi(base):
            if k % 2:
                return None  # 1/0 inside the range, of either sign
            # an even power is positive where it is defined
            reach = max(abs(_lo(base)), abs(_hi(base)))
            return _IV.mpf([0, _INF]) if reach == _INF else _IV.mpf([0, _INF]) + reach**k
        return base**k
    if e.exp.is_Rational and _lo(base) >= 0 and (e.exp > 0 or _lo(base) > 0):
        return base ** (_IV.mpf(int(e.exp.p)) / int(e.exp.q))
    return None


def _function(e: sp.Basic, fixed: Mapping, memo: dict) -> mpmath.ctx_iv.ivmpf | None:
    if isinstance(e, sp.sin | sp.cos | sp.tanh | sp.atan):
        arg = _interval(e.args[0], fixed, memo)
        if isinstance(e, sp.tanh):
            return _IV.mpf([-1, 1])
        if isinstance(e, sp.atan):
            return _IV.mpf([-1, 1]) * _IV.pi / 2
        if arg is None or _hi(arg) - _lo(arg) > 7:
            return _IV.mpf([-1, 1])
        return _IV.sin(arg) if isinstance(e, sp.sin) else _IV.cos(arg)
    arg = _interval(e.args[0], fixed, memo) if len(e.args) == 1 else None
    if arg is None:
        return None
    try:
        if isinstance(e, sp.exp):
            return _IV.exp(arg)
        if isinstance(e, sp.log) and _lo(arg) > 0:
            return _IV.log(arg)
        if isinstance(e, sp.cosh):
            return (_IV.exp(arg) + _IV.exp(-arg)) / 2
        if isinstance(e, sp.sinh) and _hi(arg) < _INF and _lo(arg) > -_INF:
            return (_IV.exp(arg) - _IV.exp(-arg)) / 2
    except (ArithmeticError, ValueError):
        return None
    return None


def lower_bound(expr: sp.Expr, fixed: Mapping) -> mpmath.mpf | None:
    """A rigorous lower bound of ``expr`` over the range of its free atoms (from their
    assumptions; the atoms in ``fixed`` at those values), or None when none is found.

    >>> import sympy as sp
    >>> x = sp.Symbol("x", real=True)
    >>> lower_bound(2 + sp.sin(x), {}), lower_bound(x**2 - sp.Rational(1, 100), {})
    (mpf('1.0'), mpf('-0.01'))
    """
    try:
        with mpmath.workprec(53):
            bound = _interval(sp.sympify(expr, strict=True), fixed, {})
    except (ArithmeticError, ValueError, TypeError, RecursionError):
        return None
    if bound is None:
        return None
    lo = _lo(bound)
    return None if mpmath.isnan(lo) else lo


# -- exact roots -----------------------------------------------------------------------------


def _exact_sign(entry: sp.Expr, coordinate: sp.Symbol) -> tuple[str, sp.Rational | None] | None:
    """("nonneg", None) or ("negative", where) for a polynomial in one real coordinate with
    rational coefficients; None when ``entry`` is not one (or too large)."""
    try:
        poly = sp.Poly(entry, coordinate)
    except sp.PolynomialError:
        return None
    exact = poly.domain.is_QQ or poly.domain.is_ZZ
    if not exact or not 1 <= poly.degree() <= ROOTS_MAX_DEGREE:
        return None
    try:
        roots = sorted({sp.Rational(str(r.evalf(30))) for r in sp.real_roots(poly)})
    except (NotImplementedError, sp.PolynomialError):  # roots sympy cannot isolate:
        return None  # the sign stays undecided here, and the caller tries its other routes
    lo = 0 if coordinate.is_nonnegative else -math.inf
    roots = [r for r in roots if r >= lo]
    if roots:
        tests = [roots[0] - 1, *((a + b) / 2 for a, b in itertools.pairwise(roots)), roots[-1] + 1]
    else:
        tests = [sp.Integer(1)]
    for t in tests:
        if t >= lo and poly.eval(t) < 0:
            return "negative", t
    return "nonneg", None


def _one_generator(entry: sp.Expr, coordinate: sp.Symbol) -> bool:
    """Whether ``entry`` is a polynomial in a single function of ``coordinate``
    (``exp(x - 1000)``, ``cosh(x/1000)``, ``sin(x)``, ``sqrt(x**2 + 1)``): what solveset
    inverts directly.  Several (``sin(x)``, ``cos(2 x)``, ``x exp(x)``) can cost it
    minutes, in a loop no deadline reaches (its own time limit is a signal, main thread
    only), so they are left to the search."""
    try:
        gens = sp.Poly(entry).gens
    except (sp.PolynomialError, sp.GeneratorsNeeded):
        return False
    return len([g for g in gens if g.has(coordinate)]) == 1


def _solved_roots(entry: sp.Expr, coordinate: sp.Symbol) -> list[sp.Expr] | None:
    """The real roots of ``entry`` (a function of one real coordinate, not a polynomial)
    that ``sympy.solveset`` finds exactly, sorted; a periodic family contributes its
    members for n = -1, 0, 1.  None when it finds none it can list, or over the budgets
    ROOTS_OPS / ROOTS_SECONDS of :mod:`symmech.algebra.budget`."""
    if sp.count_ops(entry) > limits.ROOTS_OPS or not _one_generator(entry, coordinate):
        return None
    try:
        with limits.time_limit(
            "exact roots of a metric entry", limits.ROOTS_SECONDS, "ROOTS_SECONDS"
        ):
            found = sp.solveset(entry, coordinate, sp.S.Reals)
    except limits.BudgetExceeded as exc:
        if exc.budget != "ROOTS_SECONDS":
            raise  # the deadline of a stage around this one
        return None
    except (NotImplementedError, ValueError, TypeError, RecursionError):
        return None
    parts = found.args if isinstance(found, sp.Union) else (found,)
    roots: list[sp.Expr] = []
    for part in parts:
        if isinstance(part, sp.FiniteSet):
            roots.extend(part.args)
        elif isinstance(part, sp.ImageSet) and part.base_sets == (sp.S.Integers,):
            roots.extend(part.lamda(k) for k in (-1, 0, 1))
        elif part is not sp.S.EmptySet:
            return None  # a ConditionSet, an interval: nothing to list
    if not roots or not all(r.is_number and r.is_real for r in roots):
        return None
    return sorted(set(roots), key=lambda r: sp.N(r, 30))


def _negative_past_roots(
    entry: sp.Expr, coordinate: sp.Symbol
) -> tuple[sp.Rational, list[sp.Expr]] | None:
    """``(t, roots)``: a point t where ``entry`` (one real coordinate, not a polynomial)
    is negative, between or beyond the exact real roots listed by :func:`_solved_roots`;
    None when none is found."""
    roots = _solved_roots(entry, coordinate)
    if roots is None:
        return None
    values = [sp.Rational(str(sp.N(r, 30))) for r in roots]
    lo = 0 if coordinate.is_nonnegative else -math.inf
    tests = [values[0] - 1, *((a + b) / 2 for a, b in itertools.pairwise(values)), values[-1] + 1]
    for t in tests:
        # the shortest decimal where it is negative: an integer, then 3, 6, 12 places
        for short in [sp.Rational(round(t * 10**d), 10**d) for d in (0, 3, 6, 12)] + [t]:
            if short < lo:
                continue
            value = sp.N(entry.xreplace({coordinate: short}), 30)
            if value.is_real and value.is_negative:
                return short, roots
    return None


# -- search ----------------------------------------------------------------------------------


def _compass(
    objective: Callable[[dict], float],
    start: dict,
    variables: Sequence[sp.Symbol],
    budget: int = SEARCH_EVALUATIONS,
) -> tuple[float, dict]:
    """Minimise ``objective`` from ``start`` by compass search (step halving), stopping at
    a negative value or after ``budget`` evaluations."""
    x = dict(start)
    f = objective(x)
    step, evaluations = 0.5, 1
    while evaluations < budget and step > 1e-6 and f >= 0:
        moved = False
        for v in variables:
            for sign in (1.0, -1.0):
                y = {**x, v: x[v] + sign * step}
                fy = objective(y)
                evaluations += 1
                if fy < f:
                    x, f, moved = y, fy, True
                    break
            if f < 0 or evaluations >= budget:
                break
        step = step * 2 if moved and step < 4 else step / 2 if not moved else step
    return f, x


def _float_point(point: Mapping) -> dict:
    out = {}
    for k, v in point.items():
        try:
            out[k] = float(v)
        except TypeError:
            out[k] = complex(v).real
    return out


def _rational_point(point: Mapping, coordinates: Sequence[sp.Symbol], digits: int) -> dict:
    scale = 10**digits
    return {
        **point,
        **{c: sp.Rational(round(float(point[c]) * scale), scale) for c in coordinates},
    }


def _confirm(
    G: sp.MatrixBase, found: Mapping, sample: Mapping, coordinates: Sequence[sp.Symbol]
) -> tuple[dict, str] | None:
    """The indefiniteness found at ``found`` (floats), confirmed at a rational point."""
    for digits in (4, 8, 16):
        point = _rational_point({**sample, **found}, coordinates, digits)
        try:
            A, complex_ = real_values(G, point)
        except EvaluationError:
            continue
        if complex_:
            continue
        verdict, evidence = classify_symmetric(A)
        if verdict == "indefinite":
            return point, evidence
    return None


def _scaled_min_eigenvalue(G: sp.MatrixBase) -> Callable[[dict], float]:
    def objective(point: dict) -> float:
        try:
            A = evaluate_matrix(G, point).real
        except EvaluationError:
            return math.inf
        d = np.diag(A)
        if (d <= 0).any():
            return float(d.min() / max(abs(d).max(), 1e-300)) - 1.0
        s = np.sqrt(d)
        with np.errstate(all="ignore"):
            B = A / s[:, None] / s[None, :]
        if not np.isfinite(B).all():
            return math.inf
        return float(np.linalg.eigvalsh((B + B.T) / 2)[0]) + 1e-12

    return objective


def _entry(e: sp.Expr) -> Callable[[dict], float]:
    def objective(point: dict) -> float:
        try:
            value = evaluate(e, point)
        except EvaluationError:
            return math.inf
        return value.real if abs(value.imag) <= 1e-12 * max(abs(value), 1e-300) else math.inf

    return objective


def definiteness(
    G: sp.MatrixBase,
    coordinates: Sequence[sp.Symbol],
    points: Sequence[Mapping],
    *,
    kinetic_energy: sp.Expr | None = None,
) -> Verdict:
    """Decide whether the metric ``G`` is positive semidefinite at every value of the
    ``coordinates``, for the parameter values of each of the sampled ``points`` (see the
    module docstring).  ``G`` must already have passed the sampled check."""
    if kinetic_energy is not None and proven_sign(kinetic_energy) in ("pos", "nonneg"):
        return Verdict("proven", "the kinetic energy is a sum of nonnegative terms")
    if (
        kinetic_energy is not None
        and points
        and all(
            proven_sign(_at_parameters(kinetic_energy, sample, coordinates)) in ("pos", "nonneg")
            for sample in points
        )
    ):
        return Verdict(
            "proven",
            "the kinetic energy is a sum of nonnegative terms at the sampled parameter values",
        )
    n = G.rows
    free = free_symbols_of(G)
    q = [c for c in coordinates if c in free]
    if not q:
        return Verdict("proven", "the metric does not depend on the coordinates")
    diagonal = all(G[i, j] == 0 for i in range(n) for j in range(n) if i != j)
    nodes = _nodes(G)
    budget = max(10, min(SEARCH_EVALUATIONS, SEARCH_WORK // (nodes * max(1, len(points)))))
    minors: list[sp.Expr] = []
    undecided: list[str] = []
    for sample in points:
        fixed = {k: v for k, v in sample.items() if k not in q}
        if diagonal:
            verdict = _diagonal(G, q, sample, fixed, undecided, budget)
        else:
            if _interval_cholesky(G, fixed):
                continue
            if not minors and n <= MINORS_MAX_N and nodes <= MINORS_MAX_NODES:
                minors = [G[:k, :k].det(method="berkowitz") for k in range(1, n + 1)]
            verdict = _full(G, q, minors, sample, fixed, undecided, budget)
        if verdict is not None:
            return verdict
    if undecided:
        return Verdict("undecided", undecided[0])
    return Verdict("proven", "by interval arithmetic over the coordinates")


def _diagonal(
    G: sp.MatrixBase,
    q: Sequence[sp.Symbol],
    sample: Mapping,
    fixed: Mapping,
    undecided: list,
    budget: int,
) -> Verdict | None:
    for i in range(G.rows):
        e = G[i, i]
        if not (e.free_symbols & set(q)) or proven_sign(e) in ("pos", "nonneg"):
            continue
        bound = lower_bound(e, fixed)
        if bound is not None and bound >= 0:
            continue
        at_sample = e.xreplace({k: v for k, v in fixed.items()})
        own = [c for c in q if c in at_sample.free_symbols]
        if len(own) == 1 and not (at_sample.free_symbols - set(own)):
            exact = _exact_sign(at_sample, own[0])
            if exact is not None and exact[0] == "nonneg":
                continue
            if exact is not None:
                point = {**sample, own[0]: exact[1]}
                try:
                    A, _ = real_values(G, point)
                except EvaluationError:  # another entry undefined there: the entry says it
                    return Verdict("refuted", f"diagonal entry [{i},{i}] < 0", point)
                return Verdict("refuted", classify_symmetric(A)[1], point)
            past = _negative_past_roots(at_sample, own[0])
            if past is not None:
                return _refuted_past_roots(
                    G, f"diagonal entry [{i},{i}] = {_short(e)}", own[0], past, sample
                )
        elif len(own) > 1 and not (at_sample.free_symbols - set(own)):
            for c, part in _slices(at_sample, own, sample):
                past = _past(part, c)
                if past is not None:
                    what = f"diagonal entry [{i},{i}] = {_short(e)}"
                    return _refuted_past_roots(G, what, c, past, sample)
        mine = [c for c in q if c in e.free_symbols]
        value, where = _compass(_entry(e), _float_point(sample), mine, budget)
        if value < 0:
            confirmed = _confirm(G, where, sample, q)
            if confirmed is not None:
                return Verdict("refuted", confirmed[1], confirmed[0])
        undecided.append(
            f"diagonal entry [{i},{i}] = {_short(e)} is not proven nonnegative (its interval"
            " bound is not), and no point where it is negative was found"
        )
    return None


def _full(
    G: sp.MatrixBase,
    q: Sequence[sp.Symbol],
    minors: Sequence[sp.Expr],
    sample: Mapping,
    fixed: Mapping,
    undecided: list,
    budget: int,
) -> Verdict | None:
    n = G.rows
    if minors and all(
        _minor_sign(m, fixed, q) in (("pos", "nonneg") if k == n - 1 else ("pos",))
        for k, m in enumerate(minors)
    ):
        return None
    for k, minor in enumerate(minors):
        at_sample = minor.xreplace(dict(fixed))
        own = [c for c in q if c in at_sample.free_symbols]
        if not own or at_sample.free_symbols - set(own):
            continue
        for c, part in _slices(at_sample, own, sample):
            past = _past(part, c)
            if past is not None:
                label = f"the leading minor D_{k + 1} = {_short(minor)}"
                return _refuted_past_roots(G, label, c, past, sample)
    value, where = _compass(_scaled_min_eigenvalue(G), _float_point(sample), q, budget)
    if value < 0:
        confirmed = _confirm(G, where, sample, q)
        if confirmed is not None:
            return Verdict("refuted", confirmed[1], confirmed[0])
    undecided.append(
        "not proven positive definite for every value of the coordinates (interval bounds"
        f" of{' its leading minors and' if n <= MINORS_MAX_N else ''} its Cholesky pivots do"
        " not prove it), and a local search from the sampled points found no point where it"
        " is indefinite"
    )
    return None


def _slices(
    e: sp.Expr, own: Sequence[sp.Symbol], sample: Mapping
) -> Iterator[tuple[sp.Symbol, sp.Expr]]:
    """``e`` as a function of each of its coordinates ``own`` in turn, the others at their
    sampled values (a line through the sample along that coordinate)."""
    for c in own:
        others = {d: sp.Rational(sample[d]) for d in own if d != c and d in sample}
        if len(others) == len(own) - 1:
            yield c, e.xreplace(others)


def _past(part: sp.Expr, c: sp.Symbol) -> tuple[sp.Rational, list[sp.Expr]] | None:
    """A point where ``part`` (a function of the coordinate c alone) is negative, from
    its exact real roots (a polynomial's, or those solveset finds), with the roots; None
    when none is found."""
    exact = _exact_sign(part, c)
    if exact is None:
        return _negative_past_roots(part, c)
    return (exact[1], []) if exact[0] == "negative" else None


def _refuted_past_roots(
    G: sp.MatrixBase,
    what: str,
    coordinate: sp.Symbol,
    past: tuple[sp.Rational, list[sp.Expr]],
    sample: Mapping,
) -> Verdict:
    """The refutation at the point past the exact roots of ``what`` (an entry or a
    leading minor negative there: g is not positive semidefinite)."""
    t, roots = past
    point = {**sample, coordinate: t}
    said = ", ".join(f"{coordinate} = {_short(r)}" for r in roots)
    detail = f"{what} < 0 there"
    if roots:
        plural = "s" if len(roots) > 1 else ""
        detail = f"{what} has the exact real root{plural} {said} and is < 0 past it"
    try:
        A, _ = real_values(G, point)
        detail = f"{classify_symmetric(A)[1]}: {detail}"
    except EvaluationError:  # another entry undefined there: the entry or minor says it
        pass
    found = "a point found from the exact real roots" if roots else "a point found exactly"
    return Verdict("refuted", detail, point, found)


def _interval_cholesky(G: sp.MatrixBase, fixed: Mapping) -> bool:
    """Whether the LDL^T factorisation of ``G`` in interval arithmetic (entries enclosed
    over the coordinates' ranges, :func:`lower_bound`'s rules) has pivots with lower bounds
    > 0 (the last >= 0): then every matrix with entries in those enclosures, g(q) among
    them, is positive (semi)definite.  The entries are taken as independent, so the test
    is sufficient, not necessary."""
    n = G.rows
    try:
        with mpmath.workprec(53):
            memo: dict = {}
            A: list[list[Any]] = [
                [_interval(G[i, j], fixed, memo) for j in range(n)] for i in range(n)
            ]
            if any(a is None for row in A for a in row):
                return False
            # g is symmetric (checked before): g_ij and g_ji enclose the same values
            for i in range(n):
                for j in range(i + 1, n):
                    lo = max(_lo(A[i][j]), _lo(A[j][i]))
                    hi = min(_hi(A[i][j]), _hi(A[j][i]))
                    if lo > hi:
                        return False
                    A[i][j] = A[j][i] = _IV.mpf([lo, hi])
            for k in range(n):
                pivot = A[k][k]
                if not (_lo(pivot) > 0 or (k == n - 1 and _lo(pivot) >= 0)):
                    return False
                for i in range(k + 1, n):
                    for j in range(i, n):
                        product = A[i][k] ** 2 if i == j else A[i][k] * A[k][j]
                        A[i][j] = A[i][j] - product / pivot
                        A[j][i] = A[i][j]
            return True
    except (ArithmeticError, ValueError, TypeError, RecursionError):
        return False


def _at_parameters(T: sp.Expr, sample: Mapping, coordinates: Sequence[sp.Symbol]) -> sp.Expr:
    """``T`` with every sampled value that is not a coordinate's put in (the parameters):
    its weights become numbers whose sign :func:`proven_sign` reads."""
    values = {k: v for k, v in sample.items() if k not in set(coordinates)}
    try:
        return T.xreplace(
            {k: sp.Rational(v) if not isinstance(v, sp.Basic) else v for k, v in values.items()}
        )
    except (TypeError, ValueError):
        return T


@functools.lru_cache(maxsize=64)
def _linearised(minor: sp.Expr) -> sp.Expr | None:
    """``minor`` with products of sin and cos written as sums of sin and cos of combined
    angles (``sympy.simplify.fu.TR8``, then expanded), or None (no sin or cos, or over
    the budget LINEARIZE_OPS)."""
    if not minor.has(sp.sin, sp.cos) or not limits.affordable(minor, limits.LINEARIZE_OPS):
        return None
    from sympy.simplify.fu import TR8

    try:
        return sp.expand(TR8(sp.expand(minor)))
    except (TypeError, ValueError, RecursionError):  # pragma: no cover - no verdict
        return None


def _minor_sign(minor: sp.Expr, fixed: Mapping, q: Sequence[sp.Symbol]) -> str | None:
    """ "pos" or "nonneg" when proven over the coordinates (interval bound, of the minor
    or of its linearised form, or the exact roots of a polynomial in one coordinate), for
    the parameters at ``fixed``."""
    bound = lower_bound(minor, fixed)
    if bound is None or bound < 0:
        linear = _linearised(minor)
        bound = lower_bound(linear, fixed) if linear is not None else None
    if bound is not None and bound >= 0:
        return "pos" if bound > 0 else "nonneg"
    at_sample = minor.xreplace(dict(fixed))
    own = [c for c in q if c in at_sample.free_symbols]
    if len(own) != 1 or at_sample.free_symbols - set(own):
        return None
    exact = _exact_sign(at_sample, own[0])
    if exact is None or exact[0] != "nonneg":
        return None
    # nonnegative; positive unless it has a real root
    try:
        roots = sp.Poly(at_sample, own[0]).count_roots()
    except sp.PolynomialError:
        return "nonneg"
    return "pos" if roots == 0 else "nonneg"


def _nodes(G: sp.MatrixBase) -> int:
    """The number of distinct subtrees of the entries of ``G`` (what one evaluation walks)."""
    seen: set[sp.Basic] = set()
    stack = list(G)
    while stack:
        e = stack.pop()
        if e not in seen:
            seen.add(e)
            stack.extend(e.args)
    return max(1, len(seen))


def _short(expr: object, limit: int = 50) -> str:
    s = str(expr)
    return s if len(s) <= limit else s[: limit - 3] + "..."
