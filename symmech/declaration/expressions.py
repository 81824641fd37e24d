"""Safe parsing of expression strings into sympy expressions.

Scene files and the Python API accept expressions as strings (``"m*(xdot**2 + ydot**2)/2"``).
Such a string is *never* handed to ``eval``, ``exec``, ``compile`` (other than to build an
AST), ``sympify``, ``parse_expr`` or any other sympy parser.  It is parsed by
``ast.parse(text, mode="eval")`` and the tree is checked against a whitelist before a sympy
expression is built from it, node by node:

* numbers: ``int`` literals become :class:`sympy.Integer`, ``float`` literals become
  :class:`sympy.Float` (``sympy.Float(value)``, 53-bit, as ``sympy.sympify`` gives for a
  Python float; write ``1/10`` rather than ``0.1`` for an exact rational).  Complex, boolean,
  ``None``, string and bytes literals are refused;
* names: the keys of the ``symbols`` mapping given by the caller, then the constants
  ``pi`` and ``E`` (:data:`ALLOWED_CONSTANTS`) unless a symbol of that name shadows them;
* the operators ``+ - * / **`` and unary ``-`` and ``+``; parentheses;
* calls of the smooth functions of :data:`ALLOWED_FUNCTIONS`, with positional arguments
  only, in the right number.  In call position a name always means the function (a symbol
  named ``sin`` is still usable as a bare ``sin``).

Before Python's parser sees the text, its characters are checked, so that nothing in it is
silently dropped or changed: ``#`` (Python would read the rest of the line as a comment and
drop it: ``"m*g*y # +1000*x"`` would be ``m*g*y``), ``\\`` (a line continuation), ``$ ? !``
and backquotes, control characters other than tabs and line breaks, and non-ASCII characters
that cannot be part of a name (a no-break space, a zero-width joiner, a bidirectional
override, a fullwidth ``＋``) are refused with their position.  A name must be written as
Python reads it: Python NFKC-normalises identifiers, so ``𝐱`` or a fullwidth ``ｘ`` would
silently mean ``x``; such a name is refused unless it is itself a key of ``symbols``
(names such as ``θ``, unchanged by NFKC, are allowed).  A line break is whitespace: an
expression may span lines (a TOML multi-line string) without brackets.

Everything else (attribute access, subscripts, lambdas, comprehensions, comparisons,
boolean operators, conditional expressions, f-strings, ``:=``, starred arguments, keyword
arguments, container literals, calls of any other name, ...) is refused with an
:class:`~symmech.errors.ExpressionError` naming the field, the position (line and
1-based column, in characters) and the offending text.  The exception also carries them as
attributes: ``field``, ``line`` (the file line when the caller gave ``line``, else the line
within a multi-line text, else None), ``column`` and ``token`` (None when unknown).

Resource limits (keyword arguments of :func:`parse_expression`; defaults below) keep a
hostile string from exhausting time or memory:

* ``max_length`` (:data:`MAX_LENGTH`): characters in the text;
* ``max_nodes`` (:data:`MAX_NODES`): operands, operators and calls in the parsed tree;
* ``max_depth`` (:data:`MAX_DEPTH`): nesting of brackets in the text and of operations in
  the tree (a chain ``a + b - c + ...`` or ``a*b/c*...`` counts as one level);
* ``max_exponent`` (:data:`MAX_EXPONENT`): largest absolute value of a numeric exponent,
  literal or computed (``9**9**9`` is refused because ``9**9`` exceeds it);
* ``max_digits`` (:data:`MAX_DIGITS`): digits of an integer literal.

Besides, no exact number built while parsing may have a numerator or denominator of more
than :data:`MAX_NUMBER_DIGITS` digits (``(9**64)**64`` is refused before it is computed),
and a result that is undefined (``1/0``, ``log(0)``) or complex (``sqrt(-1)``) is refused.
"""

from __future__ import annotations

import ast
import difflib
import math
import numbers
import operator
import re
import unicodedata
import warnings
from collections.abc import Callable, Iterator, Mapping
from types import MappingProxyType
from typing import NoReturn

import sympy as sp

from symmech.declaration.constants import (
    MAX_NUMBER_BITS,
    MAX_NUMBER_DIGITS,
    constant_out_of_range,
    range_problem,
)
from symmech.errors import ExpressionError

