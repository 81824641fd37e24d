"""Symbols of a scene: coordinates, their velocities, and time.

Coordinates are real sympy ``Symbol`` s.  The velocity of a coordinate ``x`` is the real
symbol named ``xdot``; sympy's LaTeX printer renders that name as ``\\dot{x}`` (and
``thetadot`` as ``\\dot{\\theta}``), so derived equations print as in the texts.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import sympy as sp

from symmech.errors import SceneError

__all__ = ["coordinates", "t", "velocities", "velocity_of"]

#: The time symbol.  Moving walls psi(t, q) and time-dependent potentials use it.
t = sp.Symbol("t", real=True)

_VELOCITY_SUFFIX = "dot"


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
    return sp.Symbol(q.name + _VELOCITY_SUFFIX, real=True)


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
