r"""Scene files: a mechanical system written in TOML, loaded without executing anything.

A scene file holds exactly what :class:`symmech.Scene` takes (coordinates, a metric or a
kinetic energy, a potential, constraints, a frame of quasi-velocities, walls), plus default
values for the parameters and functions of time.  :func:`load_scene` (a path) and
:func:`loads_scene` (text) return the :class:`~symmech.Scene`; :func:`read_scene` and
:func:`reads_scene` return a :class:`SceneFile` that also carries the defaults, the
functions and the description; :func:`save_scene` and :func:`dump_scene` write a Scene
back.

Format (version 1)
------------------
::

    format = 1                                   # optional; 1 is the only version
    name = "carnot_3_7"                          # optional; default: the file's stem
    description = "Carnot paper, example 3.7"    # optional
    coordinates = ["x", "y", "theta"]            # required; their velocities are xdot, ...
    metric = ["m", "m", "m*k**2"]                # n entries: the diagonal; or n rows of n
    # kinetic_energy = "m*(xdot**2 + ydot**2)/2 + m*k**2*thetadot**2/2"   (instead of metric)
    potential = "m*g*y"                          # optional, default 0; may use t
    forces = ["-c*xdot + u", "0", "0"]           # optional: applied generalized forces, one
                                                 # per velocity (in the quasi-velocities'
                                                 # basis with a [frame]); may use t and the
                                                 # velocities; u = {} in [functions] is a
                                                 # run-time input u(t)
    constraints = ["xdot - R*thetadot"]          # optional; linear in the velocities,
                                                 # or coefficient rows [[1, 0, "-R"]]

    [parameters]                 # every parameter, in order, with its default value
    m = 1                        # a number, or a string of numbers: "sqrt(2)/4", "2*pi"
    R = { value = 0.5 }          # the same, as a table
    alpha = { value = 0.8, sign = "nonnegative" }
    g = { sign = "real" }        # no default value

    [functions]                  # functions, used by their name alone
    f = "A*sin(omega*t)"         # defined: "x - f" in an expression means x - A sin(omega t)
    h = {}                       # arbitrary: "x - h" means x - h(t), kept symbolic
    V = { arguments = ["x", "y"] }   # arbitrary, of coordinates (and t): "V" means V(x, y)

    [inputs]                     # run-time inputs: arbitrary real functions of t, given
    tau = { description = "motor torque" }   # to generated code by name (inputs={"tau": ..})

    [frame]                      # quasi-velocities v with q_dot = S(q) v (optional)
    quasi_velocities = ["v_x", "v_y", "omega"]
    matrix = [[...], [...], [...]]     # S; or `inverse = [...]`, S^-1 (v = S^-1 q_dot),
                                       # inverted symbolically by the loader

    [[walls]]                    # one table per wall (optional)
    name = "rough_wall"          # optional identifier, default wall0, wall1, ...
    psi = "y - R"                # gap psi(t, q) >= 0 on the admissible side
    restitution = "alpha"        # a number in [0, 1], a string of numbers, or a parameter
    impulsive_constraints = ["xdot - R*thetadot"]   # optional, kept after the impact
    law = "newton"               # or "energy" (text 001, section 3.2)
    velocity = ["0", "A*omega*cos(omega*t)", "0"]   # optional: the wall's velocity field
                                 # W(t, q), one component per velocity (default: the
                                 # metric normal; see symmech.declaration.wallvelocity)

Rules:

* Every expression is a string (or a number) parsed by
  :func:`symmech.declaration.expressions.parse_expression`, a whitelist over Python's
  ``ast``; nothing is passed to ``eval``, ``sympify`` or ``parse_expr``.  The names an
  expression may use are the coordinates, their velocities (``<name>dot``), the
  quasi-velocities, ``t``, the parameters, the functions, ``pi`` and ``E``.  A ``#`` in an
  expression is refused (Python would drop the rest as a comment), and so is a name
  written with look-alike Unicode characters (``𝐱`` for ``x``); a line break is
  whitespace, so an expression may span the lines of a multi-line string.  Where a name
  may appear (only the potential, forces and walls may use ``t``, ...) is checked by
  :class:`~symmech.Scene`.  With a ``[frame]``, velocities are written in the
  quasi-velocities only (the kinetic energy and the constraints are in that basis).
* Parameters are positive unless ``sign`` says otherwise: ``"positive"``,
  ``"nonnegative"``, ``"negative"``, ``"nonpositive"``, ``"nonzero"``, ``"real"`` or
  ``"any"`` (a sympy symbol with no assumptions).  A default value must be a real number
  of that sign.  Every declared parameter must be used, and every name used must be
  declared.  The scene's parameters are in the order of the file.  A parameter used as a
  restitution must be ``"nonnegative"`` or ``"positive"``, with a default value in [0, 1].
* Functions are written by name alone (``"x - f"``; the parser refuses ``f(t)``: only its
  whitelisted functions may be called).  A defined function is an expression in t and the
  parameters, substituted where its name appears.  An arbitrary (undefined) function
  stays symbolic in the derived quantities: ``{}`` is ``f(t)``; ``{ arguments = ["x",
  "y"] }`` declares ``V(x, y)``, its arguments distinct names among t and the coordinates
  (a generic potential; its derivatives appear in the forcing); ``real = false`` makes a
  complex-valued sympy function.  Where such a function may appear is checked by
  :class:`~symmech.Scene` as for any expression.  A function of anything else (of an
  expression ``V(x + y)``, of a velocity, of a parameter) cannot be written in a file:
  :func:`dump_scene` refuses it, saying why.
* Names (coordinates, parameters, quasi-velocities, functions) are Python identifiers,
  distinct, not ``t``, not starting with ``__``, and not the names of the parser's
  functions or constants; the scene and wall names are identifiers too (they become names
  in generated code and files).
* Unknown keys are refused (with a suggestion), so a misspelt key is not silently ignored.

Limits: :data:`MAX_FILE_BYTES` bytes of file, :data:`MAX_NAMES` coordinates or parameters,
:data:`MAX_WALLS` walls, integers of at most
:data:`~symmech.declaration.expressions.MAX_DIGITS` digits; each expression has the
parser's limits on length, node count, depth and exponent size.

Errors raise :class:`SceneFileError` (a :class:`~symmech.SceneError`) listing every problem,
each naming the file, the field (``walls[0].psi``), the line and the offending token.  When
a declaration is refused (a coordinate, parameter, function or quasi-velocity name), the
expressions are not read: every use of that name would be reported again.
TOML parsers do not report where a key is, so the line is found by one linear-time scan
of the file text (:class:`_Scanner`, no regular expression): the table header
(``[parameters]``, the k-th ``[[walls]]``) is found first, then the first statement
``key =`` below it before the next header (a dotted key ``parameters.m =`` too); the
element of an array is found as its string on or after that line.  An expression in a
multi-line string (triple quotes) is located on the line where its text starts, and its errors
on the line within it.  A key written in an unusual way (inside an inline table, a string
with line-ending backslashes) may get the line of its table or no line at all: the field
name is always given.  Keys and tokens echoed in messages are cut to 60 characters.

>>> sf = reads_scene('''
... coordinates = ["x"]
... metric = ["m"]
... potential = "k*x**2/2"
... [parameters]
... m = 2
... k = { value = "1/2" }
... ''', name="oscillator")
>>> sf.scene
Scene('oscillator': q=[x])
>>> sf.defaults
{m: 2, k: 1/2}

Nothing in a file is run; what is not a plain expression is refused, with its place:

>>> reads_scene('coordinates = ["x"]\nmetric = ["().__class__"]', source="evil.toml")
Traceback (most recent call last):
...
symmech.scenefile.SceneFileError: evil.toml: metric[0,0] (line 2, col 1): attribute access '().__class__' is not allowed
"""  # noqa: E501

from __future__ import annotations

import bisect
import difflib
import importlib.resources
import keyword
import math
import os
import re
import string
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import sympy as sp
from sympy.core.function import AppliedUndef
from sympy.printing.str import StrPrinter

from symmech.declaration.expressions import (
    ALLOWED_CONSTANTS,
    ALLOWED_FUNCTIONS,
    MAX_DIGITS,
    parse_expression,
    to_expression,
)
from symmech.declaration.symbols import t as TIME
from symmech.declaration.symbols import velocity_of
from symmech.declaration.wall import LAWS, Wall
from symmech.errors import ExpressionError, SceneError
from symmech.scene import Scene

__all__ = [
    "FORMAT_VERSION",
    "MAX_FILE_BYTES",
    "MAX_NAMES",
    "MAX_WALLS",
    "SIGNS",
    "SceneFile",
    "SceneFileError",
    "builtin_scene_names",
    "builtin_scene_path",
    "dump_scene",
    "load_scene",
    "loads_scene",
    "read_scene",
    "reads_scene",
    "save_scene",
]

