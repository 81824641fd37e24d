"""Contact geometry: gap functions psi of convex bodies against a plane wall.

A wall is a plane through ``point`` with unit ``normal`` pointing into the admissible
(free) side.  The gap of a convex body B against it is the signed distance of the body's
closest point,

    psi = min_{X in B} n . (X - p) = n . (c - p) - h_B(n),

where c is the body's centre and ``h_B(u) = max_{Y in B - c} u . Y`` its support
function (B is centrally symmetric here, so ``h_B(-n) = h_B(n)``).  ``psi >= 0`` is the
admissible side, as :class:`symmech.Wall` expects.  The plane may move: ``point`` may
depend on :data:`symmech.t`.

Ellipse.  With semi-axis a along the body axis ``e1 = (cos theta, sin theta)`` and b along
``e2 = (-sin theta, cos theta)`` (the boundary is ``c + R(theta) (a cos phi, b sin phi)``,
text 001, section 3.1), the support function is

    h(u) = sqrt(a^2 (u . e1)^2 + b^2 (u . e2)^2),

smooth and exact for every orientation (a, b > 0).  Text 001 instead finds the contact
parameter from ``dX/dphi = 0`` as ``phi_c = arctan(-(b/a) tan theta)``; the principal
branch of arctan picks the right point only for ``|theta| < pi/2`` (beyond, it returns the
farthest point instead of the closest, and the gap changes sign), and ``tan theta`` blows
up at ``theta = pi/2``.  For ``|theta| < pi/2`` the two agree, and text 001's
``Phi(theta) = dh/dtheta`` (printed in a garbled but, as the tests show, correct form)
equals ``(b^2 - a^2) sin(theta) cos(theta) / h``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import sympy as sp

from symmech.errors import SceneError

__all__ = [
    "Plane",
    "disk_gap",
    "ellipse_contact_point",
    "ellipse_gap",
    "ellipse_support",
    "sphere_gap",
]

_AXES = {"x": 0, "y": 1, "z": 2}


def _scalar(value: object, what: str) -> sp.Expr:
    """``value`` (a number or a sympy expression) as sympy, never parsed: text is refused
    (:func:`symmech.parse_expression` reads text safely)."""
    try:
        return sp.sympify(value, strict=True)
    except sp.SympifyError:
        raise SceneError(
            f"{what}: expected a number or a sympy expression, got {value!r}"
            " (for text, use symmech.parse_expression)"
        ) from None


def _vector(value: Sequence, dim: int | None, what: str) -> tuple[sp.Expr, ...]:
    try:
        vec = tuple(sp.sympify(e, strict=True) for e in value)
    except (TypeError, sp.SympifyError):
        raise SceneError(f"{what}: expected a sequence of coordinates, got {value!r}") from None
    if dim is not None and len(vec) != dim:
        raise SceneError(f"{what}: expected {dim} components, got {len(vec)}")
    if len(vec) not in (2, 3):
        raise SceneError(f"{what}: planar (2) or spatial (3) vectors only, got {len(vec)}")
    return vec


@dataclass(frozen=True, init=False)
class Plane:
    """A plane wall through ``point`` with unit ``normal`` pointing to the free side.

    >>> Plane((0, 0), (0, 1)).gap((3, 2))
    2
    """

    point: tuple[sp.Expr, ...]
    normal: tuple[sp.Expr, ...]

    def __init__(self, point: Sequence, normal: Sequence):
        p = _vector(point, None, "plane point")
        n = _vector(normal, len(p), "plane normal")
        norm2 = sp.expand(sum(e**2 for e in n))
        if norm2.is_number:
            ok = sp.nsimplify(norm2) == 1 if norm2.has(sp.Float) else norm2 == 1
        else:
            ok = sp.simplify(norm2 - 1) == 0
        if not ok:
            raise SceneError(
                f"plane normal {list(n)} is not a unit vector (|n|^2 = {norm2}); give the"
                " outward unit normal, pointing into the admissible side"
            )
        object.__setattr__(self, "point", p)
        object.__setattr__(self, "normal", n)

    @classmethod
    def axis(cls, axis: str, at: object = 0, side: int = 1, dim: int = 2) -> Plane:
        """The plane ``axis = at`` with free side ``axis >= at`` (``side=1``) or ``<=``
        (``side=-1``); ``dim`` 2 or 3.  ``Plane.axis("y")`` is the floor y = 0."""
        if axis not in _AXES or _AXES[axis] >= dim or dim not in (2, 3):
            raise SceneError(f"plane axis: expected 'x', 'y' (or 'z' with dim=3), got {axis!r}")
        if side not in (1, -1):
            raise SceneError(f"plane axis: side must be 1 or -1, got {side!r}")
        point = [sp.S.Zero] * dim
        point[_AXES[axis]] = _scalar(at, "plane axis: at")
        normal = [sp.S.Zero] * dim
        normal[_AXES[axis]] = sp.Integer(side)
        return cls(point, normal)

    @property
    def dim(self) -> int:
        return len(self.point)

    def gap(self, X: Sequence) -> sp.Expr:
        """Signed distance ``n . (X - p)`` of a point X (positive on the free side)."""
        x = _vector(X, self.dim, "point")
        return sp.Add(
            *[ni * (xi - pi) for ni, xi, pi in zip(self.normal, x, self.point, strict=True)]
        )


def _plane(plane: Plane | None, dim: int) -> Plane:
    plane = Plane.axis("y" if dim == 2 else "z", dim=dim) if plane is None else plane
    if not isinstance(plane, Plane):
        raise SceneError(f"plane: expected a symmech.shapes.Plane, got {type(plane).__name__}")
    if plane.dim != dim:
        raise SceneError(f"plane: a {dim}-dimensional body needs a {dim}-dimensional plane")
    return plane


def _positive(value: object, what: str) -> sp.Expr:
    e = _scalar(value, what)
    if e.is_number and not e.is_positive:
        raise SceneError(f"{what} must be positive, got {e}")
    if e.is_nonpositive:
        raise SceneError(f"{what} must be positive, got {e} (from its assumptions)")
    return e


def disk_gap(center: Sequence, radius: object, plane: Plane | None = None) -> sp.Expr:
    """Gap of a disk: ``psi = n . (c - p) - R`` (default plane: the floor y = 0)."""
    pl = _plane(plane, 2)
    return pl.gap(center) - _positive(radius, "disk radius")


def sphere_gap(center: Sequence, radius: object, plane: Plane | None = None) -> sp.Expr:
    """Gap of a ball in space: ``psi = n . (c - p) - r`` (default plane: z = 0)."""
    pl = _plane(plane, 3)
    return pl.gap(center) - _positive(radius, "sphere radius")


def ellipse_support(semi_axes: Sequence, angle: object, direction: Sequence) -> sp.Expr:
    """Support function ``h(u) = sqrt(a^2 (u.e1)^2 + b^2 (u.e2)^2)`` of the ellipse with
    semi-axes (a, b) rotated by ``angle``, in the direction u (not necessarily unit)."""
    a, b = (_positive(s, "ellipse semi-axis") for s in semi_axes)
    th = _scalar(angle, "ellipse angle")
    ux, uy = _vector(direction, 2, "direction")
    u1 = ux * sp.cos(th) + uy * sp.sin(th)
    u2 = -ux * sp.sin(th) + uy * sp.cos(th)
    return sp.sqrt(a**2 * u1**2 + b**2 * u2**2)


def ellipse_gap(
    center: Sequence, angle: object, semi_axes: Sequence, plane: Plane | None = None
) -> sp.Expr:
    """Gap of an ellipse: ``psi = n . (c - p) - h(n)`` with the support function h.

    ``center`` (x, y), ``angle`` theta of the semi-axis a, ``semi_axes`` (a, b).  Exact and
    smooth for every orientation (see the module docstring).  Text 001's bouncing ellipse
    (wall x = 0, ellipse on the side x <= 0) is
    ``ellipse_gap((x, y), theta, (a, b), Plane((0, 0), (-1, 0)))
    = -x - sqrt(a^2 cos^2 theta + b^2 sin^2 theta)``.
    """
    pl = _plane(plane, 2)
    return pl.gap(center) - ellipse_support(semi_axes, angle, pl.normal)


def ellipse_contact_point(
    center: Sequence, angle: object, semi_axes: Sequence, plane: Plane | None = None
) -> tuple[sp.Expr, sp.Expr]:
    """The boundary point of the ellipse closest to the plane (where the gap is attained).

    For the direction ``u = -n``, ``X = c + R diag(a^2, b^2) R^T u / h(u)`` (the gradient
    of the support function).
    """
    pl = _plane(plane, 2)
    a, b = (_positive(s, "ellipse semi-axis") for s in semi_axes)
    th = _scalar(angle, "ellipse angle")
    cx, cy = _vector(center, 2, "center")
    ux, uy = (-e for e in pl.normal)
    c, s = sp.cos(th), sp.sin(th)
    u1, u2 = ux * c + uy * s, -ux * s + uy * c
    h = sp.sqrt(a**2 * u1**2 + b**2 * u2**2)
    y1, y2 = a**2 * u1 / h, b**2 * u2 / h
    return (cx + c * y1 - s * y2, cy + s * y1 + c * y2)
