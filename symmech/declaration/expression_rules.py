"""The rules of the expression parser (:mod:`symmech.declaration.expressions`): its limits,
the functions and constants a string may use, what it refuses, and the helpers that read
the source text and the numbers it builds."""

from __future__ import annotations

import ast
import difflib
import math
import numbers
import re
import unicodedata
from collections.abc import Callable, Iterator, Mapping
from types import MappingProxyType
from typing import NoReturn

import sympy as sp

from symmech.declaration.admissible import ELEMENTARY_FUNCTIONS
from symmech.declaration.constants import (
    MAX_NUMBER_BITS,
)
from symmech.errors import ExpressionError

#: Default limit on the number of characters of an expression string.
MAX_LENGTH = 10_000
#: Default limit on the number of nodes (operands, operations, calls) of the parsed tree.
MAX_NODES = 2_000
#: Default limit on the nesting depth (brackets in the text, operations in the tree).
MAX_DEPTH = 50
#: Default limit on the absolute value of a numeric exponent.
MAX_EXPONENT = 64
#: Default limit on the number of digits of an integer literal.
MAX_DIGITS = 40
#: Limit on the degree of an expression in any one symbol (function calls count as degree
#: 1): ``((x + y)**60 + 1)**60`` has exponents within MAX_EXPONENT but degree 3600 in x,
#: and expanding or differentiating it would take minutes and gigabytes.
MAX_DEGREE = 256
# MAX_NUMBER_DIGITS (from symmech.declaration.constants): limit on the digits of the
# numerator or denominator of any exact number built while parsing (root extraction and
# factoring of larger integers get slow).
_MAX_NUMBER_BITS = MAX_NUMBER_BITS

#: The functions a string may call: name -> sympy function, the elementary functions a
#: scene's fields may hold (:data:`symmech.declaration.admissible.ELEMENTARY_FUNCTIONS`,
#: one list for both) and ``sqrt``.  All are smooth (analytic) where defined.  ``atan2``
#: takes two arguments ``(y, x)``, the others one.
ALLOWED_FUNCTIONS: Mapping[str, Callable[..., sp.Expr]] = MappingProxyType(
    {**{f.__name__: f for f in ELEMENTARY_FUNCTIONS}, "sqrt": sp.sqrt}
)
_ARITY = {"atan2": 2}

#: Named constants usable in strings (a declared symbol of the same name takes precedence).
ALLOWED_CONSTANTS: Mapping[str, sp.Expr] = MappingProxyType({"pi": sp.pi, "E": sp.E})

# Chains of operators of one group are flattened (one nesting level, iterative building).
_GROUPS: dict[type, str] = {ast.Add: "+", ast.Sub: "+", ast.Mult: "*", ast.Div: "*"}
# Chains up to this length are folded left to right with Python's operators, so the result
# is exactly what the same text typed in Python with sympy objects gives.  Longer chains
# (pathological input) are built with one sympy.Add / sympy.Mul call: the same value, in
# linear rather than quadratic time, but products may then be grouped differently
# (2*(x + 1)*y gives 2*y*(x + 1) rather than y*(2*x + 2)).
_SEQUENTIAL_FOLD_MAX = 64

_OPERATOR_TOKENS: dict[type, str] = {
    ast.Add: "+",
    ast.Sub: "-",
    ast.Mult: "*",
    ast.Div: "/",
    ast.Pow: "**",
    ast.FloorDiv: "//",
    ast.Mod: "%",
    ast.MatMult: "@",
    ast.BitXor: "^",
    ast.BitOr: "|",
    ast.BitAnd: "&",
    ast.LShift: "<<",
    ast.RShift: ">>",
    ast.Not: "not",
    ast.Invert: "~",
    ast.UAdd: "+",
    ast.USub: "-",
}

_FORBIDDEN: dict[type, str] = {
    ast.Attribute: "attribute access",
    ast.Subscript: "subscript",
    ast.Slice: "slice",
    ast.Lambda: "lambda",
    ast.ListComp: "list comprehension",
    ast.SetComp: "set comprehension",
    ast.DictComp: "dict comprehension",
    ast.GeneratorExp: "generator expression",
    ast.Compare: "comparison",
    ast.BoolOp: "boolean operator",
    ast.IfExp: "conditional expression",
    ast.JoinedStr: "f-string",
    ast.FormattedValue: "f-string",
    ast.NamedExpr: "assignment expression (:=)",
    ast.Starred: "starred expression",
    ast.Dict: "dict literal",
    ast.List: "list literal",
    ast.Set: "set literal",
    ast.Tuple: "tuple",
    ast.Await: "await",
    ast.Yield: "yield",
    ast.YieldFrom: "yield",
}

