"""The common-subexpression elimination of generated functions, shared by a scene's.

:class:`Memo` is kept for one :func:`symmech.codegen.generate.generate` call: the
functions of a scene share their entries (the metric and the forcing recur in every
solve), so each entry is rewritten and folded for printing once (:meth:`Memo.printable`:
:func:`~symmech.codegen.printers.safe_rewrite`, then
:func:`~symmech.codegen.printers.fold_numbers`), one :func:`sympy.cse` runs per distinct
list of entries (:meth:`Memo.eliminated`), after which the compound base of a power
printed as a product (``(a + b)**3``) gets a temporary of its own, so it is evaluated once
(:func:`_name_power_bases`), and each expression is printed once per printer.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import sympy as sp

from symmech.algebra.opcount import count_ops
from symmech.codegen.printers import fold_numbers, product_power, safe_rewrite

if TYPE_CHECKING:
    from symmech.codegen.lower import Names

__all__ = ["Memo", "NotFinite", "eliminate", "operations"]


def _name_power_bases(
    replacements: list[tuple[sp.Symbol, sp.Expr]],
    exprs: list[sp.Expr],
    symbols: Iterator[sp.Symbol],
) -> tuple[list[tuple[sp.Symbol, sp.Expr]], list[sp.Expr]]:
    """Give the compound base of every power printed as a product a temporary, placed
    just before its first use, so ``(a + b)**3`` evaluates ``a + b`` once."""
    named: dict[sp.Expr, sp.Symbol] = {}
    pending: list[tuple[sp.Symbol, sp.Expr]] = []
    seen: dict[sp.Expr, sp.Expr] = {}  # subtree -> its rewrite (named bases stay named)

    def visit(e: sp.Expr) -> sp.Expr:
        if e.is_Atom:
            return e
        hit = seen.get(e)
        if hit is None:
            hit = seen[e] = rewrite(e)
        return hit

    def rewrite(e: sp.Expr) -> sp.Expr:
        args = tuple(visit(a) for a in e.args)
        if args != e.args:
            e = e.func(*args)
        if (
            e.is_Pow
            and not e.base.is_Atom
            and product_power(e.exp)
            and e.exp not in (sp.S.Half, -sp.S.Half, sp.S.NegativeOne)
        ):
            if e.base not in named:
                named[e.base] = next(symbols)
                pending.append((named[e.base], e.base))
            e = sp.Pow(named[e.base], e.exp)
        return e

    out: list[tuple[sp.Symbol, sp.Expr]] = []
    for s, e in replacements:
        e = visit(e)
        out.extend(pending)
        pending.clear()
        out.append((s, e))
    new_exprs = [visit(e) for e in exprs]
    out.extend(pending)
    return out, new_exprs


class Memo:
    """What the functions of one generated scene share, computed once per ``generate``
    call: each entry as it is printed (:meth:`printable`) and the CSE of each distinct
    list of entries (:meth:`eliminated`; ``acceleration`` and ``multipliers`` solve the
    same system), and the text of each expression a backend's printer printed
    (:meth:`texts`).  Scoped to the call, so nothing outlives the code it served."""

    def __init__(self) -> None:
        self._printable: dict[sp.Expr, sp.Expr] = {}
        self._folded: dict[sp.Expr, sp.Expr] = {}  # fold_numbers's, shared by the entries
        self._eliminated: dict[tuple[sp.Expr, ...], _Elimination] = {}
        self._texts: dict[tuple[object, int], tuple[Names, dict[sp.Expr, str]]] = {}

    def texts(self, make_printer: object, names: Names) -> dict[sp.Expr, str]:
        """The printed text of each expression, for one printer maker and table of names:
        a temporary prints as its name, so an expression's text is the same in every
        function of the scene (``multipliers`` prints the temporaries of
        ``acceleration`` again)."""
        key = (make_printer, id(names))
        hit = self._texts.get(key)
        if hit is None or hit[0] is not names:
            hit = self._texts[key] = (names, {})
        return hit[1]

    def printable(self, e: sp.Expr) -> sp.Expr:
        """An entry as it is printed: :func:`~symmech.codegen.printers.safe_rewrite`,
        then :func:`~symmech.codegen.printers.fold_numbers`.  Raises :class:`NotFinite`
        for an entry holding ``zoo``, ``nan`` or an infinity, and the ``ValueError`` of
        the folding."""
        hit = self._printable.get(e)
        if hit is None:
            r = safe_rewrite(e)
            if r.has(sp.zoo, sp.nan, sp.oo, -sp.oo):
                raise NotFinite(r)
            hit = self._printable[e] = fold_numbers(r, self._folded)
        return hit

    def eliminated(self, entries: tuple[sp.Expr, ...]) -> _Elimination:
        """The temporaries and reduced entries of one CSE over ``entries`` (``tmp0``,
        ``tmp1``, ... in canonical order), the compound bases of powers printed as
        products named (:func:`_name_power_bases`), and ``sympy.count_ops`` of the
        result (the figure in a function's header)."""
        hit = self._eliminated.get(entries)
        if hit is None:
            symbols = sp.numbered_symbols("tmp", real=True)
            replacements, reduced = sp.cse(list(entries), symbols=symbols, order="canonical")
            named, exprs = _name_power_bases(replacements, reduced, symbols)
            hit = self._eliminated[entries] = _Elimination(
                tuple(named), tuple(exprs), operations(named, exprs)
            )
        return hit


class NotFinite(Exception):
    """An entry holds ``zoo``, ``nan`` or an infinity (the rewritten entry is its
    argument)."""


@dataclass(frozen=True)
class _Elimination:
    replacements: tuple[tuple[sp.Symbol, sp.Expr], ...]
    reduced: tuple[sp.Expr, ...]
    ops: int


def operations(
    replacements: Sequence[tuple[sp.Symbol, sp.Expr]], reduced: Sequence[sp.Expr]
) -> int:
    """``sympy.count_ops`` of the temporaries and of the reduced entries
    (:func:`symmech.algebra.opcount.count_ops`, the same integer)."""
    memo: dict = {}
    return sum(count_ops(e, memo) for _, e in replacements) + sum(
        count_ops(e, memo) for e in reduced if not e.is_number
    )


def eliminate(
    entries: list[sp.Expr], cse: bool, memo: Memo
) -> tuple[tuple[tuple[sp.Symbol, sp.Expr], ...], list[sp.Expr], int]:
    """The temporaries of one CSE over the entries that are not numbers
    (:meth:`Memo.eliminated`; none with ``cse=False``), every entry in terms of them, and
    the operations of both."""
    nonconst = [i for i, e in enumerate(entries) if not e.is_number]
    if cse and nonconst:
        done = memo.eliminated(tuple(entries[i] for i in nonconst))
        replacements, reduced, ops = done.replacements, done.reduced, done.ops
    else:
        replacements, reduced = (), tuple(entries[i] for i in nonconst)
        ops = operations(replacements, reduced)
    final = list(entries)
    for i, e in zip(nonconst, reduced, strict=True):
        final[i] = e
    return replacements, final, ops