__all__ = [
    "ALLOWED_CONSTANTS",
    "ALLOWED_FUNCTIONS",
    "MAX_DEGREE",
    "MAX_DEPTH",
    "MAX_DIGITS",
    "MAX_EXPONENT",
    "MAX_LENGTH",
    "MAX_NODES",
    "MAX_NUMBER_DIGITS",
    "parse_expression",
    "to_expression",
]

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

#: The functions a string may call: name -> sympy function.  All are smooth (analytic)
#: where defined.  ``atan2`` takes two arguments ``(y, x)``, the others one.
ALLOWED_FUNCTIONS: Mapping[str, Callable[..., sp.Expr]] = MappingProxyType(
    {
        "sin": sp.sin,
        "cos": sp.cos,
        "tan": sp.tan,
        "asin": sp.asin,
        "acos": sp.acos,
        "atan": sp.atan,
        "atan2": sp.atan2,
        "sinh": sp.sinh,
        "cosh": sp.cosh,
        "tanh": sp.tanh,
        "exp": sp.exp,
        "log": sp.log,
        "sqrt": sp.sqrt,
    }
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


class _Parser:
    def __init__(
        self,
        src: _Source,
        symbols: Mapping[str, sp.Basic] | None,
        *,
        max_nodes: int,
        max_depth: int,
        max_exponent: int,
        max_digits: int,
    ):
        self.src = src
        self.symbols = symbols
        self.max_nodes = max_nodes
        self.max_depth = max_depth
        self.max_exponent = max_exponent
        self.max_digits = max_digits
        self.max_literal = 10**max_digits

    # -- pass 1: whitelist, size and depth, iteratively ------------------------------------

    def validate(self, root: ast.expr) -> None:
        stack: list[tuple[ast.expr, int]] = [(root, 1)]
        count = 0
        while stack:
            node, depth = stack.pop()
            count += 1
            if count > self.max_nodes:
                self.src.fail(
                    node,
                    f"expression too large: more than {self.max_nodes} operands and operations"
                    f" (limit max_nodes={self.max_nodes})",
                )
            if depth > self.max_depth and not isinstance(node, ast.Name | ast.Constant):
                self.src.fail(
                    node,
                    f"expression nested more than {self.max_depth} levels deep at"
                    f" '{self.src.snippet(node)}' (limit max_depth={self.max_depth})",
                )
            children = self._check_node(node)
            for child in reversed(children):
                same_chain = (
                    isinstance(node, ast.BinOp)
                    and child is node.left
                    and isinstance(child, ast.BinOp)
                    and type(node.op) in _GROUPS
                    and _GROUPS.get(type(child.op)) == _GROUPS[type(node.op)]
                )
                stack.append((child, depth if same_chain else depth + 1))

    def _check_node(self, node: ast.expr) -> list[ast.expr]:
        src = self.src
        if isinstance(node, ast.Constant):
            self._check_constant(node)
            return []
        if isinstance(node, ast.Name):
            self._check_name_text(node)
            return []
        if isinstance(node, ast.BinOp):
            if type(node.op) not in _GROUPS and not isinstance(node.op, ast.Pow):
                token = _OPERATOR_TOKENS.get(type(node.op), type(node.op).__name__)
                hint = "; use '**' for powers" if isinstance(node.op, ast.BitXor) else ""
                src.fail(
                    node,
                    f"operator '{token}' in '{src.snippet(node)}' is not allowed{hint}",
                    token,
                )
            return [node.left, node.right]
        if isinstance(node, ast.UnaryOp):
            if not isinstance(node.op, ast.USub | ast.UAdd):
                token = _OPERATOR_TOKENS.get(type(node.op), type(node.op).__name__)
                src.fail(node, f"operator '{token}' in '{src.snippet(node)}' is not allowed", token)
            return [node.operand]
        if isinstance(node, ast.Call):
            return self._check_call(node)
        desc = _FORBIDDEN.get(type(node), f"{type(node).__name__} expression")
        snippet = src.snippet(node)
        src.fail(node, f"{desc} '{snippet}' is not allowed", snippet)

    def _check_constant(self, node: ast.Constant) -> None:
        src, value = self.src, node.value

        def refuse(what: str) -> NoReturn:
            snippet = src.snippet(node)
            src.fail(node, what.format(snippet=snippet), snippet)

        if isinstance(value, bool) or value is None or value is Ellipsis:
            refuse("'{snippet}' is not allowed (only numbers and names)")
        if isinstance(value, str):
            refuse("string literal '{snippet}' is not allowed")
        if isinstance(value, bytes):
            refuse("bytes literal '{snippet}' is not allowed")
        if isinstance(value, complex):
            refuse("complex number '{snippet}' is not allowed")
        if isinstance(value, int):
            if abs(value) >= self.max_literal:
                refuse(
                    f"integer literal '{{snippet}}' has about {_digits_of(value)} digits"
                    f" (limit max_digits={self.max_digits})"
                )
            return
        if isinstance(value, float):
            if not math.isfinite(value):
                refuse("float literal '{snippet}' is out of range")
            if value == 0.0 and re.search(r"[1-9]", src.snippet(node).lower().split("e")[0]):
                refuse("float literal '{snippet}' underflows to 0 in float64")
            return
        refuse("literal '{snippet}' is not allowed")  # pragma: no cover

    def _check_name_text(self, node: ast.Name) -> None:
        """Refuse a name that Python's parser changed (NFKC normalisation: ``𝐱`` is ``x``).

        A name typed exactly as a key of ``symbols`` is kept (it means that symbol).
        """
        if self.src.text.isascii():
            return
        typed = self.src.raw(node)
        if typed is None or typed == node.id:
            return
        if self.symbols is not None and typed in self.symbols:
            return
        codes = ", ".join(f"U+{ord(c):04X}" for c in typed if not c.isascii())
        self.src.fail(
            node,
            f"name '{_shorten(typed)}' is written with characters ({codes}) that Python reads"
            f" as '{_shorten(node.id)}' (Unicode compatibility normalisation); write the name"
            " with the characters it was declared with",
            _shorten(typed),
        )

    def _check_call(self, node: ast.Call) -> list[ast.expr]:
        src = self.src
        func = node.func
        if isinstance(func, ast.Name):
            self._check_name_text(func)
        if isinstance(func, ast.Name) and func.id in ALLOWED_FUNCTIONS and not node.keywords:
            arity = _ARITY.get(func.id, 1)
            if len(node.args) == arity and not any(isinstance(a, ast.Starred) for a in node.args):
                return list(node.args)
        snippet = src.snippet(node)
        if not isinstance(func, ast.Name):
            callee = src.snippet(func)
            src.fail(node, f"call of '{callee}' in '{snippet}' is not allowed", callee)
        name = func.id
        if name not in ALLOWED_FUNCTIONS:
            allowed = ", ".join(sorted(ALLOWED_FUNCTIONS))
            if self.symbols is not None and name in self.symbols:
                what = f"'{_shorten(name)}' is a symbol, not a function: '{snippet}' is not allowed"
            else:
                what = f"function '{_shorten(name)}' is not allowed in '{snippet}'"
            src.fail(
                func,
                f"{what} (allowed functions: {allowed})"
                f"{_did_you_mean(name, list(ALLOWED_FUNCTIONS))}",
                _shorten(name),
            )
        if node.keywords:
            kw = node.keywords[0]
            token = "**" if kw.arg is None else f"{kw.arg}="
            src.fail(kw, f"keyword argument '{token}' in '{snippet}' is not allowed", token)
        for arg in node.args:
            if isinstance(arg, ast.Starred):
                token = src.snippet(arg)
                src.fail(arg, f"starred argument '{token}' in '{snippet}' is not allowed", token)
        arity = _ARITY.get(name, 1)
        if len(node.args) != arity:
            plural = "s" if arity != 1 else ""
            src.fail(
                node,
                f"'{name}' takes {arity} argument{plural}, got {len(node.args)} in '{snippet}'",
                name,
            )
        return list(node.args)

    # -- pass 2: build the sympy expression ----------------------------------------------

    def build(self, node: ast.expr) -> sp.Expr:
        if isinstance(node, ast.Constant):
            value = _number_to_sympy(node.value)
            assert value is not None  # checked by validate
            return value
        if isinstance(node, ast.Name):
            return self._name(node)
        if isinstance(node, ast.UnaryOp):
            operand = self.build(node.operand)
            return -operand if isinstance(node.op, ast.USub) else operand
        if isinstance(node, ast.Call):
            return self._call(node)
        assert isinstance(node, ast.BinOp)  # checked by validate
        if isinstance(node.op, ast.Pow):
            return self._power(node)
        return self._chain(node)

    def _name(self, node: ast.Name) -> sp.Expr:
        src, name = self.src, node.id
        if self.symbols is not None:
            if not src.text.isascii():  # Python NFKC-normalises names: the text as typed first
                typed = src.raw(node)
                if typed is not None and typed != name and typed in self.symbols:
                    return self._symbol_value(node, typed, self.symbols[typed])
            if name in self.symbols:
                return self._symbol_value(node, name, self.symbols[name])
        if name in ALLOWED_CONSTANTS:
            return ALLOWED_CONSTANTS[name]
        if name in ALLOWED_FUNCTIONS:
            src.fail(
                node,
                f"function '{name}' must be called with its argument, e.g. '{name}(x)'",
                name,
            )
        if self.symbols is None:
            if name.startswith("__"):
                src.fail(node, f"name '{_shorten(name)}' is not allowed", _shorten(name))
            return sp.Symbol(name, real=True)
        declared = [k for k in self.symbols if isinstance(k, str)]
        candidates = declared + list(ALLOWED_CONSTANTS)
        if not declared:
            known = "no symbols are declared"
        elif len(declared) <= 12:
            known = "declared: " + ", ".join(sorted(declared))
        else:
            known = f"{len(declared)} symbols declared"
        shown = _shorten(name)
        src.fail(node, f"unknown name '{shown}' ({known}){_did_you_mean(name, candidates)}", shown)

    def _symbol_value(self, node: ast.Name, key: str, value: object) -> sp.Expr:
        if isinstance(value, sp.Expr) and not isinstance(value, sp.MatrixBase | sp.MatrixExpr):
            return value
        number = _number_to_sympy(value)
        if number is not None:
            return number
        self.src.fail(
            node,
            f"the symbol table maps '{key}' to a {type(value).__name__},"
            " not a scalar sympy expression",
            key,
        )

    def _chain(self, node: ast.BinOp) -> sp.Expr:
        """A left-associated chain of + - (or * /), built iteratively."""
        group = _GROUPS[type(node.op)]
        rights: list[tuple[ast.operator, ast.expr]] = []
        left: ast.expr = node
        while (
            isinstance(left, ast.BinOp)
            and type(left.op) in _GROUPS
            and _GROUPS[type(left.op)] == group
        ):
            rights.append((left.op, left.right))
            left = left.left
        rights.reverse()
        first = self.build(left)
        operands: list[tuple[ast.operator, ast.expr, sp.Expr]] = []
        for op, right in rights:
            value = self.build(right)
            if isinstance(op, ast.Div) and value.is_Number and value.is_zero:
                self.src.fail(
                    right,
                    f"division by zero: '{self.src.snippet(right)}' is 0",
                    self.src.snippet(right),
                )
            operands.append((op, right, value))
        if len(operands) <= _SEQUENTIAL_FOLD_MAX:
            # left to right, checking every partial result: sympy merges the numbers of a
            # product (sqrt(a)*sqrt(b) is sqrt(a*b)), and roots of big numbers are slow
            result = first
            for op, _, value in operands:
                result = _PY_OPERATORS[type(op)](result, value)
                self._check_numbers(node, result)
            self._check_merged(node, result, product=group == "*")
            return result
        if group == "+":
            result = sp.Add(first, *(v if isinstance(op, ast.Add) else -v for op, _, v in operands))
        else:
            # One Mul call merges all the numbers at once: bound their size beforehand.
            estimate = _weight(first) + sum(_weight(v) for _, _, v in operands)
            if estimate > _MAX_NUMBER_BITS:
                self._too_large(node, estimate)
            result = sp.Mul(
                first,
                *(v if isinstance(op, ast.Mult) else sp.Pow(v, -1) for op, _, v in operands),
            )
        self._check_numbers(node, result)
        self._check_merged(node, result, product=group == "*")
        return result

    def _too_high(self, node: ast.AST, degree: int) -> NoReturn:
        snippet = self.src.snippet(node)
        self.src.fail(
            node, f"'{snippet}' has degree {degree} in a symbol (limit {MAX_DEGREE})", snippet
        )

    def _power(self, node: ast.BinOp) -> sp.Expr:
        src = self.src
        base = self.build(node.left)
        exponent = self.build(node.right)
        if exponent.is_Number:
            if abs(exponent) > self.max_exponent:
                token = src.snippet(node.right)
                src.fail(
                    node,
                    f"exponent {exponent} in '{src.snippet(node)}' is too large"
                    f" (limit max_exponent={self.max_exponent})",
                    token,
                )
            if exponent.is_Rational and abs(exponent.p) > 1:
                # the numbers of the base get raised to the power: bound the result first
                estimate = _weight(base) * abs(int(exponent.p))
                if estimate > _MAX_NUMBER_BITS:
                    self._too_large(node, estimate)
        if exponent.is_Number and base.free_symbols:
            degree = _degree(base) * math.ceil(abs(float(exponent)))
            if degree > MAX_DEGREE:
                self._too_high(node, degree)
        result = base**exponent
        self._check_value(node, result)
        return result

    def _call(self, node: ast.Call) -> sp.Expr:
        assert isinstance(node.func, ast.Name)
        args = [self.build(a) for a in node.args]
        result = ALLOWED_FUNCTIONS[node.func.id](*args)
        self._check_value(node, result)
        return result

    def _check_merged(self, node: ast.AST, value: sp.Expr, product: bool = False) -> None:
        """Refuse what sympy's merging made of ``node``'s operands, among the factors at
        the top of ``value`` (its children were checked when they were built): a power past
        the exponent limit (``(y**64)**64`` is ``y**4096``, ``y**60*y**60`` is ``y**120``),
        a number outside float64 (``m*1e308*1e308``), and for a product, a degree above
        MAX_DEGREE in a symbol."""
        for factor in _top_factors(value):
            if factor.is_Pow and factor.exp.is_Number and factor.base.free_symbols:
                if abs(factor.exp) > self.max_exponent:
                    snippet = self.src.snippet(node)
                    self.src.fail(
                        node,
                        f"'{snippet}' builds the power {_shorten(str(factor))}: exponent"
                        f" {factor.exp} (limit max_exponent={self.max_exponent})",
                        snippet,
                    )
        self._check_constant_range(node, value)
        if product and value.free_symbols:
            degree = _degree(value)
            if degree > MAX_DEGREE:
                self._too_high(node, degree)

    def _check_constant_range(self, node: ast.AST, value: sp.Expr) -> None:
        """Refuse a symbol-free value outside the range of float64 (``exp(exp(100))``,
        ``1e308*1e308``) and, in a value with symbols, a coefficient merged out of it by a
        product (``m*1e308*1e308``, ``exp(709)*exp(709)*x`` is ``x*exp(1418)``): generated
        code could not hold it, and evaluating it exactly can take minutes.  Judged by
        :func:`symmech.declaration.constants.range_problem`, never by evalf."""
        if not value.free_symbols:
            reason = range_problem(value)
            if reason is not None and not value.is_Rational:
                snippet = self.src.snippet(node)
                self.src.fail(node, f"'{snippet}' is a constant {reason}", snippet)
            return
        for term in value.args if value.is_Add else (value,):
            factors = term.args if term.is_Mul else (term,)
            constant = [f for f in factors if not f.free_symbols]
            if not constant:
                continue
            coefficient = sp.Mul(*constant, evaluate=False) if len(constant) > 1 else constant[0]
            reason = range_problem(coefficient)
            if reason is not None and not coefficient.is_Rational:
                snippet = self.src.snippet(node)
                shown = (
                    sp.N(coefficient, 3)
                    if coefficient.is_Number
                    else _shorten(str(sp.Mul(*constant)))
                )
                self.src.fail(node, f"'{snippet}' has the coefficient {shown}, {reason}", snippet)

    def _check_value(self, node: ast.AST, value: sp.Expr) -> None:
        """Refuse undefined or complex values, and too large numbers, made by ``node``."""
        src = self.src
        if value.has(*_UNDEFINED):
            src.fail(
                node,
                f"'{src.snippet(node)}' is undefined (division by zero or infinite value)",
                src.snippet(node),
            )
        if value.has(sp.I):
            src.fail(
                node,
                f"'{src.snippet(node)}' is not real (it involves the imaginary unit I)",
                src.snippet(node),
            )
        self._check_numbers(node, value)
        self._check_merged(node, value)

    def _check_numbers(self, node: ast.AST, value: sp.Expr) -> None:
        """Refuse an exact number too large, among the numbers ``node`` can have made.

        Only the numbers near the top of ``value`` are inspected (:func:`_top_numbers`):
        its children were checked when they were built, and sympy's automatic evaluation
        leaves new numbers as coefficients, constant terms or numeric bases of powers.  The
        complete result is checked once more at the end.
        """
        for number in _top_numbers(value):
            if _bits(number) > _MAX_NUMBER_BITS:
                self._too_large(node, _bits(number))

    def _too_large(self, node: ast.AST, bits: int) -> NoReturn:
        snippet = self.src.snippet(node)
        digits = math.ceil(bits * math.log10(2))
        self.src.fail(
            node,
            f"'{snippet}' builds a number of about {digits} digits (limit {MAX_NUMBER_DIGITS})",
            snippet,
        )

    def finish(self, root: ast.expr, value: sp.Expr) -> sp.Expr:
        self._check_value(root, value)
        # every constant of the result as sympy merged it, not only those at the top
        bad = constant_out_of_range(value)
        if bad is not None and not bad.constant.is_Rational:
            snippet = self.src.snippet(root)
            self.src.fail(
                root,
                f"'{snippet}' holds the constant {_shorten(str(bad.constant))}, {bad.reason}",
                snippet,
            )
        for number in value.atoms(sp.Rational):
            if _bits(number) > _MAX_NUMBER_BITS:
                self._too_large(root, _bits(number))
        return value


_PY_OPERATORS: dict[type, Callable[[sp.Expr, sp.Expr], sp.Expr]] = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
}


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


