"""symmech: symbolic geometric mechanics.

Declare a mechanical system (coordinates, kinetic metric, potential, linear constraints,
a frame of quasi-velocities, walls) and derive its geometry, constrained dynamics and
impact laws in closed form.

>>> import sympy as sp, symmech as sm
>>> r, th = sm.coordinates("r theta")
>>> scene = sm.Scene((r, th), metric=sp.diag(1, r**2))
>>> scene.christoffel()[0, 1, 1]   # Gamma^r_theta,theta of polar coordinates
-r
"""

from symmech.declaration import drawing, shapes
from symmech.declaration.expressions import parse_expression
from symmech.declaration.symbols import coordinates, t, velocities
from symmech.declaration.wall import Wall
from symmech.errors import (
    ExpressionError,
    ImpactError,
    SceneError,
    SymmechError,
    SymmechWarning,
    UndecidedWarning,
)
from symmech.geometry.distributions import bracket_rank, is_involutive
from symmech.geometry.lie import hat, lie_bracket
from symmech.scene import Scene
from symmech.scenefile import (
    SceneFile,
    SceneFileError,
    dump_scene,
    load_scene,
    loads_scene,
    read_scene,
    reads_scene,
    save_scene,
)

__version__ = "0.1.0"

_LAZY = ("codegen", "simulate", "sweep")
#: Functions re-exported from the lazily imported sub-packages.
_LAZY_FUNCTIONS = {"simulate_batch": "simulate"}


def __getattr__(name: str) -> object:
    """``symmech.codegen``, ``symmech.simulate`` and ``symmech.sweep`` are imported on first
    use (they load jinja2, ctypes, and pandas for sweeps).  The packages ``symmech.simulate``
    and ``symmech.sweep`` are callable: ``symmech.simulate(scene, q0, v0, t_end, ...)`` is
    :func:`symmech.simulate.simulate`, ``symmech.sweep(scene, grid, t_end, ...)`` is
    :func:`symmech.sweep.sweep`."""
    import importlib

    if name in _LAZY_FUNCTIONS:
        return getattr(importlib.import_module(f"symmech.{_LAZY_FUNCTIONS[name]}"), name)
    if name in _LAZY:
        return importlib.import_module(f"symmech.{name}")
    raise AttributeError(f"module 'symmech' has no attribute {name!r}")


__all__ = [
    "ExpressionError",
    "ImpactError",
    "Scene",
    "SceneError",
    "SceneFile",
    "SceneFileError",
    "SymmechError",
    "SymmechWarning",
    "UndecidedWarning",
    "Wall",
    "__version__",
    "bracket_rank",
    "codegen",
    "coordinates",
    "drawing",
    "dump_scene",
    "hat",
    "is_involutive",
    "lie_bracket",
    "load_scene",
    "loads_scene",
    "parse_expression",
    "read_scene",
    "reads_scene",
    "save_scene",
    "shapes",
    "t",
    "velocities",
]
