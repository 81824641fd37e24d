"""Degenerate walls and the singular set of an impact map.

The Carnot construction needs the Gram matrix ``C^{AB} = g(P Y^A, P Y^B)`` of the wall
gradient and the impulsive constraints, projected onto D, to be regular (Carnot paper 002,
section 3.1: "C != 0 since we are assuming that the 1-forms mu^a and d psi are independent
along N"; section 3.2: the same for ``{mu^a, d psi, nu^B}``).

* :func:`check_regular` refuses walls for which C is singular *identically*: decided
  symbolically when cheap, else at sampled points (:mod:`symmech.algebra.sampling`);
  a matrix singular at every sampled point is singular generically.  It also refuses
  walls for which C is singular *on the wall*: impacts happen only where ``psi = 0``, and
  a wall such as ``psi = y`` with the constraint ``y x_dot + y_dot = 0`` has its gradient
  in the constraint span exactly there.  The points of the wall are found by
  :func:`~symmech.declaration.wallpoints.points_on_wall` (psi solved for one coordinate
  near each sampled point).
* Walls whose gradient itself vanishes on the wall (``psi = x**2``, ``x**3``,
  ``sin(x)**2``, ``(x - 1)**2*(y + 2)``: C = 0 there whatever the constraints) never reach
  this module: the declaration refuses them
  (:func:`symmech.declaration.wallpoints.vanishing_gradient`, Newton's method for the
  multiple roots where psi and d psi vanish together).
* :func:`singular_set` lists the expressions whose vanishing makes the closed form
  undefined (denominators), with a description, so that a user can guard generated code
  instead of meeting NaN later.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import mpmath as mp
import sympy as sp
from sympy.matrices.utilities import dotprodsimp

from symmech.algebra import budget as limits
from symmech.algebra.numeric import EvaluationError
from symmech.algebra.rank import rank_at
from symmech.algebra.zero import is_zero
from symmech.declaration.wallpoints import points_on_wall
from symmech.errors import ImpactError
from symmech.impacts.adjugate_projectors import shared_denominators

if TYPE_CHECKING:
    from symmech.impacts.impact_projectors import ImpactProjectors

__all__ = [
    "FACTOR_MAX_OPS",
    "Singularity",
    "check_regular",
    "impact_singularities",
    "no_real_zeros",
    "points_on_wall",
    "singular_set",
]

_SYMBOLIC_OPS = limits.ZERO_TEST_OPS


@dataclass(frozen=True)
class Singularity:
    """An expression whose zeros make the impact map undefined, and why."""

    expression: sp.Expr
    description: str

    def __str__(self) -> str:
        return f"{self.expression} = 0: {self.description}"


def _short(expr: object, limit: int = 70) -> str:
    s = str(expr)
    return s if len(s) <= limit else s[: limit - 3] + "..."


#: ``C^{00} / g(grad psi, grad psi)`` (invariant under rescaling psi, in [0, 1]) below this
#: at a point of the wall counts as zero there; evaluated with 40 digits.
HADAMARD_TOLERANCE = 1e-20


def _singular_blocks(C: sp.MatrixBase, point: dict) -> list[bool] | None:
    """For each leading block of the Gram matrix C at ``point``: is it singular (its rank,
    :func:`symmech.algebra.rank.rank_at`, below its size)?  The rank test scales rows to
    unit size, so a metric like diag(10^6, 10^6, 10^-6), which makes the entries of C
    differ by 10^12, does not make it singular; None if C cannot be evaluated."""
    C = sp.Matrix(C)
    try:
        return [rank_at(C[: j + 1, : j + 1], point) < j + 1 for j in range(C.rows)]
    except EvaluationError:
        return None


def _wall_gradient_ratio(
    C00: sp.Expr, g: sp.MatrixBase, dpsi: sp.MatrixBase, point: dict
) -> mp.mpf | None:
    """``C^00 / g(Y^0, Y^0)`` at a point, Y^0 = g^-1 d psi: the squared sine of the angle
    between d psi and the span of the permanent constraints (1 without constraints, 0
    when d psi lies in their span); None if it cannot be evaluated."""
    try:
        with mp.workdps(40):

            def at(e: sp.Expr) -> mp.mpf:
                return mp.mpf(sp.N(e.xreplace(point), 45))

            G = mp.matrix([[at(e) for e in row] for row in g.tolist()])
            d = mp.matrix([at(e) for e in dpsi])
            scale = (d.T * mp.lu_solve(G, d))[0]
            c = mp.mpf(sp.N(C00.xreplace(point), 45))
            return c / scale if scale > 0 else None
    except (TypeError, ValueError, ZeroDivisionError):
        return None


def check_regular(
    C: sp.MatrixBase,
    points: Sequence[dict],
    *,
    wall: str,
    psi: sp.Expr,
    mu: sp.MatrixBase,
    nu: sp.MatrixBase,
    velocities: Sequence[sp.Symbol],
    g: sp.MatrixBase | None = None,
    dpsi: sp.MatrixBase | None = None,
    wall_points: Sequence[dict] = (),
) -> None:
    """Raise :class:`~symmech.ImpactError` if ``C^{AB}`` is singular identically, or at
    every point of ``wall_points`` (points of the wall ``psi = 0``, see
    :func:`points_on_wall`; ``g`` and ``dpsi`` in the velocity basis scale the test of
    ``C^00`` there).

    The first block ``C^{00} = g(P grad psi, P grad psi)`` vanishes iff ``d psi`` lies in
    the span of the permanent constraints (then the wall cannot stop any motion allowed by
    them).  Otherwise the first impulsive constraint whose leading block of C is singular is
    reported as dependent on ``d psi``, the permanent constraints and the preceding
    impulsive constraints.
    """
    v = sp.Matrix(velocities)

    def form(row: sp.MatrixBase) -> str:
        return _short(limits.expand_affordable((sp.Matrix(row) * v)[0, 0]))

    perm = [form(mu[a, :]) for a in range(mu.rows)]
    if is_zero(C[0, 0], points) is True:
        raise _in_span(wall, f"the gradient of psi = {_short(psi)}", perm, "")
    k = C.rows
    verdicts = [v for v in (_singular_blocks(C, point) for point in points) if v is not None]
    for j in range(1, k if verdicts else 1):
        if all(v[j] for v in verdicts):
            symbolic = (
                sp.simplify(C[: j + 1, : j + 1].det())
                if sp.count_ops(C[: j + 1, : j + 1]) <= _SYMBOLIC_OPS
                else None
            )
            if symbolic is not None and symbolic.is_number and symbolic != 0:
                continue
            raise _dependent(
                wall,
                f"the impulsive constraint nu^{j} = {form(nu[j - 1, :])}",
                perm,
                f"rank < {j + 1} at every sampled point",
                "drop it (as Carnot paper Example 3.13 drops omega_y)",
            )
    _check_on_the_wall(C, wall, psi, perm, nu, form, g, dpsi, wall_points)


def _in_span(wall: str, what: str, perm: list[str], where: str) -> ImpactError:
    """d psi in the span of the permanent constraints (everywhere, or ``where``)."""
    return ImpactError(
        f"wall {wall!r}: {what} lies in the span of the permanent constraints {perm}"
        f" (C = g(P grad psi, P grad psi) = 0{where}, Carnot paper eq. 7): every motion"
        " allowed by the constraints is tangent to the wall there, so no impact map exists"
    )


def _dependent(wall: str, what: str, perm: list[str], rank: str, remedy: str) -> ImpactError:
    """An impulsive constraint dependent on d psi and the constraints before it."""
    return ImpactError(
        f"wall {wall!r}: {what} is linearly dependent on d psi, the permanent constraints"
        f" {perm} and the preceding impulsive constraints (the Gram matrix"
        f" C^AB = g(P Y^A, P Y^B) has {rank}); {remedy}"
    )


def _check_on_the_wall(
    C: sp.MatrixBase,
    wall: str,
    psi: sp.Expr,
    perm: list[str],
    nu: sp.MatrixBase,
    form: Callable[[sp.MatrixBase], str],
    g: sp.MatrixBase | None,
    dpsi: sp.MatrixBase | None,
    wall_points: Sequence[dict],
) -> None:
    """The part of :func:`check_regular` on the wall: C singular at every point found on
    it (at least two) refuses the wall."""
    if len(wall_points) < 2:
        return

    def where(point: dict) -> str:
        items = sorted(point.items(), key=lambda kv: str(kv[0]))
        shown = ", ".join(f"{k}={sp.N(v, 6)}" for k, v in items if psi.has(k))
        return "{" + shown + "}"

    if g is not None and dpsi is not None and perm:
        ratios = [_wall_gradient_ratio(C[0, 0], g, dpsi, p) for p in wall_points]
        known = [(r, p) for r, p in zip(ratios, wall_points, strict=True) if r is not None]
        if len(known) >= 2 and all(abs(r) < HADAMARD_TOLERANCE for r, _ in known):
            raise _in_span(
                wall,
                f"on the wall psi = {_short(psi)} = 0 the gradient of psi",
                perm,
                f" at every point of the wall sampled, e.g. {where(known[0][1])}",
            )
    k = C.rows
    if k == 1:
        return
    verdicts = [v for v in (_singular_blocks(C, p) for p in wall_points) if v is not None]
    if len(verdicts) < 2:
        return
    for j in range(1, k):
        # the first block that becomes singular names the culprit (a singular C^00 with no
        # permanent constraints means d psi = 0 there, not a dependent nu)
        if all(v[j] for v in verdicts) and not all(v[j - 1] for v in verdicts):
            raise _dependent(
                wall,
                f"on the wall psi = {_short(psi)} = 0 the impulsive constraint"
                f" nu^{j} = {form(nu[j - 1, :])}",
                perm,
                f"rank < {j + 1} at every point of the wall sampled, e.g. {where(wall_points[0])}",
                "drop it or write it so that it is independent where the impact happens",
            )


#: Expressions with more operations than this are not factored (kept whole) and closed
#: forms with more are not scanned for denominators (see :func:`singular_set`).
FACTOR_MAX_OPS = limits.SINGULAR_FACTOR_OPS

Description = str | Callable[[sp.Expr], str]


def _factors(expr: sp.Expr) -> list[sp.Expr]:
    """The non-constant irreducible factors of the numerator of ``expr`` (the numerator
    itself, with its numeric content removed, when it is too large to factor)."""
    expr = sp.sympify(expr, strict=True)
    if not limits.affordable(expr, FACTOR_MAX_OPS):
        num = sp.fraction(sp.together(expr))[0]
        return [sp.factor_terms(num).as_coeff_Mul()[1]] if num.free_symbols else []
    expr = sp.cancel(sp.together(expr))
    num, _ = sp.fraction(expr)
    try:
        _, facs = sp.factor_list(num)
    except sp.PolynomialError:  # pragma: no cover
        return [num]
    return [f for f, _ in facs if f.free_symbols]


def _divides(f: sp.Expr, e: sp.Expr) -> bool:
    """True if the polynomial f divides the numerator of e (exact polynomial division over
    the generators of both; False when either is not a polynomial or too large)."""
    if sp.count_ops(f) > FACTOR_MAX_OPS or sp.count_ops(e) > FACTOR_MAX_OPS:
        return f == e or (
            limits.expanded_terms(f - e, limits.EXPAND_TERMS + 1)[0] <= limits.EXPAND_TERMS
            and sp.expand(f - e) == 0
        )
    if not (limits.affordable(f, FACTOR_MAX_OPS) and limits.affordable(e, FACTOR_MAX_OPS)):
        return f == e
    num = sp.fraction(sp.together(e))[0]
    try:
        pf, pe = sp.parallel_poly_from_expr([f, num])[0]
    except (sp.PolynomialError, sp.GeneratorsNeeded):
        return False
    if pf.is_zero:
        return False
    return pe.rem(pf).is_zero


def pythagorean(f: sp.Expr) -> sp.Expr:
    """f with ``sin(u)^2`` replaced by ``1 - cos(u)^2`` wherever both ``sin(u)`` and
    ``cos(u)`` occur (the remainder modulo ``sin(u)^2 + cos(u)^2 - 1``, degree <= 1 in
    each such sin(u)); f itself when it is not small or not polynomial in them."""
    f = sp.sympify(f, strict=True)
    if not limits.affordable(f, FACTOR_MAX_OPS):
        return f
    sines = {e.args[0]: e for e in f.atoms(sp.sin)}
    for cos in f.atoms(sp.cos):
        sin = sines.get(cos.args[0])
        if sin is None:
            continue
        try:
            f = sp.expand(sp.rem(f, sin**2 + cos**2 - 1, sin))
        except sp.PolynomialError:  # pragma: no cover - f not polynomial in sin(u)
            return f
    return f


def _positive_on_the_circle(f: sp.Expr) -> bool:
    """``f = p cos(u)^2 + q sin(u)^2 + r`` with p, q > 0 and r >= 0 (from the symbols'
    assumptions): then ``f >= min(p, q) > 0`` (e.g. ``a^2 cos^2 + b^2 sin^2``)."""
    for cos in f.atoms(sp.cos):
        sin = sp.sin(cos.args[0])
        if not f.has(sin):
            continue
        try:
            poly = sp.Poly(f, cos, sin)
        except sp.PolynomialError:
            continue
        terms = dict(poly.terms())
        if set(terms) - {(2, 0), (0, 2), (0, 0)} or (2, 0) not in terms or (0, 2) not in terms:
            continue
        p, q, r = terms[(2, 0)], terms[(0, 2)], terms.get((0, 0), sp.S.Zero)
        if p.is_positive and q.is_positive and r.is_nonnegative and cos.args[0].is_real:
            return True
    return False


def no_real_zeros(f: sp.Expr) -> bool:
    """True if f provably has no real zero: from the symbols' assumptions (``k**2 + r**2``
    with positive k, a sum of squares plus a positive constant), or f is a polynomial in
    one real symbol with no real root, or in one ``sin(u)``/``cos(u)`` (u real) with no
    root in [-1, 1] (counted exactly by Sturm sequences)."""
    f = sp.sympify(f, strict=True)
    if f == 0:
        return False
    if not f.free_symbols or f.is_nonzero:
        return True
    if limits.expanded_terms(f, limits.EXPAND_TERMS + 1)[0] > limits.EXPAND_TERMS:
        return False  # no verdict: the factor is kept
    if _positive_on_the_circle(f):
        return True
    try:
        poly = sp.Poly(f)
    except sp.PolynomialError:
        return False
    if len(poly.gens) != 1 or not poly.domain.is_Exact or poly.degree() < 1:
        return False
    (gen,) = poly.gens
    try:
        if gen.is_Symbol and gen.is_real:
            return poly.count_roots() == 0
        if isinstance(gen, (sp.sin, sp.cos)) and gen.args[0].is_real:
            return poly.count_roots(-1, 1) == 0
    except (sp.PolynomialError, NotImplementedError):  # pragma: no cover
        # count_roots is not implemented over some domains: no verdict, keep the factor
        return False
    return False


def singular_set(
    structural: Iterable[tuple[sp.Expr, Description]],
    closed_form: Iterable[sp.Expr] = (),
    closed_form_description: str = "",
) -> list[Singularity]:
    """Collect the singular set: the factors of the ``structural`` expressions first (each
    with its description; a callable description receives the factor), then the factors
    of the denominators of ``closed_form`` entries not already covered (entries above
    :data:`FACTOR_MAX_OPS` operations are not scanned: pass the structural denominators
    of the construction instead).

    Factors with provably no real zero (:func:`no_real_zeros`: ``k**2 + r**2`` with
    positive k, r; ``5 x^2 + x + 5``) are dropped; every kept factor is an expression in
    q, t, the parameters (and, for the energy law, the velocities).
    """
    out: list[Singularity] = []
    seen: list[sp.Expr] = []

    def add(f: sp.Expr, description: Description) -> None:
        reduced = pythagorean(f)
        if not reduced.free_symbols or no_real_zeros(reduced) or no_real_zeros(f):
            return
        if sp.count_ops(reduced) < sp.count_ops(f):
            f = reduced
        if limits.affordable(f, FACTOR_MAX_OPS):
            f = sp.factor(f)
        if any(_divides(f, s) or _divides(s, f) for s in seen):
            return
        seen.append(f)
        text = description(f) if callable(description) else description
        out.append(Singularity(f, text))

    for expr, description in structural:
        for f in _factors(expr):
            add(f, description)
    for expr in closed_form:
        if expr.is_number or not limits.affordable(expr, FACTOR_MAX_OPS):  # numbers: none
            continue
        den = sp.fraction(sp.cancel(sp.together(expr)))[1]
        for f in _factors(den):
            add(f, closed_form_description)
    return out


def _divides_row(f: sp.Expr, row: Sequence[sp.Expr]) -> bool:
    entries = [e for e in row if e != 0]
    return bool(entries) and all(_divides(f, e) for e in entries)


def impact_singularities(
    proj: ImpactProjectors,
    psi_t: sp.Expr,
    default_velocity: bool,
    extra: Sequence[sp.Expr] = (),
    closed_form: Sequence[sp.Expr] = (),
    also_scan: Sequence[sp.Expr] = (),
) -> list[Singularity]:
    """The singular set of an impact map built from ``proj``.

    Its denominators are those of the construction: the metric (det g), the permanent
    Gram matrix (the bordered determinant d1), the Gram matrix C^AB of the wall and the
    impulsive constraints (its determinant; where it is a factor of every entry of d psi
    the description says so, for then d psi itself vanishes), ``g(grad psi, grad psi)``
    for the default wall velocity of a moving wall, and the denominators of the inputs
    (entries of g, d psi, nu, psi_t and the ``extra`` expressions, e.g. a given wall
    velocity).  These are the shared denominators of the adjugate route
    (:mod:`symmech.impacts.adjugate_projectors`; formed here when another route built ``proj``), and
    the list is then complete; only when the entries admit no rational-function field are
    they formed by sympy determinants and the small entries of ``closed_form`` scanned.
    The small entries of ``also_scan`` (e.g. the weights of the energy law, which divide
    by pivots of C^AB) are always scanned.
    """
    dpsi = list(proj.dpsi)
    l = proj.nu.rows
    gradient_vanishes = (
        "d psi = 0: the gradient of the wall function vanishes here, so psi = 0 is not a"
        " regular wall (Carnot paper section 3.1 assumes d psi != 0 along N)"
    )

    def gram(f: sp.Expr) -> str:
        if _divides_row(f, dpsi) or (l == 0 and proj.mu.rows == 0):
            # without constraints C = g(grad psi, grad psi) vanishes only where d psi does
            return gradient_vanishes
        if l == 0:
            return (
                "det C^AB = C = g(P grad psi, P grad psi) = 0 (Carnot paper eq. 7): d psi lies"
                " in the span of the permanent constraints here, so every allowed motion is"
                " tangent to the wall"
            )
        return (
            "det C^AB = 0 (Carnot paper eq. 7, section 3.2): d psi and the impulsive"
            " constraints become dependent modulo the permanent constraints"
        )

    def normal(f: sp.Expr) -> str:
        if _divides_row(f, dpsi):
            return gradient_vanishes
        return "g(grad psi, grad psi) = 0 in the default wall velocity"

    metric = "the metric g (velocity basis) is singular: g^-1 and Y^A = g^-1 nu^A undefined"
    permanent = "the permanent constraints become dependent (mu g^-1 mu^T singular)"
    inputs = "denominator of the closed form (derivatives of psi, the metric or the frame)"
    structural: list[tuple[sp.Expr, Description]] = []
    dens = proj.denominators
    g = sp.Matrix(proj.g)
    if dens is None:  # the sympy route: the same denominators, formed cheaply if possible
        dens = shared_denominators(g, sp.Matrix(proj.mu), sp.Matrix(proj.dpsi), sp.Matrix(proj.nu))
    complete = dens is not None
    # without constraints C^00 = g(grad psi, grad psi) > 0 wherever some component of
    # d psi provably never vanishes
    nonvanishing = any(no_real_zeros(e) for e in dpsi)
    never_tangent = l == 0 and proj.mu.rows == 0 and nonvanishing
    if dens is not None:
        structural.append((dens.metric, metric))
        if dens.permanent is not None:
            structural.append((dens.permanent, permanent))
        if not never_tangent:
            structural.append((dens.gram, gram))
    else:
        with dotprodsimp(False):  # no simplification inside sympy's determinants
            if not all(e.is_number for e in g):
                structural.append((g.det(method="berkowitz"), metric))
            mu = sp.Matrix(proj.mu)
            if mu.rows and not all(e.is_number for e in mu * sp.Matrix(proj.Y)):
                structural.append((sp.Matrix(mu * g.LUsolve(mu.T)).det(), permanent))
            if not never_tangent:
                structural.append((sp.Matrix(proj.C).det(method="berkowitz"), gram))
    if sp.sympify(psi_t, strict=True) != 0 and default_velocity and not nonvanishing:
        structural.append(((sp.Matrix(proj.dpsi) * sp.Matrix(proj.grad_psi))[0, 0], normal))
    for e in [*g, *proj.dpsi, *proj.nu, *proj.mu, psi_t, *extra]:
        den = sp.fraction(sp.together(e))[1]
        if den.free_symbols:
            structural.append((den, inputs))
    scanned = [*(() if complete else closed_form), *also_scan]
    return singular_set(structural, scanned, inputs)
