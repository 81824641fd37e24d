"""The constants of an expression, judged in float64 *after* sympy has merged them.

sympy evaluates as it builds: ``exp(709)*exp(709)*x`` is ``x*exp(1418)``,
``pi**64*pi**64*x`` is ``pi**128*x``, ``1e308*x + 1e308*x`` is ``2.0e308*x``.  Each number
written may lie in the range of float64 while the merged one does not, and generated code
evaluating the merged constant overflows (a raw ``OverflowError``, an infinite energy) or
underflows (``x*exp(-1490)`` is 0: a silently zero energy).  :func:`constant_out_of_range`
therefore walks the expression as sympy holds it and judges

* every maximal symbol-free subtree (a constant term, a constant argument, a constant base
  or exponent): it must be 0, or of magnitude in [2^-1074, about 1.8e308];
* the symbol-free part of every product with symbols (its merged coefficient:
  ``2*pi**128`` in ``2*pi**128*x``), likewise;
* every exact rational: at most :data:`MAX_NUMBER_DIGITS` digits in its numerator and
  its denominator (the parser's limit; exact arithmetic on larger numbers gets slow).

Values are computed in float64 with overflow checks (:func:`float_value`), never by
``evalf``: ``exp(exp(100))`` is judged at once instead of being evaluated for minutes.
Products are judged in log space, so ``1e-200*1e-200*1e300`` is not taken for 0.  A
constant this arithmetic cannot judge (a function it does not know) is left alone.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from fractions import Fraction

import sympy as sp

__all__ = [
    "MAX_NUMBER_DIGITS",
    "OutOfRange",
    "constant_out_of_range",
    "float_value",
    "range_problem",
]

#: Limit on the digits of the numerator or denominator of an exact number.
MAX_NUMBER_DIGITS = 100
MAX_NUMBER_BITS = math.ceil(MAX_NUMBER_DIGITS * math.log2(10))

_LOG_MAX = math.log(1.7976931348623157e308)
_LOG_MIN = math.log(5e-324)


def _reciprocal(fn: Callable[[float], float]) -> Callable[[float], float]:
    return lambda a: 1.0 / fn(a)


#: Functions evaluated in float64 (``math`` raises OverflowError on overflow).
FLOAT_FUNCTIONS: Mapping[type, Callable[..., float]] = {
    sp.sin: math.sin,
    sp.cos: math.cos,
    sp.tan: math.tan,
    sp.cot: _reciprocal(math.tan),
    sp.sec: _reciprocal(math.cos),
    sp.csc: _reciprocal(math.sin),
    sp.asin: math.asin,
    sp.acos: math.acos,
    sp.atan: math.atan,
    sp.acot: lambda a: math.atan(1.0 / a),
    sp.atan2: math.atan2,
    sp.sinh: math.sinh,
    sp.cosh: math.cosh,
    sp.tanh: math.tanh,
    sp.coth: _reciprocal(math.tanh),
    sp.sech: _reciprocal(math.cosh),
    sp.csch: _reciprocal(math.sinh),
    sp.asinh: math.asinh,
    sp.acosh: math.acosh,
    sp.atanh: math.atanh,
    sp.exp: math.exp,
    sp.log: math.log,
}


def _product(parts: list[float]) -> float:
    """The product of ``parts`` without spurious intermediate overflow or underflow."""
    if any(p == 0 for p in parts):
        return 0.0
    if any(math.isinf(p) for p in parts):
        return math.inf
    sign = -1.0 if sum(p < 0 for p in parts) % 2 else 1.0
    log = math.fsum(math.log(abs(p)) for p in parts)
    if log > _LOG_MAX:
        return sign * math.inf
    if log < _LOG_MIN:
        return 0.0
    return sign * math.exp(log)


def float_value(value: sp.Expr) -> float | None:
    """A symbol-free expression in float64 arithmetic: ``inf`` where it overflows, ``0.0``
    where a nonzero value underflows; None where it cannot be judged this way (an unknown
    function, a complex or undefined value)."""
    try:
        return _float_value(value)
    except OverflowError:
        return math.inf
    except (ValueError, ZeroDivisionError):
        return None


def _float_value(value: sp.Expr) -> float | None:
    if value.is_Rational:
        return float(Fraction(int(value.p), int(value.q)))
    if isinstance(value, sp.Float):
        return float(value)
    if value is sp.pi:
        return math.pi
    if value is sp.E:
        return math.e
    if value.is_Add or value.is_Mul:
        parts = [_float_value(a) for a in value.args]
        if any(p is None for p in parts):
            return None
        return math.fsum(parts) if value.is_Add else _product(parts)  # type: ignore[arg-type]
    if value.is_Pow:
        base, exp = _float_value(value.base), _float_value(value.exp)
        if base is None or exp is None:
            return None
        if base < 0 and exp != int(exp):
            return None
        if base == 0:
            return 0.0 if exp > 0 else None
        log = exp * math.log(abs(base))
        if log > _LOG_MAX:
            return math.inf
        if log < _LOG_MIN:
            return 0.0
        return math.pow(base, exp)
    fn = FLOAT_FUNCTIONS.get(value.func)
    if fn is None:
        return None
    args = [_float_value(a) for a in value.args]
    if any(a is None for a in args):
        return None
    return fn(*args)


@dataclass(frozen=True)
class OutOfRange:
    """A constant of an expression that float64 cannot hold: ``constant`` (as sympy holds
    it), ``context`` (the product it is the coefficient of, or the constant itself) and
    ``reason`` (a phrase: "outside the range of float64 (...)")."""

    constant: sp.Expr
    context: sp.Expr
    reason: str


def range_problem(constant: sp.Expr) -> str | None:
    """Why the symbol-free ``constant`` cannot be a float64 value, or None if it can (or
    cannot be judged)."""
    if constant.is_Rational:
        bits = max(int(constant.p).bit_length(), int(constant.q).bit_length())
        if bits > MAX_NUMBER_BITS:
            digits = math.ceil(bits * math.log10(2))
            return f"of about {digits} digits (limit {MAX_NUMBER_DIGITS})"
        return None  # p/q with p, q < 2^333 lies well inside float64
    if isinstance(constant, sp.Float):
        x = float(constant)
        if math.isfinite(x) and (x != 0.0 or constant.is_zero):
            return None
    elif constant.is_NumberSymbol:
        return None  # pi, E, EulerGamma, ...
    value = float_value(constant)
    if value is None:
        return None
    x = value
    if not math.isfinite(x):
        return "outside the range of float64 (magnitude above about 1.8e308)"
    if x == 0.0 and constant.is_zero is False:
        return "nonzero but below the range of float64 (it underflows to 0)"
    return None


def constant_out_of_range(expr: sp.Basic) -> OutOfRange | None:
    """The first constant of ``expr`` (see the module docstring) outside float64, or None.

    One walk of the tree, each shared subtree once.

    >>> import sympy as sp
    >>> x = sp.Symbol("x", real=True)
    >>> constant_out_of_range(sp.exp(709) * sp.exp(709) * x).constant
    exp(1418)
    >>> constant_out_of_range(3 * sp.exp(709) * x).reason
    'outside the range of float64 (magnitude above about 1.8e308)'
    >>> constant_out_of_range(sp.exp(-700) * x + 1) is None
    True
    """
    # one post-order walk: which subtrees are constant (no symbol, no undefined function)
    constant: dict[sp.Basic, bool] = {}
    stack: list[tuple[sp.Basic, bool]] = [(expr, False)]
    while stack:
        e, ready = stack.pop()
        if e in constant:
            continue
        if not e.args:
            constant[e] = not isinstance(e, sp.Symbol) and getattr(e, "is_number", False)
            continue
        if not ready:
            stack.append((e, True))
            stack.extend((a, False) for a in e.args if a not in constant)
            continue
        constant[e] = isinstance(e, sp.Expr) and all(constant[a] for a in e.args)
    # then top-down: the maximal constant subtrees and the coefficients of products
    seen: set[sp.Basic] = set()
    todo = [expr]
    while todo:
        e = todo.pop()
        if e in seen or not isinstance(e, sp.Expr):
            continue
        seen.add(e)
        if constant[e]:
            if e.is_number:
                reason = range_problem(e)
                if reason is not None:
                    return OutOfRange(e, e, reason)
            continue
        if e.is_Mul:
            coefficient = [a for a in e.args if constant[a]]
            if len(coefficient) > 1:
                reason = range_problem(sp.Mul(*coefficient, evaluate=False))
                if reason is not None:
                    return OutOfRange(sp.Mul(*coefficient), e, reason)
        todo.extend(e.args)
    return None
