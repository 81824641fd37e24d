"""What every stress case shares: its result record, the sanity checks of a run (finite,
no tunnelling), the energy of a state and the table the cases print."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import sympy as sp

from symmech.scene import Scene
from symmech.simulate.result import SimulationResult

__all__ = ["StressResult", "energy", "format_table", "result", "sane"]


@dataclass(frozen=True)
class StressResult:
    """One stress case: the measured error, its tolerance, and the verdict."""

    case: str
    setting: str
    error: float
    tolerance: float
    passed: bool
    detail: str
    seconds: float


def sane(res: SimulationResult, gap: Callable[[np.ndarray], np.ndarray], atol: float) -> str:
    """'' when the run is finite and never tunnels, else what went wrong."""
    if not (np.all(np.isfinite(res.q)) and np.all(np.isfinite(res.v))):
        return "NaN or Inf in the result"
    g = gap(res.q)
    if np.min(g) < -10 * atol:
        return f"tunnelled: gap {np.min(g):.3g}"
    return ""


def result(
    case: str, setting: str, error: float, tol: float, problem: str, t0: float, extra: str = ""
) -> StressResult:
    ok = not problem and math.isfinite(error) and error <= tol
    detail = problem or extra
    return StressResult(case, setting, error, tol, ok, detail, time.perf_counter() - t0)


def energy(scene: Scene, params: dict[str, float], q: np.ndarray, v: np.ndarray) -> float:
    subs = {p: params[str(p)] for p in scene.parameters}
    subs.update(dict(zip(scene.coordinates, q, strict=True)))
    subs.update(dict(zip(scene.velocities, v, strict=True)))
    return float(sp.sympify(scene.energy(), strict=True).xreplace(subs))


def format_table(results: list[StressResult]) -> str:
    """A Markdown table of the results."""
    lines = [
        "| case | setting | error | tolerance | verdict | seconds | detail |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in results:
        lines.append(
            f"| {r.case} | {r.setting} | {r.error:.2e} | {r.tolerance:.1e} |"
            f" {'pass' if r.passed else 'FAIL'} | {r.seconds:.2f} | {r.detail} |"
        )
    return "\n".join(lines)
