"""Degenerate walls and the singular set of an impact map.

The Carnot construction needs the Gram matrix ``C^{AB} = g(P Y^A, P Y^B)`` of the wall
gradient and the impulsive constraints, projected onto D, to be regular (Carnot paper 002,
section 3.1: "C != 0 since we are assuming that the 1-forms mu^a and d psi are independent
along N"; section 3.2: the same for ``{mu^a, d psi, nu^B}``).

* :func:`check_regular` refuses walls for which C is singular *identically*: decided
  symbolically when cheap, else at sampled points (:mod:`symmech.declaration.sampling`);
  a matrix singular at every sampled point is singular generically.  The sample points
  are not restricted to the wall ``psi = 0``; the check is generic (it holds off a
  measure-zero set).
* :func:`singular_set` lists the expressions whose vanishing makes the closed form
  undefined (denominators), with a description, so that a user can guard generated code
  instead of meeting NaN later.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
import sympy as sp

from symmech.errors import ImpactError

__all__ = ["Singularity", "check_regular", "singular_set"]

_SYMBOLIC_OPS = 200


@dataclass(frozen=True)
class Singularity:
    """An expression whose zeros make the impact map undefined, and why."""

    expression: sp.Expr
    description: str

    def __str__(self) -> str:
        return f"{self.expression} = 0: {self.description}"


def _short(expr: object, limit: int = 70) -> str:
    s = str(expr)
    return s if len(s) <= limit else s[: limit - 3] + "..."


def _numeric(M: sp.MatrixBase, point: dict) -> np.ndarray | None:
    vals = sp.Matrix(M).subs(point).evalf(30)
    try:
        A = np.array([[complex(e) for e in row] for row in vals.tolist()], dtype=complex)
    except (TypeError, ValueError):
        return None
    if not np.all(np.isfinite(A)):
        return None
    return A.real


def _psd_rank(A: np.ndarray) -> int:
    w = np.linalg.eigvalsh(0.5 * (A + A.T))
    scale = max(float(np.abs(w).max(initial=0.0)), 1e-300)
    return int(np.sum(np.abs(w) > 1e-10 * scale))


def _identically_zero(expr: sp.Expr, points: Sequence[dict]) -> bool:
    """Zero at every sampled point (a cheap numeric test first), confirmed symbolically
    when the expression is small; otherwise the sampled verdict stands."""
    expr = sp.sympify(expr)
    if expr == 0:
        return True
    values = [_numeric(sp.Matrix([[expr]]), p) for p in points]
    finite = [v for v in values if v is not None]
    if any(abs(v[0, 0]) >= 1e-20 for v in finite):
        return False
    if sp.count_ops(expr) <= _SYMBOLIC_OPS:
        s = sp.simplify(expr)
        if s == 0:
            return True
        if s.is_number:
            return False
    return bool(finite)


def check_regular(
    C: sp.MatrixBase,
    points: Sequence[dict],
    *,
    wall: str,
    psi: sp.Expr,
    mu: sp.MatrixBase,
    nu: sp.MatrixBase,
    velocities: Sequence[sp.Symbol],
) -> None:
    """Raise :class:`~symmech.ImpactError` if ``C^{AB}`` is singular identically.

    The first block ``C^{00} = g(P grad psi, P grad psi)`` vanishes iff ``d psi`` lies in
    the span of the permanent constraints (then the wall cannot stop any motion allowed by
    them).  Otherwise the first impulsive constraint whose leading block of C is singular is
    reported as dependent on ``d psi``, the permanent constraints and the preceding
    impulsive constraints.
    """
    v = sp.Matrix(velocities)

    def form(row: sp.MatrixBase) -> str:
        return _short(sp.expand((sp.Matrix(row) * v)[0, 0]))

    perm = [form(mu[a, :]) for a in range(mu.rows)]
    if _identically_zero(C[0, 0], points):
        raise ImpactError(
            f"wall {wall!r}: the gradient of psi = {_short(psi)} lies in the span of the"
            f" permanent constraints {perm} (C = g(P grad psi, P grad psi) = 0, Carnot"
            " paper eq. 7): every motion allowed by the constraints is tangent to the wall,"
            " so no impact map exists"
        )
    k = C.rows
    if k == 1:
        return
    ranks: list[list[int]] = []
    for point in points:
        A = _numeric(C, point)
        if A is None:
            continue
        ranks.append([_psd_rank(A[: j + 1, : j + 1]) for j in range(k)])
    if not ranks:
        return
    for j in range(1, k):
        if all(r[j] < j + 1 for r in ranks):
            symbolic = (
                sp.simplify(C[: j + 1, : j + 1].det())
                if sp.count_ops(C[: j + 1, : j + 1]) <= _SYMBOLIC_OPS
                else None
            )
            if symbolic is not None and symbolic.is_number and symbolic != 0:
                continue
            raise ImpactError(
                f"wall {wall!r}: the impulsive constraint nu^{j} = {form(nu[j - 1, :])} is"
                " linearly dependent on d psi, the permanent constraints"
                f" {perm} and the preceding impulsive constraints (the Gram matrix"
                f" C^AB = g(P Y^A, P Y^B) has rank < {j + 1} at every sampled point);"
                " drop it (as Carnot paper Example 3.13 drops omega_y)"
            )


def _factors(expr: sp.Expr) -> list[sp.Expr]:
    expr = sp.cancel(sp.together(expr))
    num, _ = sp.fraction(expr)
    try:
        _, facs = sp.factor_list(num)
    except sp.PolynomialError:  # pragma: no cover
        return [num]
    return [f for f, _ in facs if f.free_symbols]


def _divides(f: sp.Expr, e: sp.Expr) -> bool:
    quotient = sp.cancel(e / f)
    den = sp.fraction(quotient)[1]
    return not (den.free_symbols & f.free_symbols)


def singular_set(
    structural: Iterable[tuple[sp.Expr, str]],
    closed_form: Iterable[sp.Expr],
    closed_form_description: str,
) -> list[Singularity]:
    """Collect the singular set: ``structural`` (expression, description) pairs first, then
    the factors of the denominators of ``closed_form`` not already covered.

    Factors that sympy proves non-zero from the symbols' assumptions (``k**2 + r**2`` with
    positive k, r) are dropped; every kept factor is an expression in q, t, the parameters
    (and, for the energy law, the velocities).
    """
    out: list[Singularity] = []
    seen: list[sp.Expr] = []

    def add(f: sp.Expr, description: str) -> None:
        f = sp.factor(f)
        if not f.free_symbols or f.is_nonzero:
            return
        if any(_divides(f, s) or _divides(s, f) for s in seen):
            return
        seen.append(f)
        out.append(Singularity(f, description))

    for expr, description in structural:
        for f in _factors(expr):
            add(f, description)
    for expr in closed_form:
        den = sp.fraction(sp.cancel(sp.together(expr)))[1]
        for f in _factors(den):
            add(f, closed_form_description)
    return out