def parse_expression(
    text: str,
    symbols: Mapping[str, sp.Basic] | None,
    *,
    field: str = "expression",
    line: int | None = None,
    max_length: int = MAX_LENGTH,
    max_nodes: int = MAX_NODES,
    max_depth: int = MAX_DEPTH,
    max_exponent: int = MAX_EXPONENT,
    max_digits: int = MAX_DIGITS,
) -> sp.Expr:
    """Parse the expression string ``text`` into a sympy expression, safely.

    Nothing in ``text`` is ever executed: it is parsed into a Python AST that is checked
    against a whitelist (see the module documentation) and converted node by node.

    Parameters
    ----------
    text
        The expression, in Python syntax: ``"-g*l*cos(theta)"``.
    symbols
        The names ``text`` may use, mapped to sympy expressions (usually ``Symbol`` s).
        ``None`` accepts every plain identifier as a real ``Symbol`` of that name (used to
        check a string before the scene's symbols are known).
    field
        What the text is, for error messages: ``"walls[0].psi"``.
    line
        Line of a file where the text starts, for error messages.
    max_length, max_nodes, max_depth, max_exponent, max_digits
        Resource limits, see the module documentation.

    Returns
    -------
    The sympy expression, built with sympy's usual automatic evaluation: the same as the
    text typed in Python with the symbols as sympy objects (``1/2*m`` is ``m/2``).

    Raises
    ------
    ExpressionError
        With a message naming ``field``, the position and the offending text.

    >>> import sympy as sp
    >>> x, v = sp.symbols("x v", real=True)
    >>> parse_expression("v**2/2 - 9*cos(x)", {"x": x, "v": v})
    v**2/2 - 9*cos(x)
    >>> parse_expression("x.__class__", {"x": x}, field="walls[0].psi", line=12)
    Traceback (most recent call last):
    ...
    symmech.errors.ExpressionError: walls[0].psi (line 12, col 1): attribute access 'x.__class__' is not allowed
    >>> parse_expression("sin(x) + y1", {"x": x, "y": v}, field="potential")
    Traceback (most recent call last):
    ...
    symmech.errors.ExpressionError: potential (col 10): unknown name 'y1' (declared: x, y); did you mean 'y'?
    """  # noqa: E501
    if not isinstance(field, str):
        field = str(field)
    if not isinstance(text, str):
        src = _Source("", field, line)
        raise src.error(f"expected an expression string, got a {type(text).__name__}")
    if len(text) > max_length:
        raise _Source("", field, line).error(
            f"expression is {len(text)} characters long (limit max_length={max_length})"
        )
    src = _Source(text, field, line)
    _check_characters(src)
    if not src.text.strip():
        raise src.error("empty expression")
    _check_brackets(src, max_depth)
    try:
        with warnings.catch_warnings():
            # "1if x else y" and the like: refused (a SyntaxWarning raised as an error
            # becomes a SyntaxError), and nothing leaks to the caller's warnings.
            warnings.simplefilter("error", SyntaxWarning)
            warnings.simplefilter("ignore", DeprecationWarning)
            tree = ast.parse(_joined(src), mode="eval")
    except SyntaxError as exc:
        raise _syntax_error(src, exc) from None
    except (RecursionError, MemoryError):
        raise src.error(
            "expression too complex for Python's parser (too long a chain of operators or"
            f" too deeply nested; limits max_nodes={max_nodes}, max_depth={max_depth})"
        ) from None
    except ValueError as exc:
        raise src.error(f"cannot parse: {exc}") from None
    parser = _Parser(
        src,
        symbols,
        max_nodes=max_nodes,
        max_depth=max_depth,
        max_exponent=max_exponent,
        max_digits=max_digits,
    )
    parser.validate(tree.body)
    try:
        value = parser.build(tree.body)
    except RecursionError:
        raise src.error(f"expression too deeply nested (limit max_depth={max_depth})") from None
    return parser.finish(tree.body, value)


