"""Impacts layer: impact maps of walls with restitution and instantaneous constraints.

* :func:`derive_impact_map` / :class:`ImpactMap`: the closed-form post-impact velocity of
  a wall (Carnot paper 002: eq. 10, Prop. 3.4, eq. 17, Prop. 4.2; text 001: Theorem 2.12
  and the energy law of section 3.2).  ``Scene.impact_map(wall)`` is the usual entry point.
* :func:`derive_several_impact_map` / :class:`SeveralImpactMap`: the map of a set of walls
  hit at once (generalized Newton law per wall, the normal impulses, the energy identity),
  (:mod:`symmech.impacts.several`; ``Scene.impact_map([...])``), and
  :func:`simultaneous_impulses`, the LCP that decides which walls of a touching set take
  an impulse (:mod:`symmech.impacts.decision`).
* :class:`CarnotResult`: the residual of Carnot's theorems 3.2/3.6/3.9/3.11/4.1/4.3.
* The independent impulse-momentum (KKT) route that cross-checks these maps is a test
  oracle: ``tests/kkt_oracle.py``.
* :mod:`symmech.algebra.stability`: the stabilising step for float64 evaluation.
* :mod:`symmech.impacts.adjugate_projectors`: the cost-bounded exact route for the projectors
  (adjugates over the polynomial ring, one shared denominator, bounded final gcds).
* :mod:`symmech.algebra.identity`: exact evaluation at a random point with a degree bound
  (Schwartz-Zippel), how :meth:`ImpactMap.carnot` decides large maps.
"""

from symmech.algebra.stability import stable_coefficient, stable_linear, stable_matrix
from symmech.impacts.carnot import CarnotResult
from symmech.impacts.decision import ContactDecision, simultaneous_impulses
from symmech.impacts.degeneracy import Singularity
from symmech.impacts.energy_law import EnergyLaw
from symmech.impacts.impact_map import LAWS, ImpactMap, derive_impact_map
from symmech.impacts.impact_projectors import ImpactProjectors, impact_projectors
from symmech.impacts.several import SeveralImpactMap, derive_several_impact_map

__all__ = [
    "LAWS",
    "CarnotResult",
    "ContactDecision",
    "EnergyLaw",
    "ImpactMap",
    "ImpactProjectors",
    "SeveralImpactMap",
    "Singularity",
    "derive_impact_map",
    "derive_several_impact_map",
    "impact_projectors",
    "simultaneous_impulses",
    "stable_coefficient",
    "stable_linear",
    "stable_matrix",
]
