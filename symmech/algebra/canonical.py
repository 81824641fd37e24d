"""Sums and products built exactly as sympy builds them, without its general machinery.

``mul(*args)`` returns ``sympy.Mul(*args)`` and ``add(*args)`` returns ``sympy.Add(*args)``:
the same expression, argument for argument and in the same order (``srepr`` equal), so
derived equations and the code generated from them do not depend on which of the two
built them.  sympy's ``Mul.flatten`` and ``Add.flatten`` handle every kind of object
(numbers of every type, infinities, orders, matrices, non-commutative symbols, numeric
powers such as ``sqrt(2)*sqrt(6)``); the derivations of mechanical systems (metrics from
kinetic energies, their derivatives, the forcing) combine only

* rational numbers,
* commutative symbols, undefined functions ``f(q)`` and the elementary functions listed in
  :data:`_FUNCTIONS` (sympy treats each as a base with exponent 1),
* commutative sums, products of these, and powers of them to rational exponents,

and on those the canonical form sympy computes is: the rational coefficient (first, when
it is not 1) times the bases with their exponents summed (a zero exponent drops the base,
exponent 1 leaves it bare), sorted by ``Basic.compare``; for a sum, the coefficients of
equal terms summed (zero drops the term), sorted likewise, the rational constant first.
The rules sympy applies on top of that, reproduced here to the letter:

* ``Mul`` of two arguments, a rational ``a`` and ``r*S`` with S a sum: ``(a r)*S`` kept
  as a product when ``r != 1``, else ``a`` distributed over the terms of S
  (``_keep_coeff``); and a product that ends as ``number * sum`` is distributed;
* ``Add`` of a rational and a product keeps the two as given.

Anything outside that domain, and every case where sympy would rewrite further (a zero
coefficient, a power ``Pow`` does not keep as given, evaluation switched off), is handed
to sympy itself, so the result is sympy's in every case.  The routes rely on how sympy
orders and stores arguments, which is not part of its public interface: they are taken
only on the sympy releases they were checked on (:data:`CHECKED_SYMPY`), and the tests
compare them with sympy's constructors on every release the suite runs with.

The saving is the general machinery: on the expressions of an n-link pendulum, a product
is built about three times faster than by ``Mul``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import sympy as sp
from sympy.core import basic
from sympy.core.add import Add
from sympy.core.function import AppliedUndef
from sympy.core.mul import Mul
from sympy.core.power import Pow

from symmech.algebra.memo import expression_cache

try:  # sympy internals the fast routes read (see CHECKED_SYMPY)
    from sympy.core.mul import _keep_coeff, _mulsort
    from sympy.core.parameters import global_parameters

    _INTERNALS = True
except ImportError:  # pragma: no cover - a sympy release that moved them
    _INTERNALS = False

__all__ = ["CHECKED_SYMPY", "FAST", "add", "fast_add", "fast_mul", "keep_coeff", "mul"]

_ONE = sp.S.One
_ZERO = sp.S.Zero

#: Function classes sympy's ``Mul`` treats as plain bases (``as_base_exp`` is ``(f, 1)``;
#: ``exp`` is not among them: sympy reads ``exp(x)`` as ``E**x`` and merges exponents).
_FUNCTIONS = frozenset(
    {
        sp.sin,
        sp.cos,
        sp.tan,
        sp.cot,
        sp.sec,
        sp.csc,
        sp.sinh,
        sp.cosh,
        sp.tanh,
        sp.asin,
        sp.acos,
        sp.atan,
        sp.log,
    }
)


class _Unordered(TypeError):
    """A part of an expression the sort keys do not cover (sympy's comparison decides)."""


_CLASS_KEYS: dict[type, tuple[int, str]] = {}


def _class_key(cls: type) -> tuple[int, str]:
    """The place of ``cls`` in ``Basic.compare``: its index in sympy's
    ``ordering_of_classes`` (unknown classes after all known ones, then by name)."""
    hit = _CLASS_KEYS.get(cls)
    if hit is None:
        order = basic.ordering_of_classes
        name = cls.__name__
        hit = _CLASS_KEYS[cls] = (order.index(name) if name in order else len(order) + 1, name)
    return hit


@expression_cache(maxsize=1 << 15)
def _sort_key(e: sp.Basic) -> tuple[Any, ...]:
    """A key ordering expressions as ``Basic.compare`` does: class, then the length and
    the items of ``_hashable_content()`` in turn (sub-expressions by their keys, other
    items by Python's comparison); a pure function of the (immutable) expression."""
    content = e._hashable_content()
    return (
        _class_key(type(e)),
        len(content),
        tuple(_sort_key(x) if isinstance(x, sp.Basic) else _item(x) for x in content),
    )


def _item(x: object) -> object:
    if isinstance(x, frozenset):
        raise _Unordered("a set in the hashable content")
    return x


def _item_key(e: sp.Basic) -> tuple[Any, ...]:
    """:func:`_sort_key`, not memoised for sums and products (mostly built just now)."""
    if type(e) is Mul or type(e) is Add:
        content = e._hashable_content()
        return (_class_key(type(e)), len(content), tuple(_sort_key(x) for x in content))
    return _sort_key(e)


def _sort(items: list[sp.Expr]) -> None:
    """Sort ``items`` in place in sympy's canonical order of the arguments of a sum or
    product (``Basic.compare``, as sympy's ``_addsort`` and ``_mulsort``)."""
    try:
        items[:] = sorted(items, key=_item_key)
    except TypeError:  # items the keys do not order: sympy's comparison itself
        _mulsort(items)


def _type_is_base(cls: type) -> bool:
    return cls is Add or cls in _FUNCTIONS or issubclass(cls, sp.Symbol | AppliedUndef)


def _type_is_plain(cls: type) -> bool:
    registered = basic.Basic._constructor_postprocessor_mapping
    return not any(c in registered for c in cls.__mro__)


#: Per type: whether its instances are bases (symbols, undefined functions, the listed
#: functions, sums; commutative ones only, checked per instance).
_BASE: dict[type, bool] = {}
#: Per type: whether no sympy constructor postprocessor applies to its instances (only
#: matrix, vector, tensor and quantum objects have them; sympy caches this per type too).
_PLAIN: dict[type, bool] = {}


def _is_base(o: sp.Basic) -> bool:
    """Whether ``o`` is a commutative symbol, undefined function, listed function or sum
    (a base sympy's products keep as it is, with exponent 1)."""
    t = type(o)
    hit = _BASE.get(t)
    if hit is None:
        hit = _BASE[t] = _type_is_base(t)
    return hit and o.is_commutative is True


def _build(cls: type[Mul] | type[Add], args: list[sp.Expr]) -> sp.Expr:
    """``cls`` with ``args`` in canonical order, as sympy's constructor finishes it."""
    obj = cls._from_args(args, True)
    for a in args:
        t = type(a)
        hit = _PLAIN.get(t)
        if hit is None:
            hit = _PLAIN[t] = _type_is_plain(t)
        if not hit:
            return cls._exec_constructor_postprocessors(obj)
    return obj


def _exact(args: tuple[sp.Basic, ...]) -> bool:
    """Whether the fast routes may be taken: sympy expressions, evaluation on."""
    if not (global_parameters.evaluate and global_parameters.distribute):
        return False
    for a in args:
        if not isinstance(a, sp.Expr):
            return False
    return True


def fast_mul(*args: sp.Expr) -> sp.Expr:
    """``sympy.Mul(*args)`` (the identical expression), faster on the domain of the
    module docstring; ``args`` are sympy expressions.  Use :func:`mul`."""
    if not _exact(args):
        return Mul(*args)
    seq = [a for a in args if a is not _ONE]
    if len(seq) < 2:
        return seq[0] if seq else _ONE
    if len(seq) == 2:
        # sympy's two-argument rule: a rational times (r * sum)
        a, b = seq
        if b.is_Rational:
            a, b = b, a
        if a.is_Rational and not a.is_zero:
            r, rest = b.as_coeff_Mul()
            if rest.is_Add:
                if r is not _ONE:
                    ar = a * r
                    return rest if ar is _ONE else Mul(ar, rest, evaluate=False)
                if rest.is_commutative:
                    return fast_add(*[_keep_coeff(a, t) for t in rest.args])
    coeff = _ONE
    powers: dict[sp.Expr, sp.Expr] = {}
    for o in seq:  # grows: the arguments of products are appended
        t = type(o)
        if t is Mul:
            if o.is_commutative is not True:
                return Mul(*args)
            seq.extend(o.args)
            continue
        if o.is_Rational:
            coeff *= o
            continue
        if t is Pow:
            b, e = o.args
            if not (e.is_Rational and _is_base(b)):
                return Mul(*args)
        elif _is_base(o):
            b, e = o, _ONE
        else:
            return Mul(*args)
        old = powers.get(b)
        powers[b] = e if old is None else old + e
    if not coeff.p:
        # zero times finite symbols is zero; sympy's rules for anything else (0 * oo)
        if all(
            isinstance(b, sp.Symbol) and b.is_finite is True and e.is_Integer and e > 0
            for b, e in powers.items()
        ):
            return coeff
        return Mul(*args)
    factors = []
    for b, e in powers.items():
        if e is _ZERO:
            continue
        if e is _ONE:
            factors.append(b)
            continue
        p = Pow(b, e)
        if type(p) is not Pow or p.args[0] != b:
            return Mul(*args)  # Pow rewrote the power (or e is a zero or one that is not
            # sympy's singleton): sympy's own route
        factors.append(p)
    _sort(factors)
    if coeff is not _ONE:
        if len(factors) == 1 and factors[0].is_Add:
            # number * sum: sympy distributes the number
            c = coeff
            return fast_add(*[c * f if f.is_Number else fast_mul(c, f) for f in factors[0].args])
        factors.insert(0, coeff)
    if len(factors) < 2:
        return factors[0] if factors else coeff
    return _build(Mul, factors)


def fast_add(*args: sp.Expr) -> sp.Expr:
    """``sympy.Add(*args)`` (the identical expression), faster on the domain of the
    module docstring; ``args`` are sympy expressions.  Use :func:`add`."""
    if not _exact(args):
        return Add(*args)
    seq = [a for a in args if a is not _ZERO]
    if len(seq) < 2:
        return seq[0] if seq else _ZERO
    if len(seq) == 2:
        # sympy's two-argument rule: a rational plus a product, kept as given
        a, b = seq
        if b.is_Rational:
            a, b = b, a
        if a.is_Rational and b.is_Mul:
            if b.is_commutative is not True:
                return Add(*args)
            return _build(Add, [a, b])
    coeff = _ZERO
    # a term c * s is keyed by the factors of s (the arguments of the product c * s
    # without its coefficient): sympy's key s without building it
    terms: dict[tuple[sp.Expr, ...], sp.Expr] = {}
    for o in seq:  # grows: the terms of sums are appended
        t = type(o)
        if t is Add:
            seq.extend(o.args)
            continue
        if o.is_Rational:
            coeff += o
            continue
        if t is Mul:
            if o.is_commutative is not True:
                return Add(*args)
            key = o.args
            c = key[0]
            if c.is_Number:
                if not c.is_Rational:
                    return Add(*args)
                key = key[1:]
                if len(key) == 1 and type(key[0]) is Mul:  # an unevaluated c * (x*y)
                    return Add(*args)
            else:
                c = _ONE
        elif t is Pow:
            if o.args[0].is_Number or o.is_commutative is not True:
                return Add(*args)
            c, key = _ONE, (o,)
        elif _is_base(o):
            c, key = _ONE, (o,)
        else:
            return Add(*args)
        old = terms.get(key)
        terms[key] = c if old is None else old + c
    out = []
    for key, c in terms.items():
        if not c.p:
            continue
        if len(key) > 1:
            out.append(Mul._from_args(key if c is _ONE else (c, *key), True))
        elif c is _ONE:
            out.append(key[0])
        elif key[0].is_Add:
            out.append(Mul(c, key[0], evaluate=False))
        else:
            out.append(fast_mul(c, key[0]))
    _sort(out)
    if coeff is not _ZERO:
        out.insert(0, coeff)
    if len(out) < 2:
        return out[0] if out else _ZERO
    return _build(Add, out)


#: The sympy releases (major.minor) on which :func:`fast_mul` and :func:`fast_add` were
#: checked against sympy's constructors (``tests/test_derive_speed_canonical.py``, which
#: runs on whatever sympy is installed and fails when a release orders differently).  The
#: fast routes read sympy's internals (its class order, ``_hashable_content``,
#: ``_from_args``), so on any other release :func:`mul` and :func:`add` are sympy's own.
CHECKED_SYMPY = ("1.14",)

#: Whether :func:`mul` and :func:`add` take the fast routes with the installed sympy.
FAST = _INTERNALS and ".".join(sp.__version__.split(".")[:2]) in CHECKED_SYMPY


#: ``sympy.Mul(*args)`` and ``sympy.Add(*args)``: :func:`fast_mul` and :func:`fast_add` on a
#: checked sympy (:data:`FAST`), sympy's own constructors otherwise (chosen once, here:
#: they are called for every product and sum of a derivation).
mul: Callable[..., sp.Expr] = fast_mul if FAST else Mul
add: Callable[..., sp.Expr] = fast_add if FAST else Add


def keep_coeff(c: sp.Expr, term: sp.Expr) -> sp.Expr:
    """The product ``c * term`` of a rational and a term that is not a sum, as sympy forms
    it when it distributes ``c`` over a sum (its ``_keep_coeff``; ``Mul`` where that is
    not available: the same product)."""
    return _keep_coeff(c, term) if _INTERNALS else Mul(c, term)
