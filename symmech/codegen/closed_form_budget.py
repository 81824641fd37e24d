"""Whether a scene's closed forms fit their budget, decided from its structure at once.

Code generation with strategy ``closed_form`` (or ``auto`` on a small scene) derives the
symbolic acceleration, multipliers, projectors and impact maps.  Their size follows the
structure of the scene: an exact inverse or solve of the metric, and the projectors of
an impact (Carnot paper section 2.2 and eq. 10: adjugates of ``g`` and of the bordered
matrices ``[[g, mu^T], [mu, 0]]`` and ``[[g, A^T], [A, 0]]`` with ``A = [mu; dpsi; nu]``),
have at most as many terms as the Leibniz expansion of the determinants of their
connected blocks, bounded by :func:`symmech.algebra.budget.determinant_terms`.  A diagonal metric
has blocks of size one at any n; a wall touching few coordinates borders a small block.

:func:`closed_form_cost` raises :class:`~symmech.algebra.budget.BudgetExceeded` before anything
is derived when

* that bound exceeds :data:`symmech.algebra.budget.CLOSED_FORM_TERMS` for g, for the metric
  bordered by the constraints, or for the metric bordered by the one-forms of a wall;
* an entry of the potential's gradient expands to more than
  :data:`symmech.algebra.budget.FIELD_TERMS` terms (the exact solve would expand it in full).

The derivation itself then runs under :func:`symmech.algebra.budget.time_limit`
(:data:`symmech.algebra.budget.CLOSED_FORM_SECONDS`), see :func:`symmech.codegen.plan.build_plan`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import sympy as sp

from symmech.algebra import budget as limits
from symmech.algebra.budget import BudgetExceeded

if TYPE_CHECKING:
    from symmech.scene import Scene

__all__ = ["closed_form_cost"]


def _bordered(g: sp.Matrix, A: sp.Matrix) -> sp.Matrix:
    """``[[g, A^T], [A, 0]]`` (``g`` when A has no rows)."""
    if not A.rows:
        return g
    k = A.rows
    return g.row_join(A.T).col_join(A.row_join(sp.zeros(k, k)))


def closed_form_cost(scene: Scene, walls: bool = True) -> int:
    """The structural bound (terms) of the scene's closed forms; raises
    :class:`~symmech.algebra.budget.BudgetExceeded` naming the stage when it is over budget
    (module docstring).  ``walls=False`` leaves the impact maps out."""
    g = sp.Matrix(scene.mass_matrix())
    mu = sp.Matrix(scene.constraint_matrix)
    limit = limits.CLOSED_FORM_TERMS

    def check(stage: str, M: sp.Matrix) -> int:
        terms = limits.determinant_terms(M)
        if terms > limit:
            raise BudgetExceeded(stage, "CLOSED_FORM_TERMS", "terms", limit, terms)
        return terms

    worst = check(f"closed-form inverse of the metric of scene {scene.name!r}", g)
    if mu.rows:
        worst = max(
            worst, check(f"closed-form constrained solve of scene {scene.name!r}", _bordered(g, mu))
        )
    for q in scene.coordinates:
        grad = sp.diff(scene.potential, q)
        terms, _ = limits.expanded_terms(grad)
        if terms > limits.FIELD_TERMS:
            raise BudgetExceeded(
                f"closed-form acceleration of scene {scene.name!r} (d V/d {q})",
                "FIELD_TERMS",
                "terms",
                limits.FIELD_TERMS,
                terms,
            )
    if not walls:
        return worst
    S = scene.frame
    for w in scene.walls:
        row = sp.Matrix([[sp.diff(w.psi, qi) for qi in scene.coordinates]])
        dpsi = row * sp.Matrix(S) if S is not None else row
        A = mu.col_join(dpsi).col_join(sp.Matrix(w.impulsive_matrix))
        stage = f"closed-form impact map of wall {w.name!r}"
        worst = max(worst, check(stage, _bordered(g, A)))
    return worst
