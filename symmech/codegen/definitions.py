"""Arbitrary functions of time in generated code: defined, or run-time inputs.

A scene may hold functions of t it does not define (a moving wall ``x - f(t)``).  The
code generator takes ``definitions={f: expression}`` (:func:`definition_rules`: keyed by
the function or its name, the text parsed safely in t and the parameters) and substitutes
them (:func:`defined`); every other ``f(t)`` and its derivatives become run-time inputs,
slots ``u[k]`` of the generated functions (:class:`InputSlots`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import sympy as sp
from sympy.core.function import AppliedUndef

from symmech.algebra.walk import atoms
from symmech.codegen.blocks import CodegenError
from symmech.declaration.admissible import expression_problems
from symmech.declaration.expressions import to_expression
from symmech.declaration.symbols import t as TIME
from symmech.errors import SymmechError

if TYPE_CHECKING:
    from symmech.scene import Scene

__all__ = ["InputSlots", "defined", "definition_rules"]


class InputSlots:
    """Arbitrary functions of time f(t) and their derivatives -> input slots u[k]."""

    def __init__(self, definitions: Mapping):
        self.definitions = dict(definitions)
        self.slots: dict[sp.Expr, sp.Symbol] = {}

    def _key(self, atom: sp.Expr) -> tuple[str, int]:
        if isinstance(atom, sp.Derivative):
            return (atom.expr.func.__name__, atom.derivative_count)
        return (atom.func.__name__, 0)

    def substitute(self, e: sp.Expr) -> sp.Expr:
        e = defined(sp.sympify(e, strict=True), self.definitions)
        found = atoms(e, (sp.Derivative, AppliedUndef))  # one walk over distinct subtrees
        if not found:
            return e
        derivatives = [a for a in found if isinstance(a, sp.Derivative)]
        inputs = [a for a in derivatives if isinstance(a.expr, AppliedUndef)]
        inputs += [a for a in found if isinstance(a, AppliedUndef)]
        rule = {}
        for a in inputs:
            f = a.expr if isinstance(a, sp.Derivative) else a
            if f.args != (TIME,):
                raise CodegenError(
                    f"{a}: only functions of t alone can become run-time inputs; define it"
                    " with definitions={...}"
                )
            if a not in self.slots:
                name, order = self._key(a)
                self.slots[a] = sp.Dummy(f"{name}{'_' + 'd' * order if order else ''}", real=True)
            rule[a] = self.slots[a]
        e = e.xreplace(rule) if rule else e
        leftover = sorted(map(str, atoms(e, (sp.Derivative,)))) if derivatives else []
        if leftover:
            raise CodegenError(f"unevaluated derivatives {leftover} cannot be generated")
        return e

    def ordered(self) -> tuple[tuple[sp.Symbol, sp.Expr], ...]:
        items = sorted(self.slots.items(), key=lambda kv: self._key(kv[0]))
        return tuple((d, a) for a, d in items)


def definition_rules(scene: Scene, definitions: Mapping) -> dict[sp.Expr, sp.Expr]:
    """``definitions`` as ``{f(t): expression}``.  A key is ``f``, ``f(t)`` or the name
    ``"f"`` of a function of t in the scene (matched by name); a value is a sympy
    expression, a number, or text parsed safely
    (:func:`symmech.declaration.expressions.to_expression`, never evaluated) in ``t`` and
    the scene's parameters."""
    if not isinstance(definitions, Mapping):
        raise CodegenError(
            "definitions: expected a mapping {function of t: expression in t and the"
            f" parameters}}, got {type(definitions).__name__}"
        )
    if not definitions:
        return {}
    names = {"t": TIME, **{str(p): p for p in scene.parameters}}
    present = {
        a
        for e in scene.declaration.expressions()
        for a in atoms(e, (AppliedUndef,))
        if a.args == (TIME,)
    }
    out: dict[sp.Expr, sp.Expr] = {}
    for key, value in definitions.items():
        if isinstance(key, str) and key.isidentifier():
            name = key
        elif isinstance(key, sp.FunctionClass):
            name = key.__name__
        elif isinstance(key, AppliedUndef) and key.args == (TIME,):
            name = key.func.__name__
        else:
            raise CodegenError(f"definitions: {key!r} is not an arbitrary function of t")
        # by name: the scene's f(t) whatever its assumptions (a scene file's is real)
        fs = [a for a in present if a.func.__name__ == name]
        if not fs:
            known = sorted({a.func.__name__ for a in present})
            raise CodegenError(
                f"definitions[{name!r}]: scene {scene.name!r} has no function {name}(t)"
                f" (its functions of t: {known})"
            )
        try:
            e = to_expression(value, names, field=f"definitions[{name!r}]")
        except SymmechError as exc:
            raise CodegenError(str(exc)) from None
        # what a scene's own fields may hold (declaration.admissible: elementary functions,
        # real, finite), and a function of t and the parameters only, whatever its type
        problems = expression_problems(e)
        if problems:
            raise CodegenError(f"definitions[{name!r}] = {e}: {'; '.join(problems)}")
        stray = sorted(str(x) for x in e.free_symbols if x not in set(names.values()))
        stray += sorted({str(a) for a in atoms(e, (AppliedUndef,))})
        if stray:
            raise CodegenError(
                f"definitions[{name!r}] = {e}: a definition is a function of t and the"
                f" parameters {sorted(str(p) for p in scene.parameters)} only; it uses {stray}"
            )
        out.update(dict.fromkeys(fs, e))
    return out


def defined(e: Any, rules: Mapping[sp.Expr, sp.Expr]) -> Any:
    """``e`` (an expression or a matrix) with the functions of t of
    :func:`definition_rules` replaced by their expressions, their derivatives evaluated."""
    return e.subs(rules).doit() if rules else e
