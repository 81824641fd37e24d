"""Printers for generated code: sympy's C99 and NumPy printers, made safe for float64.

Both printers print symbols through a name table (so any sympy name, ``I_{xx}``,
``lambda``, ``double``, ``pow``, becomes a valid local identifier, see :func:`identifier`),
and share the numerically safer conventions:

* integer powers ``x**k`` with ``1 <= |k| <=`` :data:`MAX_PRODUCT_POWER` (8) are products
  written by repeated squaring (``x**2 -> (x*x)``, ``x**5 -> ((x*x)*(x*x))*x``,
  ``x**-2 -> (1.0/(x*x))``; at most ``2 log2|k|`` multiplications, a relative error of at
  most ``(|k| - 1) u`` to first order, plus ``u`` for the reciprocal); beyond, ``pow``.
  Half-integer powers ``x**(p/2)`` with ``|p| <= 2 MAX_PRODUCT_POWER + 1`` are
  ``sqrt(x)`` times such a product.  An exponent that is a float with an integral or
  half-integral value (a baked constant ``k = 2.0``) follows the same rule.  The rule is
  the same in every function, so ``x**5`` in the energy and ``5 x**4`` in the forcing
  are both products;
* rational and integer constants are floating literals (``1/3 -> 0.3333333333333333``),
  never C integer division; pi and e are literals (``M_PI`` is not C99); any other
  symbol-free subexpression (``sqrt(2)``, ``3*pi/4``, ``sin(1)``) is folded by
  :func:`fold_numbers` into one correctly rounded literal;
* :func:`safe_rewrite` applies sympy's ``expm1``/``log1p`` optimisations and rewrites
  ``sqrt(a^2 + b^2)`` (each term a perfect square) to ``hypot(a, b)``, which neither
  overflows nor underflows (the ellipse support function
  ``sqrt(a^2 cos^2 + b^2 sin^2)`` of text 001 section 3.1 is one).
"""

from __future__ import annotations

import keyword
import re
from collections.abc import Mapping, Sequence
from fractions import Fraction

import sympy as sp
from sympy.codegen.cfunctions import hypot
from sympy.codegen.rewriting import ReplaceOptim, optimize, optims_c99
from sympy.printing.c import C99CodePrinter
from sympy.printing.numpy import NumPyPrinter
from sympy.printing.pycode import PythonCodePrinter

from symmech.algebra.walk import atoms

__all__ = [
    "FOLD_DIGITS",
    "MAX_PRODUCT_POWER",
    "SymmechCPrinter",
    "SymmechMathPrinter",
    "SymmechNumPyPrinter",
    "correctly_rounded",
    "fold_numbers",
    "identifier",
    "product_power",
    "safe_rewrite",
]

#: Integer powers up to this absolute exponent are printed as products (module docstring).
MAX_PRODUCT_POWER = 8

#: Digits at which a symbol-free subexpression is evaluated before rounding to float64.
FOLD_DIGITS = 40

#: Names a generated local may not take: C keywords and <math.h> names, Python keywords
#: and builtins used by the NumPy module.
_RESERVED = {
    *"auto break case char const continue default do double else enum extern float for goto"
    " if inline int long register restrict return short signed sizeof static struct switch"
    " typedef union unsigned void volatile while _Bool _Complex _Imaginary".split(),
    *"sin cos tan asin acos atan atan2 sinh cosh tanh exp log log10 sqrt pow fabs hypot"
    " expm1 log1p floor ceil fmod isfinite NAN INFINITY main out status".split(),
    *keyword.kwlist,
    *"numpy np math None True False".split(),
}


