"""Generated code against independent references: C vs NumPy vs sympy.lambdify vs mpmath.

For every built-in scene (and both strategies, closed form and linear solve), every
generated function is evaluated at random states by the compiled C and by the NumPy
module, and compared with a reference computed in mpmath at 50 digits from the scene's
symbolic quantities (see ``codegen_support``: the constrained acceleration, multipliers
and Newton impacts come from an LU solve of the full KKT systems, not from the closed
forms or the generated Cholesky code).  Each error must lie within twice its
first-order bound (running error analysis for closed forms, normwise perturbation bound
for linear solves), and the worst error in ulps is reported at the end of the run
(``symmech codegen accuracy`` in the terminal summary).  Closed forms are also checked
against the KKT references at 50 digits, and ``sympy.lambdify(..., cse=True)`` is held to
the same bound as the generated code.
"""

from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest
import sympy as sp
from codegen_support import (
    DPS,
    U,
    block_bounds,
    kkt_solution,
    norm2,
    running_bound,
    ulps,
)

import symmech as sm
from symmech import codegen
from symmech.declaration.symbols import t as TIME
from symmech.examples import (
    bouncing_ellipse,
    car,
    carnot_3_7,
    carnot_3_13,
    carnot_4_4,
    pendulum_on_cart,
    rolling_ball,
    spinning_disk,
)

ALPHA = sp.Symbol("alpha", nonnegative=True)

SCENES = {
    "bouncing_ellipse": lambda: bouncing_ellipse(ALPHA),
    "spinning_disk": spinning_disk,
    "spinning_disk_newton": lambda: spinning_disk("newton"),
    "carnot_3_7": carnot_3_7,
    "carnot_3_13": carnot_3_13,
    "carnot_4_4": carnot_4_4,
    "rolling_ball": rolling_ball,
    "car": car,
    "pendulum_on_cart_2": lambda: pendulum_on_cart(2),
}
STATES = 3


@pytest.fixture(scope="module")
def scenes():
    return {name: build() for name, build in SCENES.items()}


def _random_env(scene: sm.Scene, module: codegen.SceneModule, rng: np.random.Generator):
    """Doubles for q, v, p, t and the inputs; Euler angles theta kept away from 0 and pi."""
    n = scene.n
    q = rng.uniform(-1.0, 1.0, n)
    for i, s in enumerate(scene.coordinates):
        if s.name == "theta" and scene.frame is not None:
            q[i] = rng.uniform(0.4, 2.7)
    v = rng.uniform(-1.0, 1.0, n)
    restitutions = {w.restitution for w in scene.walls}
    p = np.array(
        [
            rng.uniform(0.0, 1.0) if s in restitutions else rng.uniform(0.5, 2.0)
            for s in module.code.plan.parameters
        ]
    )
    t = float(rng.uniform(0.0, 2.0))
    u = rng.uniform(-1.0, 1.0, len(module.inputs))
    env = dict(zip(scene.coordinates, q, strict=True))
    env.update(zip(scene.velocities, v, strict=True))
    env.update(zip(module.code.plan.parameters, p, strict=True))
    env[TIME] = t
    atoms = {a: d for d, a in module.code.plan.inputs}
    env.update({atoms[a]: float(x) for (_, a), x in zip(module.code.plan.inputs, u, strict=True)})
    return q, v, p, t, u, env, atoms


def _subs_inputs(expr: sp.Expr, atoms) -> sp.Expr:
    return sp.sympify(expr).xreplace(atoms) if atoms else sp.sympify(expr)


def _in_D(scene: sm.Scene, v: np.ndarray, env) -> np.ndarray:
    """v projected onto the constraint distribution D (float64, as a user would)."""
    if not scene.is_constrained:
        return v
    mu = np.array(
        [
            [float(e.xreplace(env)) for e in scene.constraint_matrix.row(a)]
            for a in range(scene.constraint_matrix.rows)
        ]
    )
    M = np.array(
        [[float(e.xreplace(env)) for e in scene.mass_matrix().row(i)] for i in range(scene.n)]
    )
    Z = np.linalg.solve(M, mu.T)
    return v - Z @ np.linalg.solve(mu @ Z, mu @ v)


def _mp_block(M: sp.MatrixBase, env, atoms) -> tuple[mp.matrix, mp.mpf]:
    return block_bounds([_subs_inputs(e, atoms) for e in M], env)


