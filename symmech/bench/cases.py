"""Simulation cases of the built-in scenes: initial state, horizon and parameters.

A :class:`Case` is what ``symmech simulate SCENE``, ``symmech bench SCENE`` and the
benchmarks run when no state is given: the scene's parameters are the defaults of its scene
file (``symmech/scenes/*.toml``), overridden where a case needs another value.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

from symmech.errors import SymmechError
from symmech.scene import Scene
from symmech.scenefile import SceneFile, read_scene

if TYPE_CHECKING:
    from symmech.simulate.result import SimulationResult

__all__ = ["CASES", "Case", "bouncing_ball_state", "bouncing_ball_times", "case"]


@dataclass(frozen=True)
class Case:
    """A run of a built-in scene: ``q0``, ``v0`` at t = 0 to ``t_end``."""

    scene_name: str
    q0: tuple[float, ...]
    v0: tuple[float, ...]
    t_end: float
    description: str
    overrides: Mapping[str, float] = field(default_factory=dict)
    #: the case's own name, when a scene has more than one case
    label: str = ""

    @property
    def name(self) -> str:
        return self.label or self.scene_name

    def scene(self) -> Scene:
        """The scene (loaded from its built-in scene file, once)."""
        return _built_in(self.scene_name).scene

    def params(self) -> dict[str, float]:
        """The scene file's defaults with this case's overrides."""
        return {**_defaults(self.scene_name), **self.overrides}

    def simulate(self, **options: Any) -> SimulationResult:
        """The case run by :func:`symmech.simulate` from ``q0``, ``v0`` to ``t_end`` at its
        parameters; ``options`` as there (``backend``, ``method``, ``rtol``, ...)."""
        from symmech.simulate import simulate

        return simulate(self.scene(), self.q0, self.v0, self.t_end, params=self.params(), **options)


@functools.cache
def _built_in(name: str) -> SceneFile:
    """The built-in scene file ``name``, read once (reading it declares the scene, some
    milliseconds; a benchmark runs its case many times)."""
    return read_scene(name)


@functools.cache
def _defaults(name: str) -> Mapping[str, float]:
    """The parameter defaults of the built-in scene file ``name`` as floats."""
    return MappingProxyType({str(k): float(v) for k, v in _built_in(name).defaults.items()})


CASES: dict[str, Case] = {
    c.name: c
    for c in (
        Case(
            "bouncing_ball",
            (1.0,),
            (0.0,),
            1.3,
            "dropped from 1 m, alpha = 0.5 (t* = 1.3546 s): 7 impacts before t_end",
        ),
        Case(
            "ellipse_gravity",
            (0.0, 1.5, 0.3),
            (0.0, 0.0, 2.0),
            6.0,
            "text 001 ellipse dropped from y = 1.5 with spin, alpha = 0.8: rests, then rocks",
        ),
        Case(
            "ellipse_gravity",
            (0.0, 1.5, 0.3),
            (0.0, 0.0, 2.0),
            3.5,
            "the ellipse's first 11 impacts, before the accumulation (where the baseline works)",
            label="ellipse_gravity_flight",
        ),
        Case(
            "disk_3_7_gravity",
            (0.0, 1.0, 0.0),
            (1.0, 0.0, 3.0),
            3.0,
            "Carnot 3.7 disc thrown onto the rough floor with backspin: rolls after impacts",
        ),
        Case(
            "disk_3_7_gravity",
            (0.0, 1.0, 0.0),
            (1.0, 0.0, 3.0),
            2.1,
            "the disc's first 6 impacts, before the accumulation (where the baseline works)",
            label="disk_3_7_gravity_flight",
        ),
        Case(
            "carnot_3_13",
            (2.0, 0.0, 1.0, 0.1, 1.0, 0.2),
            (-1.0, 0.0, 0.0, 0.0, -2.0, 0.3),
            3.0,
            "Carnot 3.13 sphere rolling into its rough wall (x = 0) and bouncing back",
        ),
        Case(
            "newtons_cradle_3",
            (0.0, 1.0, 2.0),
            (1.0, 0.0, 0.0),
            2.0,
            "three touching balls, the first moving: the last leaves",
        ),
        Case(
            "falling_rod",
            (0.0, 1.0, 0.2),
            (0.0, 0.0, 0.0),
            0.85,
            "rod dropped tilted, alpha = 0.5: its ends strike in turn (8 impacts, before they"
            " accumulate on one end)",
        ),
        Case(
            "ladder",
            (math.cos(1.2), math.sin(1.2), 1.2),
            (0.0, 0.0, 0.0),
            1.0,
            "ladder released at theta = 1.2 on a frictionless floor and wall: leaves the wall",
        ),
        Case(
            "pendulum_wall",
            (-0.3,),
            (4.0,),
            5.0,
            "pendulum swung into the wall at theta = pi/6, alpha = 0.9",
        ),
        Case(
            "stiff_dumbbell",
            (0.5, 1.5),
            (0.0, 0.0),
            2.0,
            "stiff dumbbell (k = 1e6) dropped onto the floor",
        ),
    )
}


def case(name: str) -> Case:
    """The case of built-in scene ``name``."""
    try:
        return CASES[name]
    except (KeyError, TypeError):
        raise SymmechError(
            f"no simulation case for {name!r}; choose one of {sorted(CASES)}"
        ) from None


def bouncing_ball_times(h: float, g: float, alpha: float, until: float) -> list[float]:
    """Impact times of a ball dropped from rest at height h: ``t_1 = sqrt(2h/g)``,
    ``t_(k+1) = t_k + 2 alpha^k sqrt(2 g h) / g`` (those before ``until``)."""
    u0 = math.sqrt(2 * g * h)
    times = [math.sqrt(2 * h / g)]
    k = 1
    while True:
        nxt = times[-1] + 2 * alpha**k * u0 / g
        if nxt >= until or nxt == times[-1]:
            break
        times.append(nxt)
        k += 1
    return [t for t in times if t < until]


def bouncing_ball_state(h: float, g: float, alpha: float, t: float) -> tuple[float, float]:
    """(y, y_dot) of the dropped ball at time t (before the accumulation time)."""
    times = bouncing_ball_times(h, g, alpha, t)
    u0 = math.sqrt(2 * g * h)
    if not times:
        return h - g * t * t / 2, -g * t
    k = len(times) - 1
    tk = times[-1]
    up = alpha ** (k + 1) * u0
    s = t - tk
    return up * s - g * s * s / 2, up - g * s
