"""Exact polynomial identity testing: is a rational expression identically zero?

Carnot's theorems are identities between rational functions of the entries of the metric,
the constraints and the wall (and of the velocities).  Forming the residual symbolically
and cancelling it costs time and memory that grow fast with the size of the impact map (a
4-DOF trigonometric system did not finish in 11 minutes).  Here the residual is instead
*evaluated exactly*, in rational arithmetic, at a random point, and the Schwartz-Zippel
lemma bounds the probability of a wrong "zero":

    if R = Num/Den is not identically zero and deg Num <= D, then for a point drawn
    uniformly from S^k (S a set of integers), P(Num(point) = 0) <= D / |S|.

The point.  Every building block of the expressions gets a value:

* symbols (coordinates, parameters, time, the velocities) and undefined functions
  ``f(t)``, ``f'(t)``: independent random integers in ``S = {-B, ..., B}``;
* ``sin`` / ``cos`` / ``tan`` of an integer combination ``sum k_i u_i`` of such atoms:
  each atom u gets a point on the unit circle with rational coordinates,
  ``cos u = (1 - s^2)/(1 + s^2)``, ``sin u = 2 s/(1 + s^2)`` for a random s in S, and
  ``exp(i sum k_i u_i)`` is multiplied out in Gaussian rationals.  So ``sin^2 + cos^2 = 1``
  and the addition theorems hold exactly at the point, while u itself stays an
  independent value (u, cos u, sin u are algebraically independent as functions, so an
  identity of the functions is an identity of polynomials modulo the circle relations,
  and the rational parametrisation of the circle is birational);
* a radical ``u^(p/q)``: ``r^p`` for one random value r per base u, and every
  occurrence of the same expression u elsewhere is read as ``r^q``;
* any other function (``exp``, ``sin(x/2)``): an independent random value.

This *generator model* specialises to the true functions (put r = u^(1/q) and the true
sin, cos), so an identity of the model is an identity of the functions: a "zero" verdict
is valid.  The converse needs relations the model does not know (u written out in
another form than the base of its root, ``exp(x) exp(-x)``), so a non-zero value proves
the identity false only when the model is exact (:attr:`Verdict.model_exact`: no
radicals and no independent function values).

The degree bound D is computed by running the same evaluation over
:class:`DegreeBound` (bounds on the degrees of numerator and denominator, combined as
fractions are: ``a/b + c/d = (ad + bc)/(bd)``), in the random integers and the circle
parameters s.  S is chosen with ``|S| >= D * 10^13``, so the probability of a wrong "zero"
is below ``10^-13`` (:attr:`Verdict.error_bound` states the exact bound).  A non-zero
value is exact, hence a proof that the residual is not identically zero whenever the
model is exact.  The point is drawn from a fixed seed, so the verdict is reproducible.
"""

from __future__ import annotations

import random
from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import sympy as sp

from symmech.algebra import budget as limits

__all__ = ["DegreeBound", "Unsupported", "Verdict", "identically_zero"]

#: |S| >= D * SAFETY: the probability of a wrong "identically zero" is below 1/SAFETY.
SAFETY = 10**13


class Unsupported(Exception):
    """The expression holds a building block that cannot be evaluated exactly (a float,
    a piecewise function, ...)."""


@dataclass(frozen=True)
class DegreeBound:
    """Bounds ``(num, den)`` on the total degrees of the numerator and denominator of a
    rational function, combined as fractions are combined (no cancellation assumed)."""

    num: int
    den: int

    def __add__(self, other: DegreeBound) -> DegreeBound:
        return DegreeBound(max(self.num + other.den, other.num + self.den), self.den + other.den)

    __sub__ = __add__

    def __mul__(self, other: DegreeBound) -> DegreeBound:
        return DegreeBound(self.num + other.num, self.den + other.den)

    def __neg__(self) -> DegreeBound:
        return self

    def inverse(self) -> DegreeBound:
        return DegreeBound(self.den, self.num)

    @property
    def total(self) -> int:
        return self.num + self.den


class _Gauss:
    """A Gaussian rational a + i b (for exp(i u) on the unit circle)."""

    __slots__ = ("im", "re")

    def __init__(self, re: Fraction, im: Fraction):
        self.re, self.im = re, im

    def __mul__(self, other: _Gauss) -> _Gauss:
        return _Gauss(
            self.re * other.re - self.im * other.im, self.re * other.im + self.im * other.re
        )

    def conj(self) -> _Gauss:
        return _Gauss(self.re, -self.im)


