"""How a scene is drawn: planar shapes whose positions are expressions in q, t and the
parameters.

A :class:`Drawing` is a list of shapes in the plane of the picture, each placed by sympy
expressions that :func:`symmech.simulate.animation.animate` evaluates at every frame:

* :class:`Point` ``at = (x, y)``: a dot (a particle, a joint);
* :class:`Segment` ``start``, ``end``: a rod, a pendulum's string;
* :class:`Disc` ``center``, ``radius`` and optionally ``angle``: a disc, with a radius
  drawn at ``angle`` (measured from the x axis) so that its rotation shows;
* :class:`Ellipse` ``center``, semi-axes ``a`` along the body axis and ``b``, ``angle`` of
  the body axis: the ellipse of text 001 section 3.1 (the body whose gap
  :func:`symmech.shapes.ellipse_gap` gives);
* a wall, :class:`symmech.shapes.Plane` (the plane ``n . (X - p) = 0``, drawn as a line
  with its blocked side hatched; :meth:`~symmech.shapes.Plane.axis` for the floor).

A scene declares its drawing with ``Scene(..., drawing=Drawing(...))`` or, in a scene file,
with ``[[drawing]]`` tables (:mod:`symmech.scenefile`).  The scene checks that every symbol
of the drawing is a coordinate, a parameter or t (:func:`check_drawing`); values are sympy
expressions or numbers, never text (:func:`symmech.parse_expression` reads text safely).

>>> import symmech as sm
>>> x, y, th = sm.coordinates("x y theta")
>>> Drawing([Ellipse((x, y), 1, 0.5, th), sm.shapes.Plane.axis("y")]).symbols() == {x, y, th}
True
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import sympy as sp
from sympy.core.function import AppliedUndef

from symmech.algebra.walk import atoms, free_symbols
from symmech.declaration.shapes import Plane
from symmech.errors import SceneError

__all__ = ["SHAPES", "Disc", "Drawing", "Ellipse", "Point", "Segment", "check_drawing"]


def _value(value: object, what: str) -> sp.Expr:
    try:
        e = sp.sympify(value, strict=True)
    except (sp.SympifyError, TypeError):
        raise SceneError(
            f"{what}: expected a number or a sympy expression, got {value!r}"
            " (for text, use symmech.parse_expression)"
        ) from None
    if not isinstance(e, sp.Expr):
        raise SceneError(f"{what}: expected a scalar expression, got {e!r}")
    return e


def _pair(value: object, what: str) -> tuple[sp.Expr, sp.Expr]:
    if isinstance(value, str) or not isinstance(value, Sequence | sp.MatrixBase):
        raise SceneError(f"{what}: expected a point (x, y), got {value!r}")
    items = list(value)
    if len(items) != 2:
        raise SceneError(f"{what}: expected 2 components (x, y), got {len(items)}")
    return _value(items[0], f"{what}[0]"), _value(items[1], f"{what}[1]")


@dataclass(frozen=True, init=False)
class Point:
    """A dot at ``at = (x, y)``."""

    at: tuple[sp.Expr, sp.Expr]

    def __init__(self, at: Sequence):
        object.__setattr__(self, "at", _pair(at, "point.at"))

    def expressions(self) -> tuple[sp.Expr, ...]:
        return self.at


@dataclass(frozen=True, init=False)
class Segment:
    """A segment from ``start`` to ``end``."""

    start: tuple[sp.Expr, sp.Expr]
    end: tuple[sp.Expr, sp.Expr]

    def __init__(self, start: Sequence, end: Sequence):
        object.__setattr__(self, "start", _pair(start, "segment.start"))
        object.__setattr__(self, "end", _pair(end, "segment.end"))

    def expressions(self) -> tuple[sp.Expr, ...]:
        return (*self.start, *self.end)


@dataclass(frozen=True, init=False)
class Disc:
    """A disc of ``radius`` about ``center``; with ``angle``, a radius drawn at that angle."""

    center: tuple[sp.Expr, sp.Expr]
    radius: sp.Expr
    angle: sp.Expr | None

    def __init__(self, center: Sequence, radius: object, angle: object = None):
        object.__setattr__(self, "center", _pair(center, "disc.center"))
        object.__setattr__(self, "radius", _value(radius, "disc.radius"))
        a = None if angle is None else _value(angle, "disc.angle")
        object.__setattr__(self, "angle", a)

    def expressions(self) -> tuple[sp.Expr, ...]:
        return (*self.center, self.radius, *(() if self.angle is None else (self.angle,)))


@dataclass(frozen=True, init=False)
class Ellipse:
    """An ellipse about ``center`` with semi-axis ``a`` along the body axis at ``angle``
    from the x axis and ``b`` across it."""

    center: tuple[sp.Expr, sp.Expr]
    a: sp.Expr
    b: sp.Expr
    angle: sp.Expr

    def __init__(self, center: Sequence, a: object, b: object, angle: object = 0):
        object.__setattr__(self, "center", _pair(center, "ellipse.center"))
        object.__setattr__(self, "a", _value(a, "ellipse.a"))
        object.__setattr__(self, "b", _value(b, "ellipse.b"))
        object.__setattr__(self, "angle", _value(angle, "ellipse.angle"))

    def expressions(self) -> tuple[sp.Expr, ...]:
        return (*self.center, self.a, self.b, self.angle)


#: The shapes a drawing may hold, by the name scene files give them.
SHAPES: dict[str, type] = {
    "point": Point,
    "segment": Segment,
    "disc": Disc,
    "ellipse": Ellipse,
    "wall": Plane,
}

Shape = Point | Segment | Disc | Ellipse | Plane


def _expressions(shape: Shape) -> tuple[sp.Expr, ...]:
    if isinstance(shape, Plane):
        return (*shape.point, *shape.normal)
    return shape.expressions()


@dataclass(frozen=True, init=False)
class Drawing:
    """The shapes that draw a scene, in drawing order (module docstring)."""

    shapes: tuple[Shape, ...]

    def __init__(self, shapes: Sequence[Any]):
        if isinstance(shapes, str) or not isinstance(shapes, Sequence):
            raise SceneError(f"drawing: expected a list of shapes, got {shapes!r}")
        out = []
        for k, s in enumerate(shapes):
            if not isinstance(s, Point | Segment | Disc | Ellipse | Plane):
                kinds = "Point, Segment, Disc, Ellipse or symmech.shapes.Plane"
                raise SceneError(f"drawing[{k}]: expected a {kinds}, got {type(s).__name__}")
            if isinstance(s, Plane) and s.dim != 2:
                raise SceneError(f"drawing[{k}]: a wall of a drawing is a line of the plane")
            out.append(s)
        object.__setattr__(self, "shapes", tuple(out))

    def __iter__(self) -> Iterator[Shape]:
        return iter(self.shapes)

    def __len__(self) -> int:
        return len(self.shapes)

    def expressions(self) -> list[sp.Expr]:
        """Every expression of every shape, in order."""
        return [e for s in self.shapes for e in _expressions(s)]

    def symbols(self) -> set[sp.Symbol]:
        """The free symbols of the drawing."""
        return set().union(*(e.free_symbols for e in self.expressions()))


#: what makes a drawing's expression other than a real function of q, t and the parameters
_NOT_REAL = (sp.Derivative, sp.core.numbers.ImaginaryUnit, AppliedUndef)


def check_drawing(
    drawing: object, allowed: Sequence[sp.Symbol], problems: list[str]
) -> Drawing | None:
    """``drawing`` as a :class:`Drawing` (None stays None), adding to ``problems`` a line
    per shape that uses a symbol outside ``allowed`` (the coordinates, parameters and t) or
    an expression that is not real-valued text-free sympy."""
    if drawing is None:
        return None
    if not isinstance(drawing, Drawing):
        try:
            drawing = Drawing(drawing)  # type: ignore[arg-type]
        except SceneError as exc:
            problems.append(str(exc))
            return None
    names = set(allowed)
    memo: dict[sp.Basic, frozenset] = {}  # the shapes share subexpressions: walked once
    for k, s in enumerate(drawing.shapes):
        for e in _expressions(s):
            stray = sorted(map(str, free_symbols(e, memo) - names))
            if stray:
                problems.append(
                    f"drawing[{k}] ({type(s).__name__.lower()}): {', '.join(stray)} is not a"
                    " coordinate, a parameter or t of the scene"
                )
                break
            if atoms(e, _NOT_REAL):
                problems.append(
                    f"drawing[{k}] ({type(s).__name__.lower()}): {e} is not a real function"
                    " of q, t and the parameters"
                )
                break
    return drawing
