"""Symbols of a scene: coordinates, their velocities, and time.

Coordinates are real sympy ``Symbol`` s.  The velocity of a coordinate ``x`` is the real
symbol named ``xdot`` (``q1dot`` for ``q1``, ``x_1dot`` for ``x_1``): scene files, strings
and generated code use that name.  It prints in LaTeX as the dot over the coordinate's
symbol, ``\\dot{x}``, ``\\dot{\\theta}``, ``\\dot{q}_{1}``, ``\\dot{x}_{1}`` (sympy's own
printer would put the dot over the whole name, ``\\dot{q1}``, or over the subscript,
``x_{\\dot{1}}``).

The velocity symbol is a :class:`VelocitySymbol`: a sympy ``Symbol`` whose class is named
``Symbol``, whose hash, ordering and printing (other than LaTeX) are those of a ``Symbol``,
and which compares equal to ``sympy.Symbol(name, real=True)``.  For sympy it is the plain
real symbol ``xdot``; only ``sympy.latex`` sees the difference.  (A plain
``Symbol("xdot", real=True)`` written by a user is the same symbol and works everywhere; it
prints in LaTeX as sympy prints it.)
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import sympy as sp
from sympy.printing.conventions import split_super_sub

from symmech.errors import SceneError

__all__ = ["VelocitySymbol", "coordinates", "t", "velocities", "velocity_of"]

#: The time symbol.  Moving walls psi(t, q) and time-dependent potentials use it.
t = sp.Symbol("t", real=True)

_VELOCITY_SUFFIX = "dot"


class VelocitySymbol(sp.Symbol):
    """The velocity ``<q>dot`` of a coordinate ``q``: a real sympy Symbol printed ``\\dot{q}``.

    Equal to (and hashed as) ``sympy.Symbol("<q>dot", real=True)``; the class is named
    ``Symbol`` so that sympy orders and prints expressions exactly as with a plain symbol
    (the canonical order of the terms of a sum depends on the class name).  Only the LaTeX
    form differs: the dot goes over the coordinate's base name, before its subscripts.

    >>> q1, x1 = coordinates("q1 x_1")
    >>> [sp.latex(v) for v in velocities((q1, x1))]
    ['\\\\dot{q}_{1}', '\\\\dot{x}_{1}']
    >>> velocities((q1,))[0] == sp.Symbol("q1dot", real=True)
    True
    """

    __slots__ = ()

    def __eq__(self, other: object) -> bool:
        if self is other:
            return True
        if isinstance(other, sp.Symbol) and type(other) in (sp.Symbol, VelocitySymbol):
            return self._hashable_content() == other._hashable_content()
        return sp.Symbol.__eq__(self, other)

    def __ne__(self, other: object) -> bool:
        return not self == other

    __hash__ = sp.Symbol.__hash__  # hash((type name "Symbol",) + name and assumptions)

    @property
    def coordinate_name(self) -> str:
        """The name of the coordinate this is the velocity of."""
        return self.name[: -len(_VELOCITY_SUFFIX)]

    def _latex(self, printer: sp.printing.latex.LatexPrinter) -> str:
        names = printer._settings.get("symbol_names") or {}
        if self in names:
            return names[self]
        # ``q1`` -> base q, subscript 1: render the symbol ``qdot_1``, i.e. \dot{q}_{1}
        base, sups, subs = split_super_sub(self.coordinate_name)
        alias = base + _VELOCITY_SUFFIX + "".join(f"_{s}" for s in subs)
        alias += "".join(f"^{s}" for s in sups)
        return printer._print(sp.Symbol(alias))


# Same name as sympy's class: Basic.compare, class_key, hashing and printer dispatch use
# the class name.  (Pickling finds the class by its qualified name, VelocitySymbol.)
VelocitySymbol.__name__ = "Symbol"


def coordinates(names: str | Iterable[str]) -> tuple[sp.Symbol, ...]:
    """Return real symbols for the coordinates ``names`` (``"x y theta"`` or a list).

    >>> coordinates("x y theta")
    (x, y, theta)
    """
    if isinstance(names, str):
        names = names.replace(",", " ").split()
    names = list(names)
    if not names:
        raise SceneError("coordinates: no names given")
    syms = []
    for name in names:
        if not isinstance(name, str) or not name.isidentifier():
            raise SceneError(f"coordinates: {name!r} is not a valid symbol name")
        if name == "t":
            raise SceneError("coordinates: 't' is reserved for time (symmech.t)")
        syms.append(sp.Symbol(name, real=True))
    if len(set(syms)) != len(syms):
        raise SceneError(f"coordinates: repeated names in {names}")
    return tuple(syms)


def velocity_of(q: sp.Symbol) -> sp.Symbol:
    """The velocity symbol of coordinate ``q``: real, named ``<q>dot``, printed ``\\dot{q}``."""
    if not isinstance(q, sp.Symbol):
        raise SceneError(f"velocities: {q!r} is not a coordinate symbol")
    return VelocitySymbol(q.name + _VELOCITY_SUFFIX, real=True)


def velocities(q: Sequence[sp.Symbol]) -> tuple[sp.Symbol, ...]:
    """Return the velocity symbols matching the coordinates ``q`` (same order).

    >>> x, th = coordinates("x theta")
    >>> velocities((x, th))
    (xdot, thetadot)
    >>> import sympy
    >>> sympy.latex(velocities((th,))[0])
    '\\\\dot{\\\\theta}'
    """
    if isinstance(q, sp.Symbol):
        q = (q,)
    return tuple(velocity_of(qi) for qi in q)