#: The version of the format this module reads and writes.
FORMAT_VERSION = 1
#: Largest scene file read, in bytes.
MAX_FILE_BYTES = 1_000_000
#: Largest number of coordinates, of parameters and of functions.
MAX_NAMES = 200
#: Largest number of walls.
MAX_WALLS = 100

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


# ---------------------------------------------------------------------------------------
# finding lines in the file text


_BARE_KEY_CHARACTERS = frozenset(string.ascii_letters + string.digits + "_-")
_ESCAPES = {"b": "\b", "t": "\t", "n": "\n", "f": "\f", "r": "\r", '"': '"', "\\": "\\"}


class _Scanner:
    """One pass over TOML text (that tomllib accepted), noting where things are.

    Linear time and no regular expression: each character is looked at a bounded number
    of times, whatever the file holds (a table header of 100 000 spaces costs what its
    length costs).  Notes the table headers ``(line, name, is_array)``, the keys of the
    statements ``key = value`` ``(line, position of their header or -1, key parts)`` (not
    the keys inside inline tables), and every string value ``(line, decoded value)``, the
    line being where its content starts (the line after an opening ``\"\"\"`` that ends its
    line, as TOML drops that line break).  Lines are 0-based.
    """

    def __init__(self, text: str):
        self.text = text
        self.i = 0
        self.line = 0
        self.headers: list[tuple[int, str, bool]] = []
        self.keys: list[tuple[int, int, tuple[str, ...]]] = []
        self.strings: list[tuple[int, str]] = []

    def run(self) -> _Scanner:
        text, n = self.text, len(self.text)
        depth = 0  # [ and { of values still open (a matrix over several lines)
        statement = True  # at the start of a statement: a header or a key
        while self.i < n:
            c = text[self.i]
            if c == "\n":
                self.line += 1
                self.i += 1
                statement = statement or depth == 0
            elif c in " \t\r":
                self.i += 1
            elif c == "#":
                end = text.find("\n", self.i)
                self.i = n if end < 0 else end
            elif statement and depth == 0:
                statement = False
                start = self.i
                if c == "[":
                    self._header()
                else:
                    self._statement_key()
                self.i = max(self.i, start + 1)
            elif c in "\"'":
                found = self._string()
                if found is not None:
                    self.strings.append(found)
            else:
                if c in "[{":
                    depth += 1
                elif c in "]}":
                    depth = max(0, depth - 1)
                self.i += 1
        return self

    def _header(self) -> None:
        line = self.line
        array = self.text.startswith("[[", self.i)
        self.i += 2 if array else 1
        parts = self._key_parts()
        closing = "]]" if array else "]"
        if parts is not None and self.text.startswith(closing, self.i):
            self.i += len(closing)
            self.headers.append((line, ".".join(parts), array))

    def _statement_key(self) -> None:
        line = self.line
        parts = self._key_parts()
        if parts is not None and self.text.startswith("=", self.i):
            self.i += 1
            self.keys.append((line, len(self.headers) - 1, tuple(parts)))

    def _skip_blanks(self) -> None:
        text, n = self.text, len(self.text)
        while self.i < n and text[self.i] in " \t":
            self.i += 1

    def _key_parts(self) -> list[str] | None:
        """A (dotted) key: bare or quoted parts separated by dots; None if there is none."""
        text, n = self.text, len(self.text)
        parts: list[str] = []
        while True:
            self._skip_blanks()
            if self.i >= n:
                return None
            c = text[self.i]
            if c in "\"'":
                if text.startswith(c * 3, self.i):
                    return None  # (a multi-line string is not a key)
                found = self._string()
                if found is None:
                    return None
                parts.append(found[1])
            else:
                j = self.i
                while j < n and text[j] in _BARE_KEY_CHARACTERS:
                    j += 1
                if j == self.i:
                    return None
                parts.append(text[self.i : j])
                self.i = j
            self._skip_blanks()
            if not self.text.startswith(".", self.i):
                return parts
            self.i += 1

    def _string(self) -> tuple[int, str] | None:
        """The string at ``self.i``: (line of its content, decoded value); None if broken."""
        text, n = self.text, len(self.text)
        quote = text[self.i]
        multi = text.startswith(quote * 3, self.i)
        self.i += 3 if multi else 1
        if multi and text.startswith(("\n", "\r\n"), self.i):
            self.i += 1 if text[self.i] == "\n" else 2
            self.line += 1
        content_line = self.line
        out: list[str] = []
        while self.i < n:
            c = text[self.i]
            if c == quote:
                run = 1
                if multi:
                    while run < 5 and text.startswith(quote, self.i + run):
                        run += 1
                    if run < 3:
                        out.append(quote * run)
                        self.i += run
                        continue
                out.append(quote * (run - 3 if multi else 0))
                self.i += run
                return content_line, "".join(out)
            if c == "\n" or (c == "\r" and text.startswith("\r\n", self.i)):
                if not multi:
                    return None
                self.i += 1 if c == "\n" else 2
                self.line += 1
                out.append("\n")
            elif c == "\\" and quote == '"':
                self._escape(out, multi)
            else:
                out.append(c)
                self.i += 1
        return None

    def _escape(self, out: list[str], multi: bool) -> None:
        text, n = self.text, len(self.text)
        nxt = text[self.i + 1 : self.i + 2]
        if multi and nxt in (" ", "\t", "\r", "\n"):
            # a line-ending backslash: the blanks and line breaks after it are dropped
            j = self.i + 1
            while j < n and text[j] in " \t\r\n":
                self.line += text[j] == "\n"
                j += 1
            self.i = j
        elif nxt in _ESCAPES:
            out.append(_ESCAPES[nxt])
            self.i += 2
        elif nxt in ("u", "U"):
            width = 4 if nxt == "u" else 8
            digits = text[self.i + 2 : self.i + 2 + width]
            if len(digits) == width and all(d in string.hexdigits for d in digits):
                code = int(digits, 16)
                if code <= 0x10FFFF:
                    out.append(chr(code))
            self.i += 2 + width
        else:
            out.append("\\")
            self.i += 1


class _Locator:
    """The lines of keys, tables and array elements of TOML text (see the module doc).

    Built from one linear :class:`_Scanner` pass; every query is a dictionary look-up or a
    binary search.  Regions: the top level runs from line 1 to the first table header; a
    table ``[name]`` (or the k-th ``[[name]]``) from its header to the next header.  All
    lines returned are 1-based.
    """

    def __init__(self, text: str):
        scan = _Scanner(text).run()
        self.headers = scan.headers
        self._header_lines = [line + 1 for line, _, _ in scan.headers]
        self._positions: dict[str, list[int]] = {}
        for pos, (_, name, _) in enumerate(scan.headers):
            self._positions.setdefault(name, []).append(pos)
        self._keys: dict[tuple[int, tuple[str, ...]], int] = {}
        for line, pos, parts in scan.keys:
            # a dotted key a.b.c = 1 is also where a and a.b are first written
            for k in range(1, len(parts) + 1):
                self._keys.setdefault((pos, parts[:k]), line + 1)
        self._strings: dict[str, list[int]] = {}
        for line, value in scan.strings:
            self._strings.setdefault(value, []).append(line + 1)

    def _header(self, table: str, index: int = 0) -> int | None:
        positions = self._positions.get(table, ())
        return positions[index] if index < len(positions) else None

    def table(self, table: str, index: int = 0) -> int | None:
        """1-based line of the header of ``table`` (the ``index``-th for arrays)."""
        pos = self._header(table, index)
        return None if pos is None else self._header_lines[pos]

    def key(self, table: str | None, key: str, index: int = 0) -> int | None:
        """1-based line of ``key =`` in ``table`` (None: top level), else of the table.

        A dotted key is found too: ``value`` of table ``parameters.m`` is ``m.value =`` in
        ``[parameters]`` or ``parameters.m.value =`` at the top level.
        """
        if table is None:
            return self._keys.get((-1, (key,)))
        pos = self._header(table, index)
        if pos is not None and (pos, (key,)) in self._keys:
            return self._keys[pos, (key,)]
        if index == 0:
            parts = tuple(table.split("."))
            for cut in range(len(parts) - 1, -1, -1):
                outer = -1 if cut == 0 else self._header(".".join(parts[:cut]))
                found = self._keys.get((outer, (*parts[cut:], key))) if outer is not None else None
                if found is not None:
                    return found
        return None if pos is None else self._header_lines[pos]

    def element(self, start: int | None, value: object) -> int | None:
        """1-based line where the string ``value`` starts, on or after line ``start`` and
        before the next table header; else ``start``."""
        if start is None or not isinstance(value, str) or not value:
            return start
        lines = self._strings.get(value)
        if not lines:
            return start
        k = bisect.bisect_left(lines, start)
        if k == len(lines):
            return start
        h = bisect.bisect_right(self._header_lines, start)
        if h < len(self._header_lines) and self._header_lines[h] <= lines[k]:
            return start
        return lines[k]


# ---------------------------------------------------------------------------------------
# the loaded file


