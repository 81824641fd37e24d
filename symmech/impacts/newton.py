"""Newton's restitution law: the linear impact map of the Carnot paper (002).

With the projectors of :mod:`symmech.impacts.impact_projectors` and the restitution coefficient
alpha, the post-impact velocity is affine in the pre-impact velocity,
``v+ = matrix v- + offset``, where

* static wall, no impulsive constraints: ``matrix = P~ - alpha Q~`` (eq. 10);
  without permanent constraints this is the restitution map, and for alpha = 1 the elastic
  map of text 001, Theorem 2.12: ``v - 2 dpsi(v)/g(grad psi, grad psi) grad psi``;
* instantaneous constraints nu^A: ``matrix = PP - alpha T~`` (Prop. 3.4, eq. 11), which
  reduces to eq. 10 on D when l = 0 (then ``PP = P~`` and ``T~ = Q~``);
* moving wall psi(t, q): ``v+ - W = (PP - alpha T~)(v- - W)`` (eq. 18 and eq. 23,
  Prop. 4.2), so ``offset = (QQ + alpha T~) W = PY K (c + alpha c_0 e_0)``, where
  ``c = [dpsi; nu] V`` are the wall-velocity components entering eqs. 19-20,
  ``W = PY K c`` (section 4.2) and ``c_0 = dpsi(V) = -psi_t``.

Example 4.4 of the paper (the sphere of Example 3.13 hitting the moving wall x = f(t))
prints the map as ``(separation) = (approach) M`` with row vectors; its 6 x 6 matrix M
reproduces this map, and the paper's velocities, only acting on *columns*,
``v+ - W = M (v- - W)`` (M is ``matrix`` here, entry by entry); read as printed (rows
times M) it gives a different, wrong map.  ``tests/test_impacts_examples.py::
test_example_4_4_matrix_multiplies_columns_not_rows`` checks both readings.

The wall velocity V: only its normal part is fixed by psi (a point of the wall stays on
the wall, ``dpsi(V) + psi_t = 0``).  :func:`wall_velocity` returns the default
``V = -(psi_t / g(grad psi, grad psi)) grad psi``, the g-normal velocity of the wall (it
reproduces Example 4.4, ``V = (f'(t), 0, ..., 0)``); another V may be given (its
tangential part matters through eq. 20, ``nu(v+ - V) = 0``).

Domain.  The paper derives these maps for ``v- in D``.  For ``v-`` outside D the matrix
still acts, but ``QQ`` and ``T~`` annihilate D^perp, so the component ``Q v-`` passes
through unchanged and ``v+`` is not in D: the map is meaningful on D only.  (The KKT
system of the tests' oracle, ``tests/kkt_oracle.py``, does have a solution for ``v-``
outside D, but it is a different model, with the permanent constraints also acting
impulsively.)
"""

from __future__ import annotations

import sympy as sp

from symmech.algebra.simplification import Level, tidy_matrix
from symmech.impacts.impact_projectors import ImpactProjectors

__all__ = ["newton_map", "wall_velocity", "wall_velocity_components"]


def wall_velocity(
    proj: ImpactProjectors, psi_t: sp.Expr, level: Level = "light", row: int = 0
) -> sp.Matrix:
    """Default wall velocity ``V = -(psi_t / g(grad psi, grad psi)) grad psi`` (n x 1).

    It is the velocity of the wall normal to itself (g-orthogonal to the wall), the only
    part of V that psi determines: ``dpsi(V) = -psi_t`` (Carnot paper, eq. 15).  Zero for
    a static wall.  ``row``: which wall row of ``proj.dpsi`` (several walls hit at once,
    :mod:`symmech.impacts.several`); ``grad psi`` is then the column ``Y^row``.
    """
    n = proj.g.rows
    psi_t = sp.sympify(psi_t, strict=True)
    if psi_t == 0:
        return sp.zeros(n, 1)
    Y0 = sp.Matrix(proj.Y[:, row])
    norm2 = (sp.Matrix(proj.dpsi[row, :]) * Y0)[0, 0]
    return tidy_matrix(-psi_t / norm2 * Y0, level)


def wall_velocity_components(proj: ImpactProjectors, V: sp.MatrixBase) -> sp.Matrix:
    """``c = [dpsi(V); nu^1(V); ...]``, i.e. ``c_A = g(Y^A, V)`` (Carnot paper, section 4.2)."""
    return sp.Matrix(proj.A) * sp.Matrix(V)


def newton_map(
    proj: ImpactProjectors,
    alpha: sp.Expr,
    psi_t: sp.Expr,
    V: sp.MatrixBase | None,
    level: Level = "light",
) -> tuple[sp.Matrix, sp.Matrix, sp.Matrix]:
    """Return ``(matrix, offset, W)`` with ``v+ = matrix v- + offset`` (Newton's law).

    ``matrix = PP - alpha T~`` (Prop. 3.4, eq. 11; eq. 10 when there are no impulsive
    constraints), ``W = sum_AB C_AB g(Y^A, V) P(Y^B)`` (section 4.2; eq. 17's
    ``C^{-1} dpsi(V) P(grad psi)`` when l = 0) and
    ``offset = (QQ + alpha T~) W = PY K (c + alpha c_0 e_0)`` (eq. 23 solved for v+).
    For a static wall (``psi_t = 0`` and no V given) offset and W are zero.
    """
    n = proj.g.rows
    alpha = sp.sympify(alpha, strict=True)
    matrix = tidy_matrix(sp.Matrix(proj.PP) - alpha * sp.Matrix(proj.T), level)
    psi_t = sp.sympify(psi_t, strict=True)
    if V is None and psi_t == 0:
        return matrix, sp.zeros(n, 1), sp.zeros(n, 1)
    if V is None:
        V = wall_velocity(proj, psi_t, level)
    c = wall_velocity_components(proj, V)
    PYK = sp.Matrix(proj.PY) * sp.Matrix(proj.K)
    W = tidy_matrix(PYK * c, level)
    e0 = sp.zeros(c.rows, 1)
    e0[0] = 1
    offset = tidy_matrix(PYK * (c + alpha * c[0] * e0), level)
    return matrix, offset, W