def _kkt_reference(scene, env, atoms, kind: str, wall=None):
    """(solution vector z, its bound data) for acceleration / multipliers / impact."""
    n = scene.n
    with mp.workdps(DPS):
        Mv, bM = _mp_block(scene.mass_matrix(), env, atoms)
        M = mp.matrix(n, n)
        for i in range(n):
            for j in range(n):
                M[i, j] = Mv[i * n + j]
        if kind in ("acceleration", "multipliers"):
            f, bf = _mp_block(scene.forcing(), env, atoms)
            mu_rows = scene.constraint_matrix
            m = mu_rows.rows
            if m:
                muv, bmu = _mp_block(mu_rows, env, atoms)
                rate, brate = _mp_block(scene.constraint_rate(), env, atoms)
                A = mp.matrix(m, n)
                for a in range(m):
                    for i in range(n):
                        A[a, i] = muv[a * n + i]
                # M acc - mu^T lam = f, mu acc = -rate: lam is the lambda of
                # Scene.multipliers (M v_dot = f + mu^T lambda)
                x, lam, K = kkt_solution(M, f, A, -rate)
                bK, bb = bM + bmu, bf + brate
                z = x if kind == "acceleration" else lam
            else:
                x = mp.lu_solve(M, f)
                K, bK, bb, lam, z = M, bM, bf, mp.matrix(0, 1), x
            return z, (K, bK, bb, norm2(list(x) + list(lam)))
        # Newton impact: g (v+ - v) = A^T lam; mu v+ = 0; dpsi v+ + psi_t =
        # -alpha (dpsi v + psi_t); nu (v+ - V) = 0 with V = -psi_t grad psi / |grad psi|^2
        q = scene.coordinates
        grad = sp.Matrix([[sp.diff(wall.psi, qi) for qi in q]])
        dpsi = grad * scene.frame if scene.frame is not None else grad
        Aexpr = (
            sp.Matrix(scene.constraint_matrix)
            .col_join(dpsi)
            .col_join(sp.Matrix(wall.impulsive_matrix))
        )
        k, m = Aexpr.rows, scene.constraint_matrix.rows
        Av, bA = _mp_block(Aexpr, env, atoms)
        A = mp.matrix(k, n)
        for a in range(k):
            for i in range(n):
                A[a, i] = Av[a * n + i]
        alpha = mp.mpf(float(sp.sympify(wall.restitution).xreplace(env)))
        psi_t, _ = running_bound(_subs_inputs(sp.diff(wall.psi, TIME), atoms), env)
        v = mp.matrix([mp.mpf(env[s]) for s in scene.velocities])
        Y = mp.matrix(n, k)
        for a in range(k):
            col = mp.lu_solve(M, mp.matrix([A[a, i] for i in range(n)]))
            for i in range(n):
                Y[i, a] = col[i]
        G = A * Y
        av = A * v
        b = mp.matrix(k, 1)
        b[m] = -alpha * av[m] - (1 + alpha) * psi_t
        for a in range(m + 1, k):
            b[a] = -psi_t * G[a, m] / G[m, m]
        x, lam, K = kkt_solution(M, M * v, A, b)
        bb = bM * norm2(v) + mp.mpf(4) * U * (norm2(b) + abs(psi_t))
        return x, (K, bM + bA, bb, norm2(list(x) + list(lam)))


def _solve_bound(data) -> mp.mpf:
    """Normwise bound of a linear solve (codegen_support docstring)."""
    K, bK, bb, znorm = data
    N = K.rows
    with mp.workdps(DPS):
        s = mp.svd_r(K, compute_uv=False)
        sv = [abs(s[i]) for i in range(len(s))]
        smax, smin = max(sv), min(sv)
        backward = (3 * N + 1) * N * U * smax
        return ((bK + backward) * znorm + bb) / smin


def _closed_reference(exprs, env, atoms):
    vals, bounds = [], []
    for e in exprs:
        val, b = running_bound(_subs_inputs(e, atoms), env)
        vals.append(val)
        bounds.append(b)
    return vals, bounds