@dataclass(frozen=True)
class SceneFile:
    """A loaded scene file: the :class:`~symmech.Scene` and what the Scene API does not hold.

    Attributes
    ----------
    scene:
        The scene.
    defaults:
        Default values of the parameters that have one: parameter Symbol -> exact sympy
        number (a Float where the file wrote a decimal), in the scene's parameter order.
    functions:
        The functions: name -> the expression substituted for it (a defined function of
        time) or the applied function ``f(t)`` or ``V(x, y)`` (an arbitrary one).
    description:
        The file's description ("" when it has none).
    path:
        The file read, or None for text given to :func:`reads_scene`.
    """

    scene: Scene
    defaults: dict[sp.Symbol, sp.Expr] = field(default_factory=dict)
    functions: dict[str, sp.Expr] = field(default_factory=dict)
    description: str = ""
    path: Path | None = None

    def numeric_defaults(self) -> dict[str, float]:
        """The default values as floats, keyed by parameter name."""
        return {s.name: float(v) for s, v in self.defaults.items()}

    def missing_defaults(self) -> list[sp.Symbol]:
        """The parameters without a default value."""
        return [p for p in self.scene.parameters if p not in self.defaults]


# ---------------------------------------------------------------------------------------
# built-in scene files


def builtin_scene_names() -> list[str]:
    """Names of the scene files shipped in ``symmech/scenes/`` (sorted)."""
    folder = importlib.resources.files(_SCENES_PACKAGE).joinpath(_SCENES_FOLDER)
    if not folder.is_dir():
        return []
    return sorted(p.name[: -len(".toml")] for p in folder.iterdir() if p.name.endswith(".toml"))


def builtin_scene_path(name: str) -> Path:
    """The path of the shipped scene file ``name`` (e.g. ``"carnot_3_7"``).

    Raises :class:`SceneFileError` naming the built-in scenes if there is none.
    """
    names = builtin_scene_names()
    if name not in names:
        hint = _did_you_mean(name, names)
        raise SceneFileError(
            [
                f"no scene file {_clip(name)!r} and no built-in scene of that name{hint};"
                f" built-in: {names}"
            ]
        )
    resource = importlib.resources.files(_SCENES_PACKAGE).joinpath(_SCENES_FOLDER, f"{name}.toml")
    return Path(str(resource))


def _did_you_mean(name: str, candidates: Sequence[str]) -> str:
    close = difflib.get_close_matches(name, list(candidates), n=3, cutoff=0.6)
    return f" (did you mean {' or '.join(repr(c) for c in close)}?)" if close else ""


def _resolve_path(path: str | os.PathLike[str]) -> Path:
    p = Path(path)
    text = os.fspath(path)
    if p.is_file() or (p.exists() and text not in builtin_scene_names()):
        return p
    if _IDENTIFIER.match(text):
        return builtin_scene_path(text)
    raise SceneFileError([f"{text}: no such scene file"], path=text)


# ---------------------------------------------------------------------------------------
# loading


def load_scene(path: str | os.PathLike[str]) -> Scene:
    """Load the scene file ``path`` and return its :class:`~symmech.Scene`.

    ``path`` is a TOML file (see the module documentation for the format), or the name of
    a built-in scene file (``"carnot_3_7"``; see :func:`builtin_scene_names`) when no file
    of that name exists.  The default values of the parameters, which a Scene does not
    hold, are in :func:`read_scene`'s :attr:`SceneFile.defaults`.

    Raises :class:`SceneFileError` listing every problem, each with the field and line.
    """
    return read_scene(path).scene


def read_scene(path: str | os.PathLike[str]) -> SceneFile:
    """Load the scene file ``path`` (or built-in scene name); return a :class:`SceneFile`."""
    p = _resolve_path(path)
    source = str(path)
    try:
        if not p.is_file():  # a folder, a device (/dev/zero never ends), a pipe
            raise SceneFileError([f"{source}: not a regular file"], path=source)
        size = p.stat().st_size
        if size > MAX_FILE_BYTES:
            raise SceneFileError(
                [f"{source}: file is {size} bytes long (limit {MAX_FILE_BYTES})"], path=source
            )
        with p.open("rb") as handle:  # bounded, should the file grow meanwhile
            data = handle.read(MAX_FILE_BYTES + 1)
        if len(data) > MAX_FILE_BYTES:
            raise SceneFileError(
                [f"{source}: file is longer than {MAX_FILE_BYTES} bytes"], path=source
            )
    except OSError as exc:
        raise SceneFileError(
            [f"{source}: cannot read: {exc.strerror or exc}"], path=source
        ) from None
    try:
        # (utf-8-sig: a byte-order mark that some editors write is not part of the text)
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise SceneFileError(
            [f"{source} (line {line}): not UTF-8 text ({exc.reason} at byte {exc.start})"],
            path=source,
            details=[(None, line, None)],
        ) from None
    stem = re.sub(r"\W", "_", p.stem) or "scene"
    if not _IDENTIFIER.match(stem):
        stem = "scene_" + stem
    return _load(text, source=source, default_name=stem[:_MAX_IDENTIFIER], path=p)


def reads_scene(text: str, *, name: str = "scene", source: str = "<string>") -> SceneFile:
    """Load a scene from TOML ``text``; ``name`` is used when the text has no ``name``."""
    if not isinstance(text, str):
        raise SceneFileError([f"{source}: expected TOML text, got a {type(text).__name__}"])
    if len(text.encode("utf-8", errors="replace")) > MAX_FILE_BYTES:
        raise SceneFileError([f"{source}: text is longer than {MAX_FILE_BYTES} bytes"])
    return _load(text, source=source, default_name=name, path=None)


def loads_scene(text: str, *, name: str = "scene", source: str = "<string>") -> Scene:
    """The Scene of a scene file given as text: :func:`load_scene` for text, as
    :func:`reads_scene` is :func:`read_scene` for text (the :class:`SceneFile` with the
    parameters' defaults, the functions and the description)."""
    return reads_scene(text, name=name, source=source).scene


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


