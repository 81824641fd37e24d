"""The scene file format's constants (version, limits, keys, signs), its error type and
the helpers every part of the reader and the writer share."""

from __future__ import annotations

import difflib
import re
from collections.abc import Mapping, Sequence

import sympy as sp

from symmech.errors import ExpressionError, SceneError

#: The version of the format this module reads and writes.
FORMAT_VERSION = 1
#: Largest scene file read, in bytes.
MAX_FILE_BYTES = 1_000_000
#: Largest number of coordinates, of parameters and of functions.
MAX_NAMES = 200
#: Largest number of walls.
MAX_WALLS = 100
#: Largest number of operands, operations and calls in all the expressions of a file
#: together (the parser's nodes; each expression may use what the others left, and is
#: charged the nodes it parsed or built, whichever is more: ``y + y + ... + y`` parses to
#: many and builds few).  A text with more names, numbers and operators than are left is
#: refused before Python's parser sees it.  The cost of reading a file grows with this
#: count, not with the length of one entry: the imported Whipple bicycle is charged about
#: 76,000 (63,000 built; forcing entries of 53,000 characters); a file of MAX_FILE_BYTES
#: holds at most about 500,000.
MAX_FILE_NODES = 200_000
#: Largest number of distinct function applications (``sin(x*3)``, as written) in all the
#: expressions of a file together.  Building one costs sympy up to milliseconds (a
#: trigonometric function looks for multiples of pi), repeating one costs nothing (sympy's
#: cache): the bicycle writes 14,000 applications of 8 distinct ones.
MAX_FILE_CALLS = 1_000

#: Signs a parameter may be declared with, and the sympy assumptions they give.
SIGNS: Mapping[str, dict[str, bool]] = {
    "positive": {"positive": True},
    "nonnegative": {"nonnegative": True},
    "negative": {"negative": True},
    "nonpositive": {"nonpositive": True},
    "nonzero": {"real": True, "nonzero": True},
    "real": {"real": True},
    "any": {},
}

_TOP_KEYS = (
    "format",
    "name",
    "description",
    "coordinates",
    "metric",
    "kinetic_energy",
    "potential",
    "forces",
    "constraints",
    "parameters",
    "functions",
    "inputs",
    "frame",
    "walls",
    "drawing",
)
_PARAMETER_KEYS = ("value", "sign", "description")
_FUNCTION_KEYS = ("expression", "arguments", "real", "description")
_FRAME_KEYS = ("quasi_velocities", "matrix", "inverse")
_WALL_KEYS = ("name", "psi", "restitution", "impulsive_constraints", "law", "velocity")
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_MAX_IDENTIFIER = 64
_SCENES_PACKAGE = "symmech"
_SCENES_FOLDER = "scenes"


# ---------------------------------------------------------------------------------------
# errors


class SceneFileError(SceneError):
    """A scene file was refused.

    ``problems`` holds one line per problem, each naming the file, the field, the line and
    the offending token when known; ``details`` holds the same as ``(field, line, token)``
    tuples (None where unknown) and ``path`` the file (None for a string).
    """

    def __init__(
        self,
        problems: Sequence[str],
        *,
        path: str | None = None,
        details: Sequence[tuple[str | None, int | None, str | None]] = (),
    ):
        super().__init__(list(problems))
        self.path = path
        self.details = list(details)


# shown (tracebacks, doctests) under the package that exports it
SceneFileError.__module__ = "symmech.scenefile"


class _Problems:
    """Collects the problems of one file, each with its field, line and token."""

    def __init__(self, source: str):
        self.source = source
        self.items: list[str] = []
        self.details: list[tuple[str | None, int | None, str | None]] = []

    def add(
        self,
        message: str,
        *,
        field: str | None = None,
        line: int | None = None,
        token: str | None = None,
    ) -> None:
        at = f" (line {line})" if line is not None else ""
        if field:
            self.items.append(f"{self.source}: {field}{at}: {message}")
        else:
            self.items.append(f"{self.source}{at}: {message}")
        self.details.append((field, line, token))

    def expression_error(self, exc: ExpressionError, field: str) -> None:
        self.items.append(f"{self.source}: {exc}")
        self.details.append((field, getattr(exc, "line", None), getattr(exc, "token", None)))

    def raise_if_any(self, path: str | None) -> None:
        if self.items:
            details = [
                (f if f is None else printable(f), line, t if t is None else printable(t))
                for f, line, t in self.details
            ]
            raise SceneFileError([printable(i) for i in self.items], path=path, details=details)


def printable(text: str) -> str:
    """``text`` with every non-printable character (terminal escapes, BEL, line breaks
    hidden in a key) written as its Python escape, so that a message from a hostile file
    cannot drive the terminal or forge a line."""
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


def _toml_type(value: object) -> str:
    names = {
        bool: "boolean",
        int: "integer",
        float: "float",
        str: "string",
        list: "array",
        dict: "table",
    }
    return names.get(type(value), f"{type(value).__name__} (a TOML date or time)")


def _allowed_kinds(field: str) -> str:
    """What the expression ``field`` may use, for error messages."""
    if field.startswith("parameters."):
        return "numbers, pi and E"
    if field.startswith("functions."):
        return "t and the parameters"
    if field.endswith(".restitution"):
        return "a number or a parameter"
    if field.startswith(("metric", "frame.")):
        return "the coordinates and the parameters"
    return "the coordinates, velocities, parameters and functions"


def _number_text(value: sp.Expr) -> str:
    """A number as the file would write it (``1.5``, not ``1.50000000000000``)."""
    if isinstance(value, sp.Float):
        return repr(float(value))
    return str(value)


def _clip(text: object, limit: int = 60) -> str:
    """``str(text)`` (a key or a token from the file) cut to ``limit`` characters and "...",
    so that a message never echoes a huge key whole."""
    shown = str(text)
    return shown if len(shown) <= limit else shown[:limit] + "..."


def _short(value: object, limit: int = 40) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _toml_error(text: str, source: str, message: str) -> SceneFileError:
    """The error for a file tomllib refused: its line, and the text where it stopped."""
    m = re.search(r"\(at line (\d+), column (\d+)\)", message)
    if m is None:
        return SceneFileError([f"{source}: not valid TOML: {message}"], path=source)
    line, column = int(m.group(1)), int(m.group(2))
    lines = text.split("\n")
    rest = lines[line - 1][column - 1 :].strip() if line <= len(lines) else ""
    token = rest[:30] or None
    near = f" near {token!r}" if token else " at the end of the line"
    reason = message[: m.start()].strip()
    return SceneFileError(
        [f"{source} (line {line}): not valid TOML: {reason} (column {column}){near}"],
        path=source,
        details=[(None, line, token)],
    )


def _did_you_mean(name: str, candidates: Sequence[str]) -> str:
    close = difflib.get_close_matches(name, list(candidates), n=3, cutoff=0.6)
    return f" (did you mean {' or '.join(repr(c) for c in close)}?)" if close else ""
