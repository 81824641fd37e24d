"""The energy law: frictional (rolling) impact with energy conservation (text 001, §3.2).

Text 001 treats a spinning disk hitting a rough wall: the tangential velocity is
projected g-orthogonally onto the rolling-constraint distribution, and the normal speed
is then fixed by energy conservation, with the sign that makes the disk leave the wall.
In the language of the Carnot paper (002) this reads, for a pre-impact velocity v- and
``x = v- - W`` (W as in :mod:`symmech.impacts.newton`; W = 0 for static walls):

* tangential part ``u = PP x``: the g-orthogonal projection onto
  ``D cap ker dpsi cap F`` (on D); this is text 001's projection onto the rolling
  constraint (for the disk, ``PP (x0, y0, th0) = alpha_001 (0, -R, 1)`` with
  ``alpha_001 = (I th0 - m R y0)/I1``);
* normal direction ``N = sum_A C_A0 P(Y^A)``, spanning Im T~ (Prop. 3.4); it satisfies
  ``dpsi(N) = 1``, ``nu^A(N) = 0`` and ``g(u, N) = 0`` (Lemma 3.5);
* ``v+ = W + u + s N`` with the normal speed
  ``s = alpha sqrt(g(QQ x, QQ x) / g(N, N))`` (``g(N, N) = C_00``).

So ``T(v+ - W) - T(u) = alpha^2 (T(v- - W) - T(u))``: the kinetic energy (relative to the
wall) of the part of the motion the impact acts on is scaled by alpha^2 ("energetic"
restitution).  ``alpha = 1`` is text 001's energy-conserving rebound, ``alpha = 0`` its
perfectly inelastic impact (``v+ = u``).  The sign of s is positive, i.e. after impact
``dpsi(v+ - V) = s >= 0``: the body separates from the wall (admissible side psi >= 0).
Text 001 takes the negative root for ``x_dot`` because its disk lies on the side
``x <= 0`` (``psi = -x`` here), where separating means ``x_dot+ < 0``.

The map is not linear in v- (square root), so it has no ``matrix``/``offset``.

Stable form of the square root (see :mod:`symmech.algebra.stability`).  With
``b = beta x`` and ``g(QQ x, QQ x) = b^T K b``, order the indices as (1, ..., l, 0) and
factor ``C = L D L^T`` (L unit lower triangular).  Then ``y = L^{-1} b`` gives
``b^T K b = sum_i y_i^2 / D_i`` and ``C_00 = 1/D_0`` (the last pivot is the Schur
complement), so ``s^2/alpha^2 = y_0^2 + sum_A (D_0/D_A) y_A^2`` - a sum of squares with
positive weights.  For the disk this is text 001's ``x0^2 + (I R^2/I1) th0^2`` when
``y0 = 0``, in the stable form.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import sympy as sp

from symmech.algebra.simplification import Level, tidy_matrix
from symmech.algebra.stability import stable_coefficient
from symmech.impacts.impact_projectors import ImpactProjectors

__all__ = ["EnergyLaw", "energy_law"]


@dataclass(frozen=True)
class EnergyLaw:
    """Pieces of the energy-law map ``v+ = W + u + s N`` (see the module docstring).

    ``tangential`` is u (n x 1), ``direction`` N (n x 1), ``normal_speed`` s,
    ``speed_squared`` ``(s/alpha)^2`` as a weighted sum of squares, ``squares`` the
    pairs (weight, linear form) of that sum, and ``post_velocity`` v+.
    """

    tangential: sp.ImmutableMatrix
    direction: sp.ImmutableMatrix
    normal_speed: sp.Expr
    speed_squared: sp.Expr
    squares: tuple[tuple[sp.Expr, sp.Expr], ...]
    post_velocity: sp.ImmutableMatrix


def energy_law(
    proj: ImpactProjectors,
    alpha: sp.Expr,
    velocities: Sequence[sp.Symbol],
    W: sp.MatrixBase,
    level: Level = "light",
    stable: bool = True,
    state: Sequence[sp.Symbol] = (),
) -> EnergyLaw:
    """Energy-law post-impact velocity ``v+ = W + PP x + alpha sqrt(...) N``, ``x = v- - W``.

    Text 001, section 3.2 (generalised with W for moving walls and alpha for an energetic
    restitution; see the module docstring).  With ``stable=True`` every coefficient goes
    through :func:`symmech.algebra.stability.stable_coefficient` (``state``: the
    coordinates and time).
    """
    n = proj.g.rows
    v = sp.Matrix(velocities)
    W = sp.Matrix(W)
    k = proj.C.rows
    order = [*range(1, k), 0]
    Cp = sp.Matrix(proj.C).extract(order, order)
    if k == 1:
        Linv, D = sp.eye(1), Cp
    else:
        L, D = Cp.LDLdecomposition(hermitian=False)
        L, D = tidy_matrix(L, level), tidy_matrix(D, level)
        Linv = tidy_matrix(L.LUsolve(sp.eye(k)), level)
    # y = L^{-1} beta_p (v - W), written as Yrows v + ywall with separate coefficients
    Yrows = tidy_matrix(Linv * sp.Matrix(proj.beta).extract(order, list(range(n))), level)
    PP = sp.Matrix(proj.PP)
    N = sp.Matrix(proj.N)
    coeff = (lambda e: stable_coefficient(e, state)) if stable else (lambda e: e)
    Yrows = Yrows.applyfunc(coeff)
    ywall = (-Yrows * W).applyfunc(coeff)
    PPs = PP.applyfunc(coeff)
    uwall = (-PP * W).applyfunc(coeff)
    Ns = N.applyfunc(coeff)

    def affine(rows: sp.Matrix, const: sp.Matrix, i: int) -> sp.Expr:
        return sp.Add(const[i], *[rows[i, j] * v[j] for j in range(n)])

    y = [affine(Yrows, ywall, i) for i in range(k)]
    d0 = D[k - 1, k - 1]
    squares: list[tuple[sp.Expr, sp.Expr]] = [(sp.S.One, y[k - 1])]
    for i in range(k - 1):
        squares.append((coeff(d0 / D[i, i]), y[i]))
    speed2 = sp.Add(*[w * f**2 for w, f in squares])
    s = sp.sympify(alpha, strict=True) * sp.sqrt(speed2)
    # u = PP (v - W) = PP v - PP W;  v+ = W + u + s N
    u = sp.Matrix([affine(PPs, uwall, i) for i in range(n)])
    post = sp.Matrix([W[i] + u[i] + Ns[i] * s for i in range(n)])
    im = sp.ImmutableMatrix
    return EnergyLaw(
        tangential=im(u),
        direction=im(Ns),
        normal_speed=s,
        speed_squared=speed2,
        squares=tuple(squares),
        post_velocity=im(post),
    )