def to_expression(
    value: object,
    symbols: Mapping[str, sp.Basic] | None,
    *,
    field: str = "expression",
    line: int | None = None,
) -> sp.Expr:
    """Return ``value`` as a sympy expression.

    * a sympy expression is returned unchanged (matrices and non-expressions such as
      relations or booleans are refused);
    * a Python (or numpy) real number becomes a sympy ``Integer``, ``Rational`` (for a
      ``fractions.Fraction``) or ``Float``; ``bool``, complex, NaN and infinities are
      refused;
    * a string is parsed by :func:`parse_expression` with ``symbols``, ``field`` and
      ``line`` (and the default limits).

    Anything else raises :class:`~symmech.errors.ExpressionError` naming ``field`` and
    the type.

    >>> import sympy as sp
    >>> th = sp.Symbol("theta", real=True)
    >>> to_expression("1 - cos(theta)", {"theta": th}, field="potential")
    1 - cos(theta)
    >>> to_expression(2, None), to_expression(0.5, None), to_expression(th, None)
    (2, 0.500000000000000, theta)
    >>> to_expression([1], None, field="walls[1].psi")
    Traceback (most recent call last):
    ...
    symmech.errors.ExpressionError: walls[1].psi: expected a sympy expression, a number or a string, got a list
    """  # noqa: E501
    if isinstance(value, str):
        return parse_expression(value, symbols, field=field, line=line)
    src = _Source("", str(field), line)
    if isinstance(value, sp.MatrixBase | sp.MatrixExpr):
        raise src.error(f"expected a scalar expression, got a matrix {value!r}")
    if isinstance(value, sp.Basic):
        if not isinstance(value, sp.Expr):
            raise src.error(
                f"expected a scalar expression, got a sympy {type(value).__name__}: {value}"
            )
        return value
    number = _number_to_sympy(value)
    if number is not None:
        return number
    if isinstance(value, bool):
        raise src.error(f"expected a number or an expression, got the boolean {value}")
    if isinstance(value, numbers.Real):
        raise src.error(f"expected a finite number, got {value!r}")
    if isinstance(value, numbers.Complex):
        raise src.error(f"expected a real number, got the complex number {value!r}")
    raise src.error(
        f"expected a sympy expression, a number or a string, got a {type(value).__name__}"
    )
