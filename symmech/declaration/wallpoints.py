"""Points of a wall psi(t, q) = 0, and walls whose gradient vanishes on them.

A wall is regular where ``d psi != 0`` on ``psi = 0`` (Carnot paper 002, section 3.1:
the impact map divides by ``g(grad psi, grad psi)``).  ``psi = x**2``, ``x**3``,
``sin(x)**2``, ``1 - cos(x)``, ``exp(x**2) - 1`` or ``(x - 1)**2*(y + 2)`` vanish to second
order on (part of) their zero set, so ``d psi = 0`` wherever an impact on that part would
happen: they are not walls, and :func:`vanishing_gradient` finds such a point.

Points of the wall are found by solving ``psi = 0`` for one coordinate, the others (and
the parameters, t and the values of undefined functions) fixed at a sampled point
(:func:`points_on_wall`): first by the secant method (:func:`mpmath.findroot`), then, for
the multiple roots where it converges too slowly, by Newton's method on ``psi/psi'``
(Schroeder's modification: quadratic convergence at a root of any multiplicity).

At a point p found, the gradient vanishes when it is negligible against psi itself one
step away: ``max_j |d psi/d q_j| h <= GRADIENT_RATIO * max_j |psi(p +- h e_j)|``, with
``h = 10^-6`` (times ``max(1, |q_j|)``).  At a simple root the two sides are equal to first
order; at a root of multiplicity k >= 2 the left side is of the order of the root's error
(10^-20 in 40-digit arithmetic) times h and the right one of h^k.  The test is free of the
units of psi and of the scale of the coordinates near 1.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import mpmath as mp
import sympy as sp

from symmech.algebra.numeric import EvaluationError, evaluate_matrix_mp, proven_sign

__all__ = ["GRADIENT_RATIO", "points_on_wall", "vanishing_gradient"]

#: Gradient-to-variation ratio below which the gradient of psi counts as zero (see the
#: module docstring).
GRADIENT_RATIO = 1e-6
_STEP = mp.mpf(10) ** -6
_STARTS = (0, 1, -1, 2, -2)
# Newton on psi/psi' converges quadratically at roots of any multiplicity: a start that has
# not converged after this many steps is abandoned.
_NEWTON_STEPS = 30


def _secant_root(fn: Callable, starts: Sequence, dps: int) -> sp.Float | None:
    with mp.workdps(dps + 10):
        for x0 in starts:
            try:
                x = mp.findroot(fn, mp.mpf(sp.N(x0, dps + 10)))
                value = fn(x)
            except (ValueError, ZeroDivisionError, TypeError, OverflowError):
                continue
            if mp.im(x) == 0 and abs(value) < mp.mpf(10) ** (5 - dps):
                return sp.Float(mp.re(x), dps)
    return None


def _values(exprs: sp.Matrix, point: Mapping, dps: int) -> list[mp.mpf] | None:
    try:
        row = evaluate_matrix_mp(exprs, point, digits=dps)[0]
    except EvaluationError:
        return None
    if any(abs(v.imag) > mp.mpf(10) ** (5 - dps) * max(abs(v), 1) for v in row):
        return None
    return [v.real for v in row]


def _multiple_root(f: sp.Expr, qj: sp.Symbol, starts: Sequence, dps: int) -> sp.Float | None:
    """A root of ``f`` (a function of ``qj`` alone) of any multiplicity, by Newton's method
    on ``f/f'``: ``s <- s - f f' / (f'^2 - f f'')``; a start whose ``|f|`` stops decreasing
    (it converges to a critical point, not a root) is abandoned."""
    fn = sp.lambdify(qj, [f, sp.diff(f, qj), sp.diff(f, qj, 2)], "mpmath")
    with mp.workdps(dps + 10):
        for x0 in starts:
            s = mp.mpf(sp.N(x0, dps + 10))
            best, stalled = mp.inf, 0
            for _ in range(_NEWTON_STEPS):
                try:
                    f0, f1, f2 = (mp.mpf(v) for v in fn(s))
                    step = f0 * f1 / (f1 * f1 - f0 * f2)
                except (ValueError, ZeroDivisionError, TypeError, OverflowError):
                    break
                if abs(f0) < best:
                    best, stalled = abs(f0), 0
                else:
                    stalled += 1
                if f0 == 0 or stalled >= 3:
                    break
                s -= step
                if abs(step) <= mp.mpf(10) ** (5 - dps) * max(1, abs(s)):
                    break
            if _is_root(f, qj, s, dps):
                return sp.Float(s, dps)
    return None


def _is_root(f: sp.Expr, qj: sp.Symbol, s: mp.mpf, dps: int) -> bool:
    """|f(s)| negligible against f one step away on both sides (a root, not a positive
    minimum, nor a steep slope)."""
    h = _STEP * max(1, abs(s))
    values = [
        _values(sp.Matrix([[f]]), {qj: sp.Float(s + d, dps + 10)}, dps + 10) for d in (0, h, -h)
    ]
    if any(v is None for v in values):
        return False
    f0, fp, fm = (v[0] for v in values if v is not None)
    return abs(f0) <= mp.mpf(10) ** -12 * min(abs(fp), abs(fm))


def _solve(
    f: sp.Expr, qj: sp.Symbol, point: Mapping, dps: int, multiple: bool = True
) -> sp.Float | None:
    fixed = {k: v for k, v in point.items() if k != qj}
    f_expr = f.xreplace(fixed)
    if f_expr.free_symbols - {qj} or f_expr.atoms(sp.core.function.AppliedUndef):
        return None  # something without a value: psi cannot be solved here
    starts = (point[qj], *_STARTS)
    root = _secant_root(sp.lambdify(qj, f_expr, "mpmath"), starts, dps)
    if root is None and multiple:
        root = _multiple_root(f_expr, qj, starts[:2], dps)
    return root


def points_on_wall(
    psi: sp.Expr, coordinates: Sequence[sp.Symbol], points: Sequence[dict], dps: int = 40
) -> list[dict]:
    """Points of the wall ``psi = 0`` near the sampled ``points``: for each, ``psi`` is
    solved (``dps`` digits, secant method: the simple roots of a regular wall) for the
    first coordinate it depends on that gives a real root, starting from the sampled value
    and a few others; the other values are kept.  A point where no root is found is left
    out (a wall that is never reached gives none)."""
    deps = [qj for qj in coordinates if sp.diff(psi, qj) != 0]
    out = []
    for point in points:
        for qj in deps:
            root = _solve(psi, qj, point, dps, multiple=False)
            if root is not None:
                out.append({**point, qj: root})
                break
    return out


def vanishing_gradient(
    psi: sp.Expr, coordinates: Sequence[sp.Symbol], points: Sequence[dict], dps: int = 40
) -> tuple[dict | None, int]:
    """``(p, found)``: a point p of the wall ``psi = 0`` where ``d psi = 0`` (see the module
    docstring), or None; ``found`` counts the points of the wall examined (one per sampled
    point, psi solved for the coordinates it depends on in turn: sampled point k starts
    with the k-th, so that every coordinate direction is tried), and is -1 when no point
    is needed: a partial derivative that is a nonzero number, or of a proven sign, and free
    of the coordinates (``psi = y - f(x)``) makes d psi != 0 everywhere."""
    partials = {qj: sp.diff(psi, qj) for qj in coordinates}
    deps = [qj for qj in coordinates if partials[qj] != 0]
    if not deps:
        return None, 0
    q = set(coordinates)
    for qj in deps:
        d = partials[qj]
        if not (d.free_symbols & q) and (
            d.is_Number or proven_sign(d) == "pos" or proven_sign(-d) == "pos"
        ):
            return None, -1  # d psi/d qj never vanishes: regular everywhere
    gradient = sp.Matrix([[partials[qj] for qj in deps]])
    found = 0
    for k, point in enumerate(points):
        # one point of the wall per sampled point, solved for the coordinates in turn
        for qj in deps[k % len(deps) :] + deps[: k % len(deps)]:
            root = _solve(psi, qj, point, dps)
            if root is None:
                continue
            p = {**point, qj: root}
            verdict = _gradient_vanishes(psi, gradient, deps, p, dps)
            if verdict is None:
                continue
            found += 1
            if verdict:
                return p, found
            break
    return None, found


def _gradient_vanishes(
    psi: sp.Expr, gradient: sp.Matrix, deps: Sequence[sp.Symbol], p: dict, dps: int
) -> bool | None:
    with mp.workdps(dps + 10):
        grad = _values(gradient, p, dps + 10)
        if grad is None:
            return None
        variation = mp.mpf(0)
        size = mp.mpf(0)
        for qj, gj in zip(deps, grad, strict=True):
            h = _STEP * max(1, abs(mp.mpf(sp.N(p[qj], dps + 10))))
            size = max(size, abs(gj) * h)
            for d in (h, -h):
                moved = {**p, qj: sp.Float(mp.mpf(sp.N(p[qj], dps + 10)) + d, dps + 10)}
                value = _values(sp.Matrix([[psi]]), moved, dps + 10)
                if value is None:
                    return None
                variation = max(variation, abs(value[0]))
        if variation == 0:
            return None
        return bool(size <= GRADIENT_RATIO * variation)