# Values that mark an undefined or complex result.
_UNDEFINED = (sp.zoo, sp.nan, sp.oo, -sp.oo)
_LINE_BREAK = re.compile(r"\r\n|\r|\n")
_SNIPPET_MAX = 60
# ASCII characters refused before parsing (Python drops what follows '#', joins lines at
# '\\'; the others are not part of any expression) and why.
_REFUSED_CHARACTERS = {
    "#": "a comment would silently drop the rest of the line",
    "\\": "a line continuation is not needed: a line break is whitespace",
    "$": "it is not part of an expression",
    "?": "it is not part of an expression",
    "!": "it is not part of an expression",
    "`": "it is not part of an expression",
}


def _bits(r: sp.Rational) -> int:
    return max(int(r.p).bit_length(), int(r.q).bit_length())


def _top_factors(value: sp.Expr) -> Iterator[sp.Expr]:
    """The factors at the top of ``value``, looking through one Add, then one Mul: where
    sympy's automatic evaluation leaves what it merges (coefficients, constant terms,
    powers of a common base)."""
    for term in value.args if value.is_Add else (value,):
        yield from term.args if term.is_Mul else (term,)


def _top_numbers(value: sp.Expr) -> list[sp.Rational]:
    """The exact numbers at the top of ``value``: constant terms, coefficients, numeric bases
    of powers (looking through one Add, then one Mul, then one Pow)."""
    found = []
    for factor in _top_factors(value):
        number = factor.base if factor.is_Pow else factor
        if number.is_Rational:
            found.append(number)
    return found


def _weight(value: sp.Expr) -> int:
    """Bound on the bits that the numbers of ``value`` add to a product or power of it.

    Products merge the coefficients and the numeric bases of the factors (bits add up); the
    terms of a sum are not merged (only their common content can be pulled out).
    """
    bits = [_bits(n) for n in _top_numbers(value)]
    if value.is_Add:
        return max(bits, default=0)
    return sum(bits)


def _digits_of(n: int) -> int:
    """Approximate number of decimal digits of ``n`` (no int-to-str conversion)."""
    return max(1, math.floor(abs(n).bit_length() * math.log10(2)) + 1)


def _number_to_sympy(value: object) -> sp.Expr | None:
    """A finite real Python number as a sympy number; None if ``value`` is not one."""
    if isinstance(value, bool):
        return None
    if isinstance(value, numbers.Integral):
        return sp.Integer(int(value))
    if isinstance(value, numbers.Rational):
        return sp.Rational(int(value.numerator), int(value.denominator))
    if isinstance(value, numbers.Real):
        f = float(value)
        if not math.isfinite(f):
            return None
        return sp.Float(f)
    return None


def _degree(value: sp.Expr) -> int:
    """A bound on the largest degree of ``value`` in any one of its symbols (what expanding
    it costs): a function call or a non-integer power of an atom counts 1 in each of its
    symbols, powers multiply, products add, sums take the largest.  A product of many
    distinct symbols has degree 1; ``((x + y)**60 + 1)**60`` has degree 3600 in x.
    Iterative and memoised: safe on deep trees."""
    memo: dict[sp.Basic, dict[sp.Basic, int]] = {}
    stack: list[tuple[sp.Basic, bool]] = [(value, False)]
    while stack:
        e, ready = stack.pop()
        if e in memo:
            continue
        if not e.free_symbols:
            memo[e] = {}
            continue
        if e.is_Symbol or not (e.is_Add or e.is_Mul or e.is_Pow):
            memo[e] = dict.fromkeys(e.free_symbols, 1)
            continue
        if not ready:
            stack.append((e, True))
            stack.extend((a, False) for a in e.args if a not in memo)
            continue
        out: dict[sp.Basic, int] = {}
        if e.is_Add:
            for a in e.args:
                for sym, d in memo[a].items():
                    out[sym] = max(out.get(sym, 0), d)
        elif e.is_Mul:
            for a in e.args:
                for sym, d in memo[a].items():
                    out[sym] = out.get(sym, 0) + d
        else:
            k = math.ceil(abs(float(e.exp))) if e.exp.is_Number else 1
            out = {sym: d * k for sym, d in memo[e.base].items()}
            for sym in e.exp.free_symbols:
                out[sym] = max(out.get(sym, 0), 1)
        memo[e] = out
    return max(memo[value].values(), default=0)