def _check(label, got: np.ndarray, ref, bounds, report_rows):
    got = np.asarray(got, dtype=np.float64).reshape(-1)
    ref = list(ref)
    # ulps are counted relative to the largest entry of the output; an output that is
    # zero (to 30 digits relative to the magnitude of its computation, bound / u) is
    # measured against that magnitude instead
    bound_list = bounds if isinstance(bounds, list) else [bounds] * len(ref)
    magnitude = max([b / U for b in bound_list] + [mp.mpf(0)])
    scale = max([abs(r) for r in ref] + [mp.mpf(0)])
    if scale <= mp.mpf(10) ** -30 * magnitude:
        scale = magnitude
    worst_ulps, worst_ratio = 0.0, 0.0
    for i, (g, r) in enumerate(zip(got, ref, strict=True)):
        err = abs(mp.mpf(g) - r)
        bound = bounds[i] if isinstance(bounds, list) else bounds
        limit = 2 * bound + mp.mpf(10) ** -300
        assert err <= limit, (
            f"{label}[{i}]: got {g!r}, reference {mp.nstr(r, 20)}, error {mp.nstr(err, 3)}"
            f" > 2 x bound {mp.nstr(bound, 3)}"
        )
        worst_ulps = max(worst_ulps, ulps(err, scale))
        if bound > 0:
            worst_ratio = max(worst_ratio, float(err / bound))
    report_rows.append((label, worst_ulps, worst_ratio))


def _lambdified(exprs, scene, module, atoms):
    syms = [
        *scene.coordinates,
        *scene.velocities,
        *module.code.plan.parameters,
        TIME,
        *[d for d, _ in module.code.plan.inputs],
    ]
    exprs = [_subs_inputs(e, atoms) for e in exprs]
    return sp.lambdify(syms, exprs, modules="numpy", cse=True)


CASES = [
    (name, strategy)
    for name in SCENES
    for strategy in ("closed_form", "linear_solve")
    if not (strategy == "closed_form" and name == "car")  # n = 4: closed form is slow
]


@pytest.mark.parametrize(("name", "strategy"), CASES)
def test_generated_functions_against_mpmath(scenes, name, strategy, request):
    scene = scenes[name]
    gen = {
        target: codegen.generate(scene, target, strategy=strategy, projectors=True)
        for target in ("c", "numpy")
    }
    mods = {target: code.load() for target, code in gen.items()}
    rng = np.random.default_rng(abs(hash((name, strategy))) % 2**32)
    rows: list[tuple] = []
    n = scene.n
    for _ in range(STATES):
        q, v, p, t, u, env, atoms = _random_env(scene, mods["c"], rng)
        env_mp = env
        for fname in mods["c"].functions:
            spec = mods["c"]._spec[fname]
            vin = v
            wall = None
            if spec.kind == "impact":
                wall = next(w for w in scene.walls if f"impact_{w.name}" == fname)
                vin = _in_D(scene, v, env)
                env_mp = dict(env)
                env_mp.update(zip(scene.velocities, vin, strict=True))
            else:
                env_mp = env
            if spec.state == ("y",):
                args = [np.concatenate([q, vin])]
            else:
                args = [q, vin][: len(spec.state)]
            outs = {
                target: mod.call(fname, *args, params=p, t=t, inputs=u if mod.inputs else None)
                for target, mod in mods.items()
            }
            # reference and bound
            kind = spec.kind
            exprs = None
            if kind == "mass_matrix":
                exprs = list(scene.mass_matrix())
            elif kind == "forcing":
                exprs = list(scene.forcing())
            elif kind == "energy":
                exprs = [scene.energy()]
            elif kind == "constraint_residual":
                exprs = list(scene.constraint_matrix * sp.Matrix(scene.velocities))
            elif kind == "projectors":
                P, Q = scene.projectors()
                exprs = list(P if fname.endswith("P") else Q)
            elif kind in ("psi", "dpsi", "psi_t"):
                w = next(w for w in scene.walls if fname.endswith("_" + w.name))
                if kind == "psi":
                    exprs = [w.psi]
                elif kind == "dpsi":
                    exprs = [sp.diff(w.psi, qi) for qi in scene.coordinates]
                else:
                    exprs = [sp.diff(w.psi, TIME)]
            if exprs is not None:
                ref, bounds = _closed_reference(exprs, env_mp, atoms)
                lam = _lambdified(exprs, scene, mods["c"], atoms)
                lam_out = np.array(lam(*q, *vin, *p, t, *u), dtype=np.float64)
                for target, got in outs.items():
                    _check(f"{name}/{strategy}/{target}/{fname}", got, ref, bounds, rows)
                _check(f"{name}/{strategy}/lambdify/{fname}", lam_out, ref, bounds, rows)
                continue
            # acceleration, multipliers, impact, rhs
            if kind == "rhs":
                qdot = list(scene.kinematics())
                ref_q, b_q = _closed_reference(qdot, env_mp, atoms)
                for target, got in outs.items():
                    _check(f"{name}/{strategy}/{target}/rhs[q]", got[:n], ref_q, b_q, rows)
                kind, outs = "acceleration", {k: o[n:] for k, o in outs.items()}
            if kind == "impact" and wall.law == "energy":
                exprs = list(scene.impact_map(wall.index).post_velocity)
                ref, bounds = _closed_reference(exprs, env_mp, atoms)
                for target, got in outs.items():
                    _check(f"{name}/{strategy}/{target}/{fname}", got, ref, bounds, rows)
                continue
            z, data = _kkt_reference(scene, env_mp, atoms, kind, wall)
            closed = spec.step is None
            if closed:
                # the closed form at 50 digits must equal the KKT solution (independent routes)
                if kind == "impact":
                    cexprs = list(scene.impact_map(wall.index).post_velocity)
                elif kind == "acceleration":
                    cexprs = list(scene.acceleration())
                else:
                    cexprs = list(scene.multipliers())
                ref, bounds = _closed_reference(cexprs, env_mp, atoms)
                gap = max(abs(a - b) for a, b in zip(ref, z, strict=True))
                tol = mp.mpf(10) ** -40 if kind != "impact" else 1e-12 * (1 + norm2(z))
                assert gap <= tol, f"{name}/{fname}: closed form and KKT differ by {gap}"
            else:
                ref, bounds = list(z), _solve_bound(data)
            for target, got in outs.items():
                _check(f"{name}/{strategy}/{target}/{fname}", got, ref, bounds, rows)
    # C and NumPy agree closely (same CSE; differences only from libm and the solves)
    request.config._symmech_accuracy = getattr(request.config, "_symmech_accuracy", [])
    request.config._symmech_accuracy.extend(rows)


