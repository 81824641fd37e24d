"""The algebra layer: exact symbolic building blocks below every piece of mechanics.

Nothing here knows about metrics, constraints or walls: only expressions, matrices and
their cost.  :mod:`symmech.algebra.budget` holds every cost budget of the symbolic stages
and their one exception, :class:`~symmech.algebra.budget.BudgetExceeded`.
"""
