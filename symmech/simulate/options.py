"""The options of a run: one frozen object, checked once, shared by every entry.

``simulate``, ``simulate_batch`` and ``sweep`` take the same run options, as keywords
(``rtol=1e-10``) or as a :class:`RunOptions` (``options=RunOptions(rtol=1e-10)``, keywords
given beside it replace its fields).  Every field is checked when the object is made, and
a problem raises :class:`~symmech.simulate.system.SimulationError` naming the field:
``100 eps <= rtol < 1`` (float64 cannot deliver less), ``atol > 0``, ``max_step > 0``;
``max_events``, ``max_steps`` and ``event_samples`` positive integers (Python or NumPy,
not bool, up to :data:`~symmech.simulate.arguments.MAX_COUNT`); ``contact`` one of
:data:`CONTACT_MODES`; ``t0`` finite; ``method`` a name (which names a backend runs is the
backend's to say: :mod:`symmech.simulate.backend`).  ``t_end`` belongs to the call
(:meth:`RunOptions.end`).

>>> from symmech.simulate.options import RunOptions
>>> o = RunOptions(rtol=1e-10, contact="stop")
>>> o.rtol, o.atol, o.with_changes(atol=1e-12).atol
(1e-10, 1e-10, 1e-12)
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from symmech.simulate.arguments import MAX_EVENT_SAMPLES, count, positive
from symmech.simulate.hybrid import MAX_STEPS, Options
from symmech.simulate.parameters import real_scalar
from symmech.simulate.system import SimulationError

__all__ = ["CONTACT_MODES", "IMPACT_LAWS", "RunOptions"]

#: What to do at an accumulation of impacts.
CONTACT_MODES = ("persistent", "stop")

#: How walls closed and approaching at the same instant are resolved: together by the
#: generalized Newton law (:mod:`symmech.simulate.impulses`), or one at a time.
IMPACT_LAWS = ("simultaneous", "sequential")

EPS = float(np.finfo(float).eps)


@dataclass(frozen=True)
class RunOptions:
    """The checked options of a run (see the module docstring).

    ``method``: the integration method (the backend's name for it); ``rtol``, ``atol``:
    the tolerances of the flow and the events; ``max_step``: the largest step (default:
    the whole span); ``max_events``, ``max_steps``: bounds on a run's events and accepted
    steps; ``contact``: ``"persistent"`` (an accumulation of impacts becomes a resting
    contact) or ``"stop"``; ``event_samples``: samples of each step's dense output
    searched for events; ``t0``: the start time; ``impact_law``: ``"simultaneous"`` (walls
    closed and approaching at one instant resolved together by the generalized Newton
    law, then in cascade) or ``"sequential"`` (one wall at a time, the most negative
    normal rate first).
    """

    method: str = "dop853"
    rtol: float = 1e-8
    atol: float = 1e-10
    max_step: float | None = None
    max_events: int = 100_000
    max_steps: int = MAX_STEPS
    contact: str = "persistent"
    event_samples: int = 8
    t0: float = 0.0
    impact_law: str = "simultaneous"

    def __post_init__(self) -> None:
        if not isinstance(self.method, str):
            raise SimulationError(f"method must be a name, got {self.method!r}")
        if self.impact_law not in IMPACT_LAWS:
            raise SimulationError(
                f"impact_law must be one of {IMPACT_LAWS}, got {self.impact_law!r}"
            )
        if self.contact not in CONTACT_MODES:
            raise SimulationError(f"contact must be one of {CONTACT_MODES}, got {self.contact!r}")
        t0 = real_scalar(self.t0, "t0")
        if not math.isfinite(t0):
            raise SimulationError(f"t0 must be finite, got {self.t0!r}")
        rtol = positive(self.rtol, "rtol")
        if not rtol < 1:
            raise SimulationError(f"rtol must be below 1, got {self.rtol!r}")
        if rtol < 100 * EPS:
            raise SimulationError(
                f"rtol = {self.rtol!r} is below 100 eps = {100 * EPS:.3g}: float64 cannot"
                " deliver it (use symmech.simulate.reference for more digits)"
            )
        checked = {
            "t0": t0,
            "rtol": rtol,
            "atol": positive(self.atol, "atol"),
            "max_step": None if self.max_step is None else positive(self.max_step, "max_step"),
            "max_events": count(self.max_events, "max_events"),
            "max_steps": count(self.max_steps, "max_steps"),
            "event_samples": count(self.event_samples, "event_samples", MAX_EVENT_SAMPLES),
        }
        for name, value in checked.items():
            object.__setattr__(self, name, value)

    @classmethod
    def build(cls, options: RunOptions | None, keywords: Mapping[str, Any]) -> RunOptions:
        """``options`` (default: the defaults) with the fields in ``keywords`` replaced; an
        unknown keyword is refused with the list of the run options."""
        if options is not None and not isinstance(options, RunOptions):
            raise SimulationError(
                f"options: expected a symmech.simulate.RunOptions, got {type(options).__name__}"
            )
        names = [f.name for f in dataclasses.fields(cls)]
        unknown = sorted(k for k in keywords if k not in names)
        if unknown:
            raise SimulationError(f"unknown run options {unknown}; the run options are {names}")
        if options is None:
            return cls(**keywords)  # (checked once: a run builds its options every call)
        return dataclasses.replace(options, **keywords) if keywords else options

    def with_changes(self, **changes: Any) -> RunOptions:
        """A copy with ``changes`` (checked like the constructor's arguments)."""
        return RunOptions.build(self, changes)

    def end(self, t_end: object) -> float:
        """``t_end`` as a float, finite and after :attr:`t0`."""
        tend = real_scalar(t_end, "t_end")
        if not math.isfinite(tend):
            raise SimulationError(f"t0 and t_end must be finite, got {self.t0!r}, {t_end!r}")
        if not tend > self.t0:
            raise SimulationError(f"t_end must be greater than t0 = {self.t0!r}, got {t_end!r}")
        return tend

    def step_cap(self, t_end: float) -> float:
        """The largest step of a run to ``t_end``: :attr:`max_step`, or the whole span."""
        return t_end - self.t0 if self.max_step is None else self.max_step

    def loop(self, t_end: float) -> Options:
        """The options of the hybrid loop (:class:`symmech.simulate.hybrid.Options`)."""
        return Options(
            t_end=t_end,
            rtol=self.rtol,
            atol=self.atol,
            max_events=self.max_events,
            contact=self.contact,
            samples=self.event_samples,
            max_steps=self.max_steps,
            impact_law=self.impact_law,
        )
