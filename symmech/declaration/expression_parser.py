"""The expression parser: a whitelist over Python's ``ast`` that builds sympy expressions
node by node within the limits of :mod:`symmech.declaration.expression_rules` (see
:mod:`symmech.declaration.expressions`)."""

from __future__ import annotations

import ast
import math
import operator
import re
from collections.abc import Callable, Mapping
from typing import NoReturn

import sympy as sp

from symmech.declaration.constants import (
    MAX_NUMBER_DIGITS,
    constant_out_of_range,
    range_problem,
)
from symmech.declaration.expression_rules import (
    _ARITY,
    _FORBIDDEN,
    _GROUPS,
    _MAX_NUMBER_BITS,
    _OPERATOR_TOKENS,
    _SEQUENTIAL_FOLD_MAX,
    _UNDEFINED,
    ALLOWED_CONSTANTS,
    ALLOWED_FUNCTIONS,
    MAX_DEGREE,
    _bits,
    _degree,
    _did_you_mean,
    _digits_of,
    _number_to_sympy,
    _shorten,
    _Source,
    _top_factors,
    _top_numbers,
    _weight,
)


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
