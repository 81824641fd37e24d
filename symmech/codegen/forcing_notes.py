"""The note of generated code on the forcing's velocity-quadratic part.

``f_k = -omega_kij v^i v^j - u_k(V)`` (Christoffel symbols Gamma_kij in coordinates):
:func:`forcing_notes` counts the coefficients (k, i <= j) that are identically zero, so
never computed, for the ``omitted`` list of :func:`symmech.codegen.generate`.

A term of f already written as ``c * v^i * v^j`` (c free of the velocities) is read as
it stands.  Any other term (an imported model's forcing holds products of sums of
velocities with trigonometric coefficients) is expanded in the velocities only: each of
its largest velocity-free parts is first replaced by a symbol (:class:`_Skeleton`), and
the result is multiplied out in sympy's sparse polynomial ring (``sympy.polys.rings``),
so the coefficients are never expanded themselves.  Monomials that cancel in the
expression cancel there too (the same symbol stands for the same part); a cancellation
that needs the parts' own algebra (sin^2 + cos^2 = 1) goes unseen, so the count is of
the coefficients zero as written.  A velocity inside a non-polynomial part (``sin(v)``,
``1/(1 + v)``), or a term whose expansion would exceed
:data:`symmech.algebra.budget.NOTE_EXPAND_TERMS` terms, counts every pair of its
velocities as present, and the note then says "at least".
"""

from __future__ import annotations

from collections.abc import Collection, Sequence

import sympy as sp
from sympy.polys.rings import ring

from symmech.algebra import budget as limits

__all__ = ["forcing_notes"]


class _Skeleton:
    """An expression with its largest velocity-free parts, and its non-polynomial parts
    that hold velocities, each replaced by a symbol (one per distinct part).
    ``carried[symbol]`` is the set of velocities a non-polynomial part holds."""

    def __init__(self, velocities: Collection[sp.Symbol]) -> None:
        self._v = set(velocities)
        self._parts: dict[sp.Basic, sp.Dummy] = {}
        self._memo: dict[sp.Basic, tuple[sp.Basic, bool]] = {}
        self.carried: dict[sp.Symbol, frozenset[sp.Symbol]] = {}

    def __call__(self, e: sp.Basic) -> sp.Basic:
        out, moving = self._visit(e)
        return out if moving else self._part(e)

    def _part(self, e: sp.Basic) -> sp.Basic:
        # symbols and rational or float numbers stay (the ring's generators and its
        # coefficients, so 0.25 and -0.25 cancel); any other part, pi or I included,
        # becomes a symbol
        keep = e.is_Symbol or e.is_Rational or e.is_Float
        return e if keep else self._parts.setdefault(e, sp.Dummy())

    def _visit(self, e: sp.Basic) -> tuple[sp.Basic, bool]:
        hit = self._memo.get(e)
        if hit is not None:
            return hit
        if e.is_Atom:
            out = (e, e in self._v) if e.is_Symbol or e.is_Number else (self._part(e), False)
        else:
            parts = [self._visit(a) for a in e.args]
            if not any(moving for _, moving in parts):
                out = (e, False)
            elif e.is_Add or e.is_Mul or (e.is_Pow and e.exp.is_Integer and e.exp > 0):
                out = (e.func(*[a if moving else self._part(a) for a, moving in parts]), True)
            else:  # velocities inside a function or a denominator: one opaque part
                symbol = self._part(e)
                self.carried[symbol] = frozenset(e.free_symbols & self._v)
                out = (symbol, True)
        self._memo[e] = out
        return out


def _pairs(indices: Sequence[int]) -> set[tuple[int, int]]:
    return {(a, b) for a in indices for b in indices if a <= b}


def _quadratic_pairs(
    term: sp.Expr, index: dict[sp.Symbol, int], skeleton: _Skeleton
) -> tuple[set[tuple[int, int]], bool]:
    """The pairs (i <= j) whose coefficient of v^i v^j in ``term`` is not zero as
    written, and whether that set is only a bound (every pair of some velocities)."""
    shape = skeleton(term)
    everything = sorted(index[s] for s in term.free_symbols & index.keys())
    if limits.expanded_terms(shape, limits.NOTE_EXPAND_TERMS + 1)[0] > limits.NOTE_EXPAND_TERMS:
        return _pairs(everything), True
    velocities = sorted(shape.free_symbols & index.keys(), key=index.__getitem__)
    others = sorted(shape.free_symbols - index.keys(), key=sp.default_sort_key)
    R, *_ = ring([*velocities, *others], sp.QQ)
    carried = [skeleton.carried.get(s) for s in others]
    found: set[tuple[int, int]] = set()
    bounded = False
    for monomial in R.from_expr(shape).monoms():
        idx = [index[s] for s, p in zip(velocities, monomial, strict=False) for _ in range(p)]
        held = [c for c, p in zip(carried, monomial[len(velocities) :], strict=True) if p and c]
        if held:
            bounded = True
            moving = set(idx).union(*[[index[s] for s in c] for c in held])
            found |= _pairs(sorted(moving))
        elif len(idx) == 2:
            found.add((idx[0], idx[1]))
    return found, bounded


def _plain_pair(term: sp.Expr, index: dict[sp.Symbol, int]) -> tuple[int, ...] | None:
    """The velocity indices of ``term`` written as ``c * v^i * v^j...`` (c free of the
    velocities), or None when a velocity sits inside another factor."""
    idx: list[int] = []
    for factor in sp.Mul.make_args(term):
        base, power = factor.as_base_exp()
        if base in index and power.is_Integer and power > 0:
            idx += [index[base]] * int(power)
        elif factor.free_symbols & index.keys():
            return None
    return tuple(sorted(idx))


def forcing_notes(f: sp.Matrix, v: Sequence[sp.Symbol], frame: bool) -> list[str]:
    """What the forcing does not compute: the identically zero coefficients of its
    velocity-quadratic part (Gamma_kij, or the connection coefficients omega_kij in a
    frame, symmetrised in i, j: only the symmetric part enters f) and its zero entries."""
    n = len(v)
    index = {s: i for i, s in enumerate(v)}
    total = n * n * (n + 1) // 2
    skeleton = _Skeleton(index.keys())
    present: set[tuple[int, int, int]] = set()
    bounded = False
    for k, e in enumerate(f):
        for term in sp.Add.make_args(e):
            plain = _plain_pair(term, index)
            if plain is None:
                found, bound = _quadratic_pairs(term, index, skeleton)
                present.update((k, a, b) for a, b in found)
                bounded = bounded or bound
            elif len(plain) == 2:
                present.add((k, *plain))
    what = "connection coefficients omega_k(ij)" if frame else "Christoffel symbols Gamma_k(ij)"
    notes = [
        f"forcing: {'at least ' if bounded else ''}{total - len(present)} of the {total} {what}"
        " (symmetrised in i, j) are identically zero and are never computed"
    ]
    zeros = [k for k, e in enumerate(f) if e == 0]
    if zeros:
        notes.append(
            f"forcing: entries {zeros} are identically zero (no velocity or potential term);"
            " they are stored as 0.0 without computation"
        )
    return notes
