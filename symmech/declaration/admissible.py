"""What an expression of a scene may hold, judged from its tree alone.

Christoffel symbols, gradients and impact maps differentiate every field, validation
evaluates them at sample points and code generation prints them as C and NumPy: a field is
therefore built from

* numbers, ``pi``, ``E`` and the other real constants of sympy (``EulerGamma``), symbols;
* ``+``, ``*``, ``**`` (``sqrt`` is a power);
* the elementary functions of :data:`ELEMENTARY_FUNCTIONS` (trigonometric and hyperbolic
  functions and their inverses, ``exp``, ``log``, ``atan2``): analytic where defined, with
  elementary derivatives, and printed by every backend;
* undefined functions ``sympy.Function("g")(x)`` and their derivatives (unknown smooth
  real functions).

:func:`expression_problems` names whatever else a field holds: special functions
(``zeta``, ``gamma``, ``besselj``, ``LambertW``, ``polylog``, ``hyper``, ...), whose
derivatives sympy may not know (``zeta(x)`` differentiated raises a raw sympy
``ArgumentIndexError`` whose ``str()`` itself raises) and whose real domain symmech cannot
check; unevaluated operations (``Integral``, ``Sum``, ``Subs``, a ``Derivative`` of
anything but an undefined function); the imaginary unit ``I`` and symbols declared
non-real (a field is real); infinite
or undefined values (``oo``, ``zoo``, ``nan``); and constants outside float64 after sympy
merged them (:mod:`symmech.declaration.constants`).  Non-smooth functions (:data:`NON_SMOOTH`:
``Abs``, ``Piecewise``, ...) are reported on their own by the declaration.

An unknown smooth function can stand for a special one: ``G = sympy.Function("G",
positive=True)`` and ``G(x)`` in the potential gives the equations in terms of ``G`` and
its derivatives, and generated code takes their values as inputs.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

import sympy as sp
from sympy.core.function import AppliedUndef

from symmech.declaration.constants import constant_out_of_range

__all__ = ["ELEMENTARY_FUNCTIONS", "NON_SMOOTH", "expression_problems"]

#: The functions a scene's fields may call (besides undefined functions).
ELEMENTARY_FUNCTIONS: tuple[type, ...] = (
    sp.sin,
    sp.cos,
    sp.tan,
    sp.cot,
    sp.sec,
    sp.csc,
    sp.asin,
    sp.acos,
    sp.atan,
    sp.acot,
    sp.atan2,
    sp.sinh,
    sp.cosh,
    sp.tanh,
    sp.coth,
    sp.sech,
    sp.csch,
    sp.asinh,
    sp.acosh,
    sp.atanh,
    sp.exp,
    sp.log,
)

#: Functions that make an expression non-smooth; refused everywhere in a scene, because
#: Christoffel symbols, gradients and impact maps need derivatives.
NON_SMOOTH = (
    sp.Abs,
    sp.sign,
    sp.Piecewise,
    sp.Heaviside,
    sp.floor,
    sp.ceiling,
    sp.Max,
    sp.Min,
    sp.frac,
    sp.Mod,
    sp.DiracDelta,
    sp.re,
    sp.im,
    sp.arg,
)

_NOT_FINITE = frozenset((sp.oo, -sp.oo, sp.zoo, sp.nan))  # by hash: an atom is compared once


def _name(node: sp.Basic) -> str:
    """The name of a node's class, never its ``str()`` (which may itself raise)."""
    return getattr(type(node), "__name__", "an object")


def expression_problems(expr: sp.Basic | sp.MatrixBase, skip: Iterable[type] = ()) -> list[str]:
    """Phrases naming what ``expr`` holds that a scene's field may not (see the module
    docstring), empty when nothing; classes in ``skip`` (the non-smooth functions, reported
    elsewhere) are passed over with their arguments.  One walk of the tree, each shared
    subtree once; nothing is evaluated but the float64 value of constants.

    >>> import sympy as sp
    >>> x = sp.Symbol("x", real=True)
    >>> expression_problems(sp.zeta(x) + sp.I * x)
    ['is not real: it holds the imaginary unit I', 'calls zeta, which symmech does not support (not an elementary function: sin, cos, ..., exp, log, atan2 and their kin; an undefined sympy.Function can stand for it)']
    >>> expression_problems(sp.sin(x) ** 2 + sp.Function("g")(x))
    []
    """  # noqa: E501
    entries = list(expr) if isinstance(expr, sp.MatrixBase) else [expr]
    cols = expr.cols if isinstance(expr, sp.MatrixBase) else 0

    def where(k: int) -> str:
        """``entry [i,j] = ...: `` for a matrix (the first entry the problem was seen in)."""
        return f"entry [{k // cols},{k % cols}] = {_short(entries[k])}: " if cols else ""

    found, ranged = _walk(entries, tuple(skip))
    out = _phrases(found, where)
    if out:
        return out
    for k, e in enumerate(entries):
        # sympy merges small rationals into a small rational; anything else is judged
        bad = constant_out_of_range(e) if k in ranged else None
        if bad is not None:
            what = (
                f"the constant {_short(bad.constant)}"
                if bad.context == bad.constant
                else f"the coefficient {_short(bad.constant)} (of {_short(bad.context)},"
                " as sympy merged it)"
            )
            return [f"{where(k)}holds {what}, {bad.reason}"]
    return []