class _Loader:
    """Builds a Scene from parsed TOML data, collecting every problem."""

    def __init__(self, data: dict[str, Any], text: str, source: str, default_name: str):
        self.data = data
        self.loc = _Locator(text)
        self.problems = _Problems(source)
        self.source = source
        self.default_name = default_name
        self.table: dict[str, sp.Expr] = {"t": TIME}
        self.reserved: dict[str, str] = {"t": "time"}
        self.field_lines: dict[str, int | None] = {}
        self.used: set[sp.Symbol] = set()
        # set when a declaration (coordinates, parameters, functions, quasi-velocities) is
        # refused: the expressions are then not read, since every use of a refused name
        # would be reported again as an unknown name
        self.names_refused = False
        self.defaults: dict[sp.Symbol, sp.Expr] = {}

    # -- small helpers ---------------------------------------------------------------------
    def line(self, table: str | None, key: str, index: int = 0) -> int | None:
        return self.loc.key(table, key, index)

    def fail(self, message: str, field: str, line: int | None, token: str | None = None) -> None:
        self.problems.add(message, field=field, line=line, token=token)

    def check_keys(
        self,
        value: Mapping[str, Any],
        allowed: Sequence[str],
        where: str,
        table: str | None,
        index: int = 0,
        *,
        inline_line: int | None = None,
    ) -> None:
        """Refuse the keys of ``value`` not in ``allowed``, suggesting the closest one.

        The line is that of ``key =`` in ``table`` (the ``index``-th for arrays of tables),
        else ``inline_line``: for an inline table (``m = { valeu = 1 }``, whose keys the
        locator does not see) pass the entry's line.
        """
        for key in value:
            if key not in allowed:
                hint = _did_you_mean(key, allowed)
                line = self.line(table, key, index)
                self.fail(
                    f"unknown key '{_clip(key)}'{hint}; allowed keys: {', '.join(allowed)}",
                    f"{where}{'.' if where else ''}{_clip(key)}",
                    line if line is not None else inline_line,
                    _clip(key),
                )

    def entry_line(self, table: str, key: str) -> int | None:
        """Line of ``key = ...`` in ``[table]``, or of the sub-table header ``[table.key]``."""
        line = self.line(table, key)
        if line is None or line == self.loc.table(table):
            line = self.loc.table(f"{table}.{key}") or line
        return line

    def sub_key_args(self, table: str, key: str, line: int | None) -> dict[str, Any]:
        """``check_keys`` arguments for the keys of the entry ``key`` of ``[table]``: in its
        sub-table ``[table.key]`` or as dotted keys (``key.value = 1``) if written so, else
        on the entry's own (inline table) line."""
        return {"table": f"{table}.{key}", "inline_line": line}

    def name_ok(self, name: object, field: str, line: int | None, kind: str) -> str | None:
        """Check a declared name; register it; return it or None."""
        if not isinstance(name, str):
            self.fail(
                f"{kind} names must be strings, got {_toml_type(name)} {_short(name, 60)}",
                field,
                line,
            )
            self.names_refused = True
            return None
        problem = None
        shown = repr(_clip(name))
        if not _IDENTIFIER.match(name):
            problem = f"{kind} name {shown} is not an identifier (letters, digits, _)"
        elif len(name) > _MAX_IDENTIFIER:
            problem = f"{kind} name {name[:20]!r}... is longer than {_MAX_IDENTIFIER} characters"
        elif name.startswith("__"):
            problem = f"{kind} name {shown} may not start with '__'"
        elif keyword.iskeyword(name):
            problem = f"{kind} name {name!r} is a Python keyword"
        elif name in ALLOWED_FUNCTIONS or name in ALLOWED_CONSTANTS:
            problem = f"{kind} name {name!r} is the name of a built-in function or constant"
        elif name in self.reserved:
            problem = f"{kind} name {name!r} is already used for {self.reserved[name]}"
        if problem:
            self.fail(problem, field, line, _clip(name))
            self.names_refused = True
            return None
        self.reserved[name] = f"the {kind} declared in {field}"
        return name

    def expression(
        self, value: object, field: str, line: int | None, table: Mapping[str, sp.Expr]
    ) -> sp.Expr | None:
        """Parse one scalar entry: a number or an expression string."""
        if isinstance(value, bool) or not isinstance(value, int | float | str):
            self.fail(
                f"expected a number or an expression string, got {_toml_type(value)}",
                field,
                line,
            )
            return None
        if isinstance(value, float) and not math.isfinite(value):
            self.fail(f"expected a finite number, got {value}", field, line, _clip(value))
            return None
        if isinstance(value, int) and abs(value) >= 10**MAX_DIGITS:
            self.fail(
                f"integer of more than {MAX_DIGITS} digits (limit {MAX_DIGITS})",
                field,
                line,
                _short(value, 20),
            )
            return None
        if isinstance(value, int | float):
            return sp.Integer(value) if isinstance(value, int) else sp.Float(value)
        # the line where the text starts: a multi-line string's content starts below its key
        line = self.loc.element(line, value)
        try:
            expr = parse_expression(value, table, field=field, line=line)
        except ExpressionError as exc:
            token = getattr(exc, "token", None)
            if token in self.function_names and "not a function" in str(exc):
                self.fail(
                    f"'{token}' is a function of time: write it by name alone ('{token}'"
                    f" means {token}(t)), not called",
                    field,
                    getattr(exc, "line", line),
                    token,
                )
            elif token in self.reserved and token not in table and "unknown name" in str(exc):
                # a declared name where it may not appear: a velocity in the metric, ...
                at_line = getattr(exc, "line", None) or line
                column = getattr(exc, "column", None)
                where = f"{field} (line {at_line}, col {column})" if column else field
                self.problems.items.append(
                    f"{self.problems.source}: {where}: '{token}' is {self.reserved[token]}; it"
                    f" may not appear in {field} (allowed: {_allowed_kinds(field)})"
                )
                self.problems.details.append((field, at_line, token))
            else:
                self.problems.expression_error(exc, field)
            return None
        self.used |= expr.free_symbols
        return expr

    def string_list(self, value: object, field: str, line: int | None) -> list[str] | None:
        if not isinstance(value, list) or not all(isinstance(s, str) for s in value):
            self.fail(
                f"expected an array of name strings, got {_toml_type(value)} {_short(value)}",
                field,
                line,
            )
            self.names_refused = True
            return None
        return value

    # -- sections --------------------------------------------------------------------------
    function_names: frozenset[str] = frozenset()

    def header(self) -> tuple[str, str]:
        data = self.data
        if "format" in data:
            fmt = data["format"]
            if isinstance(fmt, bool) or fmt != FORMAT_VERSION:
                self.fail(
                    f"unsupported format {_short(fmt, 60)}; this symmech reads format"
                    f" {FORMAT_VERSION}",
                    "format",
                    self.line(None, "format"),
                    _clip(fmt),
                )
        name = data.get("name", self.default_name)
        if not isinstance(name, str) or not _IDENTIFIER.match(name) or len(name) > 64:
            self.fail(
                f"the scene name must be an identifier of at most {_MAX_IDENTIFIER} characters"
                f" (letters, digits, _; it names generated code), got {_short(name)}",
                "name",
                self.line(None, "name"),
                str(name)[:40],
            )
            name = self.default_name
        description = data.get("description", "")
        if not isinstance(description, str):
            self.fail(
                f"expected a string, got {_toml_type(description)}",
                "description",
                self.line(None, "description"),
            )
            description = ""
        return name, description

    def coordinates(self) -> list[sp.Symbol]:
        line = self.line(None, "coordinates")
        if "coordinates" not in self.data:
            self.fail("required key 'coordinates' is missing", "coordinates", None)
            self.names_refused = True
            return []
        names = self.string_list(self.data["coordinates"], "coordinates", line)
        if names is None:
            return []
        if not names:
            self.fail("a scene needs at least one coordinate", "coordinates", line)
            self.names_refused = True
        if len(names) > MAX_NAMES:
            self.fail(f"{len(names)} coordinates (limit {MAX_NAMES})", "coordinates", line)
            self.names_refused = True
            return []
        q = []
        for i, nm in enumerate(names):
            ok = self.name_ok(nm, f"coordinates[{i}]", self.loc.element(line, nm), "coordinate")
            if ok is not None:
                q.append(sp.Symbol(ok, real=True))
        for s in q:
            vel = velocity_of(s)
            if vel.name in self.reserved:
                self.fail(
                    f"the velocity '{vel.name}' of coordinate '{s.name}' is also declared as"
                    f" {self.reserved[vel.name]}",
                    "coordinates",
                    line,
                    vel.name,
                )
                self.names_refused = True
            self.reserved[vel.name] = f"the velocity of coordinate '{s.name}'"
        self.table.update({s.name: s for s in q})
        self.table.update({velocity_of(s).name: velocity_of(s) for s in q})
        return q

    def parameters(self) -> tuple[list[sp.Symbol], dict[sp.Symbol, sp.Expr]]:
        raw = self.data.get("parameters", {})
        if not isinstance(raw, dict):
            self.fail(
                f"expected a table [parameters], got {_toml_type(raw)}",
                "parameters",
                self.line(None, "parameters"),
            )
            self.names_refused = True
            return [], {}
        if len(raw) > MAX_NAMES:
            self.fail(
                f"{len(raw)} parameters (limit {MAX_NAMES})",
                "parameters",
                self.loc.table("parameters"),
            )
            self.names_refused = True
            return [], {}
        params: list[sp.Symbol] = []
        defaults: dict[sp.Symbol, sp.Expr] = {}
        for key, spec in raw.items():
            field_name = f"parameters.{_clip(key)}"
            line = self.entry_line("parameters", key)
            name = self.name_ok(key, field_name, line, "parameter")
            if isinstance(spec, dict):
                keys = self.sub_key_args("parameters", key, line)
                self.check_keys(spec, _PARAMETER_KEYS, field_name, **keys)
                line = self.line(keys["table"], "value") or line
                value = spec.get("value")
                sign = spec.get("sign", "positive")
                if "description" in spec and not isinstance(spec["description"], str):
                    self.fail("expected a string", f"{field_name}.description", line)
            else:
                value, sign = spec, "positive"
            if not isinstance(sign, str) or sign not in SIGNS:
                self.fail(
                    f"sign must be one of {', '.join(SIGNS)}, got {_short(sign, 60)}"
                    f"{_did_you_mean(str(sign), list(SIGNS))}",
                    f"{field_name}.sign",
                    line,
                    _clip(sign),
                )
                sign = "positive"
            if name is None:
                continue
            symbol = sp.Symbol(name, **SIGNS[sign])
            params.append(symbol)
            if value is not None:
                number = self.default_value(value, symbol, sign, f"{field_name}.value", line)
                if number is not None:
                    defaults[symbol] = number
        self.table.update({p.name: p for p in params})
        return params, defaults

    def default_value(
        self, value: object, symbol: sp.Symbol, sign: str, field: str, line: int | None
    ) -> sp.Expr | None:
        number = self.expression(value, field, line, {})
        if number is None:
            return None
        if not number.is_number or not number.is_real:
            self.fail(
                f"default value {_clip(number)} is not a real number", field, line, _clip(value)
            )
            return None
        test = {
            "positive": number.is_positive,
            "nonnegative": number.is_nonnegative,
            "negative": number.is_negative,
            "nonpositive": number.is_nonpositive,
            "nonzero": number.is_nonzero,
        }.get(sign, True)
        if not test:
            self.fail(
                f"default value {number} of '{symbol.name}' is not {sign}"
                " (parameters are positive unless 'sign' says otherwise)",
                field,
                line,
                _clip(value),
            )
            return None
        return number

    def functions(self) -> dict[str, sp.Expr]:
        raw = self.data.get("functions", {})
        if not isinstance(raw, dict):
            self.fail(
                f"expected a table [functions], got {_toml_type(raw)}",
                "functions",
                self.line(None, "functions"),
            )
            self.names_refused = True
            return {}
        raw = {**raw, **self.inputs(raw)}
        if len(raw) > MAX_NAMES:
            self.fail(
                f"{len(raw)} functions (limit {MAX_NAMES})",
                "functions",
                self.loc.table("functions"),
            )
            self.names_refused = True
            return {}
        # the definitions may use t and the parameters only
        allowed = {k: v for k, v in self.table.items() if k == "t" or v not in self.coord_like}
        out: dict[str, sp.Expr] = {}
        # a refused function still gets a place-holder f(t) in the symbol table: the
        # expressions that use it are read as usual, and report their own problems only
        stand_in: dict[str, sp.Expr] = {}
        for key, spec in raw.items():
            field_name = f"functions.{_clip(key)}"
            line = self.entry_line("functions", key)
            name = self.name_ok(key, field_name, line, "function")
            expression: object = None
            arguments: object = None
            real = True
            if isinstance(spec, dict):
                keys = self.sub_key_args("functions", key, line)
                self.check_keys(spec, _FUNCTION_KEYS, field_name, **keys)
                expression = spec.get("expression")
                arguments = spec.get("arguments")
                real = spec.get("real", True)
                if not isinstance(real, bool):
                    self.fail("'real' must be true or false", f"{field_name}.real", line)
                    real = True
                if "description" in spec and not isinstance(spec["description"], str):
                    self.fail("expected a string", f"{field_name}.description", line)
            elif isinstance(spec, str | int | float) and not isinstance(spec, bool):
                expression = spec
            else:
                self.fail(
                    "expected an expression string in t (a defined function) or a table"
                    f" ({{}} for an arbitrary function), got {_toml_type(spec)}",
                    field_name,
                    line,
                )
                spec = None
            if name is None:
                continue
            value: sp.Expr | None = None
            if spec is None:
                pass
            elif expression is not None and arguments is not None:
                self.fail(
                    "give 'expression' (a defined function of t) or 'arguments' (an arbitrary"
                    " function of them), not both",
                    f"{field_name}.arguments",
                    line,
                )
            elif expression is not None:
                value = self.expression(expression, field_name, line, allowed)
            else:
                args = self.function_arguments(arguments, f"{field_name}.arguments", line)
                if args is not None:
                    fn = sp.Function(name, real=True) if real else sp.Function(name)
                    value = fn(*args)
            if value is None:
                stand_in[name] = sp.Function(name, real=True)(TIME)
            else:
                out[name] = value
        self.function_names = frozenset(raw)
        self.table.update(stand_in)
        self.table.update(out)
        return out

    def inputs(self, functions: dict) -> dict[str, dict]:
        """``[inputs]``: run-time inputs, each an arbitrary real function of t (``tau = {}``
        or ``tau = { description = "..." }``), read as ``[functions]`` entries ``{}``."""
        raw = self.data.get("inputs", {})
        if not isinstance(raw, dict):
            self.fail(
                f"expected a table [inputs], got {_toml_type(raw)}",
                "inputs",
                self.line(None, "inputs"),
            )
            self.names_refused = True
            return {}
        out: dict[str, dict] = {}
        for key, spec in raw.items():
            field_name = f"inputs.{_clip(key)}"
            line = self.entry_line("inputs", key)
            if key in functions:
                self.fail(
                    "declared both in [functions] and in [inputs]", field_name, line, _clip(key)
                )
                self.names_refused = True
                continue
            if not isinstance(spec, dict) or set(spec) - {"description"}:
                self.fail(
                    'an input is a table {} or { description = "..." } (a function of t given'
                    " at run time)",
                    field_name,
                    line,
                )
                self.names_refused = True
                continue
            out[key] = dict(spec)
        return out

    def function_arguments(
        self, raw: object, field: str, line: int | None
    ) -> list[sp.Symbol] | None:
        """The arguments of an arbitrary function: distinct names among t and the
        coordinates (default: t alone)."""
        if raw is None:
            return [TIME]
        coordinates = {s.name: s for s in self.q}
        allowed = ["t", *coordinates]
        if not isinstance(raw, list) or not raw or not all(isinstance(a, str) for a in raw):
            self.fail(
                f"expected a non-empty array of argument names (among {', '.join(allowed)}),"
                f" got {_toml_type(raw)} {_short(raw, 60)}",
                field,
                line,
            )
            return None
        args: list[sp.Symbol] = []
        for a in raw:
            if a not in allowed:
                self.fail(
                    f"'{_clip(a)}' is not t or a coordinate: an arbitrary function's arguments"
                    f" are among {', '.join(allowed)}{_did_you_mean(a, allowed)}",
                    field,
                    self.loc.element(line, a),
                    _clip(a),
                )
                return None
            arg = TIME if a == "t" else coordinates[a]
            if arg in args:
                self.fail(f"argument '{a}' is repeated", field, self.loc.element(line, a), a)
                return None
            args.append(arg)
        return args

    def frame(self, q: list[sp.Symbol]) -> tuple[sp.Matrix | None, list[sp.Symbol] | None]:
        raw = self.data.get("frame")
        if raw is None:
            return None, None
        fline = self.loc.table("frame") or self.line(None, "frame")
        if not isinstance(raw, dict):
            self.fail(f"expected a table [frame], got {_toml_type(raw)}", "frame", fline)
            return None, None
        self.check_keys(raw, _FRAME_KEYS, "frame", "frame")
        vline = self.line("frame", "quasi_velocities")
        if "quasi_velocities" in raw:
            names = self.string_list(raw["quasi_velocities"], "frame.quasi_velocities", vline)
        else:
            self.fail(
                "required key 'quasi_velocities' (the names of v, q_dot = S v) is missing",
                "frame.quasi_velocities",
                fline,
            )
            self.names_refused = True
            names = None
        n = len(q)
        v: list[sp.Symbol] = []
        if names is not None:
            if len(names) != n:
                self.fail(
                    f"expected {n} quasi-velocities (one per coordinate), got {len(names)}",
                    "frame.quasi_velocities",
                    vline,
                )
                self.names_refused = True
            for i, nm in enumerate(names):
                ok = self.name_ok(
                    nm,
                    f"frame.quasi_velocities[{i}]",
                    self.loc.element(vline, nm),
                    "quasi-velocity",
                )
                if ok is not None:
                    v.append(sp.Symbol(ok, real=True))
        has_matrix, has_inverse = "matrix" in raw, "inverse" in raw
        if has_matrix == has_inverse:
            self.fail(
                "give exactly one of 'matrix' (S, q_dot = S v) and 'inverse' (S^-1, v = S^-1"
                " q_dot)",
                "frame",
                fline,
            )
            return None, None
        key = "matrix" if has_matrix else "inverse"
        # the frame depends on the coordinates and parameters only
        table = {k: e for k, e in self.table.items() if e not in self.velocity_like}
        M = self.matrix(raw[key], n, f"frame.{key}", self.line("frame", key), table, False)
        if M is None or len(v) != n:
            return None, None
        if has_inverse:
            try:
                if M.det() == 0:
                    raise ValueError("det == 0")
                M = sp.simplify(M.inv())
            except (ValueError, ZeroDivisionError):  # sympy's NonInvertibleMatrixError
                self.fail(
                    "the matrix S^-1 is singular (determinant 0); it has no inverse S",
                    "frame.inverse",
                    self.line("frame", key),
                )
                return None, None
        self.table.update({s.name: s for s in v})
        return M, v

    def matrix(
        self,
        raw: object,
        n: int,
        field: str,
        line: int | None,
        table: Mapping[str, sp.Expr],
        diagonal_ok: bool,
    ) -> sp.Matrix | None:
        """An n x n matrix: n rows of n entries, or (``diagonal_ok``) n diagonal entries."""
        if not isinstance(raw, list):
            self.fail(f"expected an array of {n} rows, got {_toml_type(raw)}", field, line)
            return None
        if diagonal_ok and all(not isinstance(r, list) for r in raw):
            if len(raw) != n:
                self.fail(
                    f"expected {n} diagonal entries (one per coordinate) or {n} rows,"
                    f" got {len(raw)} entries",
                    field,
                    line,
                )
                return None
            entries = [
                self.expression(e, f"{field}[{i},{i}]", self.loc.element(line, e), table)
                for i, e in enumerate(raw)
            ]
            if any(e is None for e in entries):
                return None
            return sp.diag(*entries)
        if len(raw) != n or not all(isinstance(r, list) and len(r) == n for r in raw):
            shape = [len(r) if isinstance(r, list) else _toml_type(r) for r in raw]
            self.fail(
                f"expected {n} rows of {n} entries (n = number of coordinates), got rows {shape}",
                field,
                line,
            )
            return None
        out = []
        ok = True
        row_line = line
        for i, row in enumerate(raw):
            for j, e in enumerate(row):
                at = self.loc.element(row_line, e)
                value = self.expression(e, f"{field}[{i},{j}]", at, table)
                ok &= value is not None
                out.append(value)
                if isinstance(e, str) and at is not None:
                    row_line = at
        return sp.Matrix(n, n, out) if ok else None

    def constraint_list(
        self, raw: object, n: int, field: str, line: int | None
    ) -> list[sp.Expr | list[sp.Expr]] | None:
        if not isinstance(raw, list):
            self.fail(
                f"expected an array of expressions linear in the velocities (or rows of"
                f" coefficients), got {_toml_type(raw)}",
                field,
                line,
            )
            return None
        out: list[sp.Expr | list[sp.Expr]] = []
        ok = True
        coeff_table = {k: e for k, e in self.table.items() if e not in self.velocity_like}
        for a, c in enumerate(raw):
            label = f"{field}[{a}]"
            if isinstance(c, list):
                if len(c) != n:
                    self.fail(
                        f"a coefficient row needs {n} entries (one per velocity), got {len(c)}",
                        label,
                        line,
                    )
                    ok = False
                    continue
                row = [
                    self.expression(e, f"{label}[{j}]", self.loc.element(line, e), coeff_table)
                    for j, e in enumerate(c)
                ]
                ok &= all(e is not None for e in row)
                out.append(row)
            else:
                at = self.loc.element(line, c)
                self.field_lines[label] = at
                expr = self.expression(c, label, at, self.table)
                ok &= expr is not None
                out.append(expr)
        return out if ok else None

    def force_list(self, raw: object, n: int) -> list[sp.Expr] | None:
        """``forces``: n expressions (absent: None, no applied forces)."""
        if raw is None:
            return None
        line = self.line(None, "forces")
        self.field_lines["forces"] = line
        if not isinstance(raw, list) or len(raw) != n:
            got = f"{len(raw)} entries" if isinstance(raw, list) else _toml_type(raw)
            self.fail(
                f"expected an array of {n} expressions (one generalized force per velocity),"
                f" got {got}",
                "forces",
                line,
            )
            return None
        out = []
        for k, e in enumerate(raw):
            at = self.loc.element(line, e)
            self.field_lines[f"forces[{k}]"] = at
            out.append(self.expression(e, f"forces[{k}]", at, self.table))
        return None if any(e is None for e in out) else out

    def walls(self, n: int) -> list[Wall]:
        raw = self.data.get("walls", [])
        if not isinstance(raw, list) or not all(isinstance(w, dict) for w in raw):
            self.fail(
                f"expected an array of tables ([[walls]] sections), got {_toml_type(raw)}",
                "walls",
                self.line(None, "walls") or self.loc.table("walls"),
            )
            return []
        if len(raw) > MAX_WALLS:
            self.fail(f"{len(raw)} walls (limit {MAX_WALLS})", "walls", None)
            return []
        walls = []
        for k, spec in enumerate(raw):
            label = f"walls[{k}]"
            wline = self.loc.table("walls", k)
            self.field_lines[label] = wline
            self.check_keys(spec, _WALL_KEYS, label, "walls", k)
            name = spec.get("name")
            if name is not None and (
                not isinstance(name, str) or not _IDENTIFIER.match(name) or len(name) > 64
            ):
                self.fail(
                    "a wall name must be an identifier (letters, digits, _; it names generated"
                    f" code), got {_short(name)}",
                    f"{label}.name",
                    self.line("walls", "name", k),
                    str(name)[:40],
                )
                name = None
            if "psi" not in spec:
                self.fail("required key 'psi' (the gap function) is missing", f"{label}.psi", wline)
                continue
            pline = self.line("walls", "psi", k)
            self.field_lines[f"{label}.psi"] = pline
            psi = self.expression(spec["psi"], f"{label}.psi", pline, self.table)
            restitution = self.restitution(spec.get("restitution", 1), label, k)
            law = spec.get("law", "newton")
            if law not in LAWS:
                self.fail(
                    f"law must be one of {', '.join(LAWS)}, got {_short(law, 60)}",
                    f"{label}.law",
                    self.line("walls", "law", k),
                    _clip(law),
                )
                continue
            iline = self.line("walls", "impulsive_constraints", k)
            self.field_lines[f"{label}.impulsive_constraints"] = iline
            impulsive = self.constraint_list(
                spec.get("impulsive_constraints", []), n, f"{label}.impulsive_constraints", iline
            )
            velocity = self.wall_velocity(spec.get("velocity"), n, label, k)
            if psi is None or restitution is None or impulsive is None or velocity is False:
                continue
            try:
                walls.append(
                    Wall(
                        psi,
                        restitution=restitution,
                        impulsive_constraints=impulsive,
                        name=name,
                        law=law,
                        velocity=velocity,
                    )
                )
            except SceneError as exc:
                for problem in exc.problems:
                    self.fail(problem, label, wline)
        return walls

    def wall_velocity(self, raw: object, n: int, label: str, k: int) -> list | bool | None:
        """``walls[k].velocity``: n expressions in t, q and the parameters; None when absent,
        False when refused (the problem is recorded)."""
        if raw is None:
            return None
        field_name = f"{label}.velocity"
        line = self.line("walls", "velocity", k)
        self.field_lines[field_name] = line
        if not isinstance(raw, list) or len(raw) != n:
            got = f"{len(raw)} entries" if isinstance(raw, list) else _toml_type(raw)
            self.fail(
                f"expected an array of {n} expressions (one component per velocity), got {got}",
                field_name,
                line,
            )
            return False
        table = {k_: e for k_, e in self.table.items() if e not in self.velocity_like}
        out = [
            self.expression(e, f"{field_name}[{j}]", self.loc.element(line, e), table)
            for j, e in enumerate(raw)
        ]
        return False if any(e is None for e in out) else out

    def restitution(self, raw: object, label: str, k: int) -> sp.Expr | None:
        field_name = f"{label}.restitution"
        line = self.line("walls", "restitution", k)
        params = {k_: e for k_, e in self.table.items() if isinstance(e, sp.Symbol)}
        value = self.expression(raw, field_name, line, params)
        if value is None:
            return None
        if not (value.is_number or (isinstance(value, sp.Symbol) and value in self.param_set)):
            self.fail(
                f"restitution must be a number in [0, 1] or a parameter name, got {_clip(value)}",
                field_name,
                line,
                _clip(raw),
            )
            return None
        if value.is_number and (not value.is_real or value < 0 or value > 1):
            self.fail(f"restitution {_clip(raw)} is outside [0, 1]", field_name, line, _clip(raw))
            return None
        if isinstance(value, sp.Symbol):
            # a restitution parameter: alpha in [0, 1], so its sign and default must allow it
            pline = self.entry_line("parameters", value.name)
            if not (value.is_nonnegative or value.is_positive):
                self.fail(
                    f"restitution parameter '{value.name}' must be declared with sign ="
                    ' "nonnegative" (or "positive"): a restitution coefficient lies in [0, 1]',
                    f"parameters.{value.name}.sign",
                    pline,
                    value.name,
                )
                return None
            default = self.defaults.get(value)
            if default is not None and default > 1:
                self.fail(
                    f"default value {_number_text(default)} of '{value.name}' is outside"
                    f" [0, 1], but '{value.name}' is the restitution of {label}",
                    f"parameters.{value.name}.value",
                    pline,
                    _number_text(default),
                )
                return None
        return value

    # derived sets, filled in by build()
    q: tuple[sp.Symbol, ...] = ()
    coord_like: frozenset[sp.Expr] = frozenset()
    velocity_like: frozenset[sp.Expr] = frozenset()
    param_set: frozenset[sp.Symbol] = frozenset()

    def build(self) -> SceneFile:
        data = self.data
        self.check_keys(data, _TOP_KEYS, "", None)
        name, description = self.header()
        q = self.coordinates()
        self.q = tuple(q)
        params, defaults = self.parameters()
        self.defaults = defaults
        self.param_set = frozenset(params)
        self.coord_like = frozenset({*q, *(velocity_of(s) for s in q)})
        fns = self.functions()
        self.velocity_like = frozenset(velocity_of(s) for s in q)
        S, v = self.frame(q)
        if v:
            self.velocity_like = self.velocity_like | frozenset(v)
            # in a frame, the kinetic energy and the constraints are written in the
            # quasi-velocities: the coordinate velocities have no place in the file
            names = ", ".join(s.name for s in v)
            for s in q:
                vel = velocity_of(s).name
                self.table.pop(vel, None)
                self.reserved[vel] = (
                    f"the velocity of coordinate '{s.name}' (with a [frame], velocities are"
                    f" written in the quasi-velocities {names})"
                )
        if self.names_refused:
            self.problems.raise_if_any(self.source)
        n = len(q)
        # metric or kinetic energy
        has_metric, has_T = "metric" in data, "kinetic_energy" in data
        metric = kinetic = None
        if has_metric == has_T:
            self.fail(
                "give exactly one of 'metric' and 'kinetic_energy'",
                "metric",
                self.line(None, "metric") or self.line(None, "kinetic_energy"),
            )
        elif has_metric and n:
            table = {k: e for k, e in self.table.items() if e not in self.velocity_like}
            metric = self.matrix(
                data["metric"], n, "metric", self.line(None, "metric"), table, True
            )
        elif has_T:
            kline = self.line(None, "kinetic_energy")
            self.field_lines["kinetic_energy"] = kline
            kinetic = self.expression(data["kinetic_energy"], "kinetic_energy", kline, self.table)
        pline = self.line(None, "potential")
        self.field_lines["potential"] = pline
        potential = self.expression(data.get("potential", 0), "potential", pline, self.table)
        forces = self.force_list(data.get("forces"), n)
        cline = self.line(None, "constraints")
        self.field_lines["constraints"] = cline
        constraints = self.constraint_list(data.get("constraints", []), n, "constraints", cline)
        walls = self.walls(n)
        unused = [p.name for p in params if p not in self.used]
        if unused and not self.problems.items:
            # (an expression refused above may be where a parameter is used)
            self.fail(
                f"declared but not used in any expression: {', '.join(unused)}",
                f"parameters.{unused[0]}",
                self.line("parameters", unused[0]) or self.line(None, "parameters"),
                unused[0],
            )
        self.problems.raise_if_any(self.source)
        try:
            scene = Scene(
                q,
                metric=metric,
                kinetic_energy=kinetic,
                potential=potential if potential is not None else 0,
                forces=forces,
                constraints=constraints or [],
                frame=S,
                quasi_velocities=v,
                walls=walls,
                parameters=params,
                name=name,
            )
        except SceneError as exc:
            for problem in exc.problems:
                field_name, line, rest = self.locate_problem(problem)
                self.problems.add(rest, field=field_name, line=line)
            self.problems.raise_if_any(self.source)
            raise  # pragma: no cover - every SceneError has at least one problem
        return SceneFile(scene=scene, defaults=defaults, functions=fns, description=description)

    def locate_problem(self, problem: str) -> tuple[str | None, int | None, str]:
        """The field a Scene validation message is about, its line in the file, and the
        message without its leading ``field:`` (the caller writes ``field (line N):``)."""
        m = re.match(r"(walls\[\d+\])(?: \([^)]*\))?(\.\w+)?(\[\d+\])?", problem)
        if m:
            base = m.group(1)
            full = base + (m.group(2) or "")
            elem = full + (m.group(3) or "")
            for key in (elem, full, base):
                if key in self.field_lines:
                    return key, self.field_lines[key], _after_field(problem, m.end())
            return base, None, _after_field(problem, m.end())
        m = re.match(
            r"(constraints|forces)(\[\d+\])?|(metric|kinetic_energy|potential|frame|walls)\b",
            problem,
        )
        if m:
            key = m.group(0)
            rest = _after_field(problem, m.end())
            if key in self.field_lines:
                return key, self.field_lines[key], rest
            root = m.group(1) or m.group(3)
            if root in ("frame", "walls"):
                return root, self.loc.table(root) or self.line(None, root), rest
            return root, self.field_lines.get(root) or self.line(None, root), rest
        return None, None, problem


