"""The refusals the import shares: a part of the model that is not smooth, and a failure
of sympy (or of symmech's algebra) while a part is read, each turned into a
:class:`~symmech.errors.SceneError` naming the model's part."""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from typing import Any

import sympy as sp
from sympy.polys.polyerrors import BasePolynomialError

from symmech.declaration.admissible import NON_SMOOTH
from symmech.errors import SceneError

__all__ = ["FAILURES", "non_smooth_in", "reading", "refuse_non_smooth"]

#: What sympy and symmech's algebra raise when an expression cannot be handled (a
#: polynomial domain that cannot be built, a missing key, a recursion too deep ...).
FAILURES: tuple[type[BaseException], ...] = (
    ValueError,
    TypeError,
    ArithmeticError,
    AttributeError,
    NotImplementedError,
    LookupError,
    RecursionError,
    BasePolynomialError,
)


def non_smooth_in(exprs: Iterable[Any]) -> list[str]:
    """The names of the non-smooth functions (``Abs``, ``sign``, ``re`` ...:
    :data:`~symmech.declaration.admissible.NON_SMOOTH`) the expressions call, sorted."""
    return sorted(
        {type(f).__name__ for e in exprs for f in sp.sympify(e, strict=True).atoms(*NON_SMOOTH)}
    )


def refuse_non_smooth(exprs: Iterable[Any], what: str, hint: str | None = None) -> None:
    """Refuse a part of the model holding a non-smooth function, naming the part ``what``
    and the functions: symmech differentiates every part (Christoffel symbols, gradients,
    impact maps).  ``hint`` says what to do (by default: write it without them)."""
    found = non_smooth_in(exprs)
    if found:
        raise SceneError(
            f"from_mechanics: {what} contains the non-smooth functions {found}; symmech"
            " needs smooth loads and kinematics: "
            + (
                hint
                or "write it without them (a smooth law such as tanh(v/eps) for sign, a"
                " square root left unsimplified)"
            )
        )


@contextmanager
def reading(kind: str, what: str) -> Iterator[None]:
    """Turn a failure of sympy (or of symmech's algebra) while reading ``what`` of the
    model into a :class:`SceneError` naming the model and that part."""
    try:
        yield
    except SceneError:
        raise
    except FAILURES as exc:
        raise SceneError(
            f"from_mechanics: {kind}: reading {what} failed ({type(exc).__name__}: {exc})"
        ) from exc