#: What :func:`_walk` found: kind -> (the first entry it was seen in, the names found).
_Found = dict[str, tuple[int, dict[str, None]]]


def _walk(entries: list, skip: tuple[type, ...]) -> tuple[_Found, set[int]]:
    """One walk of ``entries`` (each shared subtree once): what they hold that a field may
    not, by kind (``imaginary``, ``nonreal``, ``infinite``, ``unsupported``,
    ``unevaluated``), and the entries holding constants other than small rationals (to be
    judged by :func:`constant_out_of_range`)."""
    found: _Found = {}
    seen: set[sp.Basic] = set()
    ranged: set[int] = set()

    def note(kind: str, k: int, name: str = "") -> None:
        found.setdefault(kind, (k, {}))[1][name] = None

    for k, entry in enumerate(entries):
        stack = [entry] if isinstance(entry, sp.Basic) else []
        while stack:
            e = stack.pop()
            if e in seen:
                continue
            seen.add(e)
            if skip and isinstance(e, skip):
                continue
            if e.is_Atom:
                _atom(e, k, note, ranged)
            elif isinstance(e, sp.Derivative):
                if not isinstance(e.expr, AppliedUndef):
                    note("unevaluated", k, "Derivative (of a known expression)")
            elif (
                isinstance(e, (AppliedUndef, *ELEMENTARY_FUNCTIONS))
                or e.is_Add
                or e.is_Mul
                or e.is_Pow
            ):
                if sum(a.is_Number for a in e.args) >= (1 if e.is_Function else 2):
                    ranged.add(k)  # exp(709), 2**2000 or 10*10 left unevaluated
                stack.extend(e.args)
            elif isinstance(e, sp.Integral | sp.Sum | sp.Product | sp.Subs | sp.Limit | sp.Order):
                note("unevaluated", k, _name(e))
            else:
                note("unsupported", k, _name(e))
    return found, ranged


def _atom(e: sp.Basic, k: int, note: Callable[..., None], ranged: set[int]) -> None:
    """An atom of entry ``k``: the imaginary unit, an infinity, an unsupported atom or a
    symbol declared non-real is noted; a constant other than a small rational marks the
    entry to be judged for its range (merged constants may leave float64)."""
    if e is sp.I:
        note("imaginary", k)
    elif e in _NOT_FINITE:
        note("infinite", k)
    elif not (e.is_Symbol or e.is_Number or e.is_NumberSymbol):
        note("unsupported", k, _name(e))
    elif e.is_Symbol and e.is_extended_real is False:
        note("nonreal", k, _short(e))
    elif not e.is_Symbol and not _small_rational(e):
        ranged.add(k)  # a float, pi, a large rational


def _phrases(found: _Found, where: Callable[[int], str]) -> list[str]:
    """The phrase of each kind :func:`_walk` found, in a fixed order, each naming the
    first entry it was seen in (``where``)."""
    out = []
    if "imaginary" in found:
        out.append(f"{where(found['imaginary'][0])}is not real: it holds the imaginary unit I")
    if "nonreal" in found:
        k, names = found["nonreal"]
        out.append(
            f"{where(k)}is not real: it holds symbols declared non-real ({', '.join(names)},"
            " e.g. imaginary=True); a scene's symbols are real"
        )
    if "infinite" in found:
        out.append(
            f"{where(found['infinite'][0])}holds an infinite or undefined value (oo, zoo or"
            " nan); it cannot be checked or evaluated"
        )
    if "unsupported" in found:
        k, names = found["unsupported"]
        out.append(
            f"{where(k)}calls {', '.join(names)}, which symmech does not support (not an"
            " elementary function: sin, cos, ..., exp, log, atan2 and their kin; an undefined"
            " sympy.Function can stand for it)"
        )
    if "unevaluated" in found:
        k, names = found["unevaluated"]
        out.append(
            f"{where(k)}holds an unevaluated {', '.join(names)}; write the expression it"
            " stands for (or an undefined sympy.Function)"
        )
    return out


def _small_rational(e: sp.Basic) -> bool:
    """A rational whose numerator and denominator are below 2^64 (merging such numbers by
    products and powers within the parser's limits stays inside float64)."""
    return bool(e.is_Rational) and max(int(e.p).bit_length(), int(e.q).bit_length()) <= 64


def _short(expr: object, limit: int = 50) -> str:
    if not isinstance(expr, sp.Basic):
        return type(expr).__name__
    if expr.is_Rational and not expr.is_Integer:
        return f"{_short(sp.Integer(expr.p))}/{_short(sp.Integer(expr.q))}"
    if expr.is_Integer and abs(int(expr)).bit_length() > 160:
        digits = len(str(abs(int(expr))))
        return f"{'-' if expr < 0 else ''}(an integer of {digits} digits)"
    try:
        s = str(expr)
    except Exception:  # a printer error of a sympy object must not hide the problem
        return type(expr).__name__
    return s if len(s) <= limit else s[: limit - 3] + "..."
