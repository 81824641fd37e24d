"""The linear-algebra steps of the generated code: one-coordinate scenes, the NumPy
Cholesky factorisation written in the template (the C algorithm, same operations in the
same order), and the flop counts stated in the function headers.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from codegen_support import require_c_compiler

import symmech as sm
from symmech import codegen
from symmech.codegen.lower import step_flops


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


def test_numpy_cholesky_is_written_in_the_template():
    code = codegen.generate(_polynomial_scene(), "numpy", strategy="linear_solve")
    src = code.files["symmech_polynomial.py"]
    assert "numpy.linalg.solve" not in src and "numpy.linalg.cholesky" not in src
    ns = _numpy_namespace(code)
    rng = np.random.default_rng(3)
    B = rng.uniform(-1, 1, (7, 4, 4))
    A = B @ np.swapaxes(B, -1, -2) + 0.5 * np.eye(4)
    L = ns["_cholesky"](A)
    ref = np.linalg.cholesky(A)
    np.testing.assert_allclose(np.tril(L, -1), np.tril(ref, -1), rtol=1e-13, atol=1e-14)
    np.testing.assert_allclose(np.diagonal(L, axis1=1, axis2=2), 1 / np.diagonal(ref, 0, 1, 2))
    rhs = rng.uniform(-1, 1, (7, 4, 3))
    np.testing.assert_allclose(
        ns["_cholesky_solve"](L, rhs), np.linalg.solve(A, rhs), rtol=1e-12, atol=1e-13
    )
    A[3, 2, 2] = -1.0
    with pytest.raises(np.linalg.LinAlgError, match="positive definite"):
        ns["_cholesky"](A)


def test_step_flop_counts_by_hand_and_in_the_headers():
    # Cholesky of 2 x 2: column 0: sqrt, reciprocal, l10 = a10 inv (3); column 1:
    # d = a11 - l10^2, sqrt, reciprocal (4); each triangular solve: 1 + 3 = n^2 = 4
    assert step_flops("spd_solve", (2, 0)) == 3 + 4 + 4 + 4
    # diagonal 2 x 2: one division per row
    assert step_flops("spd_solve", (2, 1)) == 2
    assert step_flops("spd_solve", (1, 0)) == 2 + 2
    # leading orders: n^3 / 3 for the factorisation, 2 n^2 for the two solves
    n = 60
    assert step_flops("spd_solve", (n, 0)) / (n**3 / 3 + 2 * n**2) == pytest.approx(1, rel=0.05)
    code = codegen.generate(_polynomial_scene(), "c", strategy="linear_solve")
    src = code.files["symmech_polynomial.c"]
    acc = next(f for f in code.functions if f.name == "acceleration")
    assert acc.solve_flops == step_flops("constrained_acceleration", (3, 1, 0))
    assert f"solve: {acc.solve_flops} flops (n = 3, m = 1)" in src
    rhs = next(f for f in code.functions if f.name == "rhs")
    assert (
        f"then the call of acceleration: {acc.operations} operations + {acc.solve_flops} flops"
        in rhs.cost
    )
    impact = next(f for f in code.functions if f.name == "impact_moving")
    assert f"solve: {impact.solve_flops} flops (n = 3, k = 3)" in src
