"""Several walls hit at once: the closed-form map of an active set, and the contact decision.

Law (frictionless generalized Newton law per contact; Moreau 1988, Glocker and Pfeiffer
1995, Brogliato "Nonsmooth Mechanics" ch. 6), written in the Carnot paper's (002) objects.
Walls i = 1..k are active together, each with its one-form ``dpsi_i`` (velocity basis:
``(d psi_i / d q) S``), restitution ``alpha_i``, moving-wall rate ``psi_t,i`` and wall
velocity ``V_i``, and its impulsive constraints ``nu_i`` (imposed when wall i is hit).
Stack the rows ``A = [dpsi_1; ...; dpsi_k; nu_1; ...; nu_k]`` (walls first).  The impulse
is ``g (v+ - v-) = mu^T lambda + A^T Lambda`` with ``mu v+ = 0`` and ``A v+ = b``:

    b_i = -alpha_i (dpsi_i v- + psi_t,i) - psi_t,i      (wall rows: eq. 9, eq. 15)
    b_A = nu_A V_i                                      (nu rows of wall i: eq. 20)

This is eq. 6 / Prop. 3.4 / Prop. 4.2 with the single wall row replaced by k rows.  With
the projectors of :func:`~symmech.impacts.impact_projectors.impact_projectors` built on
all the rows of A (P(Y^A) = PY, C^AB = A P g^-1 A^T, C_AB = K, beta = PY^T g), and
``D = diag(alpha_1, ..., alpha_k, 0, ..., 0)``, ``c = [dpsi_i V_i = -psi_t,i; nu_i V_i]``:

    Lambda = -K (I + D) (beta v- - c)                        (the multipliers of A)
    v+ = v- + PY Lambda = (PP - PY K D beta) v- + PY K (I + D) c.

For k = 1 this is Prop. 3.4 / 4.2 term by term: ``PY K D beta = alpha N beta^0 = alpha T~``
and ``PY K (I + D) c = (QQ + alpha T~) W``.  ``Lambda_i`` (i <= k) are the normal impulses:
the generalized impulse of wall i is ``Lambda_i dpsi_i`` (in the units of psi_i); the
pre-impact normal rates are ``u_i = dpsi_i v- + psi_t,i``.

Energy (the Carnot theorem for several walls; re-derived).  With ``W = PY K c`` (the
common wall velocity: ``A W = c``, W in D; section 4.2's W for k = 1), ``x = v- - W`` in D
and the relative rates ``u = beta x`` (all rows of A), ``v+ - W = x + PY Lambda`` and
``g(x, PY Lambda) = u^T Lambda``, ``g(PY Lambda, PY Lambda) = Lambda^T C Lambda``, so

    T(v+ - W) - T(v- - W) = -1/2 u^T (K - D K D) u = 1/2 Lambda^T (u+ + u-),

``u+ = beta (v+ - W) = -D u``.  For equal alpha_i = alpha and no impulsive constraints the
form is ``(1 - alpha^2) K``, positive semi-definite: no kinetic energy is gained, it is
conserved for alpha = 1, and ``T1' - T0' = -(1 - alpha)/(1 + alpha) T_l`` (Theorems 3.2 /
4.1 verbatim for several walls).  With unequal alpha_i the form ``K - D K D`` can be
indefinite (the multiple-impact energy paradox; Glocker, "Energetic consistency conditions
for standard impacts", Multibody Syst. Dyn. 2013): the sum ``1/2 sum_i (1 - alpha_i)
Lambda_i u-_i`` is then <= 0 when every Lambda_i >= 0 and every u-_i <= 0, but not in
general; impulsive constraints add ``1/2 sum_A Lambda_A u-_A``, which has no sign (as in
Theorem 3.9).  :meth:`SeveralImpactMap.carnot` proves the identity for the map.

Which walls of a touching set take an impulse is decided numerically by
:func:`symmech.impacts.decision.simultaneous_impulses` (the LCP on
:attr:`SeveralImpactMap.delassus`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from functools import cached_property
from typing import TYPE_CHECKING, Any

import sympy as sp

from symmech.algebra import budget as limits
from symmech.algebra.energy_forms import Affine, QuadraticForm
from symmech.algebra.field import common_domain
from symmech.algebra.numeric import EvaluationError
from symmech.algebra.rank import rank_at
from symmech.algebra.sampling import sample_points
from symmech.algebra.simplification import Level, tidy_matrix
from symmech.algebra.stability import stable_matrix
from symmech.declaration.symbols import t as TIME
from symmech.errors import ImpactError
from symmech.impacts.adjugate_projectors import shared_denominators
from symmech.impacts.carnot import CarnotResult, SparseEvaluation, _size, decide_identity
from symmech.impacts.degeneracy import Singularity, singular_set
from symmech.impacts.impact_map import _resolve, given_wall_velocity, wall_one_form
from symmech.impacts.impact_projectors import ImpactProjectors, impact_projectors
from symmech.impacts.newton import wall_velocity as default_wall_velocity

if TYPE_CHECKING:
    from symmech.declaration.spec import Declaration, ResolvedWall

__all__ = ["SeveralImpactMap", "derive_several_impact_map", "resolve_walls"]


class SeveralImpactMap:
    """The impact map of a set of walls all active at once (module docstring for the law).

    Attributes
    ----------
    walls, alphas, psi_t:
        The walls of the set (in the given order), their restitutions and ``d psi_i/d t``.
    post_velocity:
        v+ (n x 1) in the pre-impact velocity symbols ``velocities``, q, t, parameters.
    matrix, offset:
        ``v+ = matrix v- + offset``: ``matrix = PP - PY K D beta`` (``PP - alpha T~`` for
        one wall, Prop. 3.4) and ``offset = PY K (I + D) c`` (zero for static walls).
    impulses:
        ``Lambda_i`` (k x 1), the normal impulse of each wall (its generalized impulse is
        ``Lambda_i dpsi_i``), affine in v-: ``impulse_matrix v- + impulse_offset``;
        ``multipliers`` holds every row of A (walls, then their impulsive constraints).
    normal_rates:
        ``u_i = dpsi_i v + psi_t,i`` (k x 1), the rate of psi_i before the impact.
    W:
        ``PY K c``, the common wall velocity (section 4.2); zero for static walls.
    projectors:
        :class:`~symmech.impacts.impact_projectors.ImpactProjectors` on the rows of A
        (its T~, N, Q~, P~ are those of the first wall alone).
    singularities:
        Denominators of the closed form (det g, the permanent Gram determinant, det C^AB
        of the set, input denominators) as :class:`~symmech.impacts.degeneracy.Singularity`.
    """

    law = "newton"
    is_linear = True

    def __init__(
        self,
        *,
        declaration: Declaration,
        walls: tuple[ResolvedWall, ...],
        alphas: tuple[sp.Expr, ...],
        psi_t: tuple[sp.Expr, ...],
        rows: tuple[str, ...],
        projectors: ImpactProjectors,
        matrix: sp.Matrix,
        offset: sp.Matrix,
        W: sp.Matrix,
        impulse_matrix: sp.Matrix,
        impulse_offset: sp.Matrix,
        singularities: list[Singularity],
    ):
        im = sp.ImmutableMatrix
        self.declaration, self.walls, self.alphas, self.psi_t = declaration, walls, alphas, psi_t
        self.rows, self.projectors, self.singularities = rows, projectors, singularities
        self.matrix, self.offset, self.W = im(matrix), im(offset), im(W)
        self.impulse_matrix, self.impulse_offset = im(impulse_matrix), im(impulse_offset)
        v = self.velocities
        self.post_velocity = im(_affine(matrix, offset, v))
        self.multipliers = im(_affine(impulse_matrix, impulse_offset, v))
        k = len(walls)
        self.impulses = im(self.multipliers[:k, :])
        dpsi = sp.Matrix(projectors.dpsi)
        self.normal_rates = im(
            [sp.Add(psi_t[i], *[dpsi[i, j] * v[j] for j in range(len(v))]) for i in range(k)]
        )
        self._carnot: CarnotResult | None = None

    @property
    def velocities(self) -> tuple[sp.Symbol, ...]:
        """The pre-impact velocity symbols (the scene's velocity basis)."""
        return self.declaration.velocities

    @property
    def names(self) -> tuple[str, ...]:
        """The walls' names, in the order of the rows of :attr:`impulses`."""
        return tuple(w.name for w in self.walls)

    @property
    def moving(self) -> bool:
        """True when some wall of the set moves (psi_t != 0 or a given wall velocity)."""
        return not self.W.is_zero_matrix or any(e != 0 for e in self.psi_t)

    def __repr__(self) -> str:
        kind = "moving" if self.moving else "static"
        return (
            f"SeveralImpactMap(walls={list(self.names)}, law='newton', {kind},"
            f" alphas={list(self.alphas)}, impulsive constraints={self.projectors.nu.rows})"
        )

    @cached_property
    def delassus(self) -> sp.ImmutableMatrix:
        """The Delassus matrix of the walls' rows in the constrained metric (k x k):
        ``u+ - u- = delassus Lambda`` for the normal rates.  Without impulsive constraints
        it is ``C^{ij} = dpsi_i P g^-1 dpsi_j^T`` (the permanent constraints projected
        out); with them, the Schur complement ``C_ww - C_wn C_nn^-1 C_nw`` (the impulsive
        constraints of the set held), equal to the inverse of the walls' block of K."""
        k = len(self.walls)
        C = sp.Matrix(self.projectors.C)
        Cww = C[:k, :k]
        if C.rows == k:
            return sp.ImmutableMatrix(Cww)
        Cwn, Cnn = C[:k, k:], C[k:, k:]
        schur = Cww - Cwn * Cnn.LUsolve(Cwn.T)
        return sp.ImmutableMatrix(tidy_matrix(schur, "light"))

    @cached_property
    def loss_form(self) -> sp.ImmutableMatrix:
        """``K - D K D`` (rows of A): ``T(v+ - W) - T(v- - W) = -1/2 u^T (K - D K D) u`` with
        ``u = beta (v- - W)`` (:attr:`relative_rates`); module docstring."""
        K = sp.Matrix(self.projectors.K)
        D = sp.diag(*self._restitutions())
        return sp.ImmutableMatrix(tidy_matrix(K - D * K * D, "light"))

    @cached_property
    def relative_rates(self) -> sp.ImmutableMatrix:
        """``u = beta (v - W)`` (one entry per row of A), the rates the law acts on."""
        beta = sp.Matrix(self.projectors.beta)
        v = sp.Matrix(self.velocities)
        return sp.ImmutableMatrix(beta * v - beta * sp.Matrix(self.W))

    def _restitutions(self) -> list[sp.Expr]:
        """The diagonal of D: alpha_i on the wall rows, 0 on the impulsive-constraint rows."""
        return [*self.alphas, *[sp.S.Zero] * self.projectors.nu.rows]

    def apply(self, pre_velocity: Sequence | sp.MatrixBase | Mapping) -> sp.Matrix:
        """v+ for a given pre-impact velocity (a sequence in the velocity basis or a dict)."""
        return sp.Matrix(self.post_velocity.xreplace(self._rule(pre_velocity)))

    def impulses_at(self, pre_velocity: Sequence | sp.MatrixBase | Mapping) -> sp.Matrix:
        """The normal impulses Lambda_i for a given pre-impact velocity."""
        return sp.Matrix(self.impulses.xreplace(self._rule(pre_velocity)))

    def _rule(self, pre_velocity: Sequence | sp.MatrixBase | Mapping) -> dict:
        v = self.velocities
        if isinstance(pre_velocity, Mapping):
            values = dict(pre_velocity)
        else:
            seq = list(pre_velocity)
            if len(seq) != len(v):
                raise ImpactError(
                    f"walls {list(self.names)}: expected {len(v)} velocity components,"
                    f" got {len(seq)}"
                )
            values = dict(zip(v, seq, strict=True))
        try:
            return {key: sp.sympify(x, strict=True) for key, x in values.items()}
        except sp.SympifyError:
            raise ImpactError(
                f"walls {list(self.names)}: a velocity component is not a number or a sympy"
                " expression (for text, use symmech.parse_expression)"
            ) from None

    def energy_change(self, in_D: bool = False) -> sp.Expr:
        """``T(v+) - T(v-)`` (``T = 1/2 v^T g v``), each velocity coefficient cancelled; with
        ``in_D=True`` for the general element ``v- = P v`` of D."""
        p = self.projectors
        g, n = sp.Matrix(p.g), p.g.rows
        L = sp.Matrix(p.P) if in_D else sp.eye(n)
        ring = common_domain([g, L, self.matrix, self.offset])
        gd = ring.matrix(g)
        pre = Affine.of(ring, L, sp.zeros(n, 1))
        post = pre.apply(ring.matrix(self.matrix)).shift(ring.matrix(self.offset))
        v = sp.Matrix(self.velocities)
        return (QuadraticForm.energy(gd, post) - QuadraticForm.energy(gd, pre)).expr(v)

    def carnot(self) -> CarnotResult:
        """The energy identity of the module docstring, as a residual that vanishes:
        ``T(v+ - W) - T(v- - W) + 1/2 u^T (K - D K D) u`` for the general v- in D.

        Decided as in :mod:`symmech.impacts.carnot`: in the fraction field when small
        (a proof), else by exact evaluation at a random point (Schwartz-Zippel bound in
        ``error_bound``).  ``terms`` holds T0', T1' and the loss ``1/2 u^T (K - DKD) u``.
        """
        if self._carnot is None:
            self._carnot = _carnot(self)
        return self._carnot


def _affine(M: sp.MatrixBase, o: sp.MatrixBase, v: Sequence[sp.Symbol]) -> sp.Matrix:
    """``M v + o`` with each velocity coefficient kept separate (the entries are stable)."""
    return sp.Matrix(
        [sp.Add(o[i], *[M[i, j] * v[j] for j in range(len(v))]) for i in range(M.rows)]
    )


# -- the energy identity ----------------------------------------------------------------

_THEOREM = "Carnot, several walls (Theorems 3.2, 3.9, 4.1, 4.3 with k wall rows)"
_STATEMENT = "T1' - T0' = -1/2 u^T (K - D K D) u, u = beta (v- - W)"
Formed = tuple[sp.Expr, dict[str, sp.Expr], sp.ImmutableMatrix]


def _carnot(m: SeveralImpactMap) -> CarnotResult:
    def symbolic() -> Formed:
        return _symbolic(m)

    p = m.projectors
    parts = [p.g, p.P, p.beta, m.matrix, m.offset, m.W, m.loss_form]
    small = _size(parts) <= limits.CARNOT_FIELD_OPS
    return decide_identity(
        _THEOREM, _STATEMENT, symbolic, lambda value, const: _evaluate(m, value, const), small
    )


def _symbolic(m: SeveralImpactMap) -> Formed:
    """The residual in the fraction field of the entries, for ``v- = P v`` (v the symbols)."""
    p = m.projectors
    n = p.g.rows
    v = sp.Matrix(m.velocities)
    ring = common_domain([p.g, p.P, p.beta, m.matrix, m.offset, m.W, m.loss_form])
    g, Wd = ring.matrix(p.g), ring.matrix(m.W)
    x = Affine.of(ring, sp.Matrix(p.P), sp.zeros(n, 1))
    rel = x.shift(-Wd)
    post = x.apply(ring.matrix(m.matrix)).shift(ring.matrix(m.offset)).shift(-Wd)
    T0, T1 = QuadraticForm.energy(g, rel), QuadraticForm.energy(g, post)
    u = rel.apply(ring.matrix(p.beta))
    loss = QuadraticForm.bilinear(ring.matrix(m.loss_form), u, u).scale(sp.Rational(1, 2))
    terms = {"T0'": T0.expr(v), "T1'": T1.expr(v), "loss": loss.expr(v)}
    pre = sp.ImmutableMatrix(x.to_sympy(v).applyfunc(sp.expand))
    return (T1 - T0 + loss).expr(v, simplify=True), terms, pre


def _evaluate(m: SeveralImpactMap, value: Callable[[sp.Expr], Any], const: Callable) -> Any:
    """Twice the residual, built with + - * from ``value`` of the entries (for
    :func:`~symmech.algebra.identity.identically_zero`)."""
    p = m.projectors

    ev = SparseEvaluation(value, const)
    mat, dot, apply, sub = ev.matrix, ev.dot, ev.apply, ev.sub
    g, W = mat(p.g), [value(e) for e in m.W]
    x = apply(mat(p.P), [value(s) for s in m.velocities])
    post = [a + value(b) for a, b in zip(apply(mat(m.matrix), x), m.offset, strict=True)]
    rel, post_rel = sub(x, W), sub(post, W)
    u = apply(mat(p.beta), rel)
    twice = dot(post_rel, apply(g, post_rel)) - dot(rel, apply(g, rel))
    return twice + dot(u, apply(mat(m.loss_form), u))


# -- derivation -------------------------------------------------------------------------


def resolve_walls(declaration: Declaration, walls: Sequence[object]) -> tuple[ResolvedWall, ...]:
    """The walls of a set (names, indices or walls of this scene), refusing an empty set,
    a wall that is not the scene's and a wall given twice (:class:`~symmech.ImpactError`)."""
    if isinstance(walls, str | bytes) or not isinstance(walls, Sequence):
        raise ImpactError(
            f"impact map: a set of walls must be a list or tuple of names, indices or walls,"
            f" got {walls!r}"
        )
    if not walls:
        raise ImpactError("impact map: the set of walls is empty; name at least one wall")
    resolved = tuple(_resolve(declaration, w) for w in walls)
    seen: dict[int, object] = {}
    for given, rw in zip(walls, resolved, strict=True):
        if rw.index in seen:
            raise ImpactError(
                f"impact map: wall {rw.name!r} is given twice in the set ({seen[rw.index]!r}"
                f" and {given!r}); each wall of a set is hit once"
            )
        seen[rw.index] = given
    return resolved


def _regularity_check(
    walls: tuple[ResolvedWall, ...], rows: tuple[str, ...], points: Sequence[dict]
) -> Callable[[sp.Matrix, sp.Matrix], None]:
    """``check(C, PY)`` for :func:`impact_projectors`: refuse a set whose Gram matrix
    ``C^AB = g(P Y^A, P Y^B)`` is singular at every sampled point, naming the first row
    whose leading block becomes singular (a wall in the span of the permanent constraints
    and the walls before it, or a dependent impulsive constraint)."""
    names = [w.name for w in walls]

    def check(C: sp.Matrix, PY: sp.Matrix) -> None:
        verdicts = []
        for point in points:
            try:
                verdicts.append(
                    [rank_at(C[: j + 1, : j + 1], point) < j + 1 for j in range(C.rows)]
                )
            except EvaluationError:
                continue
        for j in range(C.rows if verdicts else 0):
            if all(v[j] for v in verdicts):
                before = ", ".join(rows[:j]) or "none"
                raise ImpactError(
                    f"walls {names}: {rows[j]} is linearly dependent on the permanent"
                    f" constraints and the rows before it in the set ({before}): the Gram"
                    " matrix C^AB = g(P Y^A, P Y^B) of the set (Carnot paper eq. 7, section"
                    " 3.2) is singular at every sampled point, so the impulses of a"
                    " simultaneous impact are not unique; remove the dependent wall (or"
                    " constraint) from the set"
                )

    return check


def _wall_rates(
    declaration: Declaration,
    walls: tuple[ResolvedWall, ...],
    forms: list[tuple[sp.Expr, sp.Expr, sp.Matrix, sp.Expr]],
    proj: ImpactProjectors,
    points: Sequence[dict],
    level: Level,
) -> tuple[sp.Matrix, list[sp.Expr]]:
    """``c = [dpsi_i V_i = -psi_t,i; nu_i V_i]`` (the rows of A applied to the walls'
    velocities, Carnot paper section 4.2), and the entries of the given wall velocities
    (for the singular set).  V_i is the wall's declared velocity, checked to move with it,
    else the g-normal default of :func:`symmech.impacts.newton.wall_velocity`."""
    n = declaration.n
    wall_rows: list[sp.Expr] = []
    nu_rows: list[sp.Expr] = []
    given: list[sp.Expr] = []
    for i, (rw, (_, _, dpsi, psi_t)) in enumerate(zip(walls, forms, strict=True)):
        wall_rows.append(-psi_t)
        nu = sp.Matrix(rw.impulsive_matrix)
        if not nu.rows:
            continue
        if rw.velocity is not None:
            V = given_wall_velocity(declaration, rw.name, rw.velocity, dpsi, psi_t, points)
            given.extend(V)
        else:
            V = default_wall_velocity(proj, psi_t, level, row=i) if psi_t != 0 else sp.zeros(n, 1)
        nu_rows.extend(nu * V)
    return sp.Matrix([*wall_rows, *nu_rows]), given


def _singularities(
    proj: ImpactProjectors, psi_t: Sequence[sp.Expr], given: Sequence[sp.Expr]
) -> list[Singularity]:
    """The denominators of the construction (:func:`~symmech.impacts.degeneracy.singular_set`)."""
    g, mu = sp.Matrix(proj.g), sp.Matrix(proj.mu)
    dpsi, nu = sp.Matrix(proj.dpsi), sp.Matrix(proj.nu)
    structural: list[tuple[sp.Expr, str]] = []
    dens = proj.denominators or shared_denominators(g, mu, dpsi, nu)
    gram = (
        "det C^AB = 0 (Carnot paper eq. 7, section 3.2): the walls' gradients and their"
        " impulsive constraints become dependent modulo the permanent constraints"
    )
    if dens is not None:
        structural.append((dens.metric, "the metric g (velocity basis) is singular"))
        if dens.permanent is not None:
            structural.append((dens.permanent, "the permanent constraints become dependent"))
        structural.append((dens.gram, gram))
    else:
        structural.append((sp.Matrix(proj.C).det(method="berkowitz"), gram))
    for i, rate in enumerate(psi_t):
        if rate != 0:
            norm = (dpsi[i, :] * sp.Matrix(proj.Y[:, i]))[0, 0]
            structural.append((norm, "g(grad psi, grad psi) = 0 in the default wall velocity"))
    inputs = "denominator of the closed form (derivatives of psi, the metric or the frame)"
    for e in [*g, *dpsi, *nu, *mu, *psi_t, *given]:
        den = sp.fraction(sp.together(e))[1]
        if den.free_symbols:
            structural.append((den, inputs))
    return singular_set(structural)


def derive_several_impact_map(
    declaration: Declaration,
    walls: Sequence[ResolvedWall | int | str],
    *,
    law: str | None = None,
    simplify: Level = "light",
    projectors: tuple[sp.MatrixBase, sp.MatrixBase] | None = None,
) -> SeveralImpactMap:
    """The impact map of the walls ``walls`` all active at once (module docstring):

        v+ = (PP - PY K D beta) v- + PY K (I + D) c,   Lambda = -K (I + D)(beta v- - c),

    Carnot paper 002 eq. 6, eq. 10, Prop. 3.4, eqs. 17-20 and Prop. 4.2 with one wall row
    per wall.  Newton's law only (``law`` None or ``"newton"``; a wall declaring the
    energy law needs ``law="newton"`` explicitly).  ``simplify`` and ``projectors`` as in
    :func:`~symmech.impacts.impact_map.derive_impact_map`.

    Raises :class:`~symmech.ImpactError` for an empty set, a wall given twice or not of
    this scene, a wall without gradient, and a dependent set (the Gram matrix of the
    walls' rows and impulsive constraints, modulo the permanent constraints, singular).
    """
    if simplify not in ("none", "light", "full"):
        raise ImpactError(
            f"impact map: simplify must be 'none', 'light' or 'full', got {simplify!r}"
        )
    resolved = resolve_walls(declaration, walls)
    _check_law(resolved, law)
    level: Level = "none" if simplify == "none" else "light"
    q, n = declaration.coordinates, declaration.n
    points = sample_points([*q, *declaration.parameters, TIME])
    forms = [wall_one_form(declaration, rw, points) for rw in resolved]
    dpsi = sp.Matrix.vstack(*[f[2] for f in forms])
    nus = [sp.Matrix(rw.impulsive_matrix) for rw in resolved]
    nu = sp.Matrix.vstack(sp.zeros(0, n), *[m for m in nus if m.rows])
    rows = tuple(
        [f"wall {rw.name!r}" for rw in resolved]
        + [
            f"the impulsive constraint nu^{a + 1} of wall {rw.name!r}"
            for rw, m in zip(resolved, nus, strict=True)
            for a in range(m.rows)
        ]
    )
    check = _regularity_check(resolved, rows, points)
    permanent = projectors if level != "none" else None
    g, mu = sp.Matrix(declaration.metric), sp.Matrix(declaration.constraint_matrix)
    proj = impact_projectors(g, mu, dpsi, nu, level, check=check, permanent=permanent, several=True)
    c, given = _wall_rates(declaration, resolved, forms, proj, points, level)
    alphas = tuple(f[1] for f in forms)
    return SeveralImpactMap(
        declaration=declaration,
        walls=resolved,
        alphas=alphas,
        psi_t=tuple(f[3] for f in forms),
        rows=rows,
        projectors=proj,
        **_closed_form(proj, alphas, c, simplify, (*q, TIME)),
        singularities=_singularities(proj, [f[3] for f in forms], given),
    )


def _check_law(walls: tuple[ResolvedWall, ...], law: str | None) -> None:
    names = [w.name for w in walls]
    if law not in (None, "newton"):
        raise ImpactError(
            f"walls {names}: a set of walls hit at once has Newton's law only, got law={law!r}"
        )
    energy = [w.name for w in walls if w.law != "newton"]
    if law is None and energy:
        raise ImpactError(
            f"walls {names}: {energy} declare the energy law (text 001 section 3.2), which is"
            " defined for one wall at a time; pass law='newton' for the generalized Newton law"
        )


def _closed_form(
    proj: ImpactProjectors,
    alphas: tuple[sp.Expr, ...],
    c: sp.Matrix,
    simplify: Level,
    state: tuple[sp.Symbol, ...],
) -> dict[str, sp.Matrix]:
    """``matrix = PP - sum_i alpha_i T~_i`` (``= PP - PY K D beta``), ``offset = PY K (I + D)
    c``, ``W = PY K c`` and the impulses ``Lambda = -(K beta + K D beta) v- + K (I + D) c``
    (module docstring; ``K D beta = sum_i alpha_i K[:, i] beta^i``), from the projectors'
    ``T_walls``, ``PYK``, ``Kbeta`` and ``Kbeta_walls``, built by the route that built the
    projectors (cancelled over shared denominators by the adjugate route) as the one-wall
    map uses ``T~`` and ``N``.  Each entry is put in the stable form of
    :mod:`symmech.algebra.stability` unless ``simplify="none"``."""
    assert proj.PYK is not None and proj.Kbeta is not None  # built with several=True
    level: Level = "none" if simplify == "none" else "light"
    D = sp.diag(*alphas, *[0] * proj.nu.rows)
    ID = sp.eye(D.rows) + D
    PYK, Kbeta, K = sp.Matrix(proj.PYK), sp.Matrix(proj.Kbeta), sp.Matrix(proj.K)
    reflected = sp.Add(*[a * sp.Matrix(T) for a, T in zip(alphas, proj.T_walls, strict=True)])
    # K D beta = sum_i alpha_i K[:, i] beta^i (D sits between K and beta)
    K_reflected = sp.Add(*[a * sp.Matrix(M) for a, M in zip(alphas, proj.Kbeta_walls, strict=True)])
    out = {
        "matrix": tidy_matrix(sp.Matrix(proj.PP) - reflected, level),
        "offset": tidy_matrix(PYK * (ID * c), level),
        "W": tidy_matrix(PYK * c, level),
        "impulse_matrix": tidy_matrix(-Kbeta - K_reflected, level),
        "impulse_offset": tidy_matrix(K * (ID * c), level),
    }
    if simplify == "none":
        return out

    def finish(e: sp.Expr) -> sp.Expr:
        if simplify == "full" and limits.affordable(e, limits.IMPACT_FULL_OPS):
            e = sp.simplify(e)
        return e

    return {key: stable_matrix(M.applyfunc(finish), state) for key, M in out.items()}
