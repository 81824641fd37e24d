"""Checks of a run's input, shared by ``simulate`` and ``simulate_batch``.

Every argument is checked before anything is generated or run, and a problem raises
:class:`~symmech.simulate.system.SimulationError` naming the argument (and the row, for a
batch): states of the right shape, real and finite; ``t_end > t0``, both finite;
``100 eps <= rtol < 1`` (float64 cannot deliver less), ``atol > 0``, ``max_step > 0``;
``max_events``, ``max_steps`` and ``event_samples`` positive integers; ``contact`` one of
:data:`CONTACT_MODES`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from symmech.simulate.hybrid import MAX_STEPS, Options
from symmech.simulate.system import SimulationError, real_scalar, real_values

__all__ = [
    "CONTACT_MODES",
    "MAX_COUNT",
    "MAX_EVENT_SAMPLES",
    "RunOptions",
    "check_run",
    "count",
    "numbers",
    "positive",
    "states",
]

#: What to do at an accumulation of impacts.
CONTACT_MODES = ("persistent", "stop")

EPS = float(np.finfo(float).eps)


@dataclass(frozen=True)
class RunOptions:
    """The checked options of a run."""

    t0: float
    t_end: float
    rtol: float
    atol: float
    max_step: float
    max_events: int
    event_samples: int
    contact: str
    max_steps: int = MAX_STEPS

    def loop(self) -> Options:
        """The options of the hybrid loop (:class:`symmech.simulate.hybrid.Options`)."""
        return Options(
            t_end=self.t_end,
            rtol=self.rtol,
            atol=self.atol,
            max_events=self.max_events,
            contact=self.contact,
            samples=self.event_samples,
            max_steps=self.max_steps,
        )


def positive(value: object, what: str) -> float:
    """``value`` as a finite positive float, or a SimulationError naming ``what``."""
    x = real_scalar(value, what)
    if not (math.isfinite(x) and x > 0):
        raise SimulationError(f"{what}: expected a finite positive number, got {value!r}")
    return x


#: Largest count an option may hold: exact in a double and in the C loop's ``long``.
MAX_COUNT = 2**53

#: Largest ``event_samples``: each step evaluates every event function that many times.
MAX_EVENT_SAMPLES = 10**6


def count(value: object, what: str, limit: int = MAX_COUNT) -> int:
    """``value`` as an int in ``[1, limit]`` (Python or NumPy integers; not bool), or a
    SimulationError naming ``what``."""
    if isinstance(value, bool | np.bool_) or not isinstance(value, int | np.integer):
        raise SimulationError(f"{what} must be a positive integer, got {value!r}")
    if not 1 <= int(value) <= limit:
        raise SimulationError(f"{what} must be a positive integer up to {limit}, got {value!r}")
    return int(value)


def states(value: object, n: int, what: str, *, rows: bool = False) -> np.ndarray:
    """``value`` as float64 of shape ``(n,)`` (or ``(N, n)`` with ``rows``, N >= 1), real
    by the rule of the generated code's arguments
    (:func:`~symmech.simulate.system.real_values`) and finite; a copy in C order."""
    a = np.array(real_values(value, what), dtype=np.float64, order="C", copy=True)
    if rows:
        if a.ndim != 2 or a.shape[1] != n or a.shape[0] < 1:
            raise SimulationError(f"{what}: expected shape (N, {n}) with N >= 1, got {a.shape}")
        bad = ~np.all(np.isfinite(a), axis=1)
        if bad.any():
            row = int(np.argmax(bad))
            raise SimulationError(f"{what}: row {row} is not finite: {a[row].tolist()}")
        return a
    if a.shape != (n,):
        raise SimulationError(f"{what}: expected shape ({n},), got {a.shape}")
    if not np.isfinite(a).all():
        raise SimulationError(f"{what}: every entry must be finite, got {a.tolist()}")
    return a


def check_run(
    *,
    t0: Any,
    t_end: Any,
    rtol: Any,
    atol: Any,
    max_step: Any,
    max_events: Any,
    event_samples: Any,
    contact: Any,
    max_steps: Any = MAX_STEPS,
) -> RunOptions:
    """The checked options (see the module docstring)."""
    if contact not in CONTACT_MODES:
        raise SimulationError(f"contact must be one of {CONTACT_MODES}, got {contact!r}")
    t0f, tend = real_scalar(t0, "t0"), real_scalar(t_end, "t_end")
    if not (math.isfinite(t0f) and math.isfinite(tend)):
        raise SimulationError(f"t0 and t_end must be finite, got {t0!r}, {t_end!r}")
    if not tend > t0f:
        raise SimulationError(f"t_end must be greater than t0 = {t0f!r}, got {t_end!r}")
    rtol_f = positive(rtol, "rtol")
    if not rtol_f < 1:
        raise SimulationError(f"rtol must be below 1, got {rtol!r}")
    if rtol_f < 100 * EPS:
        raise SimulationError(
            f"rtol = {rtol!r} is below 100 eps = {100 * EPS:.3g}: float64 cannot deliver it"
            " (use symmech.simulate.reference for more digits)"
        )
    return RunOptions(
        t0=t0f,
        t_end=tend,
        rtol=rtol_f,
        atol=positive(atol, "atol"),
        max_step=tend - t0f if max_step is None else positive(max_step, "max_step"),
        max_events=count(max_events, "max_events"),
        event_samples=count(event_samples, "event_samples", MAX_EVENT_SAMPLES),
        contact=contact,
        max_steps=count(max_steps, "max_steps"),
    )


def numbers(text: str, what: str) -> list[float]:
    """A command-line list of finite numbers (``"0, 1.5,0.3"``), or a SimulationError
    naming the option ``what``."""
    try:
        values = [float(x) for x in text.replace(",", " ").split()]
    except ValueError:
        raise SimulationError(
            f"{what}: expected numbers separated by commas, got {text!r}"
        ) from None
    if not values or not all(math.isfinite(x) for x in values):
        raise SimulationError(f"{what}: expected finite numbers, got {text!r}")
    return values
