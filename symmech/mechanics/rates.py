"""Partial velocities and accelerations of a mechanics model's vectors, formed fast.

The import needs, for each body, the partial velocities ``d v / d u^r`` of its velocities
(the metric, the loads' generalized forces, Kane's inertia forces) and their time
derivatives with ``u_dot = 0`` (Kane's inertia forces).  ``sympy.physics.vector`` forms
both through sympy's ``diff``, which builds ``Derivative`` objects and dispatches matrix
derivatives; here the same expressions are formed by walking each measure number once,
sums and products built as sympy builds them (:mod:`symmech.algebra.canonical`):
:func:`speed_partials` by :class:`~symmech.geometry.derivatives.Derivative` along the
speeds made plain symbols, :class:`TimeDerivative` by the chain rule with the rates of
the coordinates given.  The results are the expressions sympy's route gives (the tests
of the import compare them on every model of its table).
"""

from __future__ import annotations

from typing import Any

import sympy as sp
from sympy.core.function import AppliedUndef
from sympy.physics.vector.frame import CoordinateSym
from sympy.polys.rings import ring

from symmech.algebra.canonical import add, mul
from symmech.geometry.derivatives import Derivative

__all__ = [
    "TimeDerivative",
    "dyadic_dot",
    "expanded_dots",
    "speed_partials",
    "time_derivative",
    "vector_cross",
    "vector_dot",
]


def speed_partials(vec: Any, speeds: dict[sp.Expr, sp.Dummy], D: Derivative) -> list[Any]:
    """``[vec.diff(w, frame, var_in_dcm=False) for w in speeds]``: each frame's measure
    numbers differentiated entry by entry (what sympy's ``Vector.diff`` does with
    ``var_in_dcm=False``), the speeds first replaced by the plain symbols ``speeds[w]``
    that ``D`` differentiates along (in the same order); a partial velocity that still
    holds a speed (a velocity not linear in them) gets the speed back."""
    back = {d: w for w, d in speeds.items()}
    flat = vec.xreplace(speeds)
    vector = type(vec)
    parts = []
    for r in range(len(speeds)):
        measures = [(m.applyfunc(lambda e, r=r: D.partial(e, r)), f) for m, f in flat.args]
        if any(D.free_symbols(e) & back.keys() for m, _ in measures for e in m):
            measures = [(m.xreplace(back), f) for m, f in measures]
        parts.append(vector(measures))
    return parts


class _Unsupported(Exception):
    """An expression that depends on time other than through the given coordinates and
    speeds (time itself, another function of time, a derivative, a frame's coordinate
    symbol): its derivative is left to sympy."""


class TimeDerivative:
    """``d e / dt`` with ``u_dot = 0`` and ``q_dot`` replaced by ``rates[q]``: what
    ``sympy.diff(e, t)`` followed by ``xreplace`` of ``u_dot -> 0`` and ``q_dot ->
    rates`` gives, formed as :class:`~symmech.geometry.derivatives.Derivative` forms a
    partial derivative (the product and chain rules as sympy applies them, each subtree
    once).  Raises :class:`_Unsupported` (caught by :func:`time_derivative`) for an
    expression with another dependence on time."""

    def __init__(self, rates: dict[sp.Expr, sp.Expr], speeds: set[sp.Expr], t: sp.Symbol):
        self.rates, self.speeds, self.t = rates, speeds, t
        self._memo: dict[sp.Basic, sp.Expr] = {}
        self._moves: dict[sp.Basic, bool] = {}
        self._outer: dict[sp.Basic, sp.Expr] = {}

    def moves(self, e: sp.Basic) -> bool:
        """Whether ``e`` holds a coordinate (its derivative is not zero)."""
        hit = self._moves.get(e)
        if hit is None:
            if e in self.rates:
                hit = True
            elif e in self.speeds:
                hit = False
            elif e == self.t or isinstance(e, (AppliedUndef, sp.Derivative, CoordinateSym)):
                raise _Unsupported(e)
            else:
                hit = any(self.moves(a) for a in e.args)
            self._moves[e] = hit
        return hit

    def __call__(self, e: sp.Expr) -> sp.Expr:
        if not self.moves(e):
            return sp.S.Zero
        hit = self._memo.get(e)
        if hit is None:
            hit = self._memo[e] = self._derive(e)
        return hit

    def _derive(self, e: sp.Expr) -> sp.Expr:
        if e in self.rates:
            return self.rates[e]
        if e.is_Add:
            return add(*[self(a) for a in e.args if self.moves(a)])
        if e.is_Mul:
            args = e.args
            terms = [
                mul(*args[:k], self(f), *args[k + 1 :]) for k, f in enumerate(args) if self.moves(f)
            ]
            return add(*terms)
        if e.is_Pow and not self.moves(e.exp):
            return _times(_times(e.exp, e.base ** (e.exp - 1)), self(e.base))
        if isinstance(e, sp.Function) and len(e.args) == 1:
            outer = self._outer.get(e)
            if outer is None:
                outer = self._outer[e] = e.fdiff(1)
            return _times(outer, self(e.args[0]))
        raise _Unsupported(e)


def _times(x: sp.Expr, y: sp.Expr) -> sp.Expr:
    """``x * y`` as the operator computes it."""
    return x * y if x.is_Number and y.is_Number else mul(x, y)


