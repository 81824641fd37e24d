"""One solve for the acceleration and the multipliers of a large constrained system.

With the strategy ``linear_solve``, ``acceleration`` and ``multipliers`` of a constrained
scene evaluate the same blocks (g, f, mu, mu_dot v) and run the same unrolled solve
(:mod:`symmech.codegen.unroll`); they differ only in what they store at its end.  Printed
separately, the code is written, and compiled, twice.  For a small system that is what the
batch loop wants: each body is split for it (:mod:`symmech.codegen.batch_split`).  Once the
acceleration's body is too long to be split (over
:data:`~symmech.codegen.batch_split.MAX_SPLIT_CHARACTERS`), :func:`share_constrained_solve`
makes both parts of ``dynamics``, ``out = (v_dot, lambda)`` from one solve: ``acceleration``
returns its first n entries, ``multipliers`` its last m (in C, through a local array, each
checked finite as before).  The compiler then sees the solve once: the Whipple bicycle's
library compiles in about 1.0 s of gcc instead of 1.45 s.  The doubles do not change: the
solve stores both results after the same operations.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace

from symmech.codegen.batch_split import MAX_SPLIT_CHARACTERS
from symmech.codegen.kinds import DYNAMICS_DOC, DYNAMICS_EQUATION
from symmech.codegen.lower import LoweredFunction
from symmech.codegen.plan import FunctionPlan, ScenePlan

__all__ = ["share_constrained_solve"]

#: Lowers a function plan, given the function it calls (or is part of).
Lower = Callable[[FunctionPlan, LoweredFunction | None], LoweredFunction]


def share_constrained_solve(
    plan: ScenePlan, lowered: Mapping[str, LoweredFunction], lower: Lower
) -> tuple[ScenePlan, dict[str, LoweredFunction]]:
    """``plan`` and its ``lowered`` functions (by name, in order), with ``acceleration`` and
    ``multipliers`` made parts of ``dynamics`` (added before them when not asked for) when
    both solve the constrained system and the acceleration's body is longer than
    :data:`~symmech.codegen.batch_split.MAX_SPLIT_CHARACTERS`; else unchanged."""
    acc, mul = lowered.get("acceleration"), lowered.get("multipliers")
    if (
        acc is None
        or mul is None
        or acc.step != "constrained_acceleration"
        or mul.step != "constrained_multipliers"
        or acc.printed_characters <= MAX_SPLIT_CHARACTERS
    ):
        return plan, dict(lowered)
    n = plan.n
    whole_plan = _dynamics_plan(plan, lowered)
    whole = lowered.get("dynamics") or lower(whole_plan, None)
    part_plans = {
        "acceleration": _part(plan.function("acceleration"), 0),
        "multipliers": _part(plan.function("multipliers"), n),
    }
    functions: list[FunctionPlan] = []
    out: dict[str, LoweredFunction] = {}
    for f in plan.functions:
        if f.name == "acceleration" and "dynamics" not in lowered:
            functions.append(whole_plan)
            out["dynamics"] = whole
        if f.name in part_plans:
            functions.append(part_plans[f.name])
            out[f.name] = lower(part_plans[f.name], whole)
        else:
            functions.append(f)
            out[f.name] = lowered[f.name]
    return replace(plan, functions=tuple(functions)), out


def _dynamics_plan(plan: ScenePlan, lowered: Mapping[str, LoweredFunction]) -> FunctionPlan:
    """The plan's ``dynamics`` (asked for), or one made from its ``acceleration``: the same
    blocks, the step ``constrained_dynamics``, out = (v_dot, lambda)."""
    if "dynamics" in lowered:
        return plan.function("dynamics")
    acc, m = plan.function("acceleration"), lowered["multipliers"].out_size
    return replace(
        acc,
        name="dynamics",
        kind="dynamics",
        doc=DYNAMICS_DOC,
        equation=DYNAMICS_EQUATION,
        out_shape=(plan.n + m,),
        step="constrained_dynamics",
    )


def _part(f: FunctionPlan, offset: int) -> FunctionPlan:
    """``f`` as entries ``offset ...`` of ``dynamics``: no blocks, no step of its own."""
    return replace(
        f,
        doc=f"{f.doc} (part of dynamics)",
        blocks=(),
        step=None,
        step_args=(),
        part_of=("dynamics", offset),
    )
