"""The simplification policy of symmech, in one place.

Symbolic results are simplified according to a named level, so results are predictable
and large systems never pay for a full ``sympy.simplify``:

``"none"``
    Return expressions as built.  Used for the scalable quantities (mass matrix, forcing).
``"light"`` (default for accelerations, projectors, impact maps)
    Exact rational normal forms.  Quantities obtained by a linear solve (inverses,
    Christoffel symbols of the second kind, connection coefficients, accelerations,
    multipliers, projectors, commutation coefficients) come out of the exact solve of
    :mod:`symmech.algebra.field`: every entry a cancelled fraction whose numerator and
    denominator are in the *Pythagorean normal form* (``sin(a)^2`` replaced by
    ``1 - cos(a)^2`` wherever both ``sin(a)`` and ``cos(a)`` occur; canonical for
    polynomials in sin and cos), with a shared determinant; the solve chooses its route
    by cost and declines (falling back to the entries as built, then :func:`tidy`) when
    the normal form would be too large.  Single expressions (Christoffel symbols of the
    first kind, brackets) get :func:`normal_form` when they have at most
    :data:`symmech.algebra.budget.LIGHT_SIMPLIFY_OPS` operations. :func:`tidy` itself, used on
    intermediate results, applies ``sympy.cancel`` to rational expressions (no function
    applications such as sin, sqrt of a non-symbol) of at most that many operations,
    clearing nested fractions such as those from a Gram inverse, then ``factor_terms``;
    expressions with functions get ``factor_terms`` only.
``"full"`` (default for Christoffel symbols and connection coefficients)
    ``"light"``, then ``sympy.simplify`` (which includes trigsimp) on each entry of at
    most :data:`symmech.algebra.budget.FULL_SIMPLIFY_OPS` operations, the simplified form kept
    only when it has no more operations (:func:`polish`).

The thresholds (budgets of :mod:`symmech.algebra.budget`) keep the cost bounded: simplification is
skipped, never approximated, and every result is exact. An unknown level raises
:class:`symmech.errors.SceneError`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

import sympy as sp

from symmech.algebra import budget as limits
from symmech.algebra.field import RationalField
from symmech.errors import SceneError

__all__ = [
    "LEVELS",
    "Level",
    "check_level",
    "normal_form",
    "polish",
    "simplify_all",
    "tidy",
    "tidy_matrix",
]

Level = Literal["none", "light", "full"]
LEVELS: tuple[str, ...] = ("none", "light", "full")


def check_level(level: object, where: str, argument: str = "simplify") -> Level:
    """Return ``level`` if it is a simplification level, else raise a :class:`SceneError`
    naming ``where``, the argument and the allowed values."""
    if not isinstance(level, str) or level not in LEVELS:
        allowed = ", ".join(repr(v) for v in LEVELS)
        raise SceneError(f"{where}: {argument} must be one of {allowed}; got {level!r}")
    return level  # type: ignore[return-value]


def tidy(expr: sp.Expr, level: Level = "light") -> sp.Expr:
    """Simplify ``expr`` according to ``level`` (see the module docstring)."""
    check_level(level, "tidy", "level")
    expr = sp.sympify(expr, strict=True)
    if level == "none" or expr.is_number or expr.is_Symbol:
        return expr
    if not _small(expr, limits.LIGHT_SIMPLIFY_OPS):
        return expr
    if level == "full" and limits.affordable(expr, limits.FULL_SIMPLIFY_OPS):
        return sp.simplify(expr)
    if limits.affordable(expr, limits.LIGHT_SIMPLIFY_OPS):
        if _is_rational_function(expr):
            return sp.factor_terms(sp.cancel(expr))
        return sp.factor_terms(expr)
    return expr


def normal_form(expr: sp.Expr, max_ops: int | None = None) -> sp.Expr:
    """The exact rational normal form of ``expr`` with the Pythagorean reduction.

    ``expr`` is read in the fraction field of its building blocks (parameters,
    coordinates, sin/cos and other functions as generators; see
    :mod:`symmech.algebra.field`), its numerator and denominator are reduced modulo
    ``sin(a)^2 + cos(a)^2 - 1`` and cancelled, and common factors are pulled out:

    >>> x, m = sp.symbols("x m")
    >>> normal_form(m * sp.sin(x) ** 2 + m * sp.cos(x) ** 2)
    m
    >>> normal_form((1 - sp.cos(x) ** 2) / sp.sin(x))
    sin(x)

    Expressions over ``max_ops`` operations (default
    :data:`symmech.algebra.budget.LIGHT_SIMPLIFY_OPS`), numbers, and expressions admitting no exact
    field are returned as given, then passed to ``factor_terms``.
    """
    expr = sp.sympify(expr, strict=True)
    max_ops = limits.LIGHT_SIMPLIFY_OPS if max_ops is None else max_ops
    if expr.is_number or expr.is_Symbol or not _small(expr, max_ops):
        return expr
    if not limits.affordable(expr, max_ops):
        return expr
    field = RationalField([expr])
    if not field.exact:
        return sp.factor_terms(expr)
    return field.expr(field.element(expr))


def polish(expr: sp.Expr, level: Level) -> sp.Expr:
    """For ``level="full"``: ``sympy.simplify`` on expressions of at most
    :data:`symmech.algebra.budget.FULL_SIMPLIFY_OPS` operations, kept only when it has no more
    operations than ``expr``; else ``expr``."""
    if level != "full" or expr.is_number or expr.is_Symbol:
        return expr
    if not _small(expr, limits.FULL_SIMPLIFY_OPS):
        return expr
    if not limits.affordable(expr, limits.FULL_SIMPLIFY_OPS):
        return expr
    ops = sp.count_ops(expr)
    simpler = sp.simplify(expr)
    return simpler if sp.count_ops(simpler) <= ops else expr


def simplify_all(exprs: Sequence[sp.Expr], level: Level) -> list[sp.Expr]:
    """Apply the policy to single expressions: ``"none"`` as given, ``"light"``
    :func:`normal_form`, ``"full"`` :func:`normal_form` then :func:`polish`."""
    check_level(level, "simplify_all", "level")
    if level == "none":
        return [sp.sympify(e, strict=True) for e in exprs]
    return [polish(normal_form(e), level) for e in exprs]


def _small(expr: sp.Expr, max_ops: int) -> bool:
    """False when the expression tree has more than ``4 max_ops`` nodes (counted with
    repetition, stopping early): ``count_ops`` of a large nested LU quotient, whose
    shared subtrees it visits once per occurrence, would cost more than the solve."""
    limit = 4 * max_ops
    for count, _node in enumerate(sp.preorder_traversal(expr)):
        if count > limit:
            return False
    return True


def _is_rational_function(expr: sp.Expr) -> bool:
    """True when expr is built from symbols and numbers by + - * / and integer powers."""
    for node in sp.preorder_traversal(expr):
        if isinstance(node, (sp.Function, sp.Derivative)):
            return False
        if node.is_Pow and not node.exp.is_Integer:
            return False
    return True


def tidy_matrix(M: sp.MatrixBase, level: Level = "light") -> sp.Matrix:
    """Apply :func:`tidy` to every entry of ``M``."""
    check_level(level, "tidy_matrix", "level")
    return sp.Matrix(M.rows, M.cols, [tidy(e, level) for e in M])
