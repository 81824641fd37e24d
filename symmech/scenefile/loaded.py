"""The loaded scene file: the Scene and what the Scene API does not hold."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import sympy as sp

from symmech.scene import Scene

# ---------------------------------------------------------------------------------------
# the loaded file


@dataclass(frozen=True)
class SceneFile:
    """A loaded scene file: the :class:`~symmech.Scene` and what the Scene API does not hold.

    Attributes
    ----------
    scene:
        The scene.
    defaults:
        Default values of the parameters that have one: parameter Symbol -> exact sympy
        number (a Float where the file wrote a decimal), in the scene's parameter order.
    functions:
        The functions: name -> the expression substituted for it (a defined function of
        time) or the applied function ``f(t)`` or ``V(x, y)`` (an arbitrary one).
    description:
        The file's description ("" when it has none).
    path:
        The file read, or None for text given to :func:`reads_scene`.
    """

    scene: Scene
    defaults: dict[sp.Symbol, sp.Expr] = field(default_factory=dict)
    functions: dict[str, sp.Expr] = field(default_factory=dict)
    description: str = ""
    path: Path | None = None

    def numeric_defaults(self) -> dict[str, float]:
        """The default values as floats, keyed by parameter name."""
        return {s.name: float(v) for s, v in self.defaults.items()}

    def missing_defaults(self) -> list[sp.Symbol]:
        """The parameters without a default value."""
        return [p for p in self.scene.parameters if p not in self.defaults]