class _Source:
    """The text being parsed, with the bookkeeping to report positions in it."""

    def __init__(self, original: str, field: str, line: int | None):
        self.field = field
        self.line = line
        stripped = original.lstrip(" \t\f\r\n")
        prefix = original[: len(original) - len(stripped)]
        prefix_lines = _LINE_BREAK.split(prefix)
        # Python refuses an indented first line, so leading blanks are dropped before
        # parsing; positions are reported in the original text.
        self.skipped_lines = len(prefix_lines) - 1
        self.first_col_shift = len(prefix_lines[-1])
        self.text = stripped
        self.lines = _LINE_BREAK.split(stripped)
        self._encoded: list[bytes] | None = None

    def position(self, lineno: int | None, char_col: int | None) -> tuple[int | None, int | None]:
        """(line, 1-based column) to report for a 1-based line and 0-based column of the text.

        The line is the file line when the caller gave ``line``; otherwise the line within the
        text, or None for the first line (a one-line text needs no line number).
        """
        if lineno is None or char_col is None:
            return self.line, None
        rel_line = lineno + self.skipped_lines
        col = char_col + 1 + (self.first_col_shift if lineno == 1 else 0)
        if self.line is not None:
            return self.line + rel_line - 1, col
        return (rel_line if rel_line > 1 else None), col

    def char_col(self, lineno: int, byte_col: int) -> int:
        """Convert an AST column (UTF-8 bytes) into characters."""
        if not 1 <= lineno <= len(self.lines):
            return byte_col
        encoded = self.lines[lineno - 1].encode("utf-8")
        return len(encoded[:byte_col].decode("utf-8", errors="replace"))

    def raw(self, node: ast.AST) -> str | None:
        """The text of a one-line ``node`` exactly as written (None if it spans lines)."""
        lineno, end_lineno = getattr(node, "lineno", None), getattr(node, "end_lineno", None)
        col, end_col = getattr(node, "col_offset", None), getattr(node, "end_col_offset", None)
        if lineno is None or col is None or end_col is None:
            return None
        if lineno != end_lineno or lineno > len(self.lines):
            return None
        if self._encoded is None:
            self._encoded = [line.encode("utf-8") for line in self.lines]
        return self._encoded[lineno - 1][col:end_col].decode("utf-8", errors="replace")

    def snippet(self, node: ast.AST) -> str:
        """The text of ``node`` (whitespace collapsed, shortened)."""
        lineno = getattr(node, "lineno", None)
        end_lineno = getattr(node, "end_lineno", None)
        col = getattr(node, "col_offset", None)
        end_col = getattr(node, "end_col_offset", None)
        if lineno is None or end_lineno is None or col is None or end_col is None:
            return type(node).__name__
        if end_lineno > len(self.lines):
            return type(node).__name__
        if self._encoded is None:
            self._encoded = [line.encode("utf-8") for line in self.lines]
        enc = self._encoded
        if lineno == end_lineno:
            parts = [enc[lineno - 1][col:end_col]]
        else:
            parts = [enc[lineno - 1][col:], *enc[lineno : end_lineno - 1]]
            parts.append(enc[end_lineno - 1][:end_col])
        segment = " ".join(p.decode("utf-8", errors="replace") for p in parts)
        return _shorten(" ".join(segment.split()))

    def error(
        self,
        message: str,
        *,
        lineno: int | None = None,
        char_col: int | None = None,
        token: str | None = None,
    ) -> ExpressionError:
        at_line, at_col = self.position(lineno, char_col)
        parts = ([] if at_line is None else [f"line {at_line}"]) + (
            [] if at_col is None else [f"col {at_col}"]
        )
        prefix = f"{self.field} ({', '.join(parts)})" if parts else self.field
        exc = ExpressionError(f"{prefix}: {message}")
        exc.field = self.field  # type: ignore[attr-defined]
        exc.line = at_line  # type: ignore[attr-defined]
        exc.column = at_col  # type: ignore[attr-defined]
        exc.token = token  # type: ignore[attr-defined]
        return exc

    def fail(self, node: ast.AST, message: str, token: str | None = None) -> NoReturn:
        lineno = getattr(node, "lineno", None)
        col = getattr(node, "col_offset", None)
        char_col = None if lineno is None or col is None else self.char_col(lineno, col)
        raise self.error(message, lineno=lineno, char_col=char_col, token=token)


def _shorten(text: str) -> str:
    return text if len(text) <= _SNIPPET_MAX else text[: _SNIPPET_MAX - 3] + "..."


def _did_you_mean(name: str, candidates: list[str]) -> str:
    close = difflib.get_close_matches(name, candidates, n=3, cutoff=0.6)
    return f"; did you mean {' or '.join(repr(c) for c in close)}?" if close else ""


