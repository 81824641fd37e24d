"""Gaits: hybrid systems with modes, their stride maps, periodic orbits and stability.

:mod:`.modes` declares modes and transitions (:class:`Gait`), :mod:`.evaluation`
evaluates them in generated code or in mpmath, :mod:`.stride_map` computes the stride map and
its Jacobian (variational equations and saltation matrices), :mod:`.models` has the
walkers of the literature.
"""

from symmech.gait.evaluation import CompiledGait, MpGait
from symmech.gait.modes import Gait, Reset, Transition, impact_reset, pinned_scene
from symmech.gait.stride_map import GaitError, StrideOptions, StrideResult, stride

__all__ = [
    "CompiledGait",
    "Gait",
    "GaitError",
    "MpGait",
    "Reset",
    "StrideOptions",
    "StrideResult",
    "Transition",
    "impact_reset",
    "pinned_scene",
    "stride",
]
