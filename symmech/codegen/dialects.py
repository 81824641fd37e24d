"""Printing an unrolled linear-algebra step (:mod:`symmech.codegen.unroll`) in a backend's
language: a :class:`Dialect` per backend (C, NumPy, and the NumPy module's one-state
variants) prints the traced :class:`~symmech.codegen.unroll.Program` as statements."""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence

from symmech.codegen.unroll import Program, Ref, Value

__all__ = ["CDialect", "Dialect", "NumPyDialect", "ScalarDialect"]

#: Binding strength of the operations, and their C/Python symbols.
_PRECEDENCE = {"add": 1, "sub": 1, "mul": 2, "div": 2, "neg": 3}
_SYMBOL = {"add": " + ", "sub": " - ", "mul": "*", "div": "/"}


class Dialect(ABC):
    """How one backend prints a :class:`Program`: a subclass gives the backend's syntax
    (:meth:`ref`, :meth:`let`, :meth:`finite`, :meth:`positive`, :meth:`store`)."""

    sqrt = "sqrt"

    @abstractmethod
    def ref(self, r: Ref) -> str:
        """A run-time value: a local by name, or an entry of a state array."""

    def number(self, x: float) -> str:
        """A literal that reads back as ``x`` (a zero is printed ``0.0``, whatever its sign)."""
        text = repr(float(x)) if x != 0.0 else "0.0"
        if "e" not in text and "." not in text:
            text += ".0"
        return text

    def expr(self, v: Value, context: int = 0) -> str:
        """``v`` with the parentheses its evaluation order needs (no reassociation:
        ``a - (b - c)`` and ``a*(b*c)`` keep theirs)."""
        if isinstance(v, float):
            text = self.number(v)
            return f"({text})" if text.startswith("-") and context > 0 else text
        if isinstance(v, Ref):
            return self.ref(v)
        if v.op == "sqrt":
            return f"{self.sqrt}({self.expr(v.args[0])})"
        prec = _PRECEDENCE[v.op]
        if v.op == "neg":
            inner = self.expr(v.args[0], 4)
            text = f"-{inner}"
        else:
            left = self.expr(v.args[0], prec)
            right = self.expr(v.args[1], prec + 1)
            text = f"{left}{_SYMBOL[v.op]}{right}"
        return f"({text})" if prec < context or (v.op == "neg" and context > 0) else text

    def lines(
        self, prog: Program, out_shape: tuple[int, ...], exprs: Mapping[tuple[str, int], str]
    ) -> list[str]:
        """The printed statements; ``exprs[block, flat]`` is the printed expression of
        each input entry."""
        out = [self.let(i.name, exprs[i.block, i.flat]) for i in prog.inputs]
        allocated = False
        for st in prog.statements:
            kind = st[0]
            if kind == "let":
                out.append(self.let(st[1], self.expr(st[2])))
            elif kind == "finite":
                out.extend(self.finite([self.ref(r) for r in st[1]]))
            elif kind == "positive":
                out.extend(self.positive(self.expr(st[1], 1)))
            elif kind == "out":
                if not allocated:
                    out.extend(self.allocate(out_shape))
                    allocated = True
                out.append(self.store(st[1], self.expr(st[2])))
        return out

    @abstractmethod
    def let(self, name: str, expr: str) -> str:
        """A local holding ``expr``."""

    @abstractmethod
    def finite(self, refs: Sequence[str]) -> list[str]:
        """Fail (SYMMECH_NONFINITE) unless every value is finite."""

    @abstractmethod
    def positive(self, pivot: str) -> list[str]:
        """Fail (SYMMECH_NOT_SPD) unless the pivot is positive."""

    def allocate(self, out_shape: tuple[int, ...]) -> list[str]:
        """Whatever must precede the first store into ``out``."""
        return []

    @abstractmethod
    def store(self, index: int, expr: str) -> str:
        """Entry ``index`` (row-major) of the output."""


class CDialect(Dialect):
    """C99: ``const double`` locals, early returns with the SYMMECH status codes."""

    def ref(self, r: Ref) -> str:
        return f"{r.array}[{r.index}]" if r.array else r.name

    def let(self, name: str, expr: str) -> str:
        return f"const double {name} = {expr};"

    def finite(self, refs: Sequence[str]) -> list[str]:
        tests = " && ".join(f"isfinite({r})" for r in refs)
        return [f"if (!({tests})) return SYMMECH_NONFINITE;"]

    def positive(self, pivot: str) -> list[str]:
        return [f"if (!({pivot} > 0.0)) return SYMMECH_NOT_SPD;"]

    def store(self, index: int, expr: str) -> str:
        return f"out[{index}] = {expr};"


class NumPyDialect(Dialect):
    """NumPy: locals over the batch axes, LinAlgError / FloatingPointError."""

    sqrt = "numpy.sqrt"

    def ref(self, r: Ref) -> str:
        return f"{r.array}[..., {r.index}]" if r.array else r.name

    def let(self, name: str, expr: str) -> str:
        return f"{name} = {expr}"

    def finite(self, refs: Sequence[str]) -> list[str]:
        return [f"_require_finite({', '.join(refs)})"]

    def positive(self, pivot: str) -> list[str]:
        return [
            f"if not numpy.all({pivot} > 0.0):",
            '    raise numpy.linalg.LinAlgError("a matrix that must be positive definite is not")',
        ]

    def allocate(self, out_shape: tuple[int, ...]) -> list[str]:
        return [f"out = numpy.empty(shape + {out_shape})"]

    def store(self, index: int, expr: str) -> str:
        return f"out[..., {index}] = {expr}"


class ScalarDialect(NumPyDialect):
    """The one-state variants of the NumPy module: plain floats in lists, ``math``."""

    sqrt = "math.sqrt"

    def ref(self, r: Ref) -> str:
        return f"{r.array}[{r.index}]" if r.array else r.name

    def finite(self, refs: Sequence[str]) -> list[str]:
        # x - x is 0 for a finite x and NaN for an inf or a NaN, so one test of the sum of
        # the differences (which cannot overflow) checks them all, as the C batch does
        total = " + ".join(f"({r} - {r})" for r in refs)
        return [
            f"if not math.isfinite({total}):",
            '    raise FloatingPointError("an input of a linear solve is not finite")',
        ]

    def positive(self, pivot: str) -> list[str]:
        return [
            f"if not {pivot} > 0.0:",
            '    raise numpy.linalg.LinAlgError("a matrix that must be positive definite is not")',
        ]

    def allocate(self, out_shape: tuple[int, ...]) -> list[str]:
        return [f"out = [0.0] * {math.prod(out_shape)}"]

    def store(self, index: int, expr: str) -> str:
        return f"out[{index}] = {expr}"
