"""The scene file reader's shared state and primitives (see :mod:`symmech.scenefile.reader`)."""

from __future__ import annotations

import keyword
import math
from collections.abc import Mapping, Sequence
from typing import Any

import sympy as sp

from symmech.declaration.expression_rules import text_nodes
from symmech.declaration.expressions import (
    ALLOWED_CONSTANTS,
    ALLOWED_FUNCTIONS,
    MAX_DIGITS,
    parse_expression,
)
from symmech.declaration.symbols import t as TIME
from symmech.errors import ExpressionError
from symmech.scenefile.format import (
    _IDENTIFIER,
    _MAX_IDENTIFIER,
    MAX_FILE_BYTES,
    MAX_FILE_CALLS,
    MAX_FILE_NODES,
    _allowed_kinds,
    _clip,
    _did_you_mean,
    _Problems,
    _short,
    _toml_type,
)
from symmech.scenefile.locate import _Locator


def applications(text: str) -> set[str]:
    """Every function application ``name(...)`` written in ``text`` (nested ones too), by
    one scan matching brackets: the name and the text up to its closing bracket."""
    found: set[str] = set()
    opened: list[int] = []  # where each open bracket's application starts (-1: none)
    for k, ch in enumerate(text):
        if ch == "(":
            j = k
            while j > 0 and (text[j - 1].isalnum() or text[j - 1] == "_"):
                j -= 1
            opened.append(j if j < k and not text[j].isdigit() else -1)
        elif ch == ")" and opened:
            start = opened.pop()
            if start >= 0:
                found.add(text[start : k + 1])
    return found


def tree_size(expr: sp.Basic) -> int:
    """The number of nodes of ``expr``'s tree, a subtree counted where it occurs (what
    the file's text spelt out), by an iterative walk."""
    count, stack = 0, [expr]
    while stack:
        e = stack.pop()
        count += 1
        stack.extend(e.args)
    return count


class _LoaderBase:
    """What every part of the loader shares: the parsed data, the line locator, the
    problems found so far, and reading one expression or list of names."""

    # derived sets, filled in by build()
    q: tuple[sp.Symbol, ...] = ()
    coord_like: frozenset[sp.Expr] = frozenset()
    velocity_like: frozenset[sp.Expr] = frozenset()
    param_set: frozenset[sp.Symbol] = frozenset()

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
        #: the nodes the file's expressions may still use (MAX_FILE_NODES in all)
        self.nodes_left = MAX_FILE_NODES
        #: the function applications the file's expressions wrote (MAX_FILE_CALLS at most)
        self.calls: set[str] = set()
        #: set when a budget ran out: the other expressions are not read (one problem)
        self.over_budget = False

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
        if not isinstance(value, str):
            return self._number(value, field, line)
        # the line where the text starts: a multi-line string's content starts below its key
        line = self.loc.element(line, value)
        if not self._affordable(value, field, line):
            return None
        try:
            # each expression may use what the file's budget has left (the file's size
            # bounds its length)
            expr = parse_expression(
                value,
                table,
                field=field,
                line=line,
                max_length=MAX_FILE_BYTES,
                max_nodes=self.nodes_left,
            )
        except ExpressionError as exc:
            self._refused(exc, field, line, table)
            return None
        self.used |= expr.free_symbols
        # what reading it cost: the nodes parsed (an entry such as y + y + ... + y parses
        # to many and builds few), or built, whichever is more
        self.nodes_left -= max(tree_size(expr), text_nodes(value))
        return expr

    def _number(self, value: object, field: str, line: int | None) -> sp.Expr | None:
        """A number entry as an exact Integer or a Float; None after recording why it is
        not one (a boolean, another TOML type, an infinite float, too many digits)."""
        if isinstance(value, bool) or not isinstance(value, int | float):
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
        return sp.Integer(value) if isinstance(value, int) else sp.Float(value)

    def _affordable(self, value: str, field: str, line: int | None) -> bool:
        """Whether the file's budget allows parsing ``value``: operands and operations left,
        and distinct function applications; else the budget is recorded as run out."""
        if self.over_budget:
            return False  # (reported once, where the file's budget ran out)
        if self.nodes_left <= 0:
            self._over_budget(
                f"the file's expressions hold more than {MAX_FILE_NODES} operands and"
                f" operations together (limit MAX_FILE_NODES={MAX_FILE_NODES})",
                field,
                line,
            )
            return False
        self.calls |= applications(value)
        if len(self.calls) > MAX_FILE_CALLS:
            self._over_budget(
                f"the file's expressions apply functions to more than {MAX_FILE_CALLS}"
                f" distinct arguments together (limit MAX_FILE_CALLS={MAX_FILE_CALLS})",
                field,
                line,
            )
            return False
        return True

    def _refused(
        self, exc: ExpressionError, field: str, line: int | None, table: Mapping[str, sp.Expr]
    ) -> None:
        """Record why an expression string was refused, in the words of the file: the
        budget, a function of time called, a declared name where it may not appear."""
        token = getattr(exc, "token", None)
        if "expression too large" in str(exc):
            self._over_budget(
                f"expression too large: the file's expressions hold more than"
                f" {MAX_FILE_NODES} operands and operations together (limit"
                f" MAX_FILE_NODES={MAX_FILE_NODES})",
                field,
                getattr(exc, "line", line),
            )
        elif token in self.function_names and "not a function" in str(exc):
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

    def _over_budget(self, message: str, field: str, line: int | None) -> None:
        self.over_budget = True
        self.fail(message, field, line)

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
