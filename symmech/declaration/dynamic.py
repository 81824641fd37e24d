"""Scenes written with ``sympy.physics.mechanics.dynamicsymbols``.

A model written for ``sympy.physics.mechanics`` names its coordinates ``q(t)``, their rates
``q(t).diff(t)`` (or ``dynamicsymbols("q", 1)``), its generalized speeds ``u(t)`` and its
specified inputs ``tau(t)``, all functions of mechanics' own time symbol (a plain
``Symbol("t")``).  symmech's normal form uses real symbols: the coordinate ``q``, its velocity
``qdot``, the quasi-velocity ``u`` and :data:`symmech.t`.  :class:`DynamicTranslation` maps
one onto the other, field by field, before validation:

* ``q(t) -> q`` and ``q'(t) -> qdot`` for each coordinate given as a dynamic symbol;
* ``u(t) -> u`` for each quasi-velocity given as a dynamic symbol;
* mechanics' time ``t -> symmech.t``, so every other dynamic symbol ``tau(t)`` becomes the
  undefined real function ``tau`` of symmech's time: a run-time input of generated code
  (dynamic symbols carry no assumptions; inputs are real).

A second derivative of a coordinate, or a derivative of a quasi-velocity, has no place in a
declaration (accelerations are what symmech derives) and is refused with the field named.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import sympy as sp
from sympy.core.function import AppliedUndef

from symmech.algebra.walk import atoms as walk_atoms
from symmech.algebra.walk import xreplace
from symmech.declaration.symbols import t as TIME
from symmech.declaration.symbols import velocity_of
from symmech.declaration.wall import Wall
from symmech.errors import SceneError

__all__ = ["DynamicTranslation", "dynamic_translation"]


def _mechanics_time() -> sp.Symbol:
    """The time symbol of ``dynamicsymbols`` (imported lazily: mechanics is heavy)."""
    from sympy.physics.vector import dynamicsymbols

    return dynamicsymbols._t


def _is_dynamic(x: object, time: sp.Symbol) -> bool:
    return isinstance(x, AppliedUndef) and x.args == (time,)


class DynamicTranslation:
    """The substitution from dynamic symbols to symmech's symbols (module docstring)."""

    def __init__(
        self,
        coordinates: Sequence[sp.Basic],
        quasi_velocities: Sequence[sp.Basic] | None,
        time: sp.Symbol,
    ):
        self.time = time
        self.coordinates = tuple(
            sp.Symbol(str(c.func), real=True) if _is_dynamic(c, time) else c for c in coordinates
        )
        self.quasi_velocities = (
            None
            if quasi_velocities is None
            else tuple(
                sp.Symbol(str(u.func), real=True) if _is_dynamic(u, time) else u
                for u in quasi_velocities
            )
        )
        self._rates: dict[sp.Basic, sp.Basic] = {}
        self._plain: dict[sp.Basic, sp.Basic] = {}
        self._forbidden: dict[sp.Basic, str] = {}
        for given, c in zip(coordinates, self.coordinates, strict=True):
            if _is_dynamic(given, time):
                self._rates[given.diff(time)] = velocity_of(c)
                self._plain[given] = c
                self._forbidden[given.diff(time, 2)] = f"the acceleration of coordinate {c}"
        for given, u in zip(quasi_velocities or (), self.quasi_velocities or (), strict=True):
            if _is_dynamic(given, time):
                self._plain[given] = u
                self._forbidden[given.diff(time)] = f"the rate of quasi-velocity {u}"

    def expr(self, value: object, field: str) -> object:
        """``value`` with the dynamic symbols replaced (strings and numbers unchanged)."""
        if isinstance(value, sp.MatrixBase):
            return value.applyfunc(lambda e: self.expr(e, field))
        if isinstance(value, list | tuple):
            return type(value)(self.expr(e, field) for e in value)
        if not isinstance(value, sp.Basic):
            return value
        # one walk for the atoms, one substitution: xreplace matches the largest
        # sub-expression first, so q'(t) -> qdot wins over q(t) -> q inside it, and an
        # input tau(t) is replaced whole before t -> symmech.t is reached
        atoms = walk_atoms(value, (sp.Derivative, AppliedUndef))
        bad = [d for d in atoms if d in self._forbidden]
        if bad:
            raise SceneError(
                f"{field}: contains {self._forbidden[bad[0]]} ({bad[0]}); a declaration gives"
                " positions and velocities only"
            )
        inputs = {
            a: sp.Function(str(a.func), real=True)(TIME)
            for a in atoms
            if a not in self._plain and _is_dynamic(a, self.time) and a.is_real is None
        }
        return xreplace(value, {**self._rates, **self._plain, **inputs, self.time: TIME})

    def wall(self, w: object, field: str) -> object:
        if not isinstance(w, Wall):
            return w
        return Wall(
            self.expr(w.psi, f"{field}.psi"),
            restitution=w.restitution,
            impulsive_constraints=tuple(
                self.expr(c, f"{field}.impulsive_constraints") for c in w.impulsive_constraints
            ),
            name=w.name or None,
            law=w.law,
            velocity=None
            if w.velocity is None
            else tuple(self.expr(c, f"{field}.velocity") for c in w.velocity),
        )


def _has_dynamic(values: Iterable[object], time: sp.Symbol) -> bool:
    stack = list(values)
    while stack:
        value = stack.pop()
        if isinstance(value, Wall):
            stack.extend((value.psi, *value.impulsive_constraints, *(value.velocity or ())))
        elif isinstance(value, sp.MatrixBase):
            stack.extend(value)
        elif isinstance(value, list | tuple):
            stack.extend(value)
        elif isinstance(value, sp.Basic):
            if any(_is_dynamic(a, time) for a in walk_atoms(value, (AppliedUndef,))):
                return True
    return False


def dynamic_translation(
    coordinates: object, quasi_velocities: object, fields: Iterable[object]
) -> DynamicTranslation | None:
    """The translation for a declaration written with dynamic symbols, or None when
    nothing in it is one (coordinates, quasi-velocities and the ``fields`` are looked at)."""
    if isinstance(coordinates, sp.Basic):
        coordinates = (coordinates,)
    if isinstance(quasi_velocities, sp.Basic):
        quasi_velocities = (quasi_velocities,)
    try:
        q: tuple = tuple(coordinates)  # type: ignore[arg-type]
        u: tuple | None = (
            None if quasi_velocities is None else tuple(quasi_velocities)  # type: ignore[arg-type]
        )
    except TypeError:
        return None  # reported by the structural checks
    time = _mechanics_time()
    if time == TIME:
        return None
    dynamic = any(_is_dynamic(c, time) for c in (*q, *(u or ())))
    if not dynamic and not _has_dynamic(fields, time):
        return None
    return DynamicTranslation(q, u, time)
