"""The impact projectors by adjugates: exact, fraction-free, one shared denominator each.

Inverting the Gram matrix ``C^{AB}`` (and the metric) in the fraction field K of the
entries cancels a multivariate gcd at every elimination step; on a 3-DOF wall with a few
trigonometric terms that alone took minutes.  Here every inverse is a closed form
``adj(M) / det(M)`` computed in the polynomial ring R of K, where nothing is cancelled
on the way, and each object of the Carnot paper (002) is assembled as a polynomial
matrix over one shared polynomial denominator.  With the input denominators cleared
(``g = Gr / gamma``, ``mu`` and ``A = [dpsi; nu]`` row by row (``dpsi`` may stack several
walls' rows; ``N``, ``T~``, ``Q~`` are those of its first row), ``A = Lambda^{-1} Ar``; P,
QQ, T~, Q~ do not depend on the scale of the rows, and Lambda is put back into Y,
P(Y^A), C^AB, C_AB, beta^B and N):

* ``P g^{-1} = Pg / d1`` with ``Pg, d1`` the top-left block of the adjugate and the
  determinant of the bordered matrix ``B1 = [[Gr, mu^T], [mu, 0]]`` (``(B1^{-1})_11`` is
  the constrained inverse ``P g^{-1}`` of section 2.2); without permanent constraints
  ``Pg = adj Gr``, ``d1 = det Gr``.  (P itself, ``Pg Gr / d1``, is not formed here: the
  impact takes the scene's P and Q, built once by
  :func:`symmech.constraints.projectors.projectors`.)
* ``P(Y^A) = gamma Pg Ar^T Lambda^{-1} / d1``, ``beta = Lambda^{-1} Ar Pg Gr / d1`` and
  ``C^{AB} = gamma Lambda^{-1} Cn Lambda^{-1} / d1`` with ``Cn = Ar Pg Ar^T``;
* ``C_{AB} = Lambda Ka Lambda / (gamma dK)`` with ``dK = det Cn / d1^(k-1)`` and
  ``Ka = d1 adj(Cn) / d1^(k-1)`` (k the rows of A: l + 1 for one wall).  Both divisions
  are exact: by Jacobi's theorem a j x j minor of the adjugate ``Pg`` is ``d1^(j-1)``
  times a minor of B1, so
  ``dK = (-1)^k det[[B1, [Ar^T; 0]], [[Ar, 0], 0]]``;
* ``QQ = Pg Ar^T Ka Ar Pg Gr / (d1^2 dK)``, ``N = lambda_0 Pg Ar^T Ka e_0 / (d1 dK)``,
  ``T~ = N beta^0``, ``Q~ = Pg Ar_0^T Ar_0 Pg Gr / (d1 Cn_00)``; a spurious factor d1 of
  the numerators of QQ and N is divided out exactly when it divides them.

Cost.  Determinants and adjugates are formed by sympy's division-free characteristic
polynomial route (``DomainMatrix.adj_det``); the only gcds are the final ones, entry by
entry against the shared denominator, and they are taken only when the denominator has at
most :data:`symmech.algebra.budget.IMPACT_GCD_TERMS` terms and the numerator at most
:data:`symmech.algebra.budget.IMPACT_GCD_NUMERATOR_TERMS`
(otherwise only the common monomial and integer content are cancelled: the entry stays
exact, a fraction over the shared denominator).  When a polynomial grows beyond
:data:`symmech.algebra.budget.IMPACT_TERMS` terms the route gives up (``None``) and the caller uses
plain sympy arithmetic. Whenever every final gcd is taken, each entry is the cancelled
fraction of K, the same canonical element the fraction-field route produces.

Every identity used here is checked in ``tests/test_impacts_cost.py`` against the
fraction-field route and the KKT route.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import sympy as sp
from sympy.polys.matrices import DomainMatrix

from symmech.algebra import budget as limits
from symmech.algebra.budget import BudgetExceeded
from symmech.algebra.field import RationalField, common_domain
from symmech.errors import ImpactError

__all__ = [
    "Denominators",
    "adjugate_route",
    "shared_denominators",
]

Poly = Any  # a PolyElement of the ring R


class Denominators:
    """The shared polynomial denominators of the construction, as sympy expressions:
    ``metric`` (det Gr), ``permanent`` (d1, the bordered determinant; None without
    permanent constraints), ``gram`` (dK = +-det of the full bordered matrix, whose zeros
    are where C^AB is singular) and ``inputs`` (the cleared input denominators)."""

    def __init__(self, metric: sp.Expr, permanent: sp.Expr | None, gram: sp.Expr, inputs):
        self.metric, self.permanent, self.gram = metric, permanent, gram
        self.inputs: tuple[sp.Expr, ...] = tuple(inputs)


def _size(M: DomainMatrix) -> int:
    return sum(len(e) for row in M.to_list() for e in row if e)


def _guard(*items: Any) -> None:
    total = 0
    for item in items:
        total += _size(item) if isinstance(item, DomainMatrix) else len(item)
    limits.checkpoint()
    if total > limits.IMPACT_TERMS:
        raise BudgetExceeded(
            "impact projectors (adjugate route)",
            "IMPACT_TERMS",
            "terms",
            limits.IMPACT_TERMS,
            total,
        )


def _exquo_all(M: DomainMatrix, d: Poly) -> DomainMatrix | None:
    """``M / d`` if d divides every entry exactly, else None."""
    R = M.domain
    if d == R.one:
        return M
    rows = []
    for row in M.to_list():
        out = []
        for e in row:
            if not e:
                out.append(e)
                continue
            q, r = divmod(e, d)
            if r:
                return None
            out.append(q)
        rows.append(out)
    return DomainMatrix(rows, M.shape, R)


def _fraction(
    field: Any, num: Poly, den: Poly, cancel: bool, reduce: Callable[[Poly], Poly]
) -> Any:
    """``num / den`` as an element of the fraction field: fully cancelled when small (see
    the module docstring), else with the common monomial and content removed.  Numerator
    and denominator are first put in the Pythagorean normal form (``reduce``:
    ``sin^2 -> 1 - cos^2``) when that makes them shorter: so ``cos^2 / (sin^2 +
    cos^2)`` becomes ``cos^2``, while ``I a^2 cos^2 + I b^2 sin^2`` keeps its shorter form."""
    limits.checkpoint()  # one gcd per entry: the deadline holds between them
    if not num:
        return field.zero
    rn, rd = reduce(num), reduce(den)
    if not rn:
        return field.zero
    if len(rn) + len(rd) < len(num) + len(den):
        num, den = rn, rd
    if (
        cancel
        and len(den) <= limits.IMPACT_GCD_TERMS
        and len(num) <= limits.IMPACT_GCD_NUMERATOR_TERMS
    ):
        return field.new(num, den)
    mono = tuple(min(e) for e in zip(*num.monoms(), *den.monoms(), strict=True))
    ring = num.ring
    content = ring.domain.gcd(num.content(), den.content()) if cancel else ring.domain.one
    common = ring({mono: content})
    num, den = num.exquo(common), den.exquo(common)
    if den.LC < 0:
        num, den = -num, -den
    return field.raw_new(num, den)


def adjugate_route(
    field: RationalField,
    g: sp.Matrix,
    mu: sp.Matrix,
    dpsi: sp.Matrix,
    nu: sp.Matrix,
    check: Callable[[sp.Matrix, sp.Matrix], None] | None,
    cancel: bool = True,
    several: bool = False,
) -> tuple[dict[str, Any], Denominators] | None:
    """The objects of :class:`~symmech.impacts.impact_projectors.ImpactProjectors` other
    than P and Q (a dict keyed by the attribute names) and the shared denominators, by the
    formulas of the module docstring; ``None`` when the field is not a rational-function
    field or the term budget is exceeded.  ``check(C, PY)`` is called before C^AB is
    inverted.  With ``cancel=False`` no gcd is taken at all (the entries as the formulas
    build them).  With ``several=True`` also ``PYK``, ``Kbeta`` and ``T_walls`` (see
    :class:`~symmech.impacts.impact_projectors.ImpactProjectors`): ``PY K = Pg Ar^T Ka
    Lambda / (d1 dK)``, ``K beta = Lambda Ka betan / (gamma dK d1)`` and
    ``T~_i`` (column i of PYK times ``beta^i``) over QQ's denominator, as T~ is, and
    ``K[:, i] beta^i = Lambda Ka[:, i] betan_i / (gamma dK d1)``."""
    K = field.K
    if K is None or not K.is_FractionField:
        return None
    try:
        return _route(field, g, mu, dpsi, nu, check, cancel, several)
    except BudgetExceeded as exc:
        limits.propagate_time(exc)
        return None


class _Core:
    """The ring quantities shared by the objects and the denominators (module docstring):
    ``Gr, gamma, Ar, lam, MUr, mu_den, adjG, dG, Pg, d1, PYn, betan, Cn``."""

    def __init__(self, field: RationalField, g, mu, dpsi, nu):
        K = field.K
        self.field, self.K, self.R = field, K, K.get_ring()
        n, m, k = g.rows, mu.rows, dpsi.rows + nu.rows
        self.n, self.m, self.k = n, m, k
        gamma_s, Gr = field.matrix(g).clear_denoms(convert=True)
        self.gamma = gamma_s.element
        lam_d, Ar = field.matrix(dpsi.col_join(nu)).clear_denoms_rowwise(convert=True)
        self.lam = [lam_d[i, i].element for i in range(k)]
        self.mu_den: list[Poly] = []
        MUr: Any = None
        if m:
            mu_d, MUr = field.matrix(mu).clear_denoms_rowwise(convert=True)
            self.mu_den = [mu_d[i, i].element for i in range(m)]
        _guard(Gr, Ar)
        self.Gr, self.Ar = Gr, Ar
        self.adjG, self.dG = Gr.adj_det()
        _guard(self.adjG)
        if m:
            Z = DomainMatrix.zeros((m, m), self.R)
            B1 = Gr.hstack(MUr.transpose()).vstack(MUr.hstack(Z))
            adjB1, self.d1 = B1.adj_det()
            self.Pg = adjB1.extract(list(range(n)), list(range(n)))
        else:
            self.Pg, self.d1 = self.adjG, self.dG
        if not self.d1:
            raise ImpactError("the permanent constraints are dependent (bordered metric singular)")
        _guard(self.Pg)
        self.PYn = self.Pg * Ar.transpose()  # n x k
        self.betan = Ar * self.Pg * Gr  # k x n
        self.Cn = Ar * self.PYn  # k x k, symmetric
        _guard(self.PYn, self.betan, self.Cn)

    def gram_inverse(self) -> tuple[DomainMatrix, Poly]:
        """``(Ka, dK)`` with ``C_AB = Lambda Ka Lambda / (gamma dK)`` (module docstring)."""
        k, d1 = self.k, self.d1
        adjCn, detCn = self.Cn.adj_det()
        dK, rem = divmod(detCn, d1 ** (k - 1))
        if rem or not dK:  # pragma: no cover - Jacobi's theorem; C regular was checked
            raise ImpactError("the Gram matrix C^AB is singular")
        if k == 1:
            return DomainMatrix([[d1]], (1, 1), self.R), dK
        Ka = _exquo_all(adjCn, d1 ** (k - 2))
        if Ka is None:  # pragma: no cover - Jacobi's theorem
            raise ImpactError("internal error: adj C^AB not divisible by d1^(k-2)")
        return Ka, dK

    def expr(self, p: Poly) -> sp.Expr:
        return self.field.to_sympy(self.K.field.raw_new(p, self.R.one))

    def denominators(self, dK: Poly) -> Denominators:
        return Denominators(
            metric=self.expr(self.dG),
            permanent=self.expr(self.d1) if self.m else None,
            gram=self.expr(dK),
            inputs=[self.expr(x) for x in (self.gamma, *self.lam, *self.mu_den)],
        )


def shared_denominators(
    g: sp.Matrix, mu: sp.Matrix, dpsi: sp.Matrix, nu: sp.Matrix
) -> Denominators | None:
    """Only the shared denominators of the construction (cheap: no cancellation), or
    None when the entries admit no rational-function field or exceed the budget."""
    field = common_domain([g, mu, dpsi, nu])
    if field.K is None or not field.K.is_FractionField:
        return None
    try:
        core = _Core(field, g, mu, dpsi, nu)
        return core.denominators(core.gram_inverse()[1])
    except BudgetExceeded as exc:
        limits.propagate_time(exc)
        return None


def _route(field, g, mu, dpsi, nu, check, cancel, several=False):
    core = _Core(field, g, mu, dpsi, nu)
    Fd, n, k, zero = core.K.field, core.n, core.k, core.R.zero
    gamma, lam, d1, dG = core.gamma, core.lam, core.d1, core.dG
    Ar, PYn, betan, Cn = core.Ar, core.PYn, core.betan, core.Cn

    def frac(num: Poly, den: Poly) -> Any:
        return _fraction(Fd, num, den, cancel, field.reduce)

    def to_sympy(rows: list[list[Any]]) -> sp.Matrix:
        return field.to_matrix(rows)

    PYl, Cnl, betal = PYn.to_list(), Cn.to_list(), betan.to_list()
    PY = to_sympy([[frac(gamma * PYl[i][a], d1 * lam[a]) for a in range(k)] for i in range(n)])
    Crows = [[frac(gamma * Cnl[a][b], d1 * lam[a] * lam[b]) for b in range(k)] for a in range(k)]
    C = to_sympy(Crows)
    for a in range(k):  # symmetric in exact arithmetic; one printed form
        for b in range(a + 1, k):
            C[b, a] = C[a, b]
    if check is not None:
        check(C, PY)

    Ka, dK = core.gram_inverse()
    Kl = Ka.to_list()
    Krows = [[frac(lam[a] * lam[b] * Kl[a][b], gamma * dK) for b in range(k)] for a in range(k)]

    PYK = PYn * Ka  # n x k over d1 dK
    reduced = _exquo_all(PYK, d1)
    PYK, den_pyk = (reduced, dK) if reduced is not None else (PYK, d1 * dK)
    QQn = PYK * betan  # over den_pyk * d1
    Tn = PYK.extract(list(range(n)), [0]) * betan.extract([0], list(range(n)))
    _guard(PYK, QQn, Tn)
    den_qq = den_pyk * d1
    QQl, Tl, PYKl = QQn.to_list(), Tn.to_list(), PYK.to_list()
    QQ = [[frac(QQl[i][j], den_qq) for j in range(n)] for i in range(n)]
    PP = [
        [frac((den_qq if i == j else zero) - QQl[i][j], den_qq) for j in range(n)] for i in range(n)
    ]
    T = [[frac(Tl[i][j], den_qq) for j in range(n)] for i in range(n)]
    N = [[frac(lam[0] * PYKl[i][0], den_pyk)] for i in range(n)]
    Qtn = PYn.extract(list(range(n)), [0]) * betan.extract([0], list(range(n)))
    Qtl, c00 = Qtn.to_list(), Cnl[0][0]
    Qt = [[frac(Qtl[i][j], d1 * c00) for j in range(n)] for i in range(n)]
    Pt = [
        [frac((d1 * c00 if i == j else zero) - Qtl[i][j], d1 * c00) for j in range(n)]
        for i in range(n)
    ]
    beta = [[frac(betal[a][j], d1 * lam[a]) for j in range(n)] for a in range(k)]
    Yn = (core.adjG * Ar.transpose()).to_list()
    Y = [[frac(gamma * Yn[i][a], dG * lam[a]) for a in range(k)] for i in range(n)]

    objects = {
        "Y": to_sympy(Y),
        "PY": PY,
        "C": C,
        "K": to_sympy(Krows),
        "beta": to_sympy(beta),
        "QQ": to_sympy(QQ),
        "PP": to_sympy(PP),
        "T": to_sympy(T),
        "Qt": to_sympy(Qt),
        "Pt": to_sympy(Pt),
        "N": to_sympy(N),
    }

    if several:
        gamma_dK_d1 = gamma * dK * d1
        Kbn = (Ka * betan).to_list()
        objects["PYK"] = to_sympy(
            [[frac(lam[a] * PYKl[i][a], den_pyk) for a in range(k)] for i in range(n)]
        )
        objects["Kbeta"] = to_sympy(
            [[frac(lam[a] * Kbn[a][j], gamma_dK_d1) for j in range(n)] for a in range(k)]
        )
        walls = []
        for w in range(dpsi.rows):
            Tw = PYK.extract(list(range(n)), [w]) * betan.extract([w], list(range(n)))
            _guard(Tw)
            Twl = Tw.to_list()
            walls.append(to_sympy([[frac(Twl[i][j], den_qq) for j in range(n)] for i in range(n)]))
        objects["T_walls"] = tuple(walls)
        reflected = []
        for w in range(dpsi.rows):
            Kw = (Ka.extract(list(range(k)), [w]) * betan.extract([w], list(range(n)))).to_list()
            reflected.append(
                to_sympy(
                    [[frac(lam[a] * Kw[a][j], gamma_dK_d1) for j in range(n)] for a in range(k)]
                )
            )
        objects["Kbeta_walls"] = tuple(reflected)
    return objects, core.denominators(dK)
