"""Checks of a run's input values, shared by ``simulate``, ``simulate_batch``, ``sweep``
and the run options (:mod:`symmech.simulate.options`).

Every argument is checked before anything is generated or run, and a problem raises
:class:`~symmech.simulate.system.SimulationError` naming the argument (and the row, for a
batch): states of the right shape, real and finite; positive numbers; counts.
"""

from __future__ import annotations

import math

import numpy as np

from symmech.simulate.parameters import real_scalar, real_values
from symmech.simulate.system import SimulationError

__all__ = [
    "MAX_COUNT",
    "MAX_EVENT_SAMPLES",
    "count",
    "number",
    "numbers",
    "parameter_values",
    "positive",
    "states",
]


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
    (:func:`~symmech.simulate.parameters.real_values`) and finite; a copy in C order."""
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


def number(text: str, what: str) -> float:
    """One command-line number (``"9.81"``), finite, or a SimulationError naming the option
    ``what``: a list (``"9,81"``, a decimal comma, or ``"1 2"``) is refused, never read as
    its first entry."""
    values = numbers(text, what)
    if len(values) != 1:
        raise SimulationError(
            f"{what}: expected one number, got {text!r} (the decimal separator is '.')"
        )
    return values[0]


def parameter_values(items: list[str]) -> dict[str, float]:
    """The ``--param NAME=VALUE`` options of a command line as ``{name: value}`` (each value
    one number: :func:`number`), or a SimulationError naming the bad one."""
    out: dict[str, float] = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise SimulationError(f"--param: expected NAME=VALUE, got {item!r}")
        out[name.strip()] = number(value, f"--param {name.strip()}")
    return out
