"""A gait's fixed point and multipliers by several routes, with their errors and costs.

Routes (:data:`ROUTES`):

``c``, ``numpy``
    Newton on the stride map with ``DP`` from the variational equations and saltation
    matrices, in generated C or NumPy (DOP853, rtol = atol = 1e-13).
``fd``
    The multipliers of forward differences of the C stride map at the C fixed point, at
    the step (``10^-3 ... 10^-10``) that comes closest to the reference: the best a user of
    finite differences could do, knowing the answer (Coleman 2009).
``mp``
    The variational-saltation route in mpmath at ``digits`` digits (Gauss-Legendre
    collocation, tolerances ``10^-digits``): the reference.
``mp-cd``
    Central differences of the mpmath stride map (step ``10^-(digits/3)``): an
    independent check of the reference's Jacobian.

Each route's error is the largest distance from its multipliers (sorted by modulus, then
phase) to the reference's: ``mp`` when it was run, else ``c``.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import mpmath

from symmech.errors import SymmechError
from symmech.gait.evaluation import CompiledGait, MpGait
from symmech.gait.modes import Gait
from symmech.gait.periodic import difference_jacobian, fixed_point, multipliers
from symmech.gait.stride_map import StrideOptions, stride

__all__ = ["ROUTES", "RouteFigure", "solve_routes", "stride_costs"]

ROUTES = ("c", "numpy", "fd", "mp", "mp-cd")


@dataclass
class RouteFigure:
    """One route's fixed point, multipliers, run time (seconds, code generation
    excluded) and error against the reference (None before it is known)."""

    route: str
    x: list[float]
    multipliers: list[complex]
    seconds: float
    error: float | None = None
    note: str = ""
    exact: Any = field(default=None, repr=False)  # the multipliers as computed (mpc)


def _complex(values: Sequence[Any]) -> list[complex]:
    return [complex(v) for v in values]


def _distance(a: Sequence[Any], b: Sequence[Any]) -> float:
    return float(max((abs(mpmath.mpc(x) - mpmath.mpc(y)) for x, y in zip(a, b, strict=True))))


def solve_routes(
    gait: Gait,
    parameters: Mapping[str, float],
    guess: Sequence[float],
    routes: Sequence[str] = ("c", "fd"),
    *,
    digits: int = 30,
    section: int = 0,
) -> list[RouteFigure]:
    """The figures of each route in ``routes`` (module docstring), in that order."""
    unknown = [r for r in routes if r not in ROUTES]
    if unknown:
        raise SymmechError(f"routes: unknown {unknown}; choose from {list(ROUTES)}")
    figures: dict[str, RouteFigure] = {}
    compiled: dict[str, CompiledGait] = {}
    start = list(guess)
    for target in ("c", "numpy"):
        if target in routes or (target == "c" and {"fd", "mp", "mp-cd"} & set(routes)):
            fns = compiled[target] = CompiledGait(gait, parameters, target=target)
            t0 = time.perf_counter()
            fp = fixed_point(fns, section, start)
            seconds = time.perf_counter() - t0
            note = f"{fp.iterations} Newton steps, period {float(fp.period):.12g}"
            figures[target] = RouteFigure(
                target, list(map(float, fp.x)), _complex(fp.multipliers), seconds, note=note
            )
    x_c = figures["c"].x if "c" in figures else start
    if "mp" in routes or "mp-cd" in routes:
        with mpmath.workdps(digits + 8):
            mfns = MpGait(gait, parameters)
            tol = mpmath.mpf(10) ** -digits
            opts = StrideOptions(rtol=float(tol), atol=float(tol))
            t0 = time.perf_counter()
            mfp = fixed_point(mfns, section, x_c, tol=tol * 100, options=opts)
            seconds = time.perf_counter() - t0
            ref = RouteFigure(
                "mp",
                [float(v) for v in mfp.x],
                _complex(mfp.multipliers),
                seconds,
                note=f"{digits} digits, {mfp.iterations} Newton steps",
                exact=list(mfp.multipliers),
            )
            if "mp" in routes:
                figures["mp"] = ref
            if "mp-cd" in routes:
                t0 = time.perf_counter()
                h = mpmath.mpf(10) ** -(digits // 3)
                J = difference_jacobian(mfns, section, list(mfp.x), h, options=opts)
                cd = list(multipliers(J))
                figures["mp-cd"] = RouteFigure(
                    "mp-cd",
                    [float(v) for v in mfp.x],
                    _complex(cd),
                    time.perf_counter() - t0,
                    note=f"central differences, h = 1e-{digits // 3}",
                    exact=cd,
                )
            reference = ref.exact
    else:
        reference = figures["c"].multipliers if "c" in figures else None
    if "fd" in routes:
        figures["fd"] = _forward_differences(compiled["c"], section, x_c, reference)
    out = [figures[r] for r in routes]
    if reference is not None:
        for f in out:
            f.error = _distance(f.exact if f.exact is not None else f.multipliers, reference)
    return out


def _forward_differences(fns: CompiledGait, section: int, x: Sequence[float], reference):
    best: RouteFigure | None = None
    for k in range(3, 11):
        t0 = time.perf_counter()
        J = difference_jacobian(fns, section, x, 10.0**-k, central=False)
        seconds = time.perf_counter() - t0
        m = _complex(multipliers(J))
        err = _distance(m, reference) if reference is not None else None
        fig = RouteFigure("fd", list(x), m, seconds, err, note=f"forward, best h = 1e-{k}")
        if best is None or (err is not None and best.error is not None and err < best.error):
            best = fig
    assert best is not None
    return best


def stride_costs(
    fns: CompiledGait, x: Sequence[float], section: int = 0, repeat: int = 5
) -> tuple[float, float]:
    """Seconds of one stride and of one stride with its Jacobian (best of ``repeat``)."""
    plain = min(_timed(lambda: stride(fns, section, x)) for _ in range(repeat))
    full = min(_timed(lambda: stride(fns, section, x, variational=True)) for _ in range(repeat))
    return plain, full


def _timed(fn: Any) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def format_figures(figures: Sequence[RouteFigure]) -> str:
    """The figures as a text table."""
    rows = ["route   seconds     error      multipliers (nontrivial first)   fixed point"]
    for f in figures:
        err = "      -   " if f.error is None else f"{f.error:9.2e} "
        mults = ", ".join(f"{m.real:+.14f}{m.imag:+.14f}i" for m in f.multipliers)
        xs = ", ".join(f"{v:+.14f}" for v in f.x)
        rows.append(f"{f.route:7s} {f.seconds:9.4f} {err} [{mults}]  [{xs}]  {f.note}")
    return "\n".join(rows)


def figures_frame(figures: Sequence[RouteFigure]) -> Any:
    """The routes' figures as a pandas DataFrame, one row per route: seconds, error, each
    multiplier's real and imaginary parts (``mult<k>_re``, ``mult<k>_im``) and each entry
    of the fixed point (``x<k>``)."""
    import pandas as pd

    rows = []
    for f in figures:
        row: dict[str, Any] = {"route": f.route, "seconds": f.seconds, "error": f.error}
        for k, m in enumerate(f.multipliers):
            row[f"mult{k}_re"], row[f"mult{k}_im"] = m.real, m.imag
        for k, v in enumerate(f.x):
            row[f"x{k}"] = v
        row["note"] = f.note
        rows.append(row)
    return pd.DataFrame(rows).set_index("route")


def continuation_frame(points: Sequence[Any], key: str) -> Any:
    """A continuation (:func:`symmech.gait.periodic.continuation`) as a pandas DataFrame,
    one row per parameter value: stable, the multipliers, the fixed point, the period,
    and the failure when Newton found none."""
    import pandas as pd

    rows = []
    for p in points:
        row: dict[str, Any] = {key: p.value, "found": p.point is not None, "failure": p.failure}
        if p.point is not None:
            row["stable"] = p.point.stable
            row["period"] = float(p.point.period)
            for k, m in enumerate(p.point.multipliers):
                row[f"mult{k}_re"], row[f"mult{k}_im"] = m.real, m.imag
            for k, v in enumerate(p.point.x):
                row[f"x{k}"] = float(v)
        rows.append(row)
    return pd.DataFrame(rows).set_index(key)
