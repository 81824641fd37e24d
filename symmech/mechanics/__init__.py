"""Import of ``sympy.physics.mechanics`` models (see :mod:`symmech.mechanics.convert`)."""

from symmech.mechanics.convert import scene_arguments
from symmech.mechanics.refusals import reading

__all__ = ["reading", "scene_arguments"]
