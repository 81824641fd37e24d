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
import numbers
import warnings
from collections.abc import Mapping

import sympy as sp

from symmech.declaration.constants import (
    MAX_NUMBER_DIGITS,
)
from symmech.declaration.expression_parser import _Parser
from symmech.declaration.expression_rules import (
    ALLOWED_CONSTANTS,
    ALLOWED_FUNCTIONS,
    MAX_DEGREE,
    MAX_DEPTH,
    MAX_DIGITS,
    MAX_EXPONENT,
    MAX_LENGTH,
    MAX_NODES,
    _check_brackets,
    _check_characters,
    _check_operands,
    _joined,
    _number_to_sympy,
    _Source,
    _syntax_error,
)

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
    _check_operands(src, max_nodes)
    tree = _syntax_tree(src, max_nodes, max_depth)
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


def _syntax_tree(src: _Source, max_nodes: int, max_depth: int) -> ast.Expression:
    """Python's syntax tree of the text (parsed, never run); a syntax error, or a text too
    complex for Python's parser, as an :class:`ExpressionError` naming the position."""
    try:
        with warnings.catch_warnings():
            # "1if x else y" and the like: refused (a SyntaxWarning raised as an error
            # becomes a SyntaxError), and nothing leaks to the caller's warnings.
            warnings.simplefilter("error", SyntaxWarning)
            warnings.simplefilter("ignore", DeprecationWarning)
            return ast.parse(_joined(src), mode="eval")
    except SyntaxError as exc:
        raise _syntax_error(src, exc) from None
    except (RecursionError, MemoryError):
        raise src.error(
            "expression too complex for Python's parser (too long a chain of operators or"
            f" too deeply nested; limits max_nodes={max_nodes}, max_depth={max_depth})"
        ) from None
    except ValueError as exc:
        raise src.error(f"cannot parse: {exc}") from None


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
