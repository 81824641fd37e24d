"""Finding events inside a step: sampled sign changes and root-finding on the dense output.

SciPy's ``solve_ivp`` looks at an event function only at step ends, so two crossings
inside one step, or a dip below zero and back, are invisible to it.  Here every event
function ``g`` (a wall's gap psi, or the normal contact force lambda_N while in contact)
is evaluated on the step's continuous output at ``samples`` equally spaced interior points
as well as at both ends (as DifferentialEquations.jl's ``ContinuousCallback`` does with its
``interp_points``); the earliest sign change ``g >= 0 -> g < 0`` over the samples brackets
the event, and :func:`find_root` narrows the bracket on the continuous output until it is
a few ulps wide.  The event is reported at the left end of the final bracket, the side
where ``g >= 0`` (the admissible side, "LeftRootFind"): a restart from there never starts
on the wrong side of the wall.

The root finder is the Anderson-Bjorck variant of regula falsi (superlinear, never leaves
its bracket), written with plain arithmetic so that it runs unchanged on mpmath numbers.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

__all__ = ["find_root"]


def find_root(
    g: Callable[[Any], Any],
    a: Any,
    b: Any,
    ga: Any,
    gb: Any,
    eps: float,
    max_iter: int = 200,
    time_scale: Any = 1,
) -> tuple[Any, Any, Any, Any]:
    """The bracket ``[a, b]`` narrowed around a sign change of ``g`` (``ga >= 0 > gb``)
    until ``b - a <= 4 eps max(|a|, |b|, time_scale)`` or ``g`` vanishes (``time_scale``:
    the run's, ``min(1, |t_end|)``, so that an event at 1e-10 s is located to a few ulps
    of its own size); returns
    ``(a, b, g(a), g(b))`` with ``g(a) >= 0 > g(b)`` still (Anderson & Bjorck, BIT 13
    (1973) 253: regula falsi with the retained end's value scaled by ``1 - g(c)/g(new)``
    when the same end is kept twice, or by 1/2 when that factor is not positive; a bisection
    whenever three steps did not halve the bracket, so at most about twice bisection's count)."""
    if not (ga >= 0 > gb):
        raise ValueError("find_root needs g(a) >= 0 > g(b)")
    wa, wb = ga, gb  # working values (scaled by the Anderson-Bjorck rule)
    side = 0
    widths = [2 * (b - a)] * 3
    for _ in range(max_iter):
        width = b - a
        scale = max(abs(a), abs(b), time_scale)
        tol = 2 * eps * scale
        if width <= 2 * tol or (ga == 0 and side != 0):
            break  # narrow enough, or an evaluated point is an exact root
        c = a + width * wa / (wa - wb)
        if width > widths[-3] / 2:
            c = a + width / 2  # bisect when three steps did not halve the bracket
        elif not c > a + tol / 2:
            c = a + tol  # the estimate is at an end: a probe just inside closes the bracket
        elif not c < b - tol / 2:
            c = b - tol
        widths.append(width)
        gc = g(c)
        repeat = (gc >= 0) == (side == -1)
        if gc >= 0:
            if side == -1:  # a replaced twice in a row: scale the value kept at b
                m = 1 - gc / wa
                wb = wb * (m if m > 0 else 0.5)
            a, ga, wa = c, gc, gc
            side = -1
        else:
            if side == 1:
                m = 1 - gc / wb
                wa = wa * (m if m > 0 else 0.5)
            b, gb, wb = c, gc, gc
            side = 1
        if repeat and b - a > 2 * tol:
            # converging from one side: probe just past the new end to close the bracket
            d = a + tol if side == -1 else b - tol
            gd = g(d)
            if gd >= 0:
                a, ga, wa = d, gd, gd
            else:
                b, gb, wb = d, gd, gd
    return a, b, ga, gb
