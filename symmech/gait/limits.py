"""A gait in the limit of a parameter: the singular limits walking models are defined by.

Garcia et al.'s simplest walker is the limit of feet of vanishing mass: as ``beta -> 0`` a
row of the metric vanishes, the swing leg's equation is divided by beta, and the limit is
not the Euler-Lagrange system of any metric (the swing leg is driven by the stance leg,
not the converse).  It is still a first-order system ``q_ddot = a(q, q_dot)`` with
``a = lim g_beta^-1 f_beta`` finite, and the heel strike has a finite limit.

:func:`limit_gait` takes that limit of every mode and every transition of a gait: each
mode becomes a scene with unit metric and the limit field as its forces (so its
``acceleration`` is the limit field), its walls' gaps, the resets and the conditions
their limits.  Each limit is taken symbolically (the expression over a common
denominator, cancelled, then the parameter set to its value; ``sympy.limit`` where that
is 0/0), and refused when it is not finite or still reads the parameter.
"""

from __future__ import annotations

import sympy as sp

from symmech.declaration.wall import Wall
from symmech.errors import SceneError
from symmech.gait.modes import Gait, Reset, Transition
from symmech.scene import Scene

__all__ = ["limit_gait", "limit_of"]


def limit_of(e: sp.Expr, parameter: sp.Symbol, value: sp.Expr = sp.S.Zero) -> sp.Expr:
    """``lim_{parameter -> value} e``: ``e`` over a common denominator and cancelled, then
    the parameter substituted where the denominator does not vanish, ``sympy.limit``
    otherwise; simplified."""
    e = sp.cancel(sp.together(e))
    den = sp.fraction(e)[1]
    if den.subs(parameter, value) != 0:
        return sp.simplify(e.subs(parameter, value))
    return sp.simplify(sp.limit(e, parameter, value))


def _finite(e: sp.Expr, parameter: sp.Symbol, value: sp.Expr, what: str) -> sp.Expr:
    out = limit_of(e, parameter, value)
    if out.has(sp.oo, -sp.oo, sp.zoo, sp.nan) or out.has(sp.Limit):
        raise SceneError(f"{what}: the limit {parameter} -> {value} is not finite ({out})")
    if parameter in out.free_symbols:
        raise SceneError(f"{what}: the limit {parameter} -> {value} still reads {parameter}")
    return out


def _limit_mode(name: str, mode: str, scene: Scene, parameter: sp.Symbol, value: sp.Expr) -> Scene:
    """The mode with unit metric whose forces are the limit of its acceleration."""
    where = f"gait {name!r}, mode {mode!r}"
    if scene.is_constrained:
        raise SceneError(
            f"{where}: has permanent constraints; the limit is taken of unconstrained modes"
            " (pin the constraint by an embedding first: symmech.gait.pinned_scene)"
        )
    acc = [
        _finite(a, parameter, value, f"{where}, acceleration[{i}]")
        for i, a in enumerate(scene.acceleration())
    ]
    walls = [
        Wall(
            _finite(w.psi, parameter, value, f"{where}, wall {w.name!r}"),
            restitution=w.restitution,
            name=w.name,
        )
        for w in scene.walls
    ]
    return Scene(
        list(scene.coordinates),
        metric=sp.eye(scene.n),
        forces=acc,
        walls=walls,
        name=name if mode == "" else f"{name}_{mode}",
    )


def _limit_transition(
    name: str, tr: Transition, parameter: sp.Symbol, value: sp.Expr
) -> Transition:
    where = f"gait {name!r}, transition {tr.label!r}"

    def column(m: sp.ImmutableMatrix, part: str) -> sp.ImmutableMatrix:
        return sp.ImmutableMatrix(
            [_finite(e, parameter, value, f"{where}, {part}[{i}]") for i, e in enumerate(m)]
        )

    reset = Reset(
        column(tr.reset.position, "position"),
        column(tr.reset.velocity, "velocity"),
        impact=f"{tr.reset.impact} ({parameter} -> {value})" if tr.reset.impact else "",
        dissipative=tr.reset.dissipative,
    )
    condition = (
        None
        if tr.condition is None
        else _finite(tr.condition, parameter, value, f"{where}, condition")
    )
    return Transition(tr.source, tr.target, tr.guard, reset, condition, name=tr.name)


def limit_gait(
    gait: Gait, parameter: str | sp.Symbol, value: float | sp.Expr = 0, name: str | None = None
) -> Gait:
    """``gait`` in the limit ``parameter -> value`` (module docstring), named ``name``
    (default: the gait's name with ``_limit``).  The impact parts' energy checks are
    those of the finite gait (``Reset.dissipative`` carried over)."""
    key = parameter if isinstance(parameter, str) else parameter.name
    symbol = next((p for p in gait.parameters if p.name == key), None)
    if symbol is None:
        raise SceneError(
            f"gait {gait.name!r}: {key!r} is not one of its parameters"
            f" {[p.name for p in gait.parameters]}"
        )
    target = sp.nsimplify(value) if not isinstance(value, sp.Basic) else value
    if not (target.is_real and target.is_finite):
        raise SceneError(f"gait {gait.name!r}: the limit {key} -> {value!r} must be a real number")
    new_name = name or f"{gait.name}_limit"
    single = len(gait.modes) == 1
    modes = {
        mode: _limit_mode(new_name, "" if single else mode, scene, symbol, target)
        for mode, scene in gait.modes.items()
    }
    transitions = tuple(_limit_transition(new_name, tr, symbol, target) for tr in gait.transitions)
    return Gait(new_name, modes, transitions)
