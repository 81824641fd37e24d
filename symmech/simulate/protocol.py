"""The contract between the C loop and Python: codes and vector layouts, defined once.

The generated C loop (``templates/c/simulator.c.jinja``) reads an options vector, writes
an info row per run and reports statuses, reasons, event kinds and failing functions as
small integers.  Each of these tables is a tuple of names here; the template receives
them as C enums (:func:`c_enums`: ``ST_``, ``R_``, ``K_``, ``F_``, ``OPT_`` and ``I_``
followed by the upper-cased name, numbered in order), and the Python side reads the same
tuples (:func:`slot`), so neither side restates the other's numbers.
"""

from __future__ import annotations

__all__ = [
    "EVENT_KINDS",
    "FUNCTIONS",
    "INFO",
    "INFO_HEAD",
    "OPTIONS",
    "REASONS",
    "RUN_STATES",
    "c_enums",
    "slot",
]

#: A run's state: ``running`` while the loop goes on, then one of the result statuses
#: (:data:`symmech.simulate.result.STATUSES`, in this order).
RUN_STATES = ("running", "finished", "zeno", "max_events", "failed", "max_steps")

#: Why a run stopped (decoded into a message by :func:`symmech.simulate.csim.decode`).
REASONS = (
    "none",
    "end",
    "max_events",
    "sequential",
    "accumulation",
    "rest",
    "rhs_nonfinite",
    "step_small",
    "fixed_nonfinite",
    "call_failed",
    "condition",
    "max_steps",
    "mode_missing",
)

#: The kinds of events (:class:`symmech.simulate.result.Event`).
EVENT_KINDS = ("impact", "grazing", "contact", "release")

#: Generated functions whose failure the loop reports: (C enum name, function name).
FUNCTIONS = (
    ("psi", "psi"),
    ("dpsi", "dpsi"),
    ("psi_t", "psi_t"),
    ("impact", "impact"),
    ("energy", "energy"),
    ("project", "projector_P"),
    ("residual", "constraint_residual"),
    ("force", "multipliers"),
)

#: The options vector handed to the loop's ``new`` and ``batch`` entry points.
OPTIONS = (
    "rtol",
    "atol",
    "max_step",
    "fixed_step",
    "t_end",
    "zeno_factor",
    "max_events",
    "contact_stop",
    "samples",
    "max_steps",
    "sequential",
)

#: The head of a run's info row (written by the loop's ``info``); the final state
#: ``y`` (2n entries) follows it.  ``d0..d3`` are the details of the stop (times, counts,
#: speeds: see :func:`symmech.simulate.csim.decode`).
INFO = (
    "status",
    "reason",
    "wall",
    "why",
    "sub",
    "function",
    "mode",
    "d0",
    "d1",
    "d2",
    "d3",
    "steps",
    "rejected_steps",
    "rhs_calls",
    "constraint_drift",
    "energy_drift",
    "events",
    "impacts",
    "grazing",
    "contacts",
    "releases",
    "last_t",
    "impact_condition",
)

#: Entries of the info row before the state.
INFO_HEAD = len(INFO)

_TABLES: dict[str, tuple[str, ...]] = {
    "ST_": RUN_STATES,
    "R_": REASONS,
    "K_": EVENT_KINDS,
    "F_": tuple(c for c, _ in FUNCTIONS),
    "OPT_": OPTIONS,
    "I_": INFO,
}


def slot(table: tuple[str, ...], name: str) -> int:
    """The number of ``name`` in ``table`` (its C enum value)."""
    return table.index(name)


def c_enums() -> list[tuple[str, list[str]]]:
    """Every table as ``(prefix, [C names])`` for the template's enums, numbered from 0."""
    return [(prefix, [prefix + n.upper() for n in names]) for prefix, names in _TABLES.items()]