def identifier(name: str, prefix: str, taken: set[str], *, part: bool = False) -> str:
    """A valid C and Python identifier for the sympy name ``name``, unique in ``taken``.

    Non-identifier characters become ``_`` (``I_{xx} -> I_xx``, ``left wall ->
    left_wall``), runs of ``_`` are collapsed and leading or trailing ones stripped (so the
    result never contains ``__``), the ``prefix`` (``q``, ``p``, ...) keeps it apart from
    temporaries and reserved words, and a numeric suffix keeps it unique.  With
    ``part=True`` the result is only a part of a longer identifier (a wall name after
    ``psi_``): reserved words and a leading digit are then allowed.  The result is added
    to ``taken``.
    """
    base = re.sub(r"[^0-9A-Za-z_]+", "_", name).strip("_") or "s"
    base = re.sub(r"_+", "_", base)
    candidate = f"{prefix}_{base}" if prefix else base
    reserved = set() if part else _RESERVED
    if not part and (candidate in _RESERVED or candidate[0].isdigit()):
        candidate = f"s_{candidate}"
    out, k = candidate, 1
    while out in taken or out in reserved:
        out = f"{candidate}_{k}"
        k += 1
    taken.add(out)
    return out


def correctly_rounded(value: sp.Expr) -> float:
    """The float64 nearest to the real number ``value`` (a symbol-free sympy expression).

    Rationals are rounded exactly (``float(Fraction)``); anything else is evaluated to
    :data:`FOLD_DIGITS` significant digits first, so the result is correctly rounded
    unless ``value`` lies within ``10^-40`` (relative) of a midpoint between two doubles.
    Raises ``ValueError`` if ``value`` is not a finite real number.
    """
    v = sp.sympify(value, strict=True)
    if v.is_Rational:
        x = float(Fraction(int(v.p), int(v.q)))
    else:
        f = v.evalf(FOLD_DIGITS)
        if not isinstance(f, sp.Float):
            raise ValueError(f"constant {value} is not a finite real number")
        if not f.is_finite:
            raise ValueError(f"constant {value} is not a finite real number")
        sign, man, exp, _ = f._mpf_
        exact = Fraction(int(man)) * (Fraction(2) ** int(exp))
        x = float(-exact if sign else exact)
    if x != x or x in (float("inf"), float("-inf")):
        raise ValueError(f"constant {value} is not a finite float64")
    return x


def _literal(value: sp.Expr) -> sp.Expr:
    """A symbol-free value as an sympy number that prints as its correctly rounded double:
    an Integer when the double is an integer of at most 53 bits, else a 53-bit Float."""
    x = correctly_rounded(value)
    if x == int(x) and abs(x) < 2**53:
        return sp.Integer(int(x))
    return sp.Float(x, precision=53)


def _normal_exponent(k: sp.Expr) -> sp.Expr:
    """A float exponent with an integral or half-integral value as the exact Rational."""
    if isinstance(k, sp.Float):
        twice = 2 * float(k)
        if twice == int(twice) and abs(twice) <= 2**53:
            return sp.Rational(int(twice), 2)
    return k


def fold_numbers(expr: sp.Expr, memo: dict[sp.Expr, sp.Expr] | None = None) -> sp.Expr:
    """Fold every symbol-free subexpression into one correctly rounded literal.

    ``sqrt(2)*x -> 1.4142135623730951*x``, ``3*sqrt(2)*x + 1 + pi -> 4.242...*x +
    4.141...`` (the numeric factors of a product and the numeric terms of a sum are
    combined first); integers and rationals stay exact (they print as literals);
    exponents are left symbolic (``x**(1/2)`` still prints ``sqrt``), except that a float
    exponent with an integral or half-integral value becomes that rational (``x**2.0 ->
    x**2``, ``x**1.0 -> x``).  The value is the real number rounded once
    (:func:`correctly_rounded`), so its error, at most ``u/2`` relative, is no larger than
    the first-order rounding error of evaluating the subexpression in float64.  ``memo``
    (subtree -> folded) may be kept by the caller for expressions sharing subtrees.
    """

    def numeric(e: sp.Expr) -> bool:
        return bool(e.is_number) and not e.is_Rational and not isinstance(e, sp.Float)

    memo = {} if memo is None else memo

    def go(e: sp.Expr) -> sp.Expr:
        if e.is_Atom:
            return e
        out = memo.get(e)
        if out is None:
            out = memo[e] = fold(e)
        return out

    def same(new: Sequence[sp.Expr], old: Sequence[sp.Expr]) -> bool:
        return all(a is b for a, b in zip(new, old, strict=True))

    def fold(e: sp.Expr) -> sp.Expr:
        # a node whose arguments come back unchanged is kept, not rebuilt
        if e.is_number:
            return _literal(e) if numeric(e) else e
        if e.is_Pow:
            base, k = go(e.base), _normal_exponent(e.exp)
            return e if base is e.base and k is e.exp else sp.Pow(base, k)
        if e.is_Add or e.is_Mul:
            # the exact numeric arguments are combined, then rounded once
            nums = [a for a in e.args if a.is_number]
            symbolic = [a for a in e.args if not a.is_number]
            rest = [go(a) for a in symbolic]
            if len(nums) <= 1 and not any(numeric(a) for a in nums) and same(rest, symbolic):
                return e
            op = sp.Add if e.is_Add else sp.Mul
            combined = op(*nums)
            return op(_literal(combined) if numeric(combined) else combined, *rest)
        args = [go(a) for a in e.args]
        return e if same(args, e.args) else e.func(*args)

    return go(sp.sympify(expr, strict=True))


