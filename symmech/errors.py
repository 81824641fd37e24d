"""Exceptions raised by symmech.

Every error names the object it is about and the reason, so a user can act on it.
All inherit from :class:`SymmechError`; those caused by bad input are also
``ValueError`` subclasses.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

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


@dataclass(frozen=True)
class Problem:
    """One problem of a declaration.

    ``message`` is the full text (it names the object and the reason); ``field`` the input
    it is about, as a path into the declaration (``"metric"``, ``"constraints[1]"``,
    ``"walls[0].psi"``, ``"walls[0].impulsive_constraints[1]"``), None when it is about
    the scene as a whole; ``label`` how the message names that field when it differs from
    the path (``"walls[0] ('floor').psi"``).  A scene file locates the problem by looking
    its field up, and shows :attr:`reason`.
    """

    message: str
    field: str | None = None
    label: str | None = None

    def __str__(self) -> str:
        return self.message

    @property
    def reason(self) -> str:
        """The message without its leading ``label:`` (the whole message when it does not
        start that way: ``walls[0].psi = x does not ...`` reads better whole)."""
        label = self.label or self.field
        if label and self.message.startswith(label + ":"):
            return self.message[len(label) + 1 :].strip()
        return self.message


class SceneError(SymmechError, ValueError):
    """A scene declaration is invalid.

    ``problems`` lists every problem found (validation collects them all before raising);
    the message holds one line per problem, each naming the object and the reason.
    ``records`` holds the same problems as :class:`Problem` records (with their field).
    """

    def __init__(self, problems: Iterable[str | Problem] | str | Problem):
        if isinstance(problems, str | Problem):
            problems = [problems]
        self.records: list[Problem] = [
            p if isinstance(p, Problem) else Problem(str(p)) for p in problems
        ]
        self.problems: list[str] = [p.message for p in self.records]
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
