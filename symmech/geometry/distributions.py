"""Distributions spanned by vector fields: Frobenius involutivity and the bracket rank.

* "Constrained mechanical system" (Frobenius integrability condition, slides 000): a
  distribution spanned by ``X_1 .. X_k`` is integrable (holonomic) iff it is closed under
  the bracket (:func:`symmech.geometry.lie.lie_bracket`).

Generic rank policy (:data:`GENERIC_RANK_POLICY`): ranks of fields with non-constant
components are *generic* ranks, the rank at points off a measure-zero set.  Each rank is
computed twice: symbolically (exact linear algebra on the entries, simplified first when
``simplify=True``) and numerically (the largest rank, :mod:`symmech.algebra.rank`, over a few
reproducible random rational sample points, see :mod:`symmech.algebra.sampling`).
The numeric rank at a random point equals the generic rank with probability one, whereas
the symbolic rank is too large when sympy fails to recognise a zero (e.g. an unsimplified
``sin^2 + cos^2 - 1``).  So the numeric rank decides when it is available; disagreements
are reported in the result's ``notes``.  When the entries cannot be evaluated to numbers
(undefined functions), the symbolic rank is used alone and a note says so.  Matrix-valued
fields are sampled at generic points of the ambient matrix space (not of the submanifold).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import sympy as sp

from symmech.algebra.simplification import Level
from symmech.errors import SceneError
from symmech.geometry.lie import Field, _bracket, _coords, _fields, _shaped
from symmech.geometry.span_rank import (
    GENERIC_RANK_POLICY,
    Point,
    _generic_rank,
    _note,
    _points_arg,
    _sample,
)

__all__ = [
    "GENERIC_RANK_POLICY",
    "BracketRankResult",
    "InvolutivityResult",
    "bracket_rank",
    "is_involutive",
]

# ---------------------------------------------------------------------------- Frobenius


@dataclass(frozen=True)
class InvolutivityResult:
    """Outcome of the Frobenius test (slides 000, "Frobenius integrability condition").

    Truthy iff the distribution is involutive.  When it is not, ``pair = (i, j)`` and
    ``bracket = [X_i, X_j]`` (in the layout of the fields) certify it: the bracket is not in
    the span of the fields at generic points.  ``rank`` is the generic rank of the span.
    """

    involutive: bool
    rank: int
    dimension: int
    pair: tuple[int, int] | None = None
    bracket: sp.ImmutableMatrix | None = None
    notes: tuple[str, ...] = ()
    policy: str = field(default=GENERIC_RANK_POLICY, repr=False)

    def __bool__(self) -> bool:
        return self.involutive

    def _repr_latex_(self) -> str:
        if self.involutive:
            return f"$\\text{{involutive (rank {self.rank} of {self.dimension})}}$"
        i, j = self.pair or (0, 0)
        return (
            f"$\\text{{not involutive: }} [X_{{{i}}}, X_{{{j}}}] = {sp.latex(self.bracket)}"
            f" \\notin \\operatorname{{span}}\\{{X\\}}$"
        )


def is_involutive(
    fields: Sequence[Field],
    q: Any,
    *,
    simplify: bool = True,
    points: Iterable[Point] | None = None,
) -> InvolutivityResult:
    """Whether ``span{X_1 .. X_k}`` is closed under the Lie bracket (Frobenius).

    Slides 000, "Constrained mechanical system": the distribution is (locally) integrable,
    i.e. a holonomic constraint, iff ``[X_i, X_j] in span{X_1 .. X_k}`` for all i < j.
    Membership is tested as ``rank [X_1 .. X_k, [X_i, X_j]] == rank [X_1 .. X_k]`` with
    generic ranks (:data:`GENERIC_RANK_POLICY`).  Matrix-valued fields are flattened.

    Args:
        fields: the vector fields (layout as in :func:`lie_bracket`).
        q: the coordinates (sequence of symbols, or matrix of symbols).
        simplify: simplify entries before the symbolic rank and simplify the certificate.
        points: sample points ``{symbol: value}`` for the numeric check (default: three
            reproducible random rational points over all free symbols).  Pass points on a
            submanifold (e.g. rotations) to test there.

    Returns:
        An :class:`InvolutivityResult` (truthy iff involutive).
    """
    where = "is_involutive"
    cs = _coords(q, where)
    Xs = _fields(fields, cs, where)
    pts = _points_arg(points, where)
    level: Level = "light" if simplify else "none"
    sample = _sample(Xs, pts)
    base = _generic_rank(Xs, sample, simplify)
    notes = _note("rank of the fields", base)
    for i in range(len(Xs)):
        for j in range(i + 1, len(Xs)):
            Z = _bracket(Xs[i], Xs[j], cs.symbols, level)
            if all(e == 0 for e in Z):
                continue
            ext = _generic_rank([*Xs, Z], _sample([*Xs, Z], pts), simplify)
            notes += _note(f"rank with [X_{i}, X_{j}]", ext)
            if ext.rank > base.rank:
                return InvolutivityResult(
                    involutive=False,
                    rank=base.rank,
                    dimension=cs.n,
                    pair=(i, j),
                    bracket=sp.ImmutableMatrix(_shaped(Z, cs)),
                    notes=tuple(notes),
                )
    return InvolutivityResult(True, base.rank, cs.n, notes=tuple(notes))


# ---------------------------------------------------------------------------- bracket rank


@dataclass(frozen=True)
class BracketRankResult:
    """Generic rank of the fields and their iterated brackets up to a depth.

    ``fields`` lists the fields kept (in the layout of the input), ``words`` their brackets:
    the word ``(i,)`` is ``X_i``, ``(i, j)`` is ``[X_i, X_j]``, ``(i, j, k)`` is
    ``[X_i, [X_j, X_k]]`` (left-normed brackets span all iterated brackets).  A bracket is
    kept iff it raises the generic rank, so ``rank == len(fields)``.  ``dimension`` is the
    number of coordinates (matrix entries), ``manifold_dimension`` the ``dim`` compared with
    ``rank`` for ``bracket_generating``.
    """

    rank: int
    fields: tuple[sp.ImmutableMatrix, ...]
    words: tuple[tuple[int, ...], ...]
    depth: int
    dimension: int
    manifold_dimension: int
    bracket_generating: bool
    notes: tuple[str, ...] = ()
    policy: str = field(default=GENERIC_RANK_POLICY, repr=False)

    def _repr_latex_(self) -> str:
        words = ", ".join(_latex_word(w) for w in self.words)
        verdict = "bracket-generating" if self.bracket_generating else "not bracket-generating"
        return (
            f"$\\text{{rank {self.rank} of {self.manifold_dimension} at depth {self.depth}"
            f" ({verdict}): }} {words}$"
        )


def _latex_word(word: tuple[int, ...]) -> str:
    """``(i,) -> X_i``, ``(i, j, k) -> [X_i, [X_j, X_k]]`` (left-normed)."""
    out = f"X_{{{word[-1]}}}"
    for i in reversed(word[:-1]):
        out = f"[X_{{{i}}}, {out}]"
    return out


def bracket_rank(
    fields: Sequence[Field],
    q: Any,
    depth: int = 3,
    *,
    dim: int | None = None,
    simplify: bool = True,
    points: Iterable[Point] | None = None,
) -> BracketRankResult:
    """Generic rank of ``X_1 .. X_k`` and their iterated Lie brackets of length <= depth.

    The distribution is bracket-generating (Chow-Rashevskii: every nearby configuration is
    reachable, the non-holonomic situation of the slides 000 "car" and "rolling ball") when
    this rank equals the manifold dimension.  Brackets are built left-normed:
    level 1 is the fields, level d+1 is ``[X_i, W]`` for the fields ``X_i`` and the kept
    brackets ``W`` of level d.  A bracket that does not raise the generic rank is dropped;
    this loses nothing, since ``W = sum f_a W_a`` gives
    ``[X, W] = sum X(f_a) W_a + f_a [X, W_a]``.  Stops early once the rank reaches ``dim``.

    Args:
        fields: the vector fields (layout as in :func:`lie_bracket`).
        q: the coordinates.
        depth: maximal bracket length (1: the fields only).
        dim: manifold dimension (default: number of coordinates; for ``SO(3)`` in 3 x 3
            matrices pass ``dim=3``).
        simplify, points: as in :func:`is_involutive`.
    """
    where = "bracket_rank"
    cs = _coords(q, where)
    Xs = _fields(fields, cs, where)
    pts = _points_arg(points, where)
    if isinstance(depth, bool) or not isinstance(depth, int) or depth < 1:
        raise SceneError(f"{where}: depth must be an integer >= 1, got {depth!r}")
    if dim is None:
        dim = cs.n
    elif isinstance(dim, bool) or not isinstance(dim, int) or not 1 <= dim <= cs.n:
        raise SceneError(f"{where}: dim must be an integer in 1..{cs.n}, got {dim!r}")
    level: Level = "light" if simplify else "none"

    kept: list[sp.ImmutableMatrix] = []
    words: list[tuple[int, ...]] = []
    notes: list[str] = []
    rank = 0

    def offer(Z: sp.ImmutableMatrix, word: tuple[int, ...]) -> bool:
        nonlocal rank
        if all(e == 0 for e in Z):
            return False
        r = _generic_rank([*kept, Z], _sample([*kept, Z], pts), simplify)
        notes.extend(_note(f"rank with word {word}", r))
        if r.rank > rank:
            rank = r.rank
            kept.append(Z)
            words.append(word)
            return True
        return False

    frontier: list[tuple[sp.ImmutableMatrix, tuple[int, ...]]] = []
    for i, X in enumerate(Xs):
        if offer(X, (i,)):
            frontier.append((X, (i,)))
    for _ in range(2, depth + 1):
        if rank >= dim:
            break
        nxt = []
        for W, word in frontier:
            for i, X in enumerate(Xs):
                if word == (i,):
                    continue  # [X_i, X_i] = 0
                Z = _bracket(X, W, cs.symbols, level)
                if offer(Z, (i, *word)):
                    nxt.append((Z, (i, *word)))
                if rank >= dim:
                    break
            if rank >= dim:
                break
        frontier = nxt

    return BracketRankResult(
        rank=rank,
        fields=tuple(sp.ImmutableMatrix(_shaped(Z, cs)) for Z in kept),
        words=tuple(words),
        depth=depth,
        dimension=cs.n,
        manifold_dimension=dim,
        bracket_generating=rank >= dim,
        notes=tuple(notes),
    )
