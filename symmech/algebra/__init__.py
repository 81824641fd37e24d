"""The algebra layer: exact symbolic building blocks below every piece of mechanics.

Nothing here knows about metrics, constraints or walls: only expressions, matrices and
their cost.

* :mod:`~symmech.algebra.field`: the rational-function field of a set of entries, always
  in the Pythagorean normal form (``sin^2 -> 1 - cos^2``); exact solves and inverses;
* :mod:`~symmech.algebra.laplace`: division-free adjugates and determinants;
* :mod:`~symmech.algebra.block_structure`: the diagonal blocks of a sparse pattern;
* :mod:`~symmech.algebra.energy_forms`: affine maps and quadratic forms over that field
  (the energy identities of Carnot's theorems);
* :mod:`~symmech.algebra.simplification` and :mod:`~symmech.algebra.stability`: the
  normal forms of results and their stable forms for float64 evaluation;
* :mod:`~symmech.algebra.zero`: the one "is this identically zero" decision, over
  :mod:`~symmech.algebra.identity` (randomized exact evaluation with its error bound) and
  :mod:`~symmech.algebra.numeric` (evaluation at sample points, definiteness, signs);
* :mod:`~symmech.algebra.rank`: the one numeric rank test (at a point, and generic);
* :mod:`~symmech.algebra.sampling`: reproducible random sample points;
* :mod:`~symmech.algebra.budget`: every cost budget of the symbolic stages and their one
  exception, :class:`~symmech.algebra.budget.BudgetExceeded`.
"""