_TRIG = (sp.sin, sp.cos, sp.tan, sp.cot, sp.sec, sp.csc)


def _linear_angles(arg: sp.Expr) -> list[tuple[sp.Expr, int]] | None:
    """``arg = sum k_i u_i`` with integer k_i and atoms u_i (symbols, function
    applications), or None."""
    terms = []
    if limits.expanded_terms(arg, limits.EXPAND_TERMS + 1)[0] > limits.EXPAND_TERMS:
        return None
    for term in sp.Add.make_args(sp.expand(arg)):
        coeff, rest = term.as_coeff_Mul()
        if not coeff.is_Integer or rest.is_number:
            return None
        if not (rest.is_Symbol or isinstance(rest, (sp.Function, sp.Derivative))):
            return None
        if isinstance(rest, sp.Function) and isinstance(rest, (*_TRIG, sp.exp)):
            return None
        terms.append((rest, int(coeff)))
    return terms


class _Algebra:
    """Evaluation of sympy expressions at a point (``Fraction``) or of their degree bounds
    (``DegreeBound``); both walk the same tree with the same rules."""

    def __init__(
        self,
        degrees: bool,
        rng: random.Random | None,
        bound: int,
        radicals: dict[sp.Expr, int] | None = None,
    ):
        self.degrees = degrees
        self.rng, self.bound = rng, bound
        #: radical bases u (with their root index q) met so far; u itself is read as r^q
        self.radicals: dict[sp.Expr, int] = dict(radicals or {})
        self.values: dict[Any, Any] = {}
        self.circle: dict[sp.Expr, tuple[Any, Any]] = {}
        self.cache: dict[sp.Expr, Any] = {}
        self.model_exact = True

    # -- leaves -----------------------------------------------------------------
    def const(self, q: Fraction | int) -> Any:
        return DegreeBound(0, 0) if self.degrees else Fraction(q)

    def _random(self) -> Fraction:
        assert self.rng is not None
        return Fraction(self.rng.randint(-self.bound, self.bound))

    def atom(self, key: Any) -> Any:
        if key not in self.values:
            self.values[key] = DegreeBound(1, 0) if self.degrees else self._random()
        return self.values[key]

    def _cos_sin(self, u: sp.Expr) -> tuple[Any, Any]:
        if u not in self.circle:
            if self.degrees:
                self.circle[u] = (DegreeBound(2, 2), DegreeBound(2, 2))
            else:
                s = self._random()
                d = 1 + s * s
                self.circle[u] = ((1 - s * s) / d, 2 * s / d)
        return self.circle[u]

    def _trig(self, e: sp.Expr) -> Any:
        angles = _linear_angles(e.args[0])
        if angles is None:
            self.model_exact = False
            return self.atom(e)
        if self.degrees:
            k = sum(abs(c) for _, c in angles)
            cs = DegreeBound(2 * k, 2 * k)
            c: Any = cs
            s: Any = cs
        else:
            z = _Gauss(Fraction(1), Fraction(0))
            for u, k in angles:
                c0, s0 = self._cos_sin(u)
                w = _Gauss(c0, s0) if k > 0 else _Gauss(c0, -s0)
                for _ in range(abs(k)):
                    z = z * w
            c, s = z.re, z.im
        if isinstance(e, sp.cos):
            return c
        if isinstance(e, sp.sin):
            return s
        if isinstance(e, sp.tan):
            return s * self.inverse(c)
        if isinstance(e, sp.cot):
            return c * self.inverse(s)
        if isinstance(e, sp.sec):
            return self.inverse(c)
        return self.inverse(s)  # csc

    def inverse(self, x: Any) -> Any:
        if self.degrees:
            return x.inverse()
        if x == 0:
            raise ZeroDivisionError("a denominator vanishes at the sampled point")
        return 1 / x

    def power(self, x: Any, k: int) -> Any:
        if self.degrees:
            b = DegreeBound(x.num * abs(k), x.den * abs(k))
            return b if k >= 0 else b.inverse()
        y = x ** abs(k)
        return y if k >= 0 else self.inverse(y)

    # -- trees ------------------------------------------------------------------
    def value(self, e: sp.Expr) -> Any:
        hit = self.cache.get(e)
        if hit is None:
            hit = self.cache[e] = self._value(e)
        return hit

    def _value(self, e: sp.Expr) -> Any:
        q = self.radicals.get(e)
        if q is not None:  # u = r^q for the root r = u^(1/q) met elsewhere
            return self.power(self.atom(("root", e, q)), q)
        if e.is_Rational:
            return self.const(Fraction(int(e.p), int(e.q)))
        if e.is_Number:
            raise Unsupported(f"inexact or non-rational number {e}")
        if e.is_Symbol:
            return self.atom(e)
        if e.is_Add:
            args = [self.value(a) for a in e.args]
            out = args[0]
            for a in args[1:]:
                out = out + a
            return out
        if e.is_Mul:
            args = [self.value(a) for a in e.args]
            out = args[0]
            for a in args[1:]:
                out = out * a
            return out
        if e.is_Pow:
            exp = e.exp
            if exp.is_Integer:
                return self.power(self.value(e.base), int(exp))
            if exp.is_Rational:
                self.model_exact = False
                q = self.radicals.setdefault(e.base, int(exp.q))
                if q != exp.q:  # another root of the same base: an independent value
                    return self.atom(e)
                return self.power(self.atom(("root", e.base, q)), int(exp.p))
            self.model_exact = False
            return self.atom(e)
        if isinstance(e, _TRIG):
            return self._trig(e)
        if isinstance(e, (sp.Function, sp.Derivative)) and not isinstance(
            e, (sp.Piecewise, sp.Abs, sp.sign, sp.Min, sp.Max, sp.floor, sp.ceiling)
        ):
            if not (e.func.__class__ is sp.core.function.UndefinedFunction or e.is_Derivative):
                self.model_exact = False  # exp, log, ...: an independent value
            return self.atom(e)
        raise Unsupported(f"cannot evaluate {type(e).__name__} exactly: {e}")


