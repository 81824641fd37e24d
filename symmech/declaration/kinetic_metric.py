"""Extract the metric of a kinetic energy given as a quadratic form in the velocities.

For ``T = 1/2 v^T g(q) v`` the metric is the Hessian ``g_ij = d^2 T / dv^i dv^j``.  Kinetic
energies of multibody systems are sums of squares of linear forms, ``T = sum_b c_b L_b^2``
with ``L_b = a_b . v``; expanding those squares costs O(n^3) terms per body and dominates
the derivation of large systems.  :func:`metric_from_kinetic_energy` instead walks the
expression tree and uses ``Hess(c L^2) = 2 c a a^T`` and ``Hess(c L1 L2) = c (a1 a2^T +
a2 a1^T)`` directly, falling back to expansion only for shapes it does not recognise.
Terms of each entry are then grouped by their coordinate-dependent factor, so an entry
reads ``(sum of parameter products) * (function of q)``.

The walk also decides whether T is a quadratic form at all: every velocity-dependent part
must be a product of exactly two linear forms (or a square), and no part may be free of
the velocities.

:func:`linear_form_row` reads the coefficients of a linear form (a constraint one-form
``mu_i(q) v^i``) by differentiation, and decides linearity and homogeneity by evaluation
at sample points, so its cost stays linear in the size of the input.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Callable, Mapping, Sequence
from fractions import Fraction

import sympy as sp

from symmech.algebra.canonical import add, mul
from symmech.algebra.walk import free_symbols
from symmech.algebra.zero import is_zero

__all__ = [
    "NotQuadraticError",
    "group_by_factor",
    "linear_coefficients",
    "linear_form_row",
    "metric_from_kinetic_energy",
]


class NotQuadraticError(ValueError):
    """The expression is not a homogeneous quadratic (or linear) form in the velocities."""

    def __init__(self, term: sp.Expr, reason: str):
        self.term = term
        super().__init__(reason)


def _has(expr: sp.Expr, vset: frozenset) -> bool:
    return not vset.isdisjoint(expr.free_symbols)


# A term is kept as (numeric coefficient, tuple of factors) and only turned into a sympy
# expression after grouping: building one sympy Mul per term is what makes the naive
# expansion slow for large systems.
_Term = tuple[sp.Expr, tuple[sp.Expr, ...]]


def _num(x: sp.Expr) -> Fraction | sp.Expr:
    # exact rationals as Python Fractions: sympy Number arithmetic dominates otherwise
    if x.is_Integer:
        return int(x)
    return Fraction(int(x.p), int(x.q)) if x.is_Rational else x


def _int(x: Fraction | int | sp.Expr) -> Fraction | int | sp.Expr:
    return int(x) if isinstance(x, Fraction) and x.denominator == 1 else x


def _split(expr: sp.Expr) -> _Term:
    if expr.is_Mul:
        num = [f for f in expr.args if f.is_Number]
        return _num(mul(*num)), tuple(f for f in expr.args if not f.is_Number)
    if expr.is_Number:
        return _num(expr), ()
    return 1, (expr,)


def linear_coefficients(expr: sp.Expr, index: dict[sp.Symbol, int]) -> dict[int, list[_Term]]:
    """Coefficient terms of a homogeneous linear form ``sum_j a_j v^j``: ``{j: [terms of a_j]}``.

    Each term is ``(number, factors)``; raises :class:`NotQuadraticError` when ``expr`` is
    not linear and homogeneous in the velocities.
    """
    vset = frozenset(index)
    if expr in index:
        return {index[expr]: [(1, ())]}
    if expr.is_Add:
        out: dict[int, list[_Term]] = defaultdict(list)
        for arg in expr.args:
            for j, terms in linear_coefficients(arg, index).items():
                out[j].extend(terms)
        return out
    if expr.is_Mul:
        dep = [f for f in expr.args if _has(f, vset)]
        if len(dep) != 1:
            raise NotQuadraticError(expr, "not linear in the velocities")
        num, factors = _split(mul(*[f for f in expr.args if not _has(f, vset)]))
        inner = linear_coefficients(dep[0], index)
        return {j: [(num * n2, factors + f2) for n2, f2 in terms] for j, terms in inner.items()}
    if _has(expr, vset):
        raise NotQuadraticError(expr, "not linear in the velocities")
    raise NotQuadraticError(expr, "has a part that does not depend on the velocities")


def _outer(
    out: dict[tuple[int, int], list[_Term]],
    coef: _Term,
    a: dict[int, list[_Term]],
    b: dict[int, list[_Term]],
) -> None:
    """out += coef * (a b^T + b a^T), upper triangle only (i <= j)."""
    cn, cf = coef
    single, double = _int(cn), _int(2 * cn)
    for i, ai in a.items():
        for j, bj in b.items():
            if i > j and a is b:
                continue  # symmetric: (j, i) is added with the doubled factor below
            key = (i, j) if i <= j else (j, i)
            c = double if (i == j or a is b) else single
            target = out[key]
            for sn, sf in ai:
                csn, csf = c * sn if sn != 1 else c, cf + sf
                for un, uf in bj:
                    target.append((csn * un if un != 1 else csn, csf + uf))


def _hessian(expr: sp.Expr, index: dict[sp.Symbol, int], out: dict, coef: _Term) -> None:
    vset = frozenset(index)
    if expr.is_Add:
        for arg in expr.args:
            _hessian(arg, index, out, coef)
        return
    if expr.is_Pow:
        if expr.exp == 2:
            a = linear_coefficients(expr.base, index)
            _outer(out, coef, a, a)
            return
        raise NotQuadraticError(expr, "not a quadratic form in the velocities")
    if expr.is_Mul:
        dep = [f for f in expr.args if _has(f, vset)]
        num, factors = _split(mul(*[f for f in expr.args if not _has(f, vset)]))
        c = (_int(coef[0] * num), coef[1] + factors)
        if len(dep) == 1:
            _hessian(dep[0], index, out, c)
            return
        if len(dep) == 2:
            a = linear_coefficients(dep[0], index)
            b = linear_coefficients(dep[1], index)
            _outer(out, c, a, b)
            return
        raise NotQuadraticError(expr, "not a quadratic form in the velocities")
    if _has(expr, vset):
        raise NotQuadraticError(expr, "not a quadratic form in the velocities")
    raise NotQuadraticError(expr, "has a part that does not depend on the velocities")


def group_by_factor(
    terms: Sequence[_Term], q: frozenset, depends: dict[sp.Expr, bool] | None = None
) -> sp.Expr:
    """Sum ``terms``, grouping them by their coordinate-dependent factors (``depends``:
    factor -> whether it reads ``q``, kept by the caller across the entries of a metric,
    which share their factors).

    ``m1 l1 l2 cos(q1) cos(q2) + m2 l1 l2 cos(q1) cos(q2)`` becomes
    ``l1 l2 (m1 + m2) cos(q1) cos(q2)``: fewer operations, same value.
    """
    groups: dict[tuple, list[tuple[sp.Expr, list[sp.Expr]]]] = defaultdict(list)
    if depends is None:
        depends = {}
    for num, factors in terms:
        on: list[sp.Expr] = []
        off: list[sp.Expr] = []
        for f in factors:
            hit = depends.get(f)
            if hit is None:
                hit = depends[f] = not q.isdisjoint(free_symbols(f))
            (on if hit else off).append(f)
        groups[tuple(sorted(on, key=hash))].append((num, off))
    return add(*[_common_factor_sum(items, dep) for dep, items in groups.items()])


def _multiset(factors: Sequence[sp.Expr]) -> dict[sp.Expr, int]:
    counts: dict[sp.Expr, int] = {}
    for f in factors:
        counts[f] = counts.get(f, 0) + 1
    return counts


def _common_factor_sum(items: list[tuple[sp.Expr, list[sp.Expr]]], dep: tuple = ()) -> sp.Expr:
    """Sum of ``num * prod(factors)`` with the factors common to every item pulled out.

    ``m1*l1*l2 + m2*l1*l2`` -> ``l1*l2*(m1 + m2)`` (a cheap, multiset form of factor_terms).
    """
    if len(items) == 1:
        num, factors = items[0]
        return _times(num, [*factors, *dep])
    common = _multiset(items[0][1])  # the multiset intersection of the items' factors
    for _, factors in items[1:]:
        other = _multiset(factors)
        common = {f: min(k, other[f]) for f, k in common.items() if f in other}
        if not common:
            break
    rest = []
    for num, factors in items:
        kept = factors
        if common:
            left, kept = dict(common), []
            for f in factors:
                k = left.get(f)
                if k:
                    left[f] = k - 1
                else:
                    kept.append(f)
        rest.append(_times(num, kept))
    return mul(*[f for f, k in common.items() for _ in range(k)], add(*rest), *dep)


def _times(num: Fraction | sp.Expr, factors: list[sp.Expr]) -> sp.Expr:
    if num == 1:
        return mul(*factors)
    exact = isinstance(num, Fraction | int)
    coef = sp.Rational(num.numerator, num.denominator) if exact else num
    return mul(coef, *factors)


def metric_from_kinetic_energy(
    T: sp.Expr, v: Sequence[sp.Symbol], q: Sequence[sp.Symbol]
) -> sp.Matrix:
    """g with ``T = 1/2 v^T g v`` (the Hessian of T in v); raises :class:`NotQuadraticError`.

    Slides 000, "Riemannian manifold": ``KineticEnergy = 1/2 <b q_dot | q_dot>``.
    """
    index = {s: i for i, s in enumerate(v)}
    out: dict[tuple[int, int], list[_Term]] = defaultdict(list)
    _hessian(sp.sympify(T, strict=True), index, out, (1, ()))
    n = len(v)
    qset = frozenset(q)
    G = sp.zeros(n, n)
    depends: dict[sp.Expr, bool] = {}
    for (i, j), terms in out.items():
        G[i, j] = G[j, i] = group_by_factor(terms, qset, depends)
    return G


def linear_form_row(
    e: sp.Expr,
    v: Sequence[sp.Symbol],
    points: Callable[[sp.Expr], Sequence[Mapping]],
) -> list[sp.Expr]:
    """The coefficients ``[mu_1, ..., mu_n]`` of ``e = mu_i(q) v^i``: ``mu_i = de/dv^i``.

    ``e`` must be linear and homogeneous in the velocities ``v``: every second derivative
    ``d^2 e / dv^i dv^j`` and the velocity-free part ``e(v = 0)`` vanish identically, and
    some coefficient does not.  "Vanishes identically" is decided exactly where sympy's
    automatic simplification already gives 0, else by
    :func:`~symmech.algebra.zero.is_zero` at ``points(expr)``, sample points giving
    values to every symbol of ``expr`` (``sympy.simplify`` is never called: a constraint
    of a few hundred operations can keep it busy for many minutes).  A coefficient written
    with velocities that cancel is returned without them.  Raises
    :class:`NotQuadraticError` saying what is wrong.
    """
    zero = dict.fromkeys(v, 0)
    row = [sp.diff(e, vj) for vj in v]
    nonlinear = []
    for j, r in enumerate(row):
        inside = [vk for vk in v if vk in r.free_symbols]
        if not inside:
            continue
        pts = points(r)
        if all(is_zero(sp.diff(r, vk), pts) is True for vk in inside):
            row[j] = r.xreplace(zero)  # written with velocities that cancel
        else:
            nonlinear.append(str(v[j]))
    if nonlinear:
        raise NotQuadraticError(
            e,
            f"is not linear in the velocities (nonlinear in {nonlinear}); constraints must be"
            " one-forms mu_i(q) q_dot^i",
        )
    pts = points(e)
    if all(is_zero(r, pts) is True for r in row):
        raise NotQuadraticError(
            e,
            f"does not involve any velocity {sorted(map(str, v))}; a holonomic constraint"
            " h(q) = 0 is given by its differential dh (h_dot = 0)",
        )
    offset = e.xreplace(zero)
    if is_zero(offset, pts) is not True:
        raise NotQuadraticError(
            e,
            f"has the velocity-free part {_short(offset)}; constraints must be linear"
            " (homogeneous) in the velocities",
        )
    return row


def _short(expr: object, limit: int = 60) -> str:
    s = str(expr)
    return s if len(s) <= limit else s[: limit - 3] + "..."
