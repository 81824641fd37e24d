"""Gaits: hybrid systems with modes, their stride maps, periodic orbits and stability.

:mod:`.modes` declares modes and transitions (:class:`Gait`), :mod:`.limits` takes a
gait's limit in a parameter, :mod:`.evaluation` evaluates them in generated code or in
mpmath, :mod:`.stride_map` computes the stride map and its Jacobian (variational equations
and saltation matrices) and :mod:`.native` runs that loop in generated C, :mod:`.walking`
walks many strides, :mod:`.periodic` finds periodic gaits and their multipliers,
:mod:`.models` has the walkers of the literature.
"""

from symmech.gait.evaluation import CompiledGait, MpGait
from symmech.gait.limits import limit_gait
from symmech.gait.modes import Gait, Reset, Transition, impact_reset, pinned_scene
from symmech.gait.stride_map import GaitError, StrideOptions, StrideResult, stride
from symmech.gait.walking import Walk, walk

__all__ = [
    "CompiledGait",
    "Gait",
    "GaitError",
    "MpGait",
    "Reset",
    "StrideOptions",
    "StrideResult",
    "Transition",
    "Walk",
    "impact_reset",
    "limit_gait",
    "pinned_scene",
    "stride",
    "walk",
]
