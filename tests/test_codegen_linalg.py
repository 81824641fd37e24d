"""The linear-algebra steps of the generated code: one-coordinate scenes, C and NumPy
running the same unrolled algorithm, the unrolled code against the loop algorithms it
replaces (bit for bit, on random structures of zeros and constants), and the flop counts
stated in the function headers.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from codegen_support import require_c_compiler

import symmech as sm
from symmech import codegen
from symmech.codegen.dialects import NumPyDialect
from symmech.codegen.flops import step_flops
from symmech.codegen.unroll import trace_step


def _ball_1d() -> sm.Scene:
    (z,) = sm.coordinates("z")
    m = sp.Symbol("m", positive=True)
    return sm.Scene(
        (z,),
        metric=sp.Matrix([[m]]),
        potential=sp.Rational(981, 100) * m * z,
        walls=[sm.Wall(z, restitution=sp.Rational(1, 2), name="ground")],
        name="ball1d",
    )


@pytest.mark.parametrize("strategy", ["closed_form", "linear_solve"])
@pytest.mark.parametrize("target", ["c", "numpy"])
def test_one_coordinate_scene(target, strategy):
    """A 1 x 1 metric and a 1 x 1 impact matrix keep their matrix axes (the audit's
    ValueError in the NumPy linear solve)."""
    if target == "c":
        require_c_compiler()
    mod = codegen.generate(_ball_1d(), target, strategy=strategy).load()
    assert mod.acceleration([0.0], [-2.0], [1.0]).tolist() == [-9.81]
    assert mod.impact([0.0], [-2.0], [1.0]).tolist() == [1.0]  # alpha = 1/2
    assert mod.mass_matrix([0.0], [3.0]).shape == (1, 1)
    batch = mod.acceleration(np.zeros((5, 1)), np.ones((5, 1)), [2.0])
    np.testing.assert_array_equal(batch, np.full((5, 1), -9.81))


def _numpy_namespace(code: codegen.GeneratedCode) -> dict:
    namespace: dict = {}
    exec(compile(code.files[f"{code.stem}.py"], code.stem, "exec"), namespace)
    return namespace


def _polynomial_scene() -> sm.Scene:
    """Metric, forcing, constraint and walls built from + - * only (no libm call), so the
    C and NumPy code must give the same doubles if they run the same algorithm: a
    non-diagonal metric (Cholesky), a constraint (Schur complement C), a static and a
    moving wall with an impulsive constraint (KKT impact with nu rows)."""
    x, y, z = sm.coordinates("x y z")
    xd, yd, zd = sm.velocities((x, y, z))
    a = sp.Symbol("a", positive=True)
    alpha = sp.Symbol("alpha", nonnegative=True)
    f = sp.Function("f", real=True)
    metric = sp.Matrix([[2 + y**2, y / 2, 0], [y / 2, 3 + a, x / 3], [0, x / 3, 1 + x**2]])
    return sm.Scene(
        (x, y, z),
        metric=metric,
        potential=a * x * y + z**2 / 2,
        constraints=[xd + y * zd],
        walls=[
            sm.Wall(z + x * y - 1, restitution=alpha, name="static"),
            sm.Wall(z - f(sm.t), restitution=alpha, impulsive_constraints=[yd], name="moving"),
        ],
        name="polynomial",
    )


def test_numpy_and_c_run_the_same_algorithm_bit_for_bit():
    require_c_compiler()
    scene = _polynomial_scene()
    mods = {t: codegen.generate(scene, t, strategy="linear_solve").load() for t in ("c", "numpy")}
    steps = {f.name: f.step for f in mods["c"].code.functions}
    assert steps["acceleration"] == "constrained_acceleration"
    assert steps["impact_moving"] == "impact_kkt" and steps["impact_static"] == "impact_kkt"
    rng = np.random.default_rng(20240604)
    N = 64
    q = rng.uniform(-1, 1, (N, 3))
    v = rng.uniform(-1, 1, (N, 3))
    p = np.array([0.7, 0.4])  # a, alpha
    u = rng.uniform(-1, 1, (N, 2))  # f(t), f'(t)
    for name in ("acceleration", "multipliers", "rhs", "impact_static", "impact_moving"):
        args = [np.hstack([q, v])] if name == "rhs" else [q, v]
        c_out = mods["c"].call(name, *args, params=p, inputs=u)
        np_out = mods["numpy"].call(name, *args, params=p, inputs=u)
        np.testing.assert_array_equal(c_out, np_out, err_msg=name)
    # and the result solves the system: mu v_dot = -mu_dot v is met
    acc = mods["numpy"].acceleration(q, v, p)
    _, y, _ = q.T
    _, yd, zd = v.T
    mu_acc = acc[:, 0] + y * acc[:, 2]
    np.testing.assert_allclose(mu_acc, -yd * zd, rtol=1e-13, atol=1e-14)


# -------------------------------------------------- the unrolled steps against the loops
#
# The loop algorithms the generated code used before it was unrolled (the C templates'
# sm_cholesky, sm_cholesky_solve, sm_factor, sm_factor_solve, sm_constrained and
# sm_impact_kkt), written here in Python floats (IEEE binary64, as in C): the unrolled code
# must return the same doubles, bit for bit, on any structure of constants and zeros.


def _loop_cholesky(n, A):
    A = [row[:] for row in A]
    for j in range(n):
        d = A[j][j]
        for k in range(j):
            d -= A[j][k] * A[j][k]
        if not d > 0.0:
            raise np.linalg.LinAlgError("not SPD")
        inv = 1.0 / math.sqrt(d)
        A[j][j] = inv
        for i in range(j + 1, n):
            s = A[i][j]
            for k in range(j):
                s -= A[i][k] * A[j][k]
            A[i][j] = s * inv
    return A


def _loop_cholesky_solve(n, L, B):
    r = len(B[0])
    for c in range(r):
        for i in range(n):
            s = B[i][c]
            for k in range(i):
                s -= L[i][k] * B[k][c]
            B[i][c] = s * L[i][i]
        for i in range(n - 1, -1, -1):
            s = B[i][c]
            for k in range(i + 1, n):
                s -= L[k][i] * B[k][c]
            B[i][c] = s * L[i][i]


def _loop_factor(n, diag, M):
    if not diag:
        return _loop_cholesky(n, M)
    if not all(M[j][j] > 0.0 for j in range(n)):
        raise np.linalg.LinAlgError("not SPD")
    return M


def _loop_factor_solve(n, diag, L, B):
    if not diag:
        _loop_cholesky_solve(n, L, B)
        return
    for i in range(n):
        for c in range(len(B[i])):
            B[i][c] /= L[i][i]


def _loop_spd_solve(n, diag, M, f):
    L = _loop_factor(n, diag, M)
    X = [[f[i]] for i in range(n)]
    _loop_factor_solve(n, diag, L, X)
    return [X[i][0] for i in range(n)]


def _loop_constrained(n, m, diag, M, f, mu, rate, acceleration):
    L = _loop_factor(n, diag, M)
    X = [[mu[a][i] for a in range(m)] + [f[i]] for i in range(n)]
    _loop_factor_solve(n, diag, L, X)
    lam = []
    C = [[0.0] * m for _ in range(m)]
    for a in range(m):
        s = -rate[a]
        for i in range(n):
            s -= mu[a][i] * X[i][m]
        lam.append([s])
        for b in range(m):
            c = 0.0
            for i in range(n):
                c += mu[a][i] * X[i][b]
            C[a][b] = c
    LC = _loop_cholesky(m, C)
    _loop_cholesky_solve(m, LC, lam)
    if not acceleration:
        return [lam[a][0] for a in range(m)]
    out = []
    for i in range(n):
        s = X[i][m]
        for a in range(m):
            s += X[i][a] * lam[a][0]
        out.append(s)
    return out


def _loop_impact(n, k, m, diag, M, A, alpha, psi_t, v):
    L = _loop_factor(n, diag, M)
    Y = [[A[a][i] for a in range(k)] for i in range(n)]
    _loop_factor_solve(n, diag, L, Y)
    r = []
    G = [[0.0] * k for _ in range(k)]
    for a in range(k):
        av = 0.0
        for i in range(n):
            av += A[a][i] * v[i]
        r.append([-av])
        for b in range(k):
            c = 0.0
            for i in range(n):
                c += A[a][i] * Y[i][b]
            G[a][b] = c
    r[m][0] = (1.0 + alpha) * (r[m][0] - psi_t)
    for a in range(m + 1, k):
        r[a][0] += -psi_t * G[a][m] / G[m][m]
    if k == 1:  # one row: one division
        r[0][0] = r[0][0] / G[0][0]
    else:
        LG = _loop_cholesky(k, G)
        _loop_cholesky_solve(k, LG, r)
    out = []
    for i in range(n):
        s = v[i]
        for a in range(k):
            s += Y[i][a] * r[a][0]
        out.append(s)
    return out


def _structured(rng, rows, cols, zero, one):
    """A random matrix with structural zeros and exact constants (None marks the entries
    that are run-time values in the unrolled code, with their value alongside)."""
    values = rng.uniform(-1, 1, (rows, cols))
    mask = np.full((rows, cols), None, dtype=object)
    pick = rng.uniform(size=(rows, cols))
    values[pick < zero] = 0.0
    mask[pick < zero] = 0.0
    ones = (pick >= zero) & (pick < zero + one)
    values[ones] = 1.0
    mask[ones] = 1.0
    return values, mask


def _structured_spd(rng, n, diag):
    """An SPD metric with a random symmetric zero pattern (diagonally dominant)."""
    if diag:
        values = np.diag(rng.uniform(0.5, 2.0, n))
        mask = np.full((n, n), 0.0, dtype=object)
        for j in range(n):
            if rng.uniform() < 0.3:
                values[j, j] = 1.0
                mask[j, j] = 1.0
            else:
                mask[j, j] = None
        return values, mask
    B, mask = _structured(rng, n, n, zero=0.4, one=0.0)
    values = np.tril(B, -1) + np.tril(B, -1).T + np.diag(n + rng.uniform(0, 1, n))
    mask = np.where(np.tril(np.ones((n, n)), -1) > 0, mask, mask.T)
    for j in range(n):
        mask[j, j] = None
    return values, mask


def _run_unrolled(step, args, blocks, out_shape, v=None):
    """Trace ``step`` over the structure of ``blocks`` (name -> (values, mask)), print it
    with the NumPy dialect and execute it with the run-time entries bound to their
    values."""
    structure = {}
    exprs = {}
    for name, (values, mask) in blocks.items():
        values = np.atleast_1d(values)
        mask = np.atleast_1d(mask)
        structure[name] = (values.shape, [None if c is None else float(c) for c in mask.flat])
        for flat, x in enumerate(values.flat):
            exprs[name, flat] = repr(float(x))
    prog = trace_step(step, args, structure)
    lines = NumPyDialect().lines(prog, out_shape, exprs)
    namespace = {"numpy": np, "shape": (), "_require_finite": lambda *a: None}
    if v is not None:
        namespace["v"] = np.asarray(v, dtype=float)
    exec("\n".join(lines), namespace)
    return [float(x) for x in namespace["out"]], prog


def _same_doubles(got, want):
    assert len(got) == len(want)
    for g, w in zip(got, want, strict=True):
        assert g == w, (got, want)  # == : only the sign of a zero may differ


@pytest.mark.parametrize("diag", [0, 1])
def test_unrolled_steps_equal_the_loop_algorithms_bit_for_bit(diag):
    rng = np.random.default_rng(1234 + diag)
    saved = 0
    for _trial in range(60):
        n = int(rng.integers(1, 7))
        M, Mmask = _structured_spd(rng, n, diag)
        f, fmask = _structured(rng, 1, n, zero=0.3, one=0.1)
        _, dense = _run_unrolled(
            "spd_solve",
            (n, diag),
            {"M": (M, np.full((n, n), None, dtype=object)), "f": (f[0], [None] * n)},
            (n,),
        )
        got, prog = _run_unrolled(
            "spd_solve", (n, diag), {"M": (M, Mmask), "f": (f[0], fmask[0])}, (n,)
        )
        _same_doubles(got, _loop_spd_solve(n, diag, M.tolist(), f[0].tolist()))
        assert prog.flops <= dense.flops <= step_flops("spd_solve", (n, diag))
        saved += dense.flops - prog.flops
        # constrained: mu with full row rank (a unit entry per row on distinct columns)
        m = int(rng.integers(1, n + 1)) if n > 1 else 1
        if m >= n:
            m = n - 1
        if m >= 1:
            mu, mumask = _structured(rng, m, n, zero=0.5, one=0.1)
            cols = rng.permutation(n)[:m]
            for a, c in enumerate(cols):
                mu[a, c] = 1.0
                mumask[a, c] = 1.0
            rate, ratemask = _structured(rng, 1, m, zero=0.5, one=0.0)
            blocks = {
                "M": (M, Mmask),
                "f": (f[0], fmask[0]),
                "mu": (mu, mumask),
                "rate": (rate[0], ratemask[0]),
            }
            for acc in (True, False):
                step = "constrained_acceleration" if acc else "constrained_multipliers"
                got, _ = _run_unrolled(step, (n, m, diag), blocks, (n if acc else m,))
                want = _loop_constrained(
                    n, m, diag, M.tolist(), f[0].tolist(), mu.tolist(), rate[0].tolist(), acc
                )
                _same_doubles(got, want)
        # impact: A = [mu (m0 rows); dpsi; nu], full row rank
        k = int(rng.integers(1, n + 1))
        m0 = int(rng.integers(0, k))
        A, Amask = _structured(rng, k, n, zero=0.5, one=0.1)
        cols = rng.permutation(n)[:k]
        for a, c in enumerate(cols):
            A[a, c] = 2.0
            Amask[a, c] = None
        alpha = float(rng.choice([0.0, 1.0, rng.uniform()]))
        psi_t = float(rng.choice([0.0, rng.uniform(-1, 1)]))
        smask = [alpha if alpha in (0.0, 1.0) else None, 0.0 if psi_t == 0.0 else None]
        vel = rng.uniform(-1, 1, n)
        got, _ = _run_unrolled(
            "impact_kkt",
            (n, k, m0, diag),
            {"M": (M, Mmask), "A": (A, Amask), "s": (np.array([alpha, psi_t]), smask)},
            (n,),
            v=vel,
        )
        want = _loop_impact(n, k, m0, diag, M.tolist(), A.tolist(), alpha, psi_t, vel.tolist())
        _same_doubles(got, want)
    assert saved > 0  # the structures above do skip work


def test_unrolled_code_checks_pivots_and_refuses_a_constant_indefinite_matrix():
    # a run-time pivot is checked in the generated code
    M = np.array([[1.0, 2.0], [2.0, 1.0]])  # indefinite
    mask = np.full((2, 2), None, dtype=object)
    with pytest.raises(np.linalg.LinAlgError, match="positive definite"):
        _run_unrolled("spd_solve", (2, 0), {"M": (M, mask), "f": ([1.0, 1.0], [None, None])}, (2,))
    # a constant non-positive pivot is found at generation time
    with pytest.raises(codegen.CodegenError, match="never positive definite"):
        _run_unrolled(
            "spd_solve", (2, 0), {"M": (M, M.astype(object)), "f": ([1.0, 1.0], [None, None])}, (2,)
        )


def test_unrolled_code_reads_only_what_it_needs():
    """The upper triangle of a symmetric metric is never read, nor a pivot's reciprocal
    whose column meets only zeros; every value read is checked finite first."""
    code = codegen.generate(_polynomial_scene(), "c", strategy="linear_solve")
    acc = next(f for f in code.functions if f.name == "acceleration")
    text = "\n".join(acc.solve)
    assert "M0_1 =" not in text and "M1_0 =" in text  # lower triangle only
    assert "M0_2" not in text and "M2_0" not in text  # a structural zero
    assert text.index("isfinite(M0_0)") < text.index("M0_0 > 0.0")
    assert "for (" not in text


def _dense(step, args, shapes):
    """The unrolled program of ``step`` with every entry a run-time value."""
    structure = {name: (shape, [None] * int(np.prod(shape))) for name, shape in shapes.items()}
    return trace_step(step, args, structure)


def test_step_flop_counts_by_hand_and_in_the_headers():
    # Cholesky of 2 x 2: column 0: sqrt, reciprocal, l10 = a10 inv (3); column 1:
    # d = a11 - l10^2, sqrt, reciprocal (4); each triangular solve: 1 + 3 = n^2 = 4
    assert step_flops("spd_solve", (2, 0)) == 3 + 4 + 4 + 4
    assert _dense("spd_solve", (2, 0), {"M": (2, 2), "f": (2,)}).flops == 3 + 4 + 4 + 4
    # diagonal 2 x 2: one division per row
    assert step_flops("spd_solve", (2, 1)) == 2
    assert _dense("spd_solve", (2, 1), {"M": (2, 2), "f": (2,)}).flops == 2
    assert step_flops("spd_solve", (1, 0)) == 2 + 2
    # impact with one row (n = 1, diagonal): M^-1 A^T (1), A v (2), G = A Y (2), the
    # wall's right-hand side (3), r / G (1: one division, no Cholesky), v + Y lambda (2)
    assert step_flops("impact_kkt", (1, 1, 0, 1)) == 1 + 2 + 2 + 3 + 1 + 2
    # leading orders: n^3 / 3 for the factorisation, 2 n^2 for the two solves
    n = 60
    assert step_flops("spd_solve", (n, 0)) / (n**3 / 3 + 2 * n**2) == pytest.approx(1, rel=0.05)
    # constrained, n = 2, m = 1, dense: factor 7; M^-1 [mu^T | f], 2 columns of 4 + 4;
    # lambda = -rate - mu X_f (4); C = mu X_mu (3: the first 0.0 + x is exact); the 1 x 1
    # factor (2) and solve (2); acc = X_f + X_mu lambda (4)
    shapes = {"M": (2, 2), "f": (2,), "mu": (1, 2), "rate": (1,)}
    assert _dense("constrained_acceleration", (2, 1, 0), shapes).flops == 7 + 16 + 4 + 3 + 2 + 2 + 4
    assert step_flops("constrained_acceleration", (2, 1, 0)) == 7 + 16 + 4 + 4 + 2 + 2 + 4
    code = codegen.generate(_polynomial_scene(), "c", strategy="linear_solve")
    src = code.files["symmech_polynomial.c"]
    acc = next(f for f in code.functions if f.name == "acceleration")
    dense = step_flops("constrained_acceleration", (3, 1, 0))
    # the metric's structural zero g_xz = 0 saves work
    assert 0 < acc.solve_flops < dense
    assert f"solve: {acc.solve_flops} flops (n = 3, m = 1; dense: {dense})" in src
    rhs = next(f for f in code.functions if f.name == "rhs")
    assert (
        f"then the call of acceleration: {acc.operations} operations + {acc.solve_flops} flops"
        in rhs.cost
    )
    impact = next(f for f in code.functions if f.name == "impact_moving")
    assert f"solve: {impact.solve_flops} flops (n = 3, k = 3;" in src
