"""Exceptions raised by symmech.

Every error names the object it is about and the reason, so a user can act on it.
All inherit from :class:`SymmechError`; those caused by bad input are also
``ValueError`` subclasses.
"""

from __future__ import annotations

from collections.abc import Iterable

__all__ = [
    "ExpressionError",
    "ImpactError",
    "SceneError",
    "SymmechError",
    "SymmechWarning",
    "UndecidedWarning",
]


class SymmechError(Exception):
    """Base class of every exception raised by symmech."""


class ExpressionError(SymmechError, ValueError):
    """An expression (or expression string) was refused.

    The message names the field, the position and the offending token when known.
    """


class SceneError(SymmechError, ValueError):
    """A scene declaration is invalid.

    ``problems`` lists every problem found (validation collects them all before raising);
    the message holds one line per problem, each naming the object and the reason.
    """

    def __init__(self, problems: Iterable[str] | str):
        if isinstance(problems, str):
            problems = [problems]
        self.problems: list[str] = list(problems)
        if len(self.problems) == 1:
            message = self.problems[0]
        else:
            message = f"{len(self.problems)} problems in the scene:\n" + "\n".join(
                f"  - {p}" for p in self.problems
            )
        super().__init__(message)


class ImpactError(SymmechError, ValueError):
    """An impact map cannot be derived (degenerate wall, dependent constraints, ...)."""


class SymmechWarning(UserWarning):
    """Base class of every warning issued by symmech."""


class UndecidedWarning(SymmechWarning):
    """A property of a declaration that symmech could neither prove nor refute.

    The declaration is accepted; the message names the object, the property, what was
    checked (proofs tried, points searched) and what is left undecided.
    """
