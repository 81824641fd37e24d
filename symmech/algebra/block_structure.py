"""Diagonal blocks of a square matrix: the connected components of its non-zero pattern.

A matrix whose rows and columns can be permuted into a block-diagonal form is solved,
inverted and sized block by block; :func:`diagonal_blocks` finds the blocks (union-find
over the pattern, near-linear in the number of non-zero entries).
"""

from __future__ import annotations

from collections.abc import Callable

__all__ = ["diagonal_blocks"]


def diagonal_blocks(n: int, linked: Callable[[int, int], bool]) -> list[list[int]]:
    """The index sets of the diagonal blocks of an n x n pattern, sorted (each sorted):
    ``i`` and ``j`` are in one block when ``linked(i, j)`` or ``linked(j, i)``, or through
    a chain of such links."""
    parent = list(range(n))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i in range(n):
        for j in range(n):
            if i != j and linked(i, j):
                parent[find(i)] = find(j)
    groups: dict[int, list[int]] = {}
    for i in range(n):
        groups.setdefault(find(i), []).append(i)
    return sorted(groups.values())
