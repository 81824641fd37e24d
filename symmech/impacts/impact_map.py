"""The impact map of a wall: :class:`ImpactMap` and :func:`derive_impact_map`.

``derive_impact_map(declaration, wall)`` turns a declared wall into the closed-form
post-impact velocity, in the scene's velocity basis (coordinate velocities, or the
quasi-velocities when the scene has a frame ``q_dot = S v``).  In a frame the wall
one-form is ``dpsi = (d psi / d q) S`` and ``g`` is the metric in the quasi-velocities.

Laws (see the modules for the equations):

* ``"newton"`` (:mod:`symmech.impacts.newton`): Carnot paper (002) eq. 10, Prop. 3.4,
  eq. 17, Prop. 4.2; linear: ``v+ = matrix v- + offset``.
* ``"energy"`` (:mod:`symmech.impacts.energy_law`): text 001, section 3.2; not linear (a
  square root), so :attr:`ImpactMap.matrix` and :attr:`ImpactMap.offset` raise
  :class:`~symmech.ImpactError`; use :attr:`ImpactMap.post_velocity` and
  :attr:`ImpactMap.energy_law`.

The pre-impact velocity symbols are the scene's velocity symbols themselves
(``declaration.velocities``): ``post_velocity`` is an expression in them, q, t and the
parameters.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Literal

import numpy as np
import sympy as sp

from symmech.algebra import budget as limits
from symmech.algebra.energy_forms import Affine, QuadraticForm
from symmech.algebra.field import common_domain
from symmech.algebra.sampling import sample_points
from symmech.algebra.simplification import Level
from symmech.algebra.stability import stable_coefficient, stable_matrix
from symmech.algebra.zero import is_zero
from symmech.declaration.expressions import to_expression
from symmech.declaration.latex import latex_text
from symmech.declaration.symbols import t as TIME
from symmech.errors import ImpactError, SymmechError
from symmech.impacts.carnot import CarnotResult, carnot_residual
from symmech.impacts.degeneracy import (
    Singularity,
    check_regular,
    impact_singularities,
    points_on_wall,
)
from symmech.impacts.energy_law import EnergyLaw, energy_law
from symmech.impacts.impact_projectors import ImpactProjectors, impact_projectors
from symmech.impacts.newton import newton_map

if TYPE_CHECKING:
    from symmech.declaration.spec import Declaration, ResolvedWall

__all__ = ["LAWS", "ImpactMap", "derive_impact_map"]

Law = Literal["newton", "energy"]
LAWS: tuple[str, ...] = ("newton", "energy")


class ImpactMap:
    """The closed-form impact map of one wall of a scene.

    Attributes
    ----------
    post_velocity:
        v+ (n x 1) in terms of the pre-impact velocity symbols ``velocities``, q, t and
        the parameters.
    matrix, offset:
        ``v+ = matrix v- + offset`` (Newton law only; ``offset`` is non-zero only for a
        moving wall).  For the energy law both raise :class:`~symmech.ImpactError`.
    projectors:
        The Carnot-paper objects P, Q, Y^A, P(Y^A), C^AB, beta^B, QQ, PP, T~, Q~, P~
        (:class:`~symmech.impacts.impact_projectors.ImpactProjectors`).
    wall_velocity, W:
        V (the wall velocity used; the default is the g-normal velocity
        ``-psi_t grad psi / g(grad psi, grad psi)``) and
        ``W = sum_AB C_AB g(Y^A, V) P(Y^B)`` (section 4.2).  Zero for static walls.
    singularities:
        :class:`~symmech.impacts.degeneracy.Singularity` items: expressions whose zeros
        make the closed form undefined (denominators: ``det C^AB``, the metric, the
        permanent Gram matrix, derivatives of psi), with a description.
    energy_law:
        For ``law="energy"``, the pieces u, N, s of ``v+ = W + u + s N``; else None.

    The Newton law does not always dissipate: with impulsive constraints and P(Y^0) not
    in F the kinetic energy can increase even for alpha in [0, 1] (Carnot paper Theorem
    3.9; an explicit example is in :meth:`energy_change`).  The energy law conserves the
    relative energy for alpha = 1 by construction.
    """

    def __init__(
        self,
        *,
        declaration: Declaration,
        wall: ResolvedWall,
        law: str,
        alpha: sp.Expr,
        psi_t: sp.Expr,
        projectors: ImpactProjectors,
        matrix: sp.Matrix,
        offset: sp.Matrix,
        wall_velocity: sp.Matrix,
        W: sp.Matrix,
        post_velocity: sp.Matrix,
        energy: EnergyLaw | None,
        singularities: list[Singularity],
        simplify: Level,
    ):
        self.declaration = declaration
        self.wall = wall
        self.law = law
        self.alpha = alpha
        self.psi = wall.psi
        self.psi_t = psi_t
        self.projectors = projectors
        self._matrix = sp.ImmutableMatrix(matrix)
        self._offset = sp.ImmutableMatrix(offset)
        self.wall_velocity = sp.ImmutableMatrix(wall_velocity)
        self.W = sp.ImmutableMatrix(W)
        self.post_velocity = sp.ImmutableMatrix(post_velocity)
        self.energy_law = energy
        self.singularities = singularities
        self.simplify = simplify
        self._carnot: dict[bool, CarnotResult] = {}

    # -- basic data -----------------------------------------------------------------------
    @property
    def velocities(self) -> tuple[sp.Symbol, ...]:
        """The pre-impact velocity symbols (the scene's velocity basis)."""
        return self.declaration.velocities

    @property
    def moving(self) -> bool:
        """True for a moving wall psi(t, q) or a given non-zero wall velocity."""
        return self.psi_t != 0 or not self.wall_velocity.is_zero_matrix

    @property
    def is_linear(self) -> bool:
        """True for the Newton law (``v+ = matrix v- + offset``)."""
        return self.law == "newton"

    @property
    def dpsi(self) -> sp.ImmutableMatrix:
        """The wall one-form in the velocity basis, ``(d psi/d q) S`` (1 x n)."""
        return self.projectors.dpsi

    def _linear_only(self, what: str) -> None:
        if not self.is_linear:
            raise ImpactError(
                f"wall {self.wall.name!r}: the energy law (text 001, section 3.2) is not"
                f" linear in the pre-impact velocity (its normal speed is a square root), so"
                f" it has no {what}; use post_velocity (and energy_law for its parts), or"
                " law='newton'"
            )

    @property
    def matrix(self) -> sp.ImmutableMatrix:
        """``PP - alpha T~`` (Prop. 3.4; eq. 10 without impulsive constraints), n x n."""
        self._linear_only("matrix")
        return self._matrix

    @property
    def offset(self) -> sp.ImmutableMatrix:
        """``(QQ + alpha T~) W`` (eq. 17 / Prop. 4.2 solved for v+), n x 1; 0 for static walls."""
        self._linear_only("offset")
        return self._offset

    def _repr_latex_(self) -> str:
        v = sp.Matrix(self.velocities)
        label = latex_text(f"wall {self.wall.name}, {self.law} law, pre-impact ")
        return (
            f"$\\dot q^+ = {sp.latex(self.post_velocity)}\\quad(\\text{{{label}}}{sp.latex(v.T)})$"
        )

    def __repr__(self) -> str:
        kind = "moving" if self.moving else "static"
        return (
            f"ImpactMap(wall={self.wall.name!r}, law={self.law!r}, {kind},"
            f" alpha={self.alpha}, impulsive constraints={self.projectors.nu.rows})"
        )

    # -- evaluation ------------------------------------------------------------------------
    def apply(self, pre_velocity: Sequence | sp.MatrixBase | Mapping) -> sp.Matrix:
        """v+ for a given pre-impact velocity (a sequence in the velocity basis or a dict)."""
        if isinstance(pre_velocity, Mapping):
            values = dict(pre_velocity)
        else:
            seq = list(pre_velocity)
            if len(seq) != len(self.velocities):
                raise ImpactError(
                    f"apply: expected {len(self.velocities)} velocity components, got {len(seq)}"
                )
            values = dict(zip(self.velocities, seq, strict=True))
        rule = {}
        for k, v in values.items():
            try:
                rule[k] = sp.sympify(v, strict=True)
            except sp.SympifyError:
                raise ImpactError(
                    f"apply: the velocity component {k} = {v!r} is not a number or a sympy"
                    " expression (for text, use symmech.parse_expression)"
                ) from None
        return sp.Matrix(self.post_velocity.xreplace(rule))

    def energy_change(self, in_D: bool = False) -> sp.Expr:
        """``T(v+) - T(v-)`` with ``T = 1/2 v^T g v`` (velocity basis).

        With ``in_D=True`` the pre-impact velocity is the general element of D,
        ``v- = P v`` (the maps are derived for v- in D).  For the Newton law each velocity
        coefficient is cancelled; for the energy law the result contains the square root.

        Sign.  Under the Newton law with alpha in [0, 1] the energy never increases for a
        static wall without impulsive constraints (Theorem 3.2) or when P(Y^0) lies in F
        (Theorem 3.11), but it CAN increase with impulsive constraints otherwise: Theorem
        3.9's term ``-alpha g(T~ v, C v)`` has no sign.  Example: g = I (5 x 5),
        ``psi = q4 - q3 + 1``, impulsive constraint ``q4dot = 0``, alpha = 1 and
        ``v- = (0, 0, 0, 1, -1)`` (approaching: ``dpsi(v-) = -2``) give
        ``v+ = (0, 0, 0, -2, 0)``, so T goes from 1 to 2 (``T1 - T0 = -q3dot q4dot``;
        ``tests/test_impacts_properties.py::test_energy_can_grow_when_P_Y0_is_not_in_F``).
        """
        g = sp.Matrix(self.projectors.g)
        n = g.rows
        v = sp.Matrix(self.velocities)
        L = sp.Matrix(self.projectors.P) if in_D else sp.eye(n)
        if self.is_linear:
            ring = common_domain([g, L, self._matrix, self._offset])
            gd = ring.matrix(g)
            pre = Affine.of(ring, L, sp.zeros(n, 1))
            post = pre.apply(ring.matrix(self._matrix)).shift(ring.matrix(self._offset))
            return (QuadraticForm.energy(gd, post) - QuadraticForm.energy(gd, pre)).expr(v)
        pre = L * v
        post = self.apply(list(pre))
        return ((post.T * g * post)[0, 0] - (pre.T * g * pre)[0, 0]) / 2

    def carnot(self, restrict: bool = False) -> CarnotResult:
        """The residual of the applicable Carnot theorem; it simplifies to 0.

        Returns a :class:`~symmech.impacts.carnot.CarnotResult` with ``.theorem`` (e.g.
        ``"Theorem 3.11"``), ``.statement``, ``.residual``, ``.terms``; ``tuple(result)`` is
        ``(theorem, residual)``.  Theorems 3.2/3.6/3.9/3.11 (static walls) and 4.1/4.3
        (moving walls), chosen as in :mod:`symmech.impacts.carnot`; the pre-impact velocity
        is the general element of D (``restrict=True``: of (Im PP + Im T~) in D).
        Newton law only: Carnot's theorem is a statement about the restitution law (for
        the energy law use :meth:`energy_change`).
        """
        if not self.is_linear:
            raise ImpactError(
                f"wall {self.wall.name!r}: Carnot's theorems (Carnot paper 002, sections 3-4)"
                " concern Newton's restitution law; this map uses the energy law (text 001),"
                " whose energy balance is by construction T(v+ - W) - T(u) ="
                " alpha^2 (T(v- - W) - T(u)); use energy_change() or law='newton'"
            )
        if restrict not in self._carnot:
            self._carnot[restrict] = carnot_residual(
                self.projectors,
                self._matrix,
                self._offset,
                self.W,
                self.alpha,
                self.velocities,
                moving=self.moving,
                restrict=restrict,
            )
        return self._carnot[restrict]


# ---------------------------------------------------------------------------------------


def _resolve(declaration: Declaration, wall: object) -> ResolvedWall:
    walls = declaration.walls
    if hasattr(wall, "impulsive_matrix") and hasattr(wall, "psi"):
        # a resolved wall: it must be one of this declaration's (a wall resolved in another
        # scene carries that scene's coordinates and velocity basis)
        for w in walls:
            if w is wall:
                return w
        raise ImpactError(
            f"impact map: the resolved wall {getattr(wall, 'name', '')!r} (psi ="
            f" {getattr(wall, 'psi', '?')}) does not belong to this scene; pass its index,"
            " its name or the Wall object of this scene"
        )
    if isinstance(wall, bool):
        raise ImpactError(f"impact map: wall must be an index, a name or a wall, got {wall!r}")
    if isinstance(wall, int):
        if not -len(walls) <= wall < len(walls):
            raise ImpactError(
                f"impact map: wall index {wall} out of range; the scene has {len(walls)} walls"
            )
        return walls[wall]
    if isinstance(wall, str):
        for w in walls:
            if w.name == wall:
                return w
        raise ImpactError(
            f"impact map: no wall named {wall!r}; walls are {[w.name for w in walls]}"
        )
    for w in walls:
        if w.wall is wall or w.wall == wall:
            return w
    raise ImpactError(f"impact map: {wall!r} is not a wall of this scene")


def _with_undefined(points: Sequence[dict], psi: sp.Expr) -> list[dict]:
    """``points`` with a sampled value for each arbitrary function of time in ``psi``
    (a moving wall ``x - f(t)``), so that psi can be evaluated there."""
    undefined = sorted(psi.atoms(sp.core.function.AppliedUndef), key=str)
    if not undefined:
        return list(points)
    extra = sample_points(undefined, count=len(points), seed=20010102)
    return [{**p, **x} for p, x in zip(points, extra, strict=True)]


def _wall_velocity(declaration: Declaration, value: object, wall: str) -> sp.Matrix:
    """The given wall velocity as a matrix: a sympy matrix as it is; a sequence entry by
    entry, text parsed safely (:func:`symmech.declaration.expressions.to_expression`) in
    the coordinates, velocities, parameters and t, never evaluated."""
    if isinstance(value, sp.MatrixBase):
        return sp.Matrix(value)
    try:  # the entries as they are (dtype object: nothing converted), a row or a column
        items = np.asarray(value, dtype=object)
    except ValueError:  # ragged
        items = None
    if items is not None and items.ndim == 2 and 1 in items.shape:
        items = items.ravel()
    if items is None or items.ndim != 1:
        raise ImpactError(
            f"wall {wall!r}: wall_velocity must be a sequence or a sympy matrix, got {value!r}"
        )
    d = declaration
    names = {str(s): s for s in (*d.coordinates, *d.velocities, *d.parameters, TIME)}
    try:
        entries = [
            to_expression(c, names, field=f"wall_velocity[{j}]") for j, c in enumerate(items)
        ]
    except SymmechError as exc:
        raise ImpactError(f"wall {wall!r}: {exc}") from None
    return sp.Matrix(len(entries), 1, entries)


def wall_one_form(
    declaration: Declaration, rw: ResolvedWall, points: Sequence[dict]
) -> tuple[sp.Expr, sp.Expr, sp.Matrix, sp.Expr]:
    """``(psi, alpha, dpsi, psi_t)`` of a wall: the one-form ``dpsi = (d psi/d q) S`` in the
    velocity basis (1 x n; S the frame, or the identity) and ``psi_t = d psi/d t``;
    :class:`~symmech.ImpactError` when d psi/d q vanishes at every sampled point."""
    psi = sp.sympify(rw.psi, strict=True)
    alpha = sp.sympify(rw.restitution, strict=True)
    row = sp.Matrix([[sp.diff(psi, qi) for qi in declaration.coordinates]])
    dpsi = row * sp.Matrix(declaration.frame) if declaration.frame is not None else row
    if all(is_zero(e, points) is True for e in dpsi):
        raise ImpactError(
            f"wall {rw.name!r}: psi = {psi} has zero gradient d psi/d q; it does not define a wall"
        )
    return psi, alpha, dpsi, sp.diff(psi, TIME)


def given_wall_velocity(
    declaration: Declaration,
    wall: str,
    value: object,
    dpsi: sp.MatrixBase,
    psi_t: sp.Expr,
    points: Sequence[dict],
) -> sp.Matrix:
    """A given wall velocity V as an n x 1 matrix (velocity basis), checked to move with
    the wall: ``dpsi(V) + psi_t = 0`` at the sampled ``points`` (Carnot paper eq. 15);
    :class:`~symmech.ImpactError` otherwise or for a wrong shape."""
    n = declaration.n
    V = _wall_velocity(declaration, value, wall)
    if V.shape == (1, n):
        V = V.T
    if V.shape != (n, 1):
        raise ImpactError(
            f"wall {wall!r}: wall_velocity must have {n} components (velocity basis),"
            f" got shape {V.shape}"
        )
    normal = (sp.Matrix(dpsi) * V)[0, 0] + psi_t
    if is_zero(normal, points) is not True:
        raise ImpactError(
            f"wall {wall!r}: wall_velocity V does not move with the wall:"
            f" dpsi(V) + psi_t = {sp.simplify(normal)} != 0 (a point of the wall stays on"
            " psi = 0, so dpsi(V) = -d psi/d t)"
        )
    return V


def derive_impact_map(
    declaration: Declaration,
    wall: ResolvedWall | int | str,
    law: str | None = None,
    *,
    wall_velocity: Sequence | sp.MatrixBase | None = None,
    simplify: Level = "light",
    projectors: tuple[sp.MatrixBase, sp.MatrixBase] | None = None,
) -> ImpactMap:
    """Derive the impact map of ``wall`` (a ResolvedWall, or its index or name).

    ``projectors``: the scene's (P, Q) of the permanent constraints
    (:meth:`symmech.Scene.projectors`), so that the impact uses the same objects; built
    here when not given (and always, unsimplified, with ``simplify="none"``).

    ``law`` (default: the wall's) is ``"newton"``, Carnot paper 002:

        v+ = (PP - alpha T~) v- + (QQ + alpha T~) W                (Prop. 3.4, Prop. 4.2)

    which is eq. 10 (``P~ - alpha Q~``) without impulsive constraints, eq. 17 for a moving
    wall, and text 001's Theorem 2.12 for alpha = 1 without constraints; or ``"energy"``,
    text 001 section 3.2: ``v+ = W + PP(v- - W) + alpha sqrt(...) N``
    (:mod:`symmech.impacts.energy_law`).

    ``wall_velocity`` (n x 1, velocity basis; default: the wall's own ``velocity``, see
    :mod:`symmech.declaration.wallvelocity`) overrides the default wall velocity
    ``V = -(psi_t/g(grad psi, grad psi)) grad psi``; it must satisfy ``dpsi(V) = -psi_t``
    (only the normal part of V is determined by psi; the tangential part enters the
    impulsive constraints ``nu(v+ - V) = 0``, eq. 20).

    ``simplify``: ``"none"`` returns the expressions as the projector algebra builds them;
    ``"light"`` (default) applies the stabilising step of
    :mod:`symmech.algebra.stability` (cancel + factor per velocity coefficient);
    ``"full"`` runs :func:`sympy.simplify` on each coefficient first.

    Raises :class:`~symmech.ImpactError` when the wall gradient lies in the span of the
    permanent constraints, when an impulsive constraint depends on d psi and the other
    constraints (C^AB singular at every sampled point), for an unknown law, or for a
    wall velocity that does not move with the wall.
    """
    if simplify not in ("none", "light", "full"):
        raise ImpactError(
            f"impact map: simplify must be 'none', 'light' or 'full', got {simplify!r}"
        )
    rw = _resolve(declaration, wall)
    law = rw.law if law is None else law
    if law not in LAWS:
        raise ImpactError(f"wall {rw.name!r}: law must be one of {LAWS}, got {law!r}")
    level: Level = "none" if simplify == "none" else "light"
    q, n, v = declaration.coordinates, declaration.n, declaration.velocities
    points = sample_points([*q, *declaration.parameters, TIME])
    psi, alpha, dpsi, psi_t = wall_one_form(declaration, rw, points)
    permanent = projectors if level != "none" else None
    proj = _checked_projectors(declaration, rw, psi, dpsi, points, level, permanent)
    V: sp.Matrix | None = None
    if wall_velocity is None and rw.velocity is not None:
        wall_velocity = rw.velocity  # declared with the wall (checked by the declaration)
    if wall_velocity is not None:
        V = given_wall_velocity(declaration, rw.name, wall_velocity, dpsi, psi_t, points)
    matrix, offset, W = newton_map(proj, alpha, psi_t, V, level)
    if V is None:
        from symmech.impacts.newton import wall_velocity as default_velocity

        V = default_velocity(proj, psi_t, level)
    state = (*q, TIME)
    if simplify != "none":
        matrix, offset = _finished(matrix, simplify, state), _finished(offset, simplify, state)
        W, V = stable_matrix(W, state), stable_matrix(V, state)
    energy: EnergyLaw | None = None
    if law == "newton":
        # entries are already in stable form: keep each velocity coefficient separate
        post = sp.Matrix(
            [sp.Add(offset[i], *[matrix[i, j] * v[j] for j in range(n)]) for i in range(n)]
        )
    else:
        energy = energy_law(proj, alpha, v, W, level, stable=simplify != "none", state=state)
        post = sp.Matrix(energy.post_velocity)
    singularities = _singularities(
        proj, psi_t, matrix, offset, W, V if wall_velocity is not None else None, energy
    )
    return ImpactMap(
        declaration=declaration,
        wall=rw,
        law=law,
        alpha=alpha,
        psi_t=psi_t,
        projectors=proj,
        matrix=matrix,
        offset=offset,
        wall_velocity=V,
        W=W,
        post_velocity=post,
        energy=energy,
        singularities=singularities,
        simplify=simplify,
    )


def _checked_projectors(
    declaration: Declaration,
    rw: ResolvedWall,
    psi: sp.Expr,
    dpsi: sp.Matrix,
    points: list[dict],
    level: Level,
    permanent: tuple[sp.MatrixBase, sp.MatrixBase] | None,
) -> ImpactProjectors:
    """The projectors of the impact (:func:`impact_projectors`), each Gram matrix checked
    regular at the sampled points and on the wall (:func:`check_regular`)."""
    g = sp.Matrix(declaration.metric)
    mu = sp.Matrix(declaration.constraint_matrix)
    nu = sp.Matrix(rw.impulsive_matrix)
    on_wall = points_on_wall(psi, declaration.coordinates, _with_undefined(points, psi))

    def check(C: sp.Matrix, PY: sp.Matrix) -> None:
        check_regular(
            C,
            points,
            wall=rw.name,
            psi=psi,
            mu=mu,
            nu=nu,
            velocities=declaration.velocities,
            g=g,
            dpsi=dpsi,
            wall_points=on_wall,
        )

    return impact_projectors(g, mu, dpsi, nu, level, check=check, permanent=permanent)


def _finished(M: sp.Matrix, simplify: str, state: tuple[sp.Symbol, ...]) -> sp.Matrix:
    """Each entry of ``M`` in stable form (:func:`stable_coefficient`), after
    :func:`sympy.simplify` for ``simplify="full"`` (within its budget)."""

    def finish(e: sp.Expr) -> sp.Expr:
        if simplify == "full" and limits.affordable(e, limits.IMPACT_FULL_OPS):
            e = sp.simplify(e)
        return stable_coefficient(e, state)

    return sp.Matrix(M.rows, M.cols, [finish(e) for e in M])


def _singularities(
    proj: ImpactProjectors,
    psi_t: sp.Expr,
    matrix: sp.Matrix,
    offset: sp.Matrix,
    W: sp.Matrix,
    given_velocity: sp.Matrix | None,
    energy: EnergyLaw | None,
) -> list[Singularity]:
    """Where the map is singular (:func:`impact_singularities` over its closed forms), and
    for the energy law the branch point of its square root."""
    if energy is None:
        closed, scan = [*matrix, *offset], []
    else:
        closed = [*energy.tangential, *energy.direction, *W]
        scan = [w for w, _ in energy.squares]
    singularities = impact_singularities(
        proj,
        psi_t,
        default_velocity=given_velocity is None,
        extra=list(given_velocity) if given_velocity is not None else [],
        closed_form=closed,
        also_scan=scan,
    )
    if energy is not None:
        singularities.append(
            Singularity(
                energy.speed_squared,
                "branch point of the square root in the energy law (grazing impact: no"
                " normal relative velocity); v+ is continuous but not differentiable there",
            )
        )
    return singularities
