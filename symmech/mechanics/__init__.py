"""Import of ``sympy.physics.mechanics`` models (see :mod:`symmech.mechanics.convert`)."""

from symmech.mechanics.convert import scene_arguments

__all__ = ["scene_arguments"]
