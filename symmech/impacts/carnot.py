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
``x = W + (PP + T~) P v``, and 4.3 reduces to the form of 4.1.  "P(Y^0) in F" is decided by checking
``nu P(Y^0) = 0`` symbolically; when undecided the general Theorem 3.9/4.3 is used, which
is valid in every case.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import sympy as sp

from symmech.impacts.projectors import ImpactProjectors
from symmech.impacts.quadratic import Affine, QuadraticForm, common_domain

__all__ = ["CarnotResult", "carnot_residual"]


@dataclass(frozen=True)
class CarnotResult:
    """The residual of the Carnot theorem that applies to an impact map.

    ``theorem`` names it (e.g. ``"Theorem 3.11"``), ``statement`` gives the identity,
    ``residual`` is ``lhs - rhs`` (each velocity coefficient cancelled; zero iff the
    theorem holds),
    ``terms`` holds T0, T1, T_l (and T0', T1', T_C, cross where used) and
    ``pre_velocity`` the parametrised pre-impact velocity.  ``tuple(result)`` unpacks to
    ``(theorem, residual)``.
    """

    theorem: str
    statement: str
    residual: sp.Expr
    terms: dict[str, sp.Expr] = field(default_factory=dict)
    pre_velocity: sp.ImmutableMatrix | None = None

    def __iter__(self):
        return iter((self.theorem, self.residual))

    def simplified(self) -> sp.Expr:
        """``sympy.simplify`` of the residual (for residuals with trigonometric terms)."""
        return sp.simplify(self.residual)

    def is_zero(self) -> bool:
        """True if the residual simplifies to 0."""
        return self.residual == 0 or self.simplified() == 0

    def _repr_latex_(self) -> str:
        return (
            f"$\\text{{{self.theorem}: }} {self.statement_latex()}"
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


def _in_F(proj: ImpactProjectors) -> bool:
    """``P(Y^0) in F``, i.e. ``C^{A0} = nu^A(P Y^0) = 0`` for A >= 1 (Lemma 3.10)."""
    col = sp.Matrix(proj.nu) * sp.Matrix(proj.PY[:, 0])
    return all(sp.simplify(e) == 0 for e in col)


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
    """Residual of the applicable Carnot theorem (see the module docstring for the table)."""
    n = proj.g.rows
    a = sp.sympify(alpha)
    v = sp.Matrix(velocities)
    l = proj.nu.rows
    zero = sp.zeros(n, 1)
    W = sp.Matrix(W)
    k_loss, k_c = (1 - a) / (1 + a), 2 * a / (1 + a)
    ring = common_domain([proj.g, proj.P, proj.PP, proj.T, matrix, offset, W], [a, k_loss, k_c])
    g, PP, Tt = (ring.matrix(M) for M in (proj.g, proj.PP, proj.T))
    # the pre-impact velocity x = L v + o: the general element of D (or of the restriction)
    x = Affine.of(ring, sp.Matrix(proj.P), zero)
    if restrict:
        x = x.apply(PP + Tt)
        if moving:
            x = x.shift(ring.matrix(W))
    xp = x.apply(ring.matrix(matrix)).shift(ring.matrix(offset))  # v+
    Wd = ring.matrix(W)

    def energy(y: Affine) -> QuadraticForm:
        return QuadraticForm.energy(g, y)

    T0, T1, Tl = energy(x), energy(xp), energy(xp - x)
    terms: dict[str, QuadraticForm] = {"T0": T0, "T1": T1, "T_l": Tl}
    if moving:
        T0r, T1r = energy(x.shift(-Wd)), energy(xp.shift(-Wd))
        terms.update({"T0'": T0r, "T1'": T1r})
        lhs, lhs_s = T1r - T0r, "T1' - T0'"
    else:
        lhs, lhs_s = T1 - T0, "T1 - T0"
    x_rel = x.shift(-Wd) if moving else x
    C_x = x_rel.apply(ring.matrix(sp.eye(n)) - PP - Tt)
    prime = "'" if moving else ""
    if l == 0 or restrict:
        rhs = Tl.scale(-k_loss)
        statement = f"{lhs_s} = -(1-alpha)/(1+alpha) T_l"
        if moving:
            theorem = "Theorem 4.1" if l == 0 else "Theorem 4.3 (velocities in Im PP + Im T~)"
        else:
            theorem = "Theorem 3.2" if l == 0 else "Theorem 3.6"
    else:
        TC = energy(C_x)
        terms[f"T_C{prime}"] = TC
        rhs = Tl.scale(-k_loss) - TC.scale(k_c)
        statement = f"{lhs_s} = -(1-alpha)/(1+alpha) T_l - 2 alpha/(1+alpha) T_C{prime}"
        if _in_F(proj):
            theorem = "Theorem 4.3 (P(Y0) in F)" if moving else "Theorem 3.11"
        else:
            cross = QuadraticForm.bilinear(g, x_rel.apply(Tt), C_x)
            terms[f"cross{prime}"] = cross
            rhs = rhs - cross.scale(a)
            statement += f" - alpha g(T~ x{prime}, C x{prime})"
            theorem = "Theorem 4.3" if moving else "Theorem 3.9"
    return CarnotResult(
        theorem=theorem,
        statement=statement,
        residual=(lhs - rhs).expr(v, simplify=True),
        terms={name: q.expr(v) for name, q in terms.items()},
        pre_velocity=sp.ImmutableMatrix(x.to_sympy(v).applyfunc(sp.expand)),
    )
