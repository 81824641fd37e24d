"""Carnot's theorem and its extensions (Carnot paper 002, Theorems 3.2, 3.6, 3.9, 3.11,
4.1, 4.3), as residuals that vanish identically.

For the Newton map ``v+ = (PP - alpha T~) v- + offset`` (see :mod:`symmech.impacts.newton`)
and a pre-impact velocity x, write ``x' = x - W`` (W = 0 for a static wall) and

    T0 = T(x), T1 = T(v+), T_l = T(v+ - x)                       (energies, T = 1/2 g)
    T0' = T(x - W), T1' = T(v+ - W)                              (relative to the wall)
    C = id - PP - T~,  T_C = T(C x'),  cross = g(T~ x', C x')

The theorem used is the most specific one that applies:

=====================  =========================================================  ==========
theorem                residual (``lhs - rhs``)                                     when
=====================  =========================================================  ==========
3.2 (standard)         ``T1 - T0 + (1-a)/(1+a) T_l``                               static, l = 0
3.6                    same                                                        static, l > 0,
                                                                                   ``restrict=True``
3.11                   ``T1 - T0 + (1-a)/(1+a) T_l + 2a/(1+a) T_C``                static, l > 0,
                                                                                   P(Y^0) in F
3.9 (extended)         ``... + 2a/(1+a) T_C + a cross``                            static, l > 0
4.1                    ``T1' - T0' + (1-a)/(1+a) T_l``                             moving, l = 0
4.3 (P(Y^0) in F)      ``T1' - T0' + (1-a)/(1+a) T_l + 2a/(1+a) T_C'``             moving, l > 0
4.3 (extended)         ``... + a cross'``                                          moving, l > 0
=====================  =========================================================  ==========

The pre-impact velocity is the general element of D, ``x = P v`` (v the velocity
symbols), so the residual vanishing is the statement "for every v- in D".  With
``restrict=True`` it is the general element of ``(Im PP (+) Im T~) cap D``,
``x = (PP + T~) P v`` (``PP + T~`` is a projector: Lemma 3.5), where T_C = 0 and
Theorem 3.6 applies; for a moving wall the approach velocity is restricted instead,
``x = W + (PP + T~) P v``, and 4.3 reduces to the form of 4.1.  "P(Y^0) in F" is decided
by checking ``nu P(Y^0) = 0`` (symbolically when small, else by exact evaluation); when
undecided the general Theorem 3.9/4.3 is used, which is valid in every case.

Deciding "the residual is identically zero", by cost (:attr:`CarnotResult.route`):

* ``"fraction field"``: when the map is small (at most
  :data:`symmech.algebra.budget.CARNOT_FIELD_OPS` operations in the matrices involved), the
  residual is formed in the fraction field of the entries (:mod:`symmech.algebra.energy_forms`),
  each velocity coefficient cancelled (small ones also simplified, for trigonometric
  relations): a proof;
* ``"exact evaluation"``: otherwise the residual, multiplied by ``1 + alpha``, is
  evaluated exactly in rational arithmetic at a random point, with a degree bound
  (:mod:`symmech.algebra.identity`, Schwartz-Zippel: the probability of a wrong "holds"
  is below 1e-13; :attr:`CarnotResult.error_bound` gives the bound).  The symbolic
  residual is formed only on request (:meth:`CarnotResult.symbolic_residual`,
  :attr:`CarnotResult.terms`);
* ``"symbolic"``: when the evaluation cannot decide (a building block it cannot evaluate
  exactly, or a non-zero value in a model with radicals), the fraction-field residual
  decides, whatever its size.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from fractions import Fraction
from typing import Any

import sympy as sp

from symmech.algebra import budget as limits
from symmech.algebra.budget import BudgetExceeded
from symmech.algebra.energy_forms import Affine, QuadraticForm
from symmech.algebra.field import common_domain
from symmech.algebra.identity import Unsupported, identically_zero
from symmech.algebra.zero import is_zero
from symmech.declaration.latex import latex_text
from symmech.impacts.impact_projectors import ImpactProjectors

__all__ = ["CarnotResult", "SparseEvaluation", "carnot_residual", "decide_identity"]

Formed = tuple[sp.Expr, dict[str, sp.Expr], sp.ImmutableMatrix]


class CarnotResult:
    """The residual of the Carnot theorem that applies to an impact map.

    ``theorem`` names it (e.g. ``"Theorem 3.11"``), ``statement`` gives the identity,
    ``holds`` says whether the residual ``lhs - rhs`` is identically zero, ``route`` how
    that was decided (module docstring), ``error_bound`` the probability that ``holds``
    is wrong (0 for a proof) and ``detail`` the degree bound and sample size of an exact
    evaluation.  ``residual`` is 0 when the theorem holds, else the symbolic residual (each
    velocity coefficient cancelled); :meth:`symbolic_residual` always forms the symbolic
    residual, ``terms`` holds T0, T1, T_l (and T0', T1', T_C, cross where used) and
    ``pre_velocity`` the parametrised pre-impact velocity (formed on first access).
    ``tuple(result)`` unpacks to ``(theorem, residual)``.
    """

    def __init__(
        self,
        theorem: str,
        statement: str,
        holds: bool,
        route: str,
        error_bound: Fraction,
        symbolic: Callable[[], Formed],
        detail: str = "",
        formed: Formed | None = None,
    ):
        self.theorem, self.statement = theorem, statement
        self.holds, self.route, self.error_bound, self.detail = holds, route, error_bound, detail
        self._symbolic = symbolic
        self._formed_cache = formed

    def _formed(self) -> Formed:
        if self._formed_cache is None:
            self._formed_cache = self._symbolic()
        return self._formed_cache

    @property
    def residual(self) -> sp.Expr:
        """0 if the theorem holds, else the symbolic residual (formed on first access)."""
        return sp.S.Zero if self.holds else self._formed()[0]

    def symbolic_residual(self) -> sp.Expr:
        """``lhs - rhs`` formed in the fraction field, each velocity coefficient cancelled
        (and simplified when small); may be expensive for large maps."""
        return self._formed()[0]

    @property
    def terms(self) -> dict[str, sp.Expr]:
        """T0, T1, T_l (and T0', T1', T_C, cross where used), formed on first access."""
        return self._formed()[1]

    @property
    def pre_velocity(self) -> sp.ImmutableMatrix:
        """The parametrised pre-impact velocity x (module docstring)."""
        return self._formed()[2]

    def __iter__(self):
        return iter((self.theorem, self.residual))

    def __repr__(self) -> str:
        return (
            f"CarnotResult({self.theorem!r}, holds={self.holds}, route={self.route!r},"
            f" error_bound={float(self.error_bound):.1e})"
        )

    def simplified(self) -> sp.Expr:
        """``sympy.simplify`` of the residual (for residuals with trigonometric terms)."""
        return sp.simplify(self.residual)

    def is_zero(self) -> bool:
        """True if the theorem holds (the residual is identically zero)."""
        return self.holds

    def _repr_latex_(self) -> str:
        return (
            f"$\\text{{{latex_text(self.theorem)}: }} {self.statement_latex()}"
            f"\\quad\\text{{residual }} = {sp.latex(self.residual)}$"
        )

    def statement_latex(self) -> str:
        """The statement with T_1 / T_0 / alpha written as LaTeX."""
        text = self.statement
        for plain, tex in (
            ("alpha", "\\alpha"),
            ("T1'", "T_1'"),
            ("T0'", "T_0'"),
            ("T1", "T_1"),
            ("T0", "T_0"),
            ("T_l", "T_l"),
        ):
            text = text.replace(plain, tex)
        return text


def _is_zero_entry(e: sp.Expr) -> bool:
    """``e`` identically zero (:func:`symmech.algebra.zero.is_zero`; an undecided verdict
    counts as non-zero: the general theorem then applies)."""
    return is_zero(e) is True


def _in_F(proj: ImpactProjectors) -> bool:
    """``P(Y^0) in F``, i.e. ``C^{A0} = nu^A(P Y^0) = 0`` for A >= 1 (Lemma 3.10)."""
    col = sp.Matrix(proj.nu) * sp.Matrix(proj.PY[:, 0])
    return all(_is_zero_entry(e) for e in col)


def _size(matrices: Sequence[sp.MatrixBase]) -> int:
    return int(sum(sp.count_ops(e) for M in matrices for e in M if not e.is_number))


def carnot_residual(
    proj: ImpactProjectors,
    matrix: sp.MatrixBase,
    offset: sp.MatrixBase,
    W: sp.MatrixBase,
    alpha: sp.Expr,
    velocities: Sequence[sp.Symbol],
    moving: bool,
    restrict: bool = False,
) -> CarnotResult:
    """Residual of the applicable Carnot theorem (see the module docstring for the table
    and for how "identically zero" is decided)."""
    a = sp.sympify(alpha, strict=True)
    l = proj.nu.rows
    matrix, offset, W = sp.Matrix(matrix), sp.Matrix(offset), sp.Matrix(W)
    prime = "'" if moving else ""
    lhs_s = "T1' - T0'" if moving else "T1 - T0"
    if l == 0 or restrict:
        kind = "loss"
        statement = f"{lhs_s} = -(1-alpha)/(1+alpha) T_l"
        if moving:
            theorem = "Theorem 4.1" if l == 0 else "Theorem 4.3 (velocities in Im PP + Im T~)"
        else:
            theorem = "Theorem 3.2" if l == 0 else "Theorem 3.6"
    else:
        statement = f"{lhs_s} = -(1-alpha)/(1+alpha) T_l - 2 alpha/(1+alpha) T_C{prime}"
        if _in_F(proj):
            kind = "T_C"
            theorem = "Theorem 4.3 (P(Y0) in F)" if moving else "Theorem 3.11"
        else:
            kind = "cross"
            statement += f" - alpha g(T~ x{prime}, C x{prime})"
            theorem = "Theorem 4.3" if moving else "Theorem 3.9"
    setup = _Setup(proj, matrix, offset, W, a, tuple(velocities), moving, restrict, kind)

    def symbolic() -> Formed:
        return _symbolic(setup)

    small = _size([proj.g, proj.P, proj.PP, proj.T, matrix, offset, W]) <= limits.CARNOT_FIELD_OPS
    return decide_identity(theorem, statement, symbolic, setup.evaluate, small)


def decide_identity(
    theorem: str,
    statement: str,
    symbolic: Callable[[], Formed],
    evaluate: Callable[..., Any],
    small: bool,
) -> CarnotResult:
    """Decide whether a Carnot residual is identically zero, cheapest route first: the
    residual formed in the fraction field (``small``: its inputs within
    :data:`symmech.algebra.budget.CARNOT_FIELD_OPS`, and within its time budget), else
    exact evaluation at sample points (:func:`symmech.algebra.identity.identically_zero`
    with ``evaluate``), else the symbolic residual."""
    if small:
        formed = _bounded(symbolic)
        if formed is not None and formed[0] == 0:
            return CarnotResult(
                theorem, statement, True, "fraction field", Fraction(0), symbolic, formed=formed
            )
    try:
        verdict = identically_zero(evaluate)
    except (Unsupported, ZeroDivisionError):
        verdict = None
    if verdict is not None and (verdict.zero or verdict.model_exact):
        return CarnotResult(
            theorem,
            statement,
            verdict.zero,
            "exact evaluation",
            verdict.error_bound,
            symbolic,
            verdict.describe(),
        )
    formed = symbolic()
    return CarnotResult(
        theorem, statement, formed[0] == 0, "symbolic", Fraction(0), symbolic, formed=formed
    )


def _bounded(symbolic: Callable[[], Formed]) -> Formed | None:
    """The fraction-field residual within :data:`symmech.algebra.budget.CARNOT_FIELD_SECONDS`
    (None when over it: the exact evaluation decides instead).  The operation count does
    not bound the gcds of the field's additions, which grow with its generators (a wall
    with sin and cos of six arguments has twelve)."""
    stage = "Carnot residual (fraction field)"
    try:
        with limits.time_limit(stage, limits.CARNOT_FIELD_SECONDS, "CARNOT_FIELD_SECONDS"):
            return symbolic()
    except BudgetExceeded as exc:
        if exc.budget != "CARNOT_FIELD_SECONDS":
            raise
        return None


class SparseEvaluation:
    """Matrix-vector arithmetic over the values ``value(entry)`` of sympy matrices, with
    structurally zero entries skipped (the residual evaluations that
    :func:`~symmech.algebra.identity.identically_zero` runs in exact or interval
    arithmetic); ``const`` makes a constant of that arithmetic."""

    def __init__(self, value: Callable[[sp.Expr], Any], const: Callable[[Any], Any]):
        self.value, self.const = value, const

    def matrix(self, M: sp.MatrixBase) -> list[list[Any]]:
        return [[None if e == 0 else self.value(e) for e in M.row(i)] for i in range(M.rows)]

    def dot(self, x: list[Any], y: list[Any]) -> Any:
        acc = self.const(0)
        for xi, yi in zip(x, y, strict=True):
            if xi is not None:
                acc = acc + xi * yi
        return acc

    def apply(self, M: list[list[Any]], x: list[Any]) -> list[Any]:
        return [self.dot(row, x) for row in M]

    @staticmethod
    def add(x: list[Any], y: list[Any]) -> list[Any]:
        return [xi + yi for xi, yi in zip(x, y, strict=True)]

    @staticmethod
    def sub(x: list[Any], y: list[Any]) -> list[Any]:
        return [xi - yi for xi, yi in zip(x, y, strict=True)]


class _Setup:
    """The data of one Carnot check, with the residual built two ways: symbolically in the
    fraction field (:func:`_symbolic`) and over any scalar arithmetic (:meth:`evaluate`,
    for :func:`~symmech.algebra.identity.identically_zero`)."""

    def __init__(self, proj, matrix, offset, W, alpha, velocities, moving, restrict, kind):
        self.proj, self.matrix, self.offset, self.W = proj, matrix, offset, W
        self.alpha, self.velocities = alpha, velocities
        self.moving, self.restrict, self.kind = moving, restrict, kind

    def evaluate(self, value: Callable[[sp.Expr], Any], const: Callable[[Any], Any]) -> Any:
        """``(1 + alpha) (lhs - rhs)`` as one scalar, built with + - * from ``value`` of
        the entries (structurally zero entries are skipped)."""
        p = self.proj

        ev = SparseEvaluation(value, const)
        mat, dot, apply, add, sub = ev.matrix, ev.dot, ev.apply, ev.add, ev.sub

        g = mat(p.g)

        def energy(y: list[Any]) -> Any:
            return dot(y, apply(g, y)) * const(Fraction(1, 2))

        v = [value(s) for s in self.velocities]
        PP, T = mat(p.PP), mat(p.T)
        W = [value(e) for e in self.W]
        x = apply(mat(p.P), v)
        if self.restrict:
            x = add(apply(PP, x), apply(T, x))
            if self.moving:
                x = add(x, W)
        xp = add(apply(mat(self.matrix), x), [value(e) for e in self.offset])
        a, one = value(self.alpha), const(1)
        if self.moving:
            lhs = energy(sub(xp, W)) - energy(sub(x, W))
        else:
            lhs = energy(xp) - energy(x)
        # the identity times (1 + alpha): no division by 1 + alpha
        total = lhs * (one + a) + (one - a) * energy(sub(xp, x))
        if self.kind == "loss":
            return total
        x_rel = sub(x, W) if self.moving else x
        Tx = apply(T, x_rel)
        Cx = sub(sub(x_rel, apply(PP, x_rel)), Tx)
        total = total + const(2) * a * energy(Cx)
        if self.kind == "T_C":
            return total
        return total + a * (one + a) * dot(Tx, apply(g, Cx))


def _symbolic(s: _Setup) -> Formed:
    """The residual, the terms and the pre-impact velocity in the fraction field."""
    proj, a = s.proj, s.alpha
    n = proj.g.rows
    v = sp.Matrix(s.velocities)
    zero = sp.zeros(n, 1)
    k_loss, k_c = (1 - a) / (1 + a), 2 * a / (1 + a)
    ring = common_domain(
        [proj.g, proj.P, proj.PP, proj.T, s.matrix, s.offset, s.W], [a, k_loss, k_c]
    )
    g, PP, Tt = (ring.matrix(M) for M in (proj.g, proj.PP, proj.T))
    x = Affine.of(ring, sp.Matrix(proj.P), zero)
    if s.restrict:
        x = x.apply(PP + Tt)
        if s.moving:
            x = x.shift(ring.matrix(s.W))
    xp = x.apply(ring.matrix(s.matrix)).shift(ring.matrix(s.offset))  # v+
    Wd = ring.matrix(s.W)

    def energy(y: Affine) -> QuadraticForm:
        return QuadraticForm.energy(g, y)

    T0, T1, Tl = energy(x), energy(xp), energy(xp - x)
    terms: dict[str, QuadraticForm] = {"T0": T0, "T1": T1, "T_l": Tl}
    if s.moving:
        T0r, T1r = energy(x.shift(-Wd)), energy(xp.shift(-Wd))
        terms.update({"T0'": T0r, "T1'": T1r})
        lhs = T1r - T0r
    else:
        lhs = T1 - T0
    prime = "'" if s.moving else ""
    x_rel = x.shift(-Wd) if s.moving else x
    C_x = x_rel.apply(ring.matrix(sp.eye(n)) - PP - Tt)
    rhs = Tl.scale(-k_loss)
    if s.kind != "loss":
        TC = energy(C_x)
        terms[f"T_C{prime}"] = TC
        rhs = rhs - TC.scale(k_c)
        if s.kind == "cross":
            cross = QuadraticForm.bilinear(g, x_rel.apply(Tt), C_x)
            terms[f"cross{prime}"] = cross
            rhs = rhs - cross.scale(a)
    return (
        (lhs - rhs).expr(v, simplify=True),
        {name: q.expr(v) for name, q in terms.items()},
        sp.ImmutableMatrix(x.to_sympy(v).applyfunc(limits.expand_affordable)),
    )
