"""The projectors of an impact (Carnot paper (002), sections 3.1, 3.2, 4.1, 4.2).

Everything is written in the *velocity basis* of the scene (coordinate velocities, or
quasi-velocities v with ``q_dot = S v``); a matrix acts on velocity columns.  Inputs:

* ``g`` (n x n), the metric in the velocity basis, ``T = 1/2 v^T g v``;
* ``mu`` (m x n), permanent constraints ``mu v = 0``, with the projectors (P, Q) onto
  D = ker mu and D^perp (:func:`symmech.constraints.projectors.projectors`);
* ``dpsi`` (1 x n), the wall one-form ``d psi`` in the velocity basis: ``(d psi/d q) S``
  (or w x n, the one-forms of w walls hit at once, :mod:`symmech.impacts.several`: then
  A, C, K, beta, QQ and PP are those of all the rows, while T~, N, Q~ and P~ are built
  from the first row only);
* ``nu`` (l x n), the instantaneous (impulsive) constraints nu^A, A = 1..l.

With ``A = [dpsi; nu]`` ((l+1) x n) the paper's objects are

* ``Y^A = g^{-1} A_A^T`` (``Y^0 = grad psi``), the columns of ``Y``;
* ``P(Y^A)``, the columns of ``PY``;
* ``C^{AB} = g(P Y^A, P Y^B)``, computed as ``A_A P Y^B`` (equal because P is a
  g-self-adjoint idempotent); ``C_{AB}`` its inverse ``K``;
* ``beta^B = g(P Y^B, .)``, the rows of ``beta = PY^T g``;
* ``QQ = sum C_AB P(Y^A) (x) beta^B = PY K beta`` and ``PP = id - QQ`` (section 3.2);
* ``T~ = sum_A C_A0 P(Y^A) (x) beta^0 = N beta^0`` with ``N = PY K e_0`` (Prop. 3.4);
* ``Q~ = C^{-1} P(grad psi) (x) beta`` with ``C = C^{00}``, ``P~ = id - Q~`` (eq. 7).

Facts used below (all follow from the definitions and are checked in the tests):
``beta PY = C``; ``A PY = C``; hence ``dpsi(N) = 1``, ``beta^0(N) = 1``, ``T~`` is
idempotent, ``QQ N = N`` and ``g(PP u, N) = 0`` (Lemma 3.5).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import sympy as sp
from sympy.matrices.utilities import dotprodsimp
from sympy.polys.matrices import DomainMatrix

from symmech.algebra.block_structure import diagonal_blocks
from symmech.algebra.field import common_domain
from symmech.algebra.simplification import Level, tidy, tidy_matrix
from symmech.constraints.projectors import projectors as permanent_projectors
from symmech.constraints.projectors import solve_spd
from symmech.impacts.adjugate_projectors import Denominators, adjugate_route

__all__ = ["ImpactProjectors", "impact_projectors"]


@dataclass(frozen=True)
class ImpactProjectors:
    """The objects of the Carnot paper for one wall (see the module docstring).

    Attributes use the paper's names: ``P``, ``Q`` (permanent constraints), ``Y``
    (columns ``Y^0 = grad psi``, ``Y^A``), ``PY`` (columns ``P(Y^A)``), ``C`` (``C^{AB}``),
    ``K`` (``C_{AB}``, the inverse of C), ``beta`` (rows ``beta^B``), ``QQ`` and ``PP``
    (section 3.2), ``T`` (T~, Prop. 3.4), ``Qt`` and ``Pt`` (Q~ and P~, eq. 7) and ``N``
    (the column ``sum_A C_A0 P(Y^A)`` spanning Im T~).  ``denominators`` holds the
    shared polynomial denominators when the adjugate route built the objects
    (:class:`~symmech.impacts.adjugate_projectors.Denominators`), else None.  Built only
    with ``several=True`` (several walls hit at once, :mod:`symmech.impacts.several`):
    ``PYK = PY K`` (n x rows of A; its column A is ``sum_B C_AB P(Y^B)``, the column 0 is
    N), ``Kbeta = K beta``, ``T_walls``, the ``T~_i = PYK[:, i] beta^i`` of each wall
    row i (Prop. 3.4's T~ for i = 0), and ``Kbeta_walls``, the ``K[:, i] beta^i``.
    """

    g: sp.ImmutableMatrix
    mu: sp.ImmutableMatrix
    dpsi: sp.ImmutableMatrix
    nu: sp.ImmutableMatrix
    P: sp.ImmutableMatrix
    Q: sp.ImmutableMatrix
    Y: sp.ImmutableMatrix
    PY: sp.ImmutableMatrix
    C: sp.ImmutableMatrix
    K: sp.ImmutableMatrix
    beta: sp.ImmutableMatrix
    QQ: sp.ImmutableMatrix
    PP: sp.ImmutableMatrix
    T: sp.ImmutableMatrix
    Qt: sp.ImmutableMatrix
    Pt: sp.ImmutableMatrix
    N: sp.ImmutableMatrix
    denominators: Denominators | None = None
    PYK: sp.ImmutableMatrix | None = None
    Kbeta: sp.ImmutableMatrix | None = None
    T_walls: tuple[sp.ImmutableMatrix, ...] = ()
    Kbeta_walls: tuple[sp.ImmutableMatrix, ...] = ()

    @property
    def A(self) -> sp.ImmutableMatrix:
        """The stacked one-forms ``[d psi; nu^1; ...; nu^l]`` ((l+1) x n)."""
        return sp.ImmutableMatrix(sp.Matrix(self.dpsi).col_join(sp.Matrix(self.nu)))

    @property
    def grad_psi(self) -> sp.ImmutableMatrix:
        """``Y^0 = grad psi = g^{-1} d psi^T`` (n x 1)."""
        return sp.ImmutableMatrix(self.Y[:, 0])


def _inverse(C: sp.Matrix, level: Level) -> sp.Matrix:
    """``C^{-1} = adj(C) / det(C)`` (closed form, one shared denominator; C is small)."""
    k = C.rows
    if k == 1:
        return sp.Matrix([[tidy(1 / C[0, 0], level)]])
    if C.is_diagonal():
        return sp.diag(*[tidy(1 / C[i, i], level) for i in range(k)])
    with dotprodsimp(False):  # no simplification inside sympy's matrix arithmetic
        det = C.det(method="berkowitz")
        adj = C.adjugate(method="berkowitz")
    return tidy_matrix(adj / det, level)


def impact_projectors(
    g: sp.MatrixBase,
    mu: sp.MatrixBase,
    dpsi: sp.MatrixBase,
    nu: sp.MatrixBase,
    level: Level = "light",
    check: Callable[[sp.Matrix, sp.Matrix], None] | None = None,
    permanent: tuple[sp.MatrixBase, sp.MatrixBase] | None = None,
    several: bool = False,
) -> ImpactProjectors:
    """Build P, Q, Y^A, P(Y^A), C^AB, C_AB, beta^B, QQ, PP, T~, Q~, P~ (Carnot paper 002).

    Section 2.2 (P, Q), eq. 7 (Q~, P~), section 3.2 and Prop. 3.4 (QQ, PP, T~).  ``level``
    is the simplification level of :mod:`symmech.algebra.simplification`.  With a level
    other than ``"none"`` the algebra is exact: over the rationals when every entry is a
    number (:func:`_in_field`), else by the adjugate route of
    :mod:`symmech.impacts.adjugate_projectors` (polynomial arithmetic, one shared denominator per
    object, cost-bounded final cancellation), which yields cancelled entries when they
    are small.  Otherwise, or when that route declines, the objects are built with
    sympy arithmetic, inverses as ``adj/det``, and :func:`~symmech.geometry.
    simplification.tidy` applied to the intermediate results.  ``check(C, PY)``, if given,
    is called before C is inverted (see :func:`symmech.impacts.degeneracy.check_regular`)
    and may raise.

    P and Q are the permanent constraints' projectors, ``permanent`` when given (the
    scene's, :meth:`symmech.Scene.projectors`), else built here by
    :func:`symmech.constraints.projectors.projectors` at ``level``: every route below
    takes them as they are and builds only the impact's own objects.

    ``several``: also build ``PYK``, ``Kbeta``, ``T_walls`` and ``Kbeta_walls`` (every row
    of ``dpsi`` a wall), by the same route.
    """
    g = sp.Matrix(g)
    n = g.rows
    mu = sp.Matrix(mu) if mu.rows else sp.zeros(0, n)
    dpsi = sp.Matrix(dpsi)
    nu = sp.Matrix(nu) if nu.rows else sp.zeros(0, n)
    touched = _touched(g, mu, dpsi.col_join(nu))
    if len(touched) < n:
        return _restricted(g, mu, dpsi, nu, level, check, permanent, several, touched)
    P, Q = (sp.Matrix(M) for M in (permanent or permanent_projectors(g, mu, level)))
    if level != "none":
        field = common_domain([g, mu, dpsi, nu])
        if field.K is not None and not field.K.is_FractionField:
            return _in_field(field, g, mu, dpsi, nu, P, Q, check, several)
        routed = adjugate_route(field, g, mu, dpsi, nu, check, several=several)
        if routed is not None:
            objects, denominators = routed
            return _pack(g, mu, dpsi, nu, P, Q, **objects, denominators=denominators)
    A = dpsi.col_join(nu)
    Y = solve_spd(g, A.T, level)
    PY = tidy_matrix(P * Y, level)
    C = tidy_matrix(A * PY, level)
    # C is symmetric in exact arithmetic; symmetrise the printed form.
    for i in range(C.rows):
        for j in range(i + 1, C.cols):
            C[j, i] = C[i, j]
    if check is not None:
        check(C, PY)
    K = _inverse(C, level)
    beta = tidy_matrix(PY.T * g, level)
    QQ = tidy_matrix(PY * K * beta, level)
    PP = tidy_matrix(sp.eye(n) - QQ, level)
    N = tidy_matrix(PY * K[:, 0], level)
    T = tidy_matrix(N * beta[0, :], level)
    Qt = tidy_matrix(PY[:, 0] * beta[0, :] / C[0, 0], level)
    Pt = tidy_matrix(sp.eye(n) - Qt, level)
    extras = {}
    if several:
        PYK = tidy_matrix(PY * K, level)
        extras = {
            "PYK": PYK,
            "Kbeta": tidy_matrix(K * beta, level),
            "T_walls": tuple(tidy_matrix(PYK[:, i] * beta[i, :], level) for i in range(dpsi.rows)),
            "Kbeta_walls": tuple(
                tidy_matrix(K[:, i] * beta[i, :], level) for i in range(dpsi.rows)
            ),
        }
    return _pack(g, mu, dpsi, nu, P, Q, Y, PY, C, K, beta, QQ, PP, T, Qt, Pt, N, **extras)


def _touched(g: sp.Matrix, mu: sp.Matrix, A: sp.Matrix) -> list[int]:
    """The velocities the impact can change: the union of the diagonal blocks of ``g``
    (joined by the rows of ``mu`` that link them) that meet a row of ``A`` (sorted)."""
    n = g.rows
    links = [[j for j in range(n) if mu[a, j] != 0] for a in range(mu.rows)]
    joined: dict[int, set[int]] = {}
    for row in links:
        for i in row:
            joined.setdefault(i, set()).update(row)
    blocks = diagonal_blocks(n, lambda i, j: g[i, j] != 0 or (i in joined and j in joined[i]))
    hit = {j for a in range(A.rows) for j in range(n) if A[a, j] != 0}
    return sorted(i for block in blocks if hit.intersection(block) for i in block)


def _restricted(
    g: sp.Matrix,
    mu: sp.Matrix,
    dpsi: sp.Matrix,
    nu: sp.Matrix,
    level: Level,
    check: Callable[[sp.Matrix, sp.Matrix], None] | None,
    permanent: tuple[sp.MatrixBase, sp.MatrixBase] | None,
    several: bool,
    S: list[int],
) -> ImpactProjectors:
    """The objects built on the touched velocities ``S`` only (:func:`_touched`), then put
    back in n dimensions.  With the velocities ordered (S, R), g, P and Q are block
    diagonal and every row of A vanishes on R, so ``Y = g^-1 A^T``, ``P Y``, ``N`` and
    the rows of ``beta = (P Y)^T g`` vanish on R: QQ, T~, Q~ are zero outside the S x S
    block, PP and P~ are the identity on R, and C, K are those of the S block.  Exact
    (no step depends on R), and an impact on one coordinate of a 200-coordinate
    diagonal scene is a 1 x 1 problem instead of a dense 201 x 201 adjugate."""
    n = g.rows
    rows = [a for a in range(mu.rows) if any(mu[a, j] != 0 for j in S)]
    sub_permanent = None
    if permanent is not None:
        sub_permanent = tuple(sp.Matrix(M).extract(S, S) for M in permanent)
    part = impact_projectors(
        g.extract(S, S),
        mu.extract(rows, S) if rows else sp.zeros(0, len(S)),
        dpsi.extract(list(range(dpsi.rows)), S),
        nu.extract(list(range(nu.rows)), S) if nu.rows else sp.zeros(0, len(S)),
        level,
        check,
        sub_permanent,
        several,
    )
    P, Q = (sp.Matrix(M) for M in (permanent or permanent_projectors(g, mu, level)))

    def rows_of(M: sp.MatrixBase) -> sp.Matrix:  # S rows -> n rows, zero on R
        out = sp.zeros(n, M.cols)
        for r, i in enumerate(S):
            out[i, :] = M[r, :]
        return out

    def cols_of(M: sp.MatrixBase) -> sp.Matrix:  # S columns -> n columns, zero on R
        return rows_of(sp.Matrix(M).T).T

    def square(M: sp.MatrixBase, identity: bool = False) -> sp.Matrix:
        out = sp.eye(n) if identity else sp.zeros(n, n)
        for r, i in enumerate(S):
            for c, j in enumerate(S):
                out[i, j] = M[r, c]
        return out

    extras = {}
    if several:
        assert part.PYK is not None and part.Kbeta is not None
        extras = {
            "PYK": rows_of(part.PYK),
            "Kbeta": cols_of(part.Kbeta),
            "T_walls": tuple(square(T) for T in part.T_walls),
            "Kbeta_walls": tuple(cols_of(M) for M in part.Kbeta_walls),
        }
    return _pack(
        g,
        mu,
        dpsi,
        nu,
        P,
        Q,
        rows_of(part.Y),
        rows_of(part.PY),
        part.C,
        part.K,
        cols_of(part.beta),
        square(part.QQ),
        square(part.PP, identity=True),
        square(part.T),
        square(part.Qt),
        square(part.Pt, identity=True),
        rows_of(part.N),
        denominators=part.denominators,
        **extras,
    )


def _pack(
    g,
    mu,
    dpsi,
    nu,
    P,
    Q,
    Y,
    PY,
    C,
    K,
    beta,
    QQ,
    PP,
    T,
    Qt,
    Pt,
    N,
    denominators=None,
    PYK=None,
    Kbeta=None,
    T_walls=(),
    Kbeta_walls=(),
) -> ImpactProjectors:
    im = sp.ImmutableMatrix
    return ImpactProjectors(
        g=im(g),
        mu=im(mu),
        dpsi=im(dpsi),
        nu=im(nu),
        P=im(P),
        Q=im(Q),
        Y=im(Y),
        PY=im(PY),
        C=im(C),
        K=im(K),
        beta=im(beta),
        QQ=im(QQ),
        PP=im(PP),
        T=im(T),
        Qt=im(Qt),
        Pt=im(Pt),
        N=im(N),
        denominators=denominators,
        PYK=None if PYK is None else im(PYK),
        Kbeta=None if Kbeta is None else im(Kbeta),
        T_walls=tuple(im(T) for T in T_walls),
        Kbeta_walls=tuple(im(M) for M in Kbeta_walls),
    )


def _in_field(
    ring,
    g: sp.Matrix,
    mu: sp.Matrix,
    dpsi: sp.Matrix,
    nu: sp.Matrix,
    P: sp.Matrix,
    Q: sp.Matrix,
    check: Callable[[sp.Matrix, sp.Matrix], None] | None,
    several: bool = False,
) -> ImpactProjectors:
    """The same construction in exact arithmetic over the rationals (every entry a
    number): exact and cheap, no simplification needed."""
    n = g.rows
    Kf = ring.K
    G = ring.matrix(g)
    eye = DomainMatrix.eye(n, Kf)
    Ginv = G.inv()
    Pd = ring.matrix(P)
    A = ring.matrix(dpsi.col_join(nu))
    Yd = Ginv * A.transpose()
    PYd = Pd * Yd
    Cd = A * PYd
    out = ring.to_sympy_matrix
    C, PY = out(Cd), out(PYd)
    if check is not None:
        check(C, PY)
    adj, det = Cd.adj_det()
    Kd = adj * Kf.quo(Kf.one, det)
    betad = PYd.transpose() * G
    QQd = PYd * Kd * betad
    Nd = PYd * Kd[:, 0]
    Td = Nd * betad[0, :]
    Qtd = (PYd[:, 0] * betad[0, :]) * Kf.quo(Kf.one, Cd[0, 0].element)
    extras = {}
    if several:
        PYKd = PYd * Kd
        extras = {
            "PYK": out(PYKd),
            "Kbeta": out(Kd * betad),
            "T_walls": tuple(out(PYKd[:, i] * betad[i, :]) for i in range(dpsi.rows)),
            "Kbeta_walls": tuple(out(Kd[:, i] * betad[i, :]) for i in range(dpsi.rows)),
        }
    return _pack(
        g,
        mu,
        dpsi,
        nu,
        P,
        Q,
        out(Yd),
        PY,
        C,
        out(Kd),
        out(betad),
        out(QQd),
        out(eye - QQd),
        out(Td),
        out(Qtd),
        out(eye - Qtd),
        out(Nd),
        **extras,
    )
