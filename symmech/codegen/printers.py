"""Printers for generated code: sympy's C99 and NumPy printers, made safe for float64.

Both printers print symbols through a name table (so any sympy name, ``I_{xx}``,
``lambda``, ``double``, ``pow``, becomes a valid local identifier, see :func:`identifier`),
and share the numerically safer conventions:

* integer powers are products: ``x**2 -> x*x``, ``x**-2 -> 1.0/(x*x)`` (``pow(x, 2)`` is
  slower and, in some libms, less accurate); half-integer powers use ``sqrt``;
* rational and integer constants are floating literals (``1/3 -> 0.3333333333333333``),
  never C integer division; pi and e are literals (``M_PI`` is not C99);
* :func:`safe_rewrite` applies sympy's ``expm1``/``log1p`` optimisations and rewrites
  ``sqrt(a^2 + b^2)`` (each term a perfect square) to ``hypot(a, b)``, which neither
  overflows nor underflows (the ellipse support function
  ``sqrt(a^2 cos^2 + b^2 sin^2)`` of text 001 section 3.1 is one).
"""

from __future__ import annotations

import keyword
import re
from collections.abc import Mapping

import sympy as sp
from sympy.codegen.cfunctions import hypot
from sympy.codegen.rewriting import ReplaceOptim, optimize, optims_c99
from sympy.printing.c import C99CodePrinter
from sympy.printing.numpy import NumPyPrinter

__all__ = ["SymmechCPrinter", "SymmechNumPyPrinter", "identifier", "safe_rewrite"]

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


def identifier(name: str, prefix: str, taken: set[str]) -> str:
    """A valid C and Python identifier for the sympy name ``name``, unique in ``taken``.

    Non-identifier characters become ``_`` (``I_{xx} -> I_xx``), the ``prefix`` (``q``,
    ``p``, ...) keeps it apart from temporaries and reserved words, and a numeric suffix
    keeps it unique.  The result is added to ``taken``.
    """
    base = re.sub(r"[^0-9A-Za-z_]+", "_", name).strip("_") or "s"
    base = re.sub(r"_+", "_", base)
    candidate = f"{prefix}_{base}" if prefix else base
    if candidate in _RESERVED or candidate[0].isdigit():
        candidate = f"s_{candidate}"
    out, k = candidate, 1
    while out in taken or out in _RESERVED:
        out = f"{candidate}_{k}"
        k += 1
    taken.add(out)
    return out


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
    expr = sp.sympify(expr)
    if expr.is_Atom:
        return expr
    expm1_opt, log1p_opt = optims_c99[:2]
    optims = []
    if expr.has(sp.exp):
        optims.append(expm1_opt)
    if expr.has(sp.log):
        optims.append(log1p_opt)
    if any(p.exp in (sp.S.Half, -sp.S.Half) for p in expr.atoms(sp.Pow)):
        optims.append(_hypot_opt)
    return optimize(expr, optims) if optims else expr


def _float_literal(value: sp.Expr) -> str:
    x = float(value)
    if x != x or x in (float("inf"), float("-inf")):
        raise ValueError(f"constant {value} is not a finite float64")
    s = repr(x)
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

    def _product(self, base: sp.Expr, k: int) -> str:
        """``(b*b*...)``, parenthesised: the Mul printer writes ``1.0/`` before a power in
        a denominator without parentheses, and ``1.0/y*y`` would mean ``(1/y)*y``."""
        b = self.parenthesize(base, 50)  # type: ignore[attr-defined]
        return b if k == 1 else "(" + "*".join([b] * k) + ")"

    def _print_Pow(self, expr: sp.Pow) -> str:
        b, e = expr.base, expr.exp
        if e.is_Integer and 1 <= abs(int(e)) <= 4:
            body = self._product(b, abs(int(e)))
            return body if e > 0 else f"(1.0/{body})"
        if e == sp.S.Half:
            return f"{self._sqrt}({self._print(b)})"  # type: ignore[attr-defined]
        if e == -sp.S.Half:
            return f"(1.0/{self._sqrt}({self._print(b)}))"  # type: ignore[attr-defined]
        if e.is_Rational and e.q == 2 and abs(e.p) <= 7:
            k = abs(int(e.p)) // 2
            root = f"{self._sqrt}({self._print(b)})"  # type: ignore[attr-defined]
            factors = [root] + [self.parenthesize(b, 50)] * k  # type: ignore[attr-defined]
            body = "(" + "*".join(factors) + ")"
            return body if e > 0 else f"(1.0/{body})"
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