def product_power(k: sp.Expr) -> bool:
    """Whether ``x**k`` prints as a product (times ``sqrt(x)`` for a half-integer k)."""
    k = _normal_exponent(k)
    if k.is_Integer:
        return 1 <= abs(int(k)) <= MAX_PRODUCT_POWER
    if k.is_Rational and k.q == 2:
        return abs(int(k.p)) // 2 <= MAX_PRODUCT_POWER
    return False


def _perfect_square_root(term: sp.Expr) -> sp.Expr | None:
    """r with r**2 == term when term is a product of even powers and a positive number."""
    factors = term.args if isinstance(term, sp.Mul) else (term,)
    roots = []
    for f in factors:
        if f.is_Number:
            if not f.is_positive:
                return None
            roots.append(sp.sqrt(f))
        elif f.is_Pow and f.exp.is_Integer and f.exp % 2 == 0:
            roots.append(f.base ** (f.exp // 2))
        else:
            return None
    return sp.Mul(*roots)


def _hypot_query(e: sp.Expr) -> bool:
    if not (e.is_Pow and e.exp in (sp.S.Half, -sp.S.Half) and isinstance(e.base, sp.Add)):
        return False
    if len(e.base.args) != 2:
        return False
    return all(_perfect_square_root(a) is not None for a in e.base.args)


def _hypot_value(e: sp.Expr) -> sp.Expr:
    a, b = (_perfect_square_root(x) for x in e.base.args)
    return hypot(a, b) if e.exp > 0 else 1 / hypot(a, b)


_hypot_opt = ReplaceOptim(_hypot_query, _hypot_value)


def safe_rewrite(expr: sp.Expr) -> sp.Expr:
    """``exp(x) - 1 -> expm1(x)``, ``log(1 + x) -> log1p(x)``, ``sqrt(a^2 + b^2) -> hypot``.

    Each rewrite runs only when its function occurs: sympy's ``expm1`` optimisation calls
    ``factor`` on the whole expression, which takes minutes on a multibody forcing term.
    """
    expr = sp.sympify(expr, strict=True)
    if expr.is_Atom:
        return expr
    expm1_opt, log1p_opt = optims_c99[:2]
    found = atoms(expr, (sp.exp, sp.log, sp.Pow))  # one walk over distinct subtrees
    optims = []
    if any(isinstance(a, sp.exp) for a in found):
        optims.append(expm1_opt)
    if any(isinstance(a, sp.log) for a in found):
        optims.append(log1p_opt)
    if any(a.is_Pow and a.exp in (sp.S.Half, -sp.S.Half) for a in found):
        optims.append(_hypot_opt)
    return optimize(expr, optims) if optims else expr


def _float_literal(value: sp.Expr) -> str:
    s = repr(correctly_rounded(value))
    return s if any(c in s for c in ".en") else s + ".0"


class _Float64Mixin:
    """Conventions shared by both printers: names from a table, floating literals,
    integer powers as products, half-integer powers through sqrt."""

    _sqrt: str

    def _init_names(self, names: Mapping[sp.Symbol, str]) -> None:
        self._names = dict(names)

    def _print_Symbol(self, expr: sp.Symbol) -> str:
        try:
            return self._names[expr]
        except KeyError:
            raise ValueError(f"no generated name for the symbol {expr}") from None

    _print_Dummy = _print_Symbol

    def _print_Rational(self, expr: sp.Rational) -> str:
        return _float_literal(expr)

    _print_Integer = _print_Rational
    _print_Float = _print_Rational

    def _print_Pi(self, expr: sp.Expr) -> str:
        return _float_literal(sp.pi)

    def _print_Exp1(self, expr: sp.Expr) -> str:
        return _float_literal(sp.E)

    def _print_Half(self, expr: sp.Expr) -> str:
        return "0.5"

    def _print_One(self, expr: sp.Expr) -> str:
        return "1.0"

    def _print_NegativeOne(self, expr: sp.Expr) -> str:
        return "-1.0"

    def _print_Zero(self, expr: sp.Expr) -> str:
        return "0.0"

    def _power(self, b: str, k: int) -> str:
        """``b**k`` for ``k >= 1`` by repeated squaring, parenthesised (the Mul printer
        writes ``1.0/`` before a power in a denominator without parentheses, and
        ``1.0/y*y`` would mean ``(1/y)*y``)."""
        if k == 1:
            return b
        half = self._power(b, k // 2)
        square = f"({half}*{half})"
        return f"({square}*{b})" if k % 2 else square

    def _print_Pow(self, expr: sp.Pow) -> str:
        b, e = expr.base, _normal_exponent(expr.exp)
        if e.is_Integer and product_power(e):
            body = self._power(self.parenthesize(b, 50), abs(int(e)))  # type: ignore[attr-defined]
            return body if e > 0 else f"(1.0/{body})"
        if e.is_Rational and e.q == 2 and product_power(e):
            k = abs(int(e.p)) // 2
            root = f"{self._sqrt}({self._print(b)})"  # type: ignore[attr-defined]
            if k:
                root = f"({root}*{self._power(self.parenthesize(b, 50), k)})"  # type: ignore[attr-defined]
            return root if e > 0 else f"(1.0/{root})"
        if e is not expr.exp:
            expr = sp.Pow(b, e, evaluate=False)
        return super()._print_Pow(expr)  # type: ignore[misc]


class SymmechCPrinter(_Float64Mixin, C99CodePrinter):
    """C99 printer with symmech's name table and float64 conventions (module docstring)."""

    _sqrt = "sqrt"

    def __init__(self, names: Mapping[sp.Symbol, str]):
        super().__init__({"strict": True})
        self._init_names(names)


class SymmechNumPyPrinter(_Float64Mixin, NumPyPrinter):
    """NumPy printer with symmech's name table and float64 conventions."""

    _sqrt = "numpy.sqrt"

    def __init__(self, names: Mapping[sp.Symbol, str]):
        super().__init__({"fully_qualified_modules": True, "allow_unknown_functions": False})
        self._init_names(names)

    def _print_hypot(self, expr: sp.Expr) -> str:
        return f"numpy.hypot({self._print(expr.args[0])}, {self._print(expr.args[1])})"

    def _print_expm1(self, expr: sp.Expr) -> str:
        return f"numpy.expm1({self._print(expr.args[0])})"

    def _print_log1p(self, expr: sp.Expr) -> str:
        return f"numpy.log1p({self._print(expr.args[0])})"


class SymmechMathPrinter(_Float64Mixin, PythonCodePrinter):
    """Python printer over plain floats (``math`` functions): the one-state variants of the
    NumPy module's functions, with the NumPy printer's names and float64 conventions.  An
    expression ``math`` cannot evaluate raises ``ValueError`` (the variant is then not
    emitted)."""

    _sqrt = "math.sqrt"

    def __init__(self, names: Mapping[sp.Symbol, str]):
        super().__init__(
            {"fully_qualified_modules": True, "allow_unknown_functions": False, "strict": True}
        )
        self._init_names(names)

    def _print_hypot(self, expr: sp.Expr) -> str:
        return f"math.hypot({self._print(expr.args[0])}, {self._print(expr.args[1])})"

    def _print_expm1(self, expr: sp.Expr) -> str:
        return f"math.expm1({self._print(expr.args[0])})"

    def _print_log1p(self, expr: sp.Expr) -> str:
        return f"math.log1p({self._print(expr.args[0])})"
