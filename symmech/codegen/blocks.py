"""The pieces a function plan is made of: named blocks of expressions, the generated names
of the walls' functions, and the error type of code generation."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import sympy as sp

from symmech.codegen.printers import identifier
from symmech.errors import SymmechError

__all__ = [
    "BATCH_SUFFIX",
    "WALL_PREFIXES",
    "Block",
    "CodegenError",
    "matrix_block",
    "scalar_block",
    "vector_block",
    "wall_function_name",
    "wall_ids",
]

#: Prefixes of the per-wall functions (see :mod:`symmech.codegen.plan` for why they are
#: prefix-free).
WALL_PREFIXES = {"psi": "psi_", "dpsi": "dpsi_", "psi_t": "psit_", "impact": "impact_"}
#: Suffix of the C batch form of every function.
BATCH_SUFFIX = "_batch"


class CodegenError(SymmechError, ValueError):
    """Code cannot be generated as asked (bad option, unsupported expression, ...)."""


@dataclass(frozen=True)
class Block:
    """A named array of expressions: ``shape`` (), (k,) or (r, c); ``entries`` row-major."""

    name: str
    shape: tuple[int, ...]
    entries: tuple[sp.Expr, ...]

    @property
    def size(self) -> int:
        return len(self.entries)


def matrix_block(name: str, M: sp.MatrixBase) -> Block:
    """A matrix block, always two-dimensional (a 1 x 1 metric stays (1, 1))."""
    M = sp.Matrix(M)
    return Block(name, (M.rows, M.cols), tuple(M))


def vector_block(name: str, x: sp.MatrixBase | Sequence[sp.Expr]) -> Block:
    """A vector block of shape (k,), from a column, a row or a sequence."""
    entries = tuple(x)
    return Block(name, (len(entries),), entries)


def scalar_block(name: str, e: sp.Expr) -> Block:
    """A scalar block of shape ()."""
    return Block(name, (), (sp.sympify(e, strict=True),))


def wall_ids(names: Sequence[str]) -> tuple[str, ...]:
    """Sanitised, unique identifiers for wall names (module docstring), by index."""
    taken: set[str] = set()
    out = []
    for name in names:
        wid = identifier(name, "", taken, part=True)
        if wid == BATCH_SUFFIX[1:] or wid.endswith(BATCH_SUFFIX):
            taken.discard(wid)
            wid = identifier(wid + "_w", "", taken, part=True)
        out.append(wid)
    return tuple(out)


def wall_function_name(kind: str, wall_id: str) -> str:
    """The generated name of the ``kind`` function (psi, dpsi, psi_t, impact) of a wall."""
    return WALL_PREFIXES[kind] + wall_id