def time_derivative(vec: Any, frame: Any, d: TimeDerivative) -> Any:
    """``vec.dt(frame)`` with ``u_dot = 0`` and ``q_dot`` replaced by ``d``'s rates, as
    sympy's ``time_derivative`` forms it: each frame's measure numbers differentiated,
    plus ``w x v`` for a frame rotating in ``frame`` (its angular velocity as the model
    set it: the caller substitutes the rates there).  A vector ``d`` cannot differentiate
    (another dependence on time) is left to sympy, then substituted alike."""
    vector = type(vec)
    try:
        out = []
        for m, f in vec.args:
            out.append((m.applyfunc(d), f))
            if f != frame:
                out += vector_cross(f.ang_vel_in(frame), vector([(m, f)])).args
        return vector(out)
    except _Unsupported:
        t = d.t
        still = {w.diff(t): 0 for w in d.speeds}
        return vec.dt(frame).xreplace(still).xreplace({q.diff(t): r for q, r in d.rates.items()})


def vector_dot(a: Any, b: Any) -> sp.Expr:
    """``a & b`` as sympy's ``Vector.dot`` sums it: for each pair of frame components,
    ``(b^T D) a`` with ``D = b_frame.dcm(a_frame)``, each matrix product summed as sympy's
    sparse product sums it (``Add`` over the non-zero products of an entry), without its
    conversion to and from a domain matrix and its checks of every entry for
    infinities (a number's ``0 * x`` test on every term, which asks each big
    expression whether it is finite)."""
    out = sp.S.Zero
    for ca, fa in a.args:
        for cb, fb in b.args:
            D = fb.dcm(fa)
            row = {}
            for j in range(3):
                terms = [cb[k] * D[k, j] for k in range(3) if cb[k] != 0 and D[k, j] != 0]
                if terms:
                    entry = sp.Add(*terms)
                    if entry:
                        row[j] = entry
            terms = [row[j] * ca[j] for j in row if ca[j] != 0]
            if terms:
                out += sp.Add(*terms)
    return out


def expanded_dots(pairs: list[tuple[Any, Any]]) -> list[sp.Expr]:
    """``sp.expand(a & b)`` for each pair of vectors: the products ``b_i D_ij a_j`` of
    their measure numbers and direction cosines (``D`` between their frames) multiplied
    out in one sparse polynomial ring over QQ for all pairs (each measure number
    converted once), then written back as sympy writes an expanded polynomial.  When a
    part is not a polynomial of rationals in symbols and function values that ``expand``
    leaves alone (a float, a fractional power, a function whose argument it would
    expand), every pair is expanded by ``sp.expand`` instead."""
    triples = [_dot_terms(a, b) for a, b in pairs]
    R = _ring_of([f for terms in triples for t in terms for f in t])
    if R is None:
        return [sp.expand(sp.Add(*[x * y * z for x, y, z in terms])) for terms in triples]
    converted: dict[sp.Expr, Any] = {}

    def element(e: sp.Expr) -> Any:
        hit = converted.get(e)
        if hit is None:
            hit = converted[e] = R.from_expr(e)
        return hit

    out = []
    for terms in triples:
        p = R.zero
        for x, y, z in terms:
            p += element(x) * element(y) * element(z)
        out.append(p.as_expr())
    return out


def _dot_terms(a: Any, b: Any) -> list[tuple[sp.Expr, sp.Expr, sp.Expr]]:
    """The factors ``(b_i, D_ij, a_j)`` of the non-zero products that sum to ``a . b``."""
    if a == 0 or b == 0:
        return []
    out = []
    for ca, fa in a.args:
        for cb, fb in b.args:
            D = fb.dcm(fa)
            out += [
                (cb[i], D[i, j], ca[j])
                for i in range(3)
                if cb[i] != 0
                for j in range(3)
                if D[i, j] != 0 and ca[j] != 0
            ]
    return out


def _ring_of(parts: list[sp.Expr]) -> Any:
    """A polynomial ring over QQ whose generators are those of ``parts`` (reached through
    sums, products and positive integer powers), or None when a part holds a number
    other than a rational or a generator other than a symbol or a function value that
    ``sp.expand`` returns unchanged."""
    found: set[sp.Expr] = set()
    seen: set[sp.Expr] = set()
    stack = list(parts)
    while stack:
        e = stack.pop()
        if e in seen:
            continue
        seen.add(e)
        if e.is_Number:
            if not e.is_Rational:
                return None
        elif e.is_Add or e.is_Mul:
            stack.extend(e.args)
        elif e.is_Pow and e.exp.is_Integer and e.exp > 0:
            stack.append(e.base)
        elif e.is_Symbol or (isinstance(e, sp.Function) and sp.expand(e) == e):
            found.add(e)
        else:
            return None
    if not found:
        return None
    R, *_ = ring(sorted(found, key=sp.default_sort_key), sp.QQ)
    return R


def dyadic_dot(dyadic: Any, vec: Any) -> Any:
    """``dyadic & vec`` as sympy's ``Dyadic.dot`` forms it (``sum c b1 (b2 . vec)``),
    with :func:`vector_dot` for the dot products."""
    out = type(vec)(0)
    for c, b1, b2 in dyadic.args:
        out += c * b1 * vector_dot(b2, vec)
    return out


def vector_cross(a: Any, b: Any) -> Any:
    """``a ^ b`` as sympy's ``Vector.cross`` forms it (a determinant per frame component
    of ``b``, its rows the frame's unit vectors, their dot products with ``a`` and with
    the component), with :func:`vector_dot` for the dot products."""
    vector = type(a)
    if b.args == []:
        return vector(0)
    out = []
    for component in b.args:
        units = [component[1].x, component[1].y, component[1].z]
        part = vector([component])
        m = [units, [vector_dot(a, e) for e in units], [vector_dot(part, e) for e in units]]
        det = (
            m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            + m[0][1] * (m[1][2] * m[2][0] - m[1][0] * m[2][2])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
        )
        out += det.args
    return vector(out)
