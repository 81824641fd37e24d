"""Declaration of a wall: a one-sided holonomic constraint psi(t, q) >= 0.

A wall is declared with its gap function ``psi`` (admissible side ``psi >= 0``), the
restitution coefficient alpha in [0, 1] (Carnot paper, eq. 8-9: the normal component of the
velocity is reversed and scaled by alpha), constraints imposed at the instant of impact and
kept afterwards (Carnot paper, section 3.2, "instantaneous non-holonomic constraints"), and
the impact law.  How ``psi`` depends on the coordinates is checked when the wall is put into
a :class:`~symmech.Scene`, which knows the coordinates.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import sympy as sp

from symmech.declaration.admissible import NON_SMOOTH, expression_problems
from symmech.declaration.expressions import to_expression
from symmech.errors import SceneError

__all__ = ["LAWS", "Wall"]

#: Impact laws: "newton" is the restitution law of the Carnot paper (eq. 10, Prop. 3.4,
#: eq. 17); "energy" is the energy-conserving frictional rebound of the hybrid Lagrangian
#: text (001), section 3.2.
LAWS = ("newton", "energy")


def _restitution(value: object, name: str) -> sp.Expr:
    label = f"wall {name!r}: restitution" if name else "wall: restitution"
    if isinstance(value, bool) or value is None:
        raise SceneError(f"{label} must be a number in [0, 1] or a symbol, got {value!r}")
    if isinstance(value, str):
        raise SceneError(
            f"{label} must be a number in [0, 1] or a sympy symbol, got the string {value!r}"
        )
    try:
        alpha = sp.sympify(value, strict=True)
    except (sp.SympifyError, TypeError) as exc:
        raise SceneError(f"{label} must be a number in [0, 1] or a symbol, got {value!r}") from exc
    if alpha.is_number:
        if not alpha.is_real:
            raise SceneError(f"{label} = {alpha} is not real; it must lie in [0, 1]")
        if alpha < 0 or alpha > 1:
            raise SceneError(f"{label} = {alpha} is outside [0, 1]")
        return sp.nsimplify(alpha) if isinstance(alpha, sp.Float) else alpha
    if alpha.is_negative or (alpha - 1).is_positive:
        raise SceneError(f"{label} = {alpha} is known (from its assumptions) to lie outside [0, 1]")
    if not isinstance(alpha, sp.Symbol):
        raise SceneError(f"{label} must be a number in [0, 1] or a single symbol, got {alpha}")
    return alpha


@dataclass(frozen=True, init=False)
class Wall:
    """A wall psi(t, q) >= 0 with restitution alpha and constraints imposed at impact.

    Parameters
    ----------
    psi:
        Gap function, an expression in the coordinates (and ``symmech.t`` for a moving
        wall).  The admissible side is ``psi >= 0``; an impact happens when psi reaches 0
        with dpsi/dt < 0.
    restitution:
        alpha in [0, 1]: after impact ``dpsi(q_dot+) = -alpha dpsi(q_dot-)`` (relative
        velocity for moving walls).  A number or a sympy symbol.
    impulsive_constraints:
        Velocity constraints imposed at the instant of impact and kept after it (rolling on
        contact), linear in the velocities (expressions or coefficient rows).
    name:
        Optional name, used in messages and to look the wall up: ``scene.impact_map("floor")``.
    law:
        ``"newton"`` (default) or ``"energy"``; see :data:`LAWS`.
    velocity:
        Optional: the wall's velocity field W(t, q) in the velocity basis (n entries), the
        velocity a configuration riding with the wall would have.  It must move with the
        wall (``dpsi(W) + psi_t = 0``); its tangential part is what the impulsive
        constraints hold the body to, ``nu (v+ - W) = 0`` (Carnot paper eq. 20).  Default:
        the metric normal ``W = -psi_t grad psi / g(grad psi, grad psi)``, which has no
        tangential part in the metric; that is the floor's own velocity only when the
        metric does not couple the normal direction with the tangential ones (see the
        README's worked example: a disc with an off-centre mass on a vertically moving
        floor).

    >>> import sympy as sp, symmech as sm
    >>> x, y = sm.coordinates("x y")
    >>> Wall(y, restitution=sp.Rational(1, 2), name="floor").restitution
    1/2
    """

    psi: sp.Expr
    restitution: sp.Expr
    impulsive_constraints: tuple
    name: str
    law: str
    velocity: tuple | None

    def __init__(
        self,
        psi: sp.Expr | str,
        restitution: float | sp.Expr = 1,
        impulsive_constraints: Sequence = (),
        name: str | None = None,
        law: str = "newton",
        velocity: Sequence | sp.MatrixBase | None = None,
    ):
        name = "" if name is None else str(name)
        label = f"wall {name!r}" if name else "wall"
        if law not in LAWS:
            raise SceneError(f"{label}: law must be one of {LAWS}, got {law!r}")
        if isinstance(psi, str):
            # Names are resolved when the wall joins a scene; here only the syntax and the
            # safety of the string are checked (no eval), with every name allowed.
            psi_expr: sp.Expr | str = psi
        else:
            try:
                psi_expr = to_expression(psi, None, field=f"{label}: psi")
            except ValueError as exc:
                raise SceneError(str(exc)) from exc
            found = expression_problems(psi_expr, skip=NON_SMOOTH)
            if found:
                raise SceneError([f"{label}: psi {p}" for p in found])
        if isinstance(impulsive_constraints, (str, sp.Basic)) and not isinstance(
            impulsive_constraints, sp.MatrixBase
        ):
            impulsive_constraints = [impulsive_constraints]
        if isinstance(impulsive_constraints, sp.MatrixBase):
            impulsive_constraints = [
                list(impulsive_constraints.row(i)) for i in range(impulsive_constraints.rows)
            ]
        object.__setattr__(self, "psi", psi_expr)
        object.__setattr__(self, "restitution", _restitution(restitution, name))
        object.__setattr__(self, "impulsive_constraints", tuple(impulsive_constraints))
        object.__setattr__(self, "name", name)
        object.__setattr__(self, "law", law)
        if velocity is not None:
            if isinstance(velocity, (str, bytes, sp.Basic)) and not isinstance(
                velocity, sp.MatrixBase
            ):
                raise SceneError(
                    f"{label}: velocity must be a sequence of components (one per velocity),"
                    f" got {velocity!r}"
                )
            try:
                velocity = tuple(velocity)
            except TypeError:
                raise SceneError(
                    f"{label}: velocity must be a sequence of components, got {velocity!r}"
                ) from None
        object.__setattr__(self, "velocity", velocity)

    def __repr__(self) -> str:
        extra = (
            f", impulsive_constraints={list(self.impulsive_constraints)}"
            if self.impulsive_constraints
            else ""
        )
        nm = f", name={self.name!r}" if self.name else ""
        law = f", law={self.law!r}" if self.law != "newton" else ""
        vel = f", velocity={list(self.velocity)}" if self.velocity is not None else ""
        return f"Wall({self.psi}, restitution={self.restitution}{extra}{nm}{law}{vel})"