def _after_field(problem: str, end: int) -> str:
    """``problem`` without the field name that ends at ``end`` (kept if more than a colon
    follows: ``walls[0].psi = x does not ...`` reads better whole)."""
    rest = problem[end:]
    if rest.startswith(":"):
        return rest[1:].strip()
    return problem


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


def _load(text: str, *, source: str, default_name: str, path: Path | None) -> SceneFile:
    if "\x00" in text:
        line = text[: text.index("\x00")].count("\n") + 1
        raise SceneFileError(
            [f"{source} (line {line}): null character in the file"],
            path=source,
            details=[(None, line, "\\x00")],
        )
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise _toml_error(text, source, str(exc)) from None
    except RecursionError:
        raise SceneFileError(
            [f"{source}: not valid TOML: arrays or tables nested too deeply"], path=source
        ) from None
    except ValueError as exc:  # an integer too long for int() (sys.get_int_max_str_digits)
        m = re.search(rf"[0-9][0-9_]{{{MAX_DIGITS},}}", text)
        if m is None:
            raise SceneFileError([f"{source}: not valid TOML: {exc}"], path=source) from None
        line = text[: m.start()].count("\n") + 1
        token = m.group(0)[:20] + "..."
        raise SceneFileError(
            [
                f"{source} (line {line}): integer {token} has {len(m.group(0))} digits"
                f" (limit {MAX_DIGITS})"
            ],
            path=source,
            details=[(None, line, token)],
        ) from None
    loader = _Loader(data, text, source, default_name)
    result = loader.build()
    return SceneFile(
        scene=result.scene,
        defaults=result.defaults,
        functions=result.functions,
        description=result.description,
        path=path,
    )


