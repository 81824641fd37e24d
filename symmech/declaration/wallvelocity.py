"""The velocity field of a wall, W(t, q), declared with :class:`~symmech.Wall` ``velocity=``.

A wall psi(t, q) = 0 that moves has a velocity only in part determined by psi: a point of
the configuration space riding with the wall stays on psi = 0, so ``dpsi(W) + psi_t = 0``
(Carnot paper, eqs. 14-18), and the tangential part of W is free.  It matters where the
impulsive constraints hold the body to the wall, ``nu (v+ - W) = 0`` (eq. 20): a disc
rolling on a floor that moves up and down must leave the impact with no slip relative to
the floor, whose material velocity is vertical.  The default (no ``velocity=``) is the
metric normal ``W = -psi_t g^-1 dpsi^T / (dpsi g^-1 dpsi^T)``
(:func:`symmech.impacts.newton.wall_velocity`).

The components are in the velocity basis (the quasi-velocities with a frame) and may depend
on q, t and the parameters.  A static wall may have a velocity too, tangential
(``dpsi(W) = 0``): a conveyor belt.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import sympy as sp

from symmech.algebra.budget import expand_affordable
from symmech.algebra.zero import is_zero
from symmech.declaration.checks import Field, Points, Problems, short
from symmech.declaration.symbols import t as TIME
from symmech.declaration.wall import Wall

__all__ = ["check_wall_velocity", "wall_velocity_field"]


def wall_velocity_field(
    w: Wall,
    label: str,
    n: int,
    allowed: frozenset,
    expr: Callable[[object, str], sp.Expr | None],
    problems: Problems,
    key: str | None = None,
) -> Field | None:
    """The ``velocity`` of wall ``w`` as an n x 1 field, or None (absent or malformed);
    ``key`` is the wall's path in the declaration (``walls[0]``) when not ``label``."""
    if w.velocity is None:
        return None
    if len(w.velocity) != n:
        problems.add(
            f"{label}.velocity: {len(w.velocity)} components for {n} velocities (one per"
            " velocity of the basis)"
        )
        return None
    entries = [expr(c, f"{label}.velocity[{j}]") for j, c in enumerate(w.velocity)]
    if any(e is None for e in entries):
        return None
    path = None if key is None else f"{key}.velocity"
    return Field(f"{label}.velocity", sp.Matrix(n, 1, entries), allowed, key=path)


def check_wall_velocity(
    W: sp.Matrix,
    psi: sp.Expr,
    label: str,
    q: Sequence[sp.Symbol],
    frame: sp.Matrix | None,
    points: Points,
    problems: Problems,
) -> bool:
    """Whether W moves with the wall: ``dpsi(S W) + psi_t`` vanishes identically."""
    grad = sp.Matrix([[sp.diff(psi, c) for c in q]])
    row = grad * frame if frame is not None else grad
    normal = expand_affordable((row * W)[0, 0] + sp.diff(psi, TIME))
    if is_zero(normal, points.for_(normal)):
        return True
    problems.add(
        f"{label}.velocity does not move with the wall: dpsi(W) + psi_t = {short(normal)}"
        " != 0 (a point riding with the wall stays on psi = 0)"
    )
    return False
