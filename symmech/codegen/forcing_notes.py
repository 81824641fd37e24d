"""The note of generated code on the forcing's velocity-quadratic part.

``f_k = -omega_kij v^i v^j - u_k(V)`` (Christoffel symbols Gamma_kij in coordinates):
:func:`forcing_notes` counts the coefficients (k, i <= j) that are identically zero, so
never computed, for the ``omitted`` list of :func:`symmech.codegen.generate`.

A term of f already written as ``c * v^i * v^j`` (c free of the velocities) is read as
it stands.  Any other term (an imported model's forcing holds products of sums of
velocities with trigonometric coefficients) is expanded in the velocities only: each of
its largest velocity-free parts is first replaced by a symbol (:class:`_Skeleton`), and
the result is multiplied out in sympy's sparse polynomial ring (``sympy.polys.rings``) in
the velocities, over a prime field in which each part is a pseudo-random residue
(:class:`_InRing`), so the coefficients are never expanded themselves.  Monomials that
cancel in the expression cancel there too (the same residue stands for the same part; a
coefficient that does not cancel, of degree d in the parts, vanishes at the residues
with probability below d / 2^61, Schwartz-Zippel); a cancellation that needs the parts'
own algebra (sin^2 + cos^2 = 1) goes unseen, so the count is of the coefficients zero
as written.  A velocity inside a non-polynomial part (``sin(v)``, ``1/(1 + v)``), or a
term whose expansion would exceed :data:`symmech.algebra.budget.NOTE_EXPAND_TERMS` terms,
counts every pair of its velocities as present, and the note then says "at least".
"""

from __future__ import annotations

import random
from collections.abc import Collection, Sequence

import sympy as sp
from sympy.polys.rings import PolyElement, PolyRing, ring

from symmech.algebra import budget as limits
from symmech.algebra.walk import free_symbols

__all__ = ["forcing_notes"]

#: The seed of the residues of :class:`_InRing` (the note is the same on every run).
_SEED = 20261127


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
    term: sp.Expr, index: dict[sp.Symbol, int], skeleton: _Skeleton, memo: dict
) -> tuple[set[tuple[int, int]], bool]:
    """The pairs (i <= j) whose coefficient of v^i v^j in ``term`` is not zero as
    written, and whether that set is only a bound (every pair of some velocities).
    ``memo``: :func:`symmech.algebra.walk.free_symbols`'s, shared by the terms."""
    shape = skeleton(term)
    if limits.expanded_terms(shape, limits.NOTE_EXPAND_TERMS + 1)[0] > limits.NOTE_EXPAND_TERMS:
        return _pairs(sorted(index[s] for s in term.free_symbols & index.keys())), True
    symbols = free_symbols(shape, memo)
    velocities = sorted(symbols & index.keys(), key=index.__getitem__)
    moving = sorted(symbols & skeleton.carried.keys(), key=sp.default_sort_key)
    R, *elements = ring([*velocities, *moving], _FIELD)
    carried = [skeleton.carried[s] for s in moving]
    found: set[tuple[int, int]] = set()
    bounded = False
    in_ring = _InRing(R, dict(zip([*velocities, *moving], elements, strict=True)))
    for monomial in in_ring(shape):
        idx = [index[s] for s, p in zip(velocities, monomial, strict=False) for _ in range(p)]
        held = [c for c, p in zip(carried, monomial[len(velocities) :], strict=True) if p]
        if held:
            bounded = True
            found |= _pairs(sorted(set(idx).union(*[[index[s] for s in c] for c in held])))
        elif len(idx) == 2:
            found.add((idx[0], idx[1]))
    return found, bounded


#: The prime field of :class:`_InRing` (2^61 - 1).
_FIELD = sp.GF(2**61 - 1)


class _InRing:
    """The monomials of an expression in ``gens`` (the velocities and the parts that hold
    them) with a non-zero coefficient, multiplied out over the prime field ``_FIELD`` with
    every other part (velocity-free) a pseudo-random residue.  A coefficient that is zero
    as written (the same part cancels) is zero there; one that is not is a non-zero
    polynomial in the parts, zero at the residues with probability below its degree over
    2^61 (Schwartz-Zippel).  The ring's terms are monomials of the velocities only, where
    the parts as generators would be multiplied out with them."""

    def __init__(self, R: PolyRing, gens: dict[sp.Basic, PolyElement]) -> None:
        self._R, self._gens = R, gens
        self._draw = random.Random(_SEED)
        self._memo: dict[sp.Basic, PolyElement] = {}

    def __call__(self, shape: sp.Expr) -> list[tuple[int, ...]]:
        return [m for m, c in self._visit(shape).terms() if c]

    def _visit(self, e: sp.Basic) -> PolyElement:
        hit = self._memo.get(e)
        if hit is not None:
            return hit
        if e in self._gens:
            out = self._gens[e]
        elif e.is_Rational or e.is_Float:
            r = sp.Rational(e)  # (exact: a float's binary value)
            out = self._R(int(r.p) * pow(int(r.q), -1, _FIELD.mod))
        elif e.is_Add or e.is_Mul:
            parts = [self._visit(a) for a in e.args]
            out = parts[0]
            for part in parts[1:]:
                out = out + part if e.is_Add else out * part
        elif e.is_Pow and e.exp.is_Integer and e.exp > 0:
            out = self._visit(e.base) ** int(e.exp)
        else:  # a velocity-free part
            out = self._R(self._draw.randrange(1, _FIELD.mod))
        self._memo[e] = out
        return out


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
    memo: dict = {}
    present: set[tuple[int, int, int]] = set()
    bounded = False
    for k, e in enumerate(f):
        for term in sp.Add.make_args(e):
            plain = _plain_pair(term, index)
            if plain is None:
                found, bound = _quadratic_pairs(term, index, skeleton, memo)
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