def test_both_backends_agree_on_a_batch(scenes):
    """Batch calls (N states at once) give the single-state results, for C and NumPy."""
    scene = scenes["carnot_4_4"]
    mods = {t: codegen.generate(scene, t).load() for t in ("c", "numpy")}
    rng = np.random.default_rng(7)
    N = 50
    q = rng.uniform(-1, 1, (N, 6))
    q[:, 4] = rng.uniform(0.4, 2.7, N)
    v = rng.uniform(-1, 1, (N, 6))
    p = np.array([0.5, 1.2, 0.7])
    u = rng.uniform(-1, 1, (N, 2))
    for fname in mods["c"].functions:
        spec = mods["c"]._spec[fname]
        args = [np.hstack([q, v])] if spec.state == ("y",) else [q, v][: len(spec.state)]
        batch = {t: m.call(fname, *args, params=p, t=0.3, inputs=u) for t, m in mods.items()}
        assert batch["c"].shape[0] == N
        np.testing.assert_allclose(batch["c"], batch["numpy"], rtol=1e-13, atol=1e-13)
        for i in (0, N // 2, N - 1):
            one = mods["c"].call(fname, *[a[i] for a in args], params=p, t=0.3, inputs=u[i])
            np.testing.assert_array_equal(one, batch["c"][i])


@pytest.mark.parametrize("target", ["c", "numpy"])
def test_stable_forms_survive_code_generation(target):
    """A nearly circular ellipse (b = a (1 + 1e-9)): the wall gradient
    (a^2 - b^2) sin cos / sqrt(a^2 cos^2 + b^2 sin^2) must be evaluated as
    (a - b)(a + b) ..., else a^2 - b^2 cancels and loses 9 of its 16 digits."""
    mod = codegen.generate(bouncing_ellipse(), target).load()
    a, b, th = 1.0, 1.0 + 1e-9, 0.7
    params = dict(zip(mod.parameters, [0.3, a, b, 2.0], strict=True))  # I, a, b, m
    got = mod.dpsi([0.0, 0.0, th], params)[2]
    with mp.workdps(DPS):
        A, B, T = mp.mpf(a), mp.mpf(b), mp.mpf(th)
        exact = (
            (A**2 - B**2)
            * mp.sin(T)
            * mp.cos(T)
            / mp.sqrt(A**2 * mp.cos(T) ** 2 + B**2 * mp.sin(T) ** 2)
        )
        rel = abs((mp.mpf(got) - exact) / exact)
    assert rel < 1e-14, f"relative error {mp.nstr(rel, 3)}"