# ---------------------------------------------------------------------------------------
# writing


_REWRITES: dict[type, Any] = {
    sp.cot: lambda a: 1 / sp.tan(a),
    sp.sec: lambda a: 1 / sp.cos(a),
    sp.csc: lambda a: 1 / sp.sin(a),
    sp.coth: lambda a: 1 / sp.tanh(a),
    sp.sech: lambda a: 1 / sp.cosh(a),
    sp.csch: lambda a: 1 / sp.sinh(a),
    sp.acot: lambda a: sp.atan(1 / a),
}


class _FilePrinter(StrPrinter):
    """Prints expressions in the subset :func:`parse_expression` reads back.

    Applied functions of time print as their name (the scene file's convention).
    """

    def _print_Function(self, expr: sp.Function) -> str:
        if isinstance(expr, AppliedUndef):
            return expr.func.__name__
        return super()._print_Function(expr)


def _print_expression(expr: sp.Expr, where: str, table: Mapping[str, sp.Expr]) -> str:
    expr = sp.sympify(expr)
    for fn, rewrite in _REWRITES.items():
        if expr.has(fn):
            expr = expr.replace(fn, rewrite)
    if expr.has(sp.Derivative, sp.Integral, sp.Subs):
        raise SceneFileError([f"{where}: cannot write {_short(expr, 60)}: it holds a derivative"])
    text = _FilePrinter().doprint(expr)
    try:
        back = parse_expression(text, table, field=where)
    except ExpressionError as exc:
        raise SceneFileError(
            [f"{where}: cannot write {_short(expr, 60)} as a scene-file expression ({exc})"]
        ) from None
    if back != expr and sp.simplify(back - expr) != 0:
        raise SceneFileError(
            [f"{where}: {_short(expr, 60)} does not read back as itself (as {text!r})"]
        )
    return text


