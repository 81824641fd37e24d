"""Large and adversarial scenes derive and generate in seconds, with the right numbers.

Inputs (tests/scale_support.py): a 200-coordinate scene file with an identity metric and
one wall; the potential ``(sin(x) + cos(y) + x*y*z + 1)**64``; a dense trigonometric
3 x 3 metric with a curved wall; the 4-link pendulum on a cart with a wall at its tip;
the 32-link pendulum on a cart (slow).  Time guards are generous (the machine is
shared); the figures are measured in benchmarks/.  The generated code is checked against
independent routes: the impact of a diagonal metric by hand, accelerations against
``numpy.linalg.solve`` of sympy-evaluated g and f, impacts against the mpmath KKT solve
of tests/test_impacts_support.py.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import mpmath as mp
import numpy as np
import pytest
import sympy as sp
from scale_support import (
    DENSE_POLYNOMIAL_6,
    DENSE_TRIG_3,
    DIAGONAL_200,
    NESTED_EXP,
    POWER_64,
    WALL_POWER_64,
    WALLS_100,
    cart_with_tip_wall,
)
from test_impacts_support import kkt_at

import symmech as sm
from symmech import codegen
from symmech.examples import pendulum_on_cart

ROOT = Path(__file__).resolve().parents[1]
#: the target of the hostile-input issue is 30 s per scene file on this machine
GUARD = 30.0


def _timed(build):
    start = time.perf_counter()
    out = build()
    return out, time.perf_counter() - start


def test_scene_files_are_small():
    for text in (
        DIAGONAL_200,
        WALLS_100,
        WALL_POWER_64,
        POWER_64,
        DENSE_TRIG_3,
        DENSE_POLYNOMIAL_6,
        NESTED_EXP,
    ):
        assert len(text.encode()) < 10_000


def test_diagonal_metric_with_200_coordinates_derives_and_generates_in_seconds():
    (scene, code), elapsed = _timed(
        lambda: (
            (s := sm.reads_scene(DIAGONAL_200, source="diag200.toml").scene),
            codegen.generate(s, "numpy"),
        )
    )
    assert elapsed < GUARD, f"{elapsed:.1f} s"
    assert scene.n == 200 and code.plan.strategy == "linear_solve"
    mod = code.load()
    rng = np.random.default_rng(3)
    q, v = rng.normal(size=200), rng.normal(size=200)
    v[0] = -abs(v[0])  # approaching the wall q0 + 1 = 0
    # identity metric, wall q0 + 1, restitution 1: only v_0 flips
    expected = v.copy()
    expected[0] = -v[0]
    np.testing.assert_allclose(mod.impact(q, v), expected, rtol=0, atol=1e-15)
    np.testing.assert_allclose(mod.acceleration(q, v), np.zeros(200), atol=0)


def test_wall_with_a_64th_power_gap_falls_back_at_once():
    scene = sm.reads_scene(WALL_POWER_64).scene
    code, elapsed = _timed(lambda: codegen.generate(scene, "numpy"))
    assert elapsed < GUARD, f"{elapsed:.1f} s"
    assert code.plan.strategy == "linear_solve"
    assert "closed-form impact map of wall" in code.plan.fallback
    mod = code.load()
    q_num = [sp.Rational(1, 10), sp.Rational(-1, 20), sp.Rational(1, 40)]
    point = dict(zip(scene.coordinates, q_num, strict=True))
    v_minus = [sp.Rational(-1, 2), sp.Rational(1, 3), sp.Rational(-1, 4)]
    expected = [float(e) for e in kkt_at(scene, 0, point, v_minus)]
    got = mod.impact([float(e) for e in q_num], [float(e) for e in v_minus])
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-14)


@pytest.mark.slow
def test_a_wall_on_each_of_100_coordinates():
    """3.8 KB: 100 impact functions of a 100 x 100 metric (about 20 s here)."""
    code, elapsed = _timed(lambda: codegen.generate(sm.reads_scene(WALLS_100).scene, "numpy"))
    assert elapsed < GUARD, f"{elapsed:.1f} s"
    mod = code.load()
    rng = np.random.default_rng(100)
    q, v = rng.normal(size=100), -np.abs(rng.normal(size=100))
    for wall in (0, 57, 99):
        expected = v.copy()
        expected[wall] = -v[wall]
        np.testing.assert_allclose(mod.impact(q, v, wall=wall), expected, rtol=0, atol=1e-15)


def test_power_64_potential_is_generated_by_linear_solve_at_once():
    scene = sm.reads_scene(POWER_64).scene
    code, elapsed = _timed(lambda: codegen.generate(scene, "numpy"))
    assert elapsed < GUARD, f"{elapsed:.1f} s"
    assert code.plan.strategy == "linear_solve" and "FIELD_TERMS" in code.plan.fallback
    mod = code.load()
    x, y, z = scene.coordinates
    V = (sp.sin(x) + sp.cos(y) + x * y * z + 1) ** 64
    point = {x: sp.Rational(1, 10), y: sp.Rational(-1, 5), z: sp.Rational(3, 10)}
    with mp.workdps(40):
        expected = [float(sp.N(-sp.diff(V, s).xreplace(point), 30)) for s in (x, y, z)]
    got = mod.acceleration([0.1, -0.2, 0.3], [0.5, -1.0, 2.0])
    np.testing.assert_allclose(got, expected, rtol=1e-12)


def test_dense_trigonometric_metric_with_a_wall_generates_and_solves():
    scene = sm.reads_scene(DENSE_TRIG_3).scene
    code, elapsed = _timed(lambda: codegen.generate(scene, "numpy"))
    assert elapsed < GUARD, f"{elapsed:.1f} s"
    assert code.plan.strategy == "linear_solve"
    mod = code.load()
    g = sp.Matrix(scene.mass_matrix())
    f = sp.Matrix(scene.forcing())
    q_num, v_num = [0.3, 1.1, -0.7], [0.2, -0.4, 0.9]
    at = dict(zip(scene.coordinates, q_num, strict=True))
    at.update(dict(zip(scene.velocities, v_num, strict=True)))
    G = np.array(g.xreplace(at).evalf(20), dtype=float)
    F = np.array(f.xreplace(at).evalf(20), dtype=float).ravel()
    np.testing.assert_allclose(mod.acceleration(q_num, v_num), np.linalg.solve(G, F), rtol=1e-12)
    point = {s: sp.Rational(str(val)) for s, val in zip(scene.coordinates, q_num, strict=True)}
    v_minus = [sp.Rational(1, 2), sp.Rational(-3, 4), sp.Rational(1, 3)]
    expected = [float(e) for e in kkt_at(scene, 0, point, v_minus)]
    got = mod.impact([float(point[s]) for s in scene.coordinates], [float(e) for e in v_minus])
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("text", [DENSE_POLYNOMIAL_6, NESTED_EXP], ids=["dense_6", "exp3"])
def test_other_hostile_scene_files_accelerate_right(text):
    """The acceleration of the generated code (whichever strategy auto takes) against
    numpy.linalg.solve of g and f evaluated by sympy at 30 digits."""
    scene = sm.reads_scene(text).scene
    code, elapsed = _timed(lambda: codegen.generate(scene, "numpy"))
    assert elapsed < GUARD, f"{elapsed:.1f} s"
    mod = code.load()
    n = scene.n
    q_num = [0.1 * (k + 1) * (-1) ** k for k in range(n)]
    v_num = [0.3 - 0.1 * k for k in range(n)]
    at = dict(zip(scene.coordinates, q_num, strict=True))
    at.update(dict(zip(scene.velocities, v_num, strict=True)))
    G = np.array(sp.Matrix(scene.mass_matrix()).xreplace(at).evalf(30), dtype=float)
    F = np.array(sp.Matrix(scene.forcing()).xreplace(at).evalf(30), dtype=float).ravel()
    np.testing.assert_allclose(mod.acceleration(q_num, v_num), np.linalg.solve(G, F), rtol=1e-11)


def test_four_link_cart_with_a_tip_wall_linear_solve():
    scene = cart_with_tip_wall(4)
    code, elapsed = _timed(lambda: codegen.generate(scene, "numpy", strategy="linear_solve"))
    assert elapsed < GUARD, f"{elapsed:.1f} s (target 5 s, benchmarks/codegen.py)"
    mod = code.load()
    values = {"alpha": 0.7, "d": 2.0, "g": 9.81}
    params = {p: values.get(p.name, 1.0 + 0.1 * k) for k, p in enumerate(code.plan.parameters)}
    q_num = [0.1, 0.3, -0.2, 0.5, 0.4]
    v_minus = [sp.Rational(1, 2), sp.Rational(1, 3), sp.Rational(-1, 4), sp.Rational(1, 5), 1]
    point = {s: sp.Rational(str(val)) for s, val in zip(scene.coordinates, q_num, strict=True)}
    point.update({p: sp.Rational(str(val)) for p, val in params.items()})
    expected = [float(e) for e in kkt_at(scene, 0, point, v_minus)]
    got = mod.impact(q_num, [float(e) for e in v_minus], [params[p] for p in code.plan.parameters])
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-14)


def test_cli_derive_says_when_auto_falls_back(tmp_path: Path):
    path = tmp_path / "dense.toml"
    path.write_text(DENSE_TRIG_3)
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    start = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "symmech", "derive", str(path), "--emit", "numpy", "-o", "out"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
    )
    elapsed = time.perf_counter() - start
    assert proc.returncode == 0, proc.stderr
    assert elapsed < GUARD + 10, f"{elapsed:.1f} s"
    assert "linear_solve is used instead of closed forms" in proc.stderr
    assert "CLOSED_FORM_TERMS" in proc.stderr


@pytest.mark.slow
def test_32_link_pendulum_linear_solve_c_generation():
    """Issue 13's row: C generation of the 32-link pendulum on a cart (target < 20 s,
    measured by benchmarks/codegen.py); the acceleration against numpy.linalg.solve."""
    scene = pendulum_on_cart(32)
    code, elapsed = _timed(lambda: codegen.generate(scene, "c", strategy="linear_solve"))
    assert elapsed < 60, f"{elapsed:.1f} s"
    mod = code.load()
    rng = np.random.default_rng(32)
    q, v = rng.normal(size=33), rng.normal(size=33)
    params = {p: 0.5 + rng.random() for p in code.plan.parameters}
    at = {**dict(zip(scene.coordinates, q, strict=True)), **params}
    at.update(dict(zip(scene.velocities, v, strict=True)))
    lam = sp.lambdify(
        [*scene.coordinates, *scene.velocities, *code.plan.parameters],
        [sp.Matrix(scene.mass_matrix()), sp.Matrix(scene.forcing())],
    )
    G, F = lam(*q, *v, *[params[p] for p in code.plan.parameters])
    expected = np.linalg.solve(np.array(G, float), np.array(F, float).ravel())
    got = mod.acceleration(q, v, [params[p] for p in code.plan.parameters])
    np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-9)
