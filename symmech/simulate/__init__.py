"""Hybrid simulation of scenes with walls: flow, events, impact maps, resting contact.

``simulate(scene, q0, v0, t_end, ...)`` runs one trajectory (:mod:`.run`) on one of the
backends of :mod:`.backend`, with the options of :mod:`.options`; the package
itself is callable, so ``symmech.simulate(scene, ...)`` is that function;
``simulate_batch`` runs many in one call of the generated C loop (:mod:`.batch`).  The
loop itself is described in :mod:`.hybrid`, event location in :mod:`.events`, the
integrators in :mod:`.steppers`, :mod:`.flow` and :mod:`.scipy_flow`, the compiled
functions (free flight and contact modes) in :mod:`.system`.
"""

import sys
import types

from symmech.simulate.backend import BACKENDS, Backend
from symmech.simulate.batch import BatchResult, simulate_batch
from symmech.simulate.options import CONTACT_MODES, RunOptions
from symmech.simulate.result import Event, SimulationResult
from symmech.simulate.run import simulate, system_for
from symmech.simulate.system import HybridSystem, SimulationError, contact_scene

__all__ = [
    "BACKENDS",
    "CONTACT_MODES",
    "Backend",
    "BatchResult",
    "Event",
    "HybridSystem",
    "RunOptions",
    "SimulationError",
    "SimulationResult",
    "contact_scene",
    "simulate",
    "simulate_batch",
    "system_for",
]


class _CallablePackage(types.ModuleType):
    """``symmech.simulate(...)`` calls :func:`simulate` (the package and the function share
    the name the API promises)."""

    def __call__(self, *args: object, **kwargs: object) -> SimulationResult:
        return simulate(*args, **kwargs)  # type: ignore[arg-type]


sys.modules[__name__].__class__ = _CallablePackage