def _toml_string(text: str) -> str:
    out = ['"']
    for ch in text:
        if ch == '"':
            out.append('\\"')
        elif ch == "\\":
            out.append("\\\\")
        elif ch == "\n":
            out.append("\\n")
        elif ch == "\t":
            out.append("\\t")
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    out.append('"')
    return "".join(out)


def _toml_value(expr: sp.Expr, where: str, table: Mapping[str, sp.Expr]) -> str:
    if isinstance(expr, sp.Integer) and abs(int(expr)) < 2**53:
        return str(int(expr))
    if isinstance(expr, sp.Float) and expr._prec == 53 and math.isfinite(float(expr)):
        return repr(float(expr))  # a TOML float, read back as the same 53-bit Float
    return _toml_string(_print_expression(expr, where, table))


def _sign_of(symbol: sp.Symbol) -> str | None:
    for sign, assumptions in SIGNS.items():
        if sp.Symbol(symbol.name, **assumptions) == symbol:
            return sign
    return None


def _matrix_toml(M: sp.MatrixBase, where: str, table: Mapping[str, sp.Expr]) -> str:
    n = M.rows
    if all(M[i, j] == 0 for i in range(n) for j in range(n) if i != j):
        entries = ", ".join(_toml_value(M[i, i], f"{where}[{i},{i}]", table) for i in range(n))
        return f"[{entries}]"
    rows = [
        "  [" + ", ".join(_toml_value(M[i, j], f"{where}[{i},{j}]", table) for j in range(n)) + "],"
        for i in range(n)
    ]
    return "[\n" + "\n".join(rows) + "\n]"


def _row_expression(row: sp.MatrixBase, v: Sequence[sp.Symbol]) -> sp.Expr:
    return sp.Add(*[c * s for c, s in zip(row, v, strict=True)])


