"""An entry of the round-trip table (:mod:`mechanics_table`) and how its outcome is
judged: the import agrees with the model's own equations, or refuses it as listed."""

from __future__ import annotations

import re
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass

from mechanics_support import c_worst_difference, random_values, worst_difference

import symmech as sm

#: the largest relative difference of the accelerations accepted as agreement
TOLERANCE = 1e-9


@dataclass(frozen=True)
class Entry:
    """A model of the table: its name, where it was copied from, its builder (returns the
    model with its equations formed), and the reason it is refused (a regular expression
    the SceneError's message must match; None: it must import and agree).  ``slow``:
    left out of CI and of ``--quick``; ``c``: the generated C is checked too;
    ``values``: parameters given a value of their own (the rest random in [0.5, 1.5])."""

    name: str
    source: str
    build: Callable[[], object]
    refused: str | None = None
    slow: bool = False
    c: bool = False
    #: parameter values (by name) fixed for the comparison, the others random
    values: tuple[tuple[str, float], ...] = ()


@dataclass(frozen=True)
class Outcome:
    """What the import did with an entry: ``kind`` is "imported" (agreeing to
    :data:`TOLERANCE`), "refused" (with the listed reason) or "wrong" (anything else:
    a disagreement, a refusal not listed or with another reason, an import of a model
    listed as refused); ``what`` the difference or the message."""

    entry: Entry
    kind: str
    what: str
    seconds: float


def judge(entry: Entry, c: bool = False) -> Outcome:
    """Build the entry's model, import it and judge the outcome (the model's own
    ``mass_matrix_full \\ forcing_full`` at random states is the reference; with ``c``,
    the generated C's ``rhs`` too).  An exception other than a SceneError out of the
    import is wrong whatever the table says."""
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = entry.build()
        try:
            scene = sm.Scene.from_mechanics(model, name="model")
        except sm.SceneError as exc:
            kind, what = "refused", str(exc)
        except Exception as exc:  # (any other exception is a defect of the import)
            kind, what = "raised", f"{type(exc).__name__}: {exc}"
        else:
            values = random_values(model)
            fixed = dict(entry.values)
            values = {k: fixed.get(str(k), v) for k, v in values.items()}
            kind = "imported"
            worst = worst_difference(model, scene, values)
            if c:
                worst = max(worst, c_worst_difference(model, scene, values))
    seconds = time.perf_counter() - t0
    if kind == "imported":
        ok = entry.refused is None and worst < TOLERANCE
        listed = "" if entry.refused is None else " (listed as refused)"
        return Outcome(entry, "imported" if ok else "wrong", f"{worst:.1e}{listed}", seconds)
    ok = kind == "refused" and entry.refused is not None and re.search(entry.refused, what)
    return Outcome(entry, "refused" if ok else "wrong", what, seconds)