def _check_brackets(src: _Source, max_depth: int) -> None:
    """Refuse brackets nested deeper than ``max_depth`` before Python's parser sees them."""
    depth = 0
    for lineno, line in enumerate(src.lines, start=1):
        for col, ch in enumerate(line):
            if ch in "([{":
                depth += 1
                if depth > max_depth:
                    raise src.error(
                        f"brackets nested more than {max_depth} levels deep at '{ch}'"
                        f" (limit max_depth={max_depth})",
                        lineno=lineno,
                        char_col=col,
                        token=ch,
                    )
            elif ch in ")]}":
                depth = max(0, depth - 1)


#: a run of word characters and dots (a name, a number such as 1_000, 0x1F, 2.5j, with an
#: exponent's sign: 1e-5), or of operator characters (``+``, ``**``, ``*-``): each is at
#: least one node of the expression's tree (an operand, an operation)
_NODE = re.compile(r"[\w.]+(?:(?<=[eE])[+-][\w.]+)?|[-+*/%@<>=!&|^~]+")


def text_nodes(text: str) -> int:
    """A lower bound of the nodes (operands and operations) of the tree of the valid
    expression ``text``, read from its text alone: the runs of :data:`_NODE`."""
    return sum(1 for _ in _NODE.finditer(text))


def _check_operands(src: _Source, max_nodes: int) -> None:
    """Refuse a text of more than ``max_nodes`` operands and operations before Python's
    parser sees it (parsing 400 kB of bracketed products takes it a second or more).
    Each run of :data:`_NODE` is at least one node of the tree that
    :meth:`_Parser.validate` counts, so their number bounds that count from below for
    every valid expression (only forms refused anyway, strings and keywords, can count
    more); the message is ``validate``'s."""
    count = text_nodes(src.text)
    if count > max_nodes:
        raise src.error(
            f"expression too large: more than {max_nodes} operands and operations"
            f" (limit max_nodes={max_nodes}; at least {count} in its text)"
        )


def _check_characters(src: _Source) -> None:
    """Refuse the characters Python would drop or reinterpret, and those of no expression.

    See the module documentation: ``#`` and ``\\`` (a comment, a line continuation), ``$ ? !``
    and backquotes, control characters but tabs, and non-ASCII characters that cannot be
    part of a name.  Line breaks are not in ``src.lines``.
    """
    for lineno, line in enumerate(src.lines, start=1):
        if line.isascii() and line.isprintable() and not any(c in line for c in "#\\$?!`"):
            continue  # the common case, checked at C speed
        for col, ch in enumerate(line):
            if ch in _REFUSED_CHARACTERS:
                why = _REFUSED_CHARACTERS[ch]
            elif ch == "\t" or (" " <= ch <= "~"):
                continue
            elif ch == "\x00":
                why = "null character in the text"
                raise src.error(why, lineno=lineno, char_col=col, token="\\x00")
            elif ch.isascii() or not ("a" + ch).isidentifier():
                name = unicodedata.name(ch, "a control character")
                token = f"U+{ord(ch):04X}"
                raise src.error(
                    f"character {token} ({name}) is not allowed: an expression is written with"
                    " letters, digits, _ . + - * / ( ) , and spaces",
                    lineno=lineno,
                    char_col=col,
                    token=token,
                )
            else:
                continue
            raise src.error(
                f"character '{ch}' is not allowed: {why}", lineno=lineno, char_col=col, token=ch
            )


def _joined(src: _Source) -> str:
    """The text for Python's parser: a line break is whitespace (explicit line joining).

    Each line but the last ends with `` \\``, so the parser reads one logical line while the
    positions it reports stay those of the physical lines (and of their characters).
    """
    lines = _LINE_BREAK.split(src.text.rstrip())
    return " \\\n".join(lines)


def _syntax_error(src: _Source, exc: SyntaxError) -> ExpressionError:
    lineno = exc.lineno if exc.lineno and exc.lineno >= 1 else None
    char_col = exc.offset - 1 if lineno is not None and exc.offset and exc.offset >= 1 else None
    near = ""
    token = None
    if lineno is not None and char_col is not None and lineno <= len(src.lines):
        rest = src.lines[lineno - 1][char_col:].strip()
        token = _shorten(rest[:20]) if rest else None
        if token:
            near = f" at '{token}'"
        else:
            near = (
                " at the end of the line" if lineno < len(src.lines) else " at the end of the text"
            )
    message = (exc.msg or "invalid syntax").rstrip(".")
    return src.error(
        f"syntax error: {message}{near}", lineno=lineno, char_col=char_col, token=token
    )