def _check_function(
    f: sp.Expr, arguments: Sequence[sp.Symbol], applied: Mapping[str, sp.Expr]
) -> None:
    """Refuse an applied undefined function that a scene file cannot declare."""
    name = f.func.__name__
    allowed = ", ".join(a.name for a in arguments)
    if not _IDENTIFIER.match(name) or len(name) > _MAX_IDENTIFIER:
        raise SceneFileError([f"functions: the name of {_short(f, 60)} is not an identifier"])
    if f.func not in (sp.Function(name, real=True), sp.Function(name)):
        raise SceneFileError(
            [
                f"functions: {name} has sympy assumptions that a scene file cannot write (it"
                " declares a function real, the default, or not: real = false)"
            ]
        )
    bad = [a for a in f.args if a not in arguments]
    if not f.args or bad or len(set(f.args)) != len(f.args):
        why = (
            f"its argument {_short(bad[0], 60)} is not t or a coordinate"
            if bad
            else "it has no arguments"
            if not f.args
            else "an argument is repeated"
        )
        raise SceneFileError(
            [
                f"functions: cannot write {_short(f, 60)}: {why}.  A scene file declares an"
                f" arbitrary function by its name and its arguments, distinct names among"
                f" {allowed} (a function of an expression, of a velocity or of a parameter"
                " would need the expression written in the file, which the format does not"
                " have: substitute a new function of the coordinates, or a symbol, before"
                " writing)"
            ]
        )
    if name in applied and applied[name] != f:
        raise SceneFileError(
            [
                f"functions: {applied[name]} and {f} have the same name; a scene file names"
                " each function once"
            ]
        )


def dump_scene(
    scene: Scene,
    *,
    defaults: Mapping[sp.Symbol | str, object] | None = None,
    description: str = "",
    functions: Mapping[str, sp.Expr] | None = None,
) -> str:
    """The TOML text of ``scene`` in the scene-file format (see the module documentation).

    ``defaults`` (parameter Symbol or name -> number) become the parameters' default
    values; ``functions`` (name -> expression in t) are written as defined functions.  The
    applied undefined functions in the scene (``f(t)``, ``V(x, y)``) are written as
    arbitrary functions with their arguments.  The metric is written as a matrix (also for
    a scene declared by its kinetic energy), the frame as ``matrix`` (S), constraints as
    expressions in the velocities.  ``load``-ing the text gives a scene with the same
    coordinates, parameters, metric, potential, frame, constraints and walls.

    Raises :class:`SceneFileError` when something cannot be written (a name that is not an
    identifier, a parameter with assumptions no ``sign`` gives, an expression outside the
    parser's subset such as a derivative, an undefined function of something else than
    distinct coordinates and t, such as ``V(x + y)``: the format declares a function by
    its argument names only).
    """
    decl = scene.declaration
    q, v = decl.coordinates, decl.velocities
    defaults = dict(defaults or {})
    by_name = {(k if isinstance(k, str) else k.name): val for k, val in defaults.items()}
    lines = [f"# symmech scene file (format {FORMAT_VERSION}); load with symmech.load_scene"]
    lines.append(f"format = {FORMAT_VERSION}")
    if not _IDENTIFIER.match(decl.name):
        raise SceneFileError([f"name: the scene name {decl.name!r} is not an identifier"])
    lines.append(f"name = {_toml_string(decl.name)}")
    if description:
        lines.append(f"description = {_toml_string(description)}")
    for s in (*q, *(v if decl.frame is not None else ())):
        if not _IDENTIFIER.match(s.name) or sp.Symbol(s.name, real=True) != s:
            raise SceneFileError(
                [f"coordinates: {s.name!r} must be a real symbol named by an identifier"]
            )
    lines.append("coordinates = [" + ", ".join(_toml_string(s.name) for s in q) + "]")

    # the symbol table for the read-back check
    table: dict[str, sp.Expr] = {"t": TIME}
    table.update({s.name: s for s in q})
    table.update({velocity_of(s).name: velocity_of(s) for s in q})
    table.update({s.name: s for s in v})
    # a symbolic restitution is a parameter too (the Scene may not list it)
    params = list(decl.parameters)
    for w in decl.walls:
        if isinstance(w.restitution, sp.Symbol) and w.restitution not in params:
            params.append(w.restitution)
    table.update({p.name: p for p in params})
    applied: dict[str, sp.Expr] = {}
    everything = [
        *decl.metric,
        decl.potential,
        *decl.forces,
        *decl.constraint_matrix,
        *(decl.frame if decl.frame is not None else []),
    ]
    for w in decl.walls:
        everything.extend([w.psi, *w.impulsive_matrix, *(w.velocity or [])])
    arguments = (TIME, *q)
    for e in everything:
        for f in sorted(sp.sympify(e).atoms(AppliedUndef), key=sp.default_sort_key):
            _check_function(f, arguments, applied)
            applied[f.func.__name__] = f
    table.update(applied)
    fn_defs = dict(functions or {})

    lines.append("metric = " + _matrix_toml(decl.metric, "metric", table))
    if decl.potential != 0:
        lines.append("potential = " + _toml_value(decl.potential, "potential", table))
    if any(e != 0 for e in decl.forces):
        forces = [_toml_value(e, f"forces[{k}]", table) for k, e in enumerate(decl.forces)]
        lines.append("forces = [" + ", ".join(forces) + "]")
    if decl.m:
        cons = [
            _toml_value(
                _row_expression(decl.constraint_matrix.row(a), v), f"constraints[{a}]", table
            )
            for a in range(decl.m)
        ]
        lines.append("constraints = [" + ", ".join(cons) + "]")

    unknown = sorted(set(by_name) - {p.name for p in params})
    if unknown:
        raise SceneFileError([f"defaults: {unknown} are not parameters of the scene"])
    lines.append("")
    lines.append("[parameters]")
    for p in params:
        sign = _sign_of(p)
        if sign is None:
            raise SceneFileError(
                [f"parameters.{p.name}: its assumptions {p.assumptions0} match no sign"]
            )
        parts = []
        if p.name in by_name:
            value = by_name[p.name]
            try:
                # a string is parsed by the safe parser, never sympified
                number = to_expression(value, {}, field=f"defaults[{p.name!r}]")
            except ExpressionError as exc:
                raise SceneFileError([str(exc)]) from None
            if not number.is_number:
                raise SceneFileError([f"defaults: {p.name} = {value!r} is not a number"])
            parts.append(f"value = {_toml_value(number, f'parameters.{p.name}', {})}")
        if sign != "positive":
            parts.append(f"sign = {_toml_string(sign)}")
        lines.append(f"{p.name} = {{ {', '.join(parts)} }}" if parts else f"{p.name} = {{}}")

    if applied or fn_defs:
        lines.append("")
        lines.append("[functions]")
        for nm, f in applied.items():
            parts = []
            if f.args != (TIME,):
                parts.append("arguments = [" + ", ".join(f'"{a.name}"' for a in f.args) + "]")
            if f.func != sp.Function(nm, real=True):
                parts.append("real = false")
            lines.append(f"{nm} = {{ {', '.join(parts)} }}" if parts else f"{nm} = {{}}")
        for nm, expr in fn_defs.items():
            lines.append(f"{nm} = {_toml_value(expr, f'functions.{nm}', table)}")

    if decl.frame is not None:
        lines.append("")
        lines.append("[frame]")
        lines.append("quasi_velocities = [" + ", ".join(_toml_string(s.name) for s in v) + "]")
        rows = [
            "  ["
            + ", ".join(
                _toml_value(decl.frame[i, j], f"frame.matrix[{i},{j}]", table)
                for j in range(decl.n)
            )
            + "],"
            for i in range(decl.n)
        ]
        lines.append("matrix = [\n" + "\n".join(rows) + "\n]")

    for k, w in enumerate(decl.walls):
        label = f"walls[{k}]"
        lines.append("")
        lines.append("[[walls]]")
        if w.wall.name:
            if not _IDENTIFIER.match(w.wall.name):
                raise SceneFileError([f"{label}.name: {w.wall.name!r} is not an identifier"])
            lines.append(f"name = {_toml_string(w.wall.name)}")
        lines.append(f"psi = {_toml_value(w.psi, f'{label}.psi', table)}")
        if w.restitution != 1:
            lines.append(
                f"restitution = {_toml_value(w.restitution, f'{label}.restitution', table)}"
            )
        if w.impulsive_matrix.rows:
            nus = [
                _toml_value(
                    _row_expression(w.impulsive_matrix.row(A), v),
                    f"{label}.impulsive_constraints[{A}]",
                    table,
                )
                for A in range(w.impulsive_matrix.rows)
            ]
            lines.append("impulsive_constraints = [" + ", ".join(nus) + "]")
        if w.law != "newton":
            lines.append(f"law = {_toml_string(w.law)}")
        if w.velocity is not None:
            comps = [
                _toml_value(c, f"{label}.velocity[{j}]", table) for j, c in enumerate(w.velocity)
            ]
            lines.append("velocity = [" + ", ".join(comps) + "]")
    return "\n".join(lines) + "\n"


def save_scene(
    scene: Scene,
    path: str | os.PathLike[str],
    *,
    defaults: Mapping[sp.Symbol | str, object] | None = None,
    description: str = "",
    functions: Mapping[str, sp.Expr] | None = None,
) -> Path:
    """Write :func:`dump_scene` of ``scene`` to ``path``; return the path."""
    text = dump_scene(scene, defaults=defaults, description=description, functions=functions)
    p = Path(path)
    p.write_text(text, encoding="utf-8")
    return p
