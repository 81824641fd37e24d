"""Straight-line linear algebra: the solves of the generated code, unrolled at generation time.

The strategy ``linear_solve`` solves ``M v_dot = f``, the constrained system and the
impulse-momentum (KKT) system of an impact inside the generated code with Cholesky
factorisations ``A = L L^T`` (the algorithms are listed in :mod:`symmech.codegen.lower`).
The matrix sizes and which entries are exact constants (structural zeros, unit masses,
the zero forcing of a free rigid body, a static wall's ``psi_t = 0``) are known when the
code is generated, so the algorithms are executed here, once, over symbolic cells, and
every floating-point operation that cannot be decided in advance is emitted as one line
of straight-line code.  The generated code has no loops, no index arithmetic and no work
on known zeros, and the compiler sees every dependency.

Same operations, same order.  An operation is left out only when IEEE 754 arithmetic
gives its result exactly, whatever the run-time operand:

* ``x*0 = 0``, ``0/x = 0``, ``x*1 = x``, ``x/1 = x``, ``x*(-1) = -x``,
* ``x - 0 = x``, ``0 - x = -x``, ``x + 0 = 0 + x = x``,
* operations on two constants are done here in Python floats (IEEE binary64, correctly
  rounded: ``math.sqrt`` too), which is what the machine would do at run time.

Every other operation is emitted with its operands in the order of the loop algorithm, so
the unrolled code returns the same doubles, bit for bit, as the loops it replaces
(``tests/test_codegen_linalg.py`` runs both), and the rounding-error analysis of the
loops (``tests/codegen_support.py``) holds for it unchanged.  The exceptions above hold
for finite ``x``: the generated code therefore checks that every run-time input of the
solve is finite first (``SYMMECH_NONFINITE``), so a NaN or an infinity cannot be hidden
by a skipped product with zero.  (Only the sign of a zero result may differ from the
loop version, ``-0.0`` for ``0.0``.)

A pivot that is a constant is checked here: a non-positive constant pivot means the
matrix is never positive definite, and generation fails with a :class:`CodegenError`.

The result is a :class:`Program` of statements over expression trees; a
:class:`~symmech.codegen.dialects.Dialect` prints it for one backend (C or NumPy).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from symmech.codegen.plan import CodegenError

__all__ = [
    "Input",
    "Op",
    "Program",
    "Ref",
    "trace_step",
]


# --------------------------------------------------------------------------- expressions


@dataclass(frozen=True)
class Ref:
    """A named run-time value: a local (an input entry or an emitted temporary), or an
    entry of a state array (``array`` set: ``v[i]``)."""

    name: str
    array: str | None = None
    index: int = 0


@dataclass(frozen=True)
class Op:
    """An operation: ``neg`` (one argument), ``sqrt`` (one), ``add``, ``sub``, ``mul``,
    ``div`` (two, left then right)."""

    op: str
    args: tuple[Value, ...]


Value = float | Ref | Op


def _is(x: Value, c: float) -> bool:
    return isinstance(x, float) and x == c


def neg(a: Value) -> Value:
    if isinstance(a, float):
        return -a
    if isinstance(a, Op) and a.op == "neg":
        return a.args[0]
    return Op("neg", (a,))


def add(a: Value, b: Value) -> Value:
    if isinstance(a, float) and isinstance(b, float):
        return a + b
    if _is(b, 0.0):
        return a
    if _is(a, 0.0):
        return b
    return Op("add", (a, b))


def sub(a: Value, b: Value) -> Value:
    if isinstance(a, float) and isinstance(b, float):
        return a - b
    if _is(b, 0.0):
        return a
    if _is(a, 0.0):
        return neg(b)
    return Op("sub", (a, b))


def mul(a: Value, b: Value) -> Value:
    if isinstance(a, float) and isinstance(b, float):
        return a * b
    if _is(a, 0.0) or _is(b, 0.0):
        return 0.0
    if _is(a, 1.0):
        return b
    if _is(b, 1.0):
        return a
    if _is(a, -1.0):
        return neg(b)
    if _is(b, -1.0):
        return neg(a)
    return Op("mul", (a, b))


def div(a: Value, b: Value) -> Value:
    if isinstance(a, float) and isinstance(b, float):
        return a / b  # b is a checked positive pivot or a nonzero diagonal
    if _is(a, 0.0):
        return 0.0
    if _is(b, 1.0):
        return a
    if _is(b, -1.0):
        return neg(a)
    return Op("div", (a, b))


def sqrt(a: Value) -> Value:
    if isinstance(a, float):
        return math.sqrt(a)
    return Op("sqrt", (a,))


def flops(v: Value) -> int:
    """Arithmetic operations in ``v`` (+ - * / sqrt one each; a negation is free)."""
    if isinstance(v, Op):
        return (v.op != "neg") + sum(flops(a) for a in v.args)
    return 0


def refs(v: Value) -> list[Ref]:
    if isinstance(v, Ref):
        return [v]
    if isinstance(v, Op):
        return [r for a in v.args for r in refs(a)]
    return []


# --------------------------------------------------------------------------- programs


@dataclass(frozen=True)
class Input:
    """A run-time input entry of the solve: the local ``name`` holding entry ``flat``
    (row-major) of the block ``block`` (M, f, mu, rate, A or s), not a constant."""

    name: str
    block: str
    flat: int


@dataclass
class Program:
    """Straight-line code of one step.

    ``statements`` in order: ``("let", name, value)``, ``("finite", (refs...))`` (fail with
    SYMMECH_NONFINITE unless every one is finite), ``("positive", value, matrix)`` (fail
    with SYMMECH_NOT_SPD unless the pivot is > 0), ``("out", i, value)``.
    """

    inputs: list[Input] = field(default_factory=list)
    statements: list[tuple] = field(default_factory=list)
    out_size: int = 0
    _names: set[str] = field(default_factory=set)

    @property
    def flops(self) -> int:
        """Floating-point operations emitted (+ - * / sqrt one each)."""
        total = 0
        for s in self.statements:
            if s[0] in ("let", "out"):
                total += flops(s[2])
        return total

    def reads_state(self, array: str) -> bool:
        """Whether the code reads an entry of the state array ``array``."""
        return any(r.array == array for st in self.statements for r in _statement_refs(st))

    def fresh(self, name: str) -> str:
        out, k = name, 2
        while out in self._names:
            out = f"{name}_{k}"
            k += 1
        self._names.add(out)
        return out

    def let(self, name: str, value: Value) -> Value:
        """``value`` as a named temporary, unless it is a constant or a bare reference."""
        if isinstance(value, (float, Ref)):
            return value
        if isinstance(value, Op) and value.op == "neg" and isinstance(value.args[0], Ref):
            return value
        local = self.fresh(name)
        self.statements.append(("let", local, value))
        return Ref(local)

    def positive(self, pivot: Value, what: str) -> None:
        if isinstance(pivot, float):
            if not pivot > 0.0:
                raise CodegenError(
                    f"{what} is never positive definite: a pivot of its Cholesky"
                    f" factorisation is the constant {pivot!r}"
                )
            return
        self.statements.append(("positive", pivot, what))


# --------------------------------------------------------------------------- algorithms
#
# Each mirrors a loop algorithm of the earlier linalg templates exactly (same operands,
# same order; see the module docstring).  Matrices are functions (i, j) -> Value read
# only where the loop version reads them (the lower triangle for a Cholesky factorisation).

Matrix = Callable[[int, int], Value]


@dataclass
class _Factor:
    """A factored SPD matrix: the Cholesky factor (``lower[i, j]``, i > j, and the
    reciprocals ``inv[j]`` of its diagonal), or for a structurally diagonal metric its
    diagonal (``diagonal``)."""

    n: int
    lower: dict[tuple[int, int], Value] = field(default_factory=dict)
    inv: list[Value] = field(default_factory=list)
    diagonal: list[Value] | None = None


def _cholesky(prog: Program, n: int, A: Matrix, tag: str, what: str) -> _Factor:
    """A = L L^T (sm_cholesky): column j: d = a_jj - sum_k l_jk^2, a positive check,
    1/sqrt(d), then l_ij = (a_ij - sum_k l_ik l_jk) / l_jj for i > j."""
    F = _Factor(n)
    for j in range(n):
        d = A(j, j)
        for k in range(j):
            d = sub(d, mul(F.lower[j, k], F.lower[j, k]))
        d = prog.let(f"{tag}p{j}", d)
        prog.positive(d, what)
        F.inv.append(prog.let(f"{tag}i{j}", div(1.0, sqrt(d))))
        for i in range(j + 1, n):
            s = A(i, j)
            for k in range(j):
                s = sub(s, mul(F.lower[i, k], F.lower[j, k]))
            F.lower[i, j] = prog.let(f"{tag}{i}_{j}", mul(s, F.inv[j]))
    return F


def _cholesky_solve(prog: Program, F: _Factor, B: list[list[Value]], tag: str) -> None:
    """L L^T X = B in place (sm_cholesky_solve): per column, forward then back
    substitution, multiplying by the stored reciprocals."""
    n = F.n
    for c in range(len(B[0]) if B else 0):
        for i in range(n):
            s = B[i][c]
            for k in range(i):
                s = sub(s, mul(F.lower[i, k], B[k][c]))
            B[i][c] = prog.let(f"{tag}{i}_{c}", mul(s, F.inv[i]))
        for i in range(n - 1, -1, -1):
            s = B[i][c]
            for k in range(i + 1, n):
                s = sub(s, mul(F.lower[k, i], B[k][c]))
            B[i][c] = prog.let(f"{tag}{i}_{c}", mul(s, F.inv[i]))


def _factor(prog: Program, n: int, diag: bool, M: Matrix) -> _Factor:
    """sm_factor: Cholesky, or for a structurally diagonal metric a positive check of its
    diagonal (its solve then divides by it)."""
    if not diag:
        return _cholesky(prog, n, M, "L", "the metric")
    F = _Factor(n, diagonal=[M(j, j) for j in range(n)])
    for d in F.diagonal:  # type: ignore[union-attr]
        prog.positive(d, "the metric")
    return F


def _factor_solve(prog: Program, F: _Factor, B: list[list[Value]], tag: str) -> None:
    """sm_factor_solve: M^-1 B in place."""
    if F.diagonal is None:
        _cholesky_solve(prog, F, B, tag)
        return
    for i, d in enumerate(F.diagonal):
        for c in range(len(B[i])):
            B[i][c] = prog.let(f"{tag}{i}_{c}", div(B[i][c], d))


def _dot_from_zero(terms: Sequence[tuple[Value, Value]]) -> Value:
    """``c = 0.0; c += a*b ...`` (the loop's accumulation, in order)."""
    c: Value = 0.0
    for a, b in terms:
        c = add(c, mul(a, b))
    return c


def _spd_solve(prog: Program, n: int, diag: bool, M: Matrix, f: Sequence[Value]) -> None:
    F = _factor(prog, n, diag, M)
    X = [[f[i]] for i in range(n)]
    _factor_solve(prog, F, X, "x")
    for i in range(n):
        prog.statements.append(("out", i, X[i][0]))
    prog.out_size = n


def _constrained(
    prog: Program,
    n: int,
    m: int,
    diag: bool,
    M: Matrix,
    f: Sequence[Value],
    mu: Matrix,
    rate: Sequence[Value],
    outputs: str,
) -> None:
    """sm_constrained: X = M^-1 [mu^T | f], C = mu X_mu, lambda = C^-1 (-rate - mu X_f),
    acc = X_f + X_mu lambda (Carnot paper section 2.2); ``outputs``: ``"acceleration"``
    (out = acc), ``"multipliers"`` (out = lambda) or ``"dynamics"`` (out = (acc,
    lambda))."""
    F = _factor(prog, n, diag, M)
    X = [[mu(a, i) for a in range(m)] + [f[i]] for i in range(n)]
    _factor_solve(prog, F, X, "X")
    lam: list[list[Value]] = []
    C: dict[tuple[int, int], Value] = {}
    for a in range(m):
        s = neg(rate[a])
        for i in range(n):
            s = sub(s, mul(mu(a, i), X[i][m]))
        lam.append([prog.let(f"lam{a}", s)])
        for b in range(a + 1):  # the factorisation reads the lower triangle only
            C[a, b] = prog.let(f"C{a}_{b}", _dot_from_zero([(mu(a, i), X[i][b]) for i in range(n)]))
    FC = _cholesky(prog, m, lambda i, j: C[i, j], "Lc", "the Gram matrix C = mu M^-1 mu^T")
    _cholesky_solve(prog, FC, lam, "lam")
    prog.out_size = 0
    if outputs in ("acceleration", "dynamics"):
        for i in range(n):
            s = X[i][m]
            for a in range(m):
                s = add(s, mul(X[i][a], lam[a][0]))
            prog.statements.append(("out", i, s))
        prog.out_size = n
    if outputs in ("multipliers", "dynamics"):
        for a in range(m):
            prog.statements.append(("out", prog.out_size + a, lam[a][0]))
        prog.out_size += m


def _impact_kkt(
    prog: Program,
    n: int,
    k: int,
    m: int,
    diag: bool,
    M: Matrix,
    A: Matrix,
    alpha: Value,
    psi_t: Value,
    v: Sequence[Value],
    nu_w: Sequence[Value] | None = None,
) -> None:
    """sm_impact_kkt: Y = M^-1 A^T, G = A Y, r = b - A v, v+ = v + Y G^-1 r (Carnot
    paper eqs. 6, 15, 20, by the Schur complement; G^-1 r by Cholesky, or for one row by
    one division).  ``nu_w``: the values ``nu W`` of a
    declared wall velocity W; None for the default W (normal in the metric), whose
    ``nu W = -psi_t G[a, m] / G[m, m]``."""
    F = _factor(prog, n, diag, M)
    Y = [[A(a, i) for a in range(k)] for i in range(n)]
    _factor_solve(prog, F, Y, "Y")
    r: list[list[Value]] = []
    G: dict[tuple[int, int], Value] = {}
    for a in range(k):
        av = _dot_from_zero([(A(a, i), v[i]) for i in range(n)])
        r.append([neg(av)])
        for b in range(a + 1):
            G[a, b] = prog.let(f"G{a}_{b}", _dot_from_zero([(A(a, i), Y[i][b]) for i in range(n)]))
    # the wall row: b_m - dpsi(v) = -(1 + alpha)(dpsi(v) + psi_t)
    r[m][0] = prog.let(f"r{m}", mul(add(1.0, alpha), sub(r[m][0], psi_t)))
    for a in range(m + 1, k):  # the nu rows: nu (v+ - W) = 0
        if nu_w is not None:
            r[a][0] = prog.let(f"r{a}", add(r[a][0], nu_w[a - m - 1]))
        else:  # nu W = -psi_t G[a, m] / G[m, m]
            r[a][0] = prog.let(f"r{a}", add(r[a][0], div(mul(neg(psi_t), G[a, m]), G[m, m])))
    if k == 1:
        # one row: r / G, not (r / sqrt(G)) / sqrt(G), which rounds twice and leaves
        # residues where the exact answer is 0 (equal balls exchanging their speeds)
        prog.positive(G[0, 0], "the Gram matrix G = A M^-1 A^T")
        r[0][0] = prog.let("r0_0", div(r[0][0], G[0, 0]))
    else:
        FG = _cholesky(prog, k, lambda i, j: G[i, j], "Lg", "the Gram matrix G = A M^-1 A^T")
        _cholesky_solve(prog, FG, r, "r")
    for i in range(n):
        s = v[i]
        for a in range(k):
            s = add(s, mul(Y[i][a], r[a][0]))
        prog.statements.append(("out", i, s))
    prog.out_size = n


def _statement_refs(st: tuple) -> list[Ref]:
    if st[0] == "finite":
        return list(st[1])
    return refs(st[1] if st[0] == "positive" else st[2])


def _prune(statements: list[tuple]) -> list[tuple]:
    """Drop the temporaries nothing reads (a reciprocal pivot whose column only meets
    zeros); the outputs and every check stay (a matrix that is not positive definite
    is reported even where its factor is not needed)."""
    live: set[str] = set()
    kept: list[tuple] = []
    for st in reversed(statements):
        if st[0] == "let" and st[1] not in live:
            continue
        kept.append(st)
        live.update(r.name for r in _statement_refs(st))
    kept.reverse()
    return kept


#: The steps of the constrained equations of motion, and what each writes to ``out``.
CONSTRAINED_STEPS = {
    "constrained_acceleration": "acceleration",
    "constrained_multipliers": "multipliers",
    "constrained_dynamics": "dynamics",
}

#: Input block names of each step, in the order of the step's arguments.
STEP_INPUTS = {
    "spd_solve": ("M", "f"),
    "constrained_acceleration": ("M", "f", "mu", "rate"),
    "constrained_multipliers": ("M", "f", "mu", "rate"),
    "constrained_dynamics": ("M", "f", "mu", "rate"),
    "impact_kkt": ("M", "A", "s"),
}


def trace_step(
    step: str,
    args: tuple[int, ...],
    blocks: dict[str, tuple[tuple[int, ...], Sequence[float | None]]],
) -> Program:
    """Unroll ``step`` (see :mod:`symmech.codegen.lower`) with sizes ``args``.

    ``blocks`` maps each input block name to its shape and row-major entries: a float for
    an entry that is an exact constant, None for a run-time value.  ``Program.inputs``
    lists the run-time entries the code reads (an entry that is never read, such as the
    upper triangle of a symmetric metric, is not listed); the state ``v`` (``impact_kkt``)
    is read as ``Ref(array="v")``.
    """
    if step not in STEP_INPUTS:
        raise CodegenError(f"unknown linear-algebra step {step!r}")
    prog = Program()
    cells: dict[str, list[Value]] = {}
    for name in STEP_INPUTS[step]:
        shape, entries = blocks[name]
        values: list[Value] = []
        for flat, e in enumerate(entries):
            if isinstance(e, float):
                values.append(e)
                continue
            idx = (flat,) if len(shape) <= 1 else divmod(flat, shape[1])
            local = prog.fresh(name + "_".join(str(i) for i in idx))
            prog.inputs.append(Input(local, name, flat))
            values.append(Ref(local))
        cells[name] = values

    def matrix(name: str) -> Matrix:
        cols = blocks[name][0][1]
        data = cells[name]
        return lambda i, j: data[i * cols + j]

    body = Program(_names=prog._names)
    if step == "spd_solve":
        n, diag = args
        _spd_solve(body, n, bool(diag), matrix("M"), cells["f"])
    elif step in CONSTRAINED_STEPS:
        n, m, diag = args
        _constrained(
            body,
            n,
            m,
            bool(diag),
            matrix("M"),
            cells["f"],
            matrix("mu"),
            cells["rate"],
            CONSTRAINED_STEPS[step],
        )
    else:
        n, k, m, diag = args
        v = [Ref(f"v{i}", "v", i) for i in range(n)]
        s = cells["s"]
        nu_w = list(s[2:]) if len(s) > 2 else None
        _impact_kkt(body, n, k, m, bool(diag), matrix("M"), matrix("A"), s[0], s[1], v, nu_w)
    body.statements = _prune(body.statements)
    # every run-time value the body reads must be finite (see the module docstring)
    read: dict[Ref, None] = {}
    lets = {st[1] for st in body.statements if st[0] == "let"}
    for st in body.statements:
        for r in _statement_refs(st):
            if r.array is not None or r.name not in lets:
                read[r] = None
    prog.inputs = [i for i in prog.inputs if Ref(i.name) in read]
    if read:
        prog.statements.append(("finite", tuple(read)))
    prog.statements.extend(body.statements)
    prog.out_size = body.out_size
    return prog