@dataclass(frozen=True)
class Verdict:
    """Outcome of :func:`identically_zero`.

    ``zero``: the value at the point was 0.  ``error_bound``: an upper bound on the
    probability that ``zero`` is wrong (Schwartz-Zippel, ``degree / |S|``; 0 when not
    ``zero``, a non-zero value being exact).  ``model_exact``: no building block was read
    as an independent generator that may obey a relation (radicals, exp, sin of a
    non-integer combination), so a non-zero value proves the identity false.
    """

    zero: bool
    degree: int
    sample_size: int
    error_bound: Fraction
    model_exact: bool

    def describe(self) -> str:
        return (
            f"exact rational evaluation at a random point, numerator degree <= {self.degree},"
            f" |S| = {self.sample_size}: P(wrong 'zero') <= {float(self.error_bound):.1e}"
        )


def identically_zero(
    build: Callable[[Callable[[sp.Expr], Any], Callable[[int], Any]], Any],
    seed: int = 20240302,
    attempts: int = 5,
) -> Verdict:
    """Decide whether the scalar ``build(value, const)`` is identically zero.

    ``build`` receives ``value(expr)`` (the value of a sympy expression at the point) and
    ``const(q)`` (a rational constant) and returns one scalar made with ``+ - *``; it is
    run once over degree bounds and once over exact values (see the module docstring).
    Raises :class:`Unsupported` for expressions that cannot be evaluated exactly.
    """
    scan = _Algebra(True, None, 0)  # first pass: find the radicals
    build(scan.value, scan.const)
    deg_alg = _Algebra(True, None, 0, scan.radicals)
    bound = build(deg_alg.value, deg_alg.const)
    degree = max(bound.total, 1)
    half = (degree * SAFETY) // 2 + 1
    size = 2 * half + 1
    rng = random.Random(seed)
    last: ZeroDivisionError | None = None
    for _ in range(attempts):
        alg = _Algebra(False, rng, half, scan.radicals)
        try:
            value = build(alg.value, alg.const)
        except ZeroDivisionError as exc:  # a denominator vanishes at this point
            last = exc
            continue
        zero = value == 0
        return Verdict(
            zero=zero,
            degree=degree,
            sample_size=size,
            error_bound=Fraction(degree, size) if zero else Fraction(0),
            model_exact=alg.model_exact,
        )
    raise ZeroDivisionError(f"every sampled point hit a vanishing denominator: {last}")
