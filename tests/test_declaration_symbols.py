"""Symbols of a declaration: one name, one symbol; deterministic parameters; velocity LaTeX.

Issue 2: "velocity symbols or unknown symbols where only coordinates and parameters may
appear" are refused, and "parameters= default: every other free symbol, in a
deterministic order".
"""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import symmech as sm

ROOT = Path(__file__).resolve().parents[1]

x, y, th = sm.coordinates("x y theta")
xd, yd, thd = sm.velocities((x, y, th))
m, I, R = sp.symbols("m I R", positive=True)
Q = (x, y, th)


def refused(q=Q, **kwargs) -> sm.SceneError:
    with pytest.raises(sm.SceneError) as info:
        sm.Scene(q, **kwargs)
    return info.value


# -- one name, one symbol --------------------------------------------------------------------


def test_symbol_named_like_a_coordinate_is_refused_not_made_a_parameter():
    # the audit's case: Symbol("r") is not the real coordinate r; it used to become a
    # parameter, and the polar metric then had no Christoffel symbols at all
    r, theta = sm.coordinates("r theta")
    err = refused((r, theta), metric=sp.diag(1, sp.Symbol("r") ** 2))
    (problem,) = err.problems
    assert problem.startswith("metric: symbol r (no assumptions)")
    assert "same name as the coordinate r (real=True)" in problem
    assert "different assumptions" in problem and "use the coordinate" in problem
    # with the coordinate itself: Gamma^r_theta,theta = -r (polar coordinates)
    polar = sm.Scene((r, theta), metric=sp.diag(1, r**2))
    assert polar.parameters == ()
    assert polar.christoffel()[0, 1, 1] == -r


def test_symbol_named_like_a_velocity_or_t_is_refused():
    err = refused(metric=sp.eye(3), potential=sp.Symbol("xdot") * y)
    (problem,) = err.problems
    assert problem.startswith("potential: symbol xdot (no assumptions)")
    assert "same name as the velocity xdot of coordinate x" in problem
    assert "velocities of coordinates that are not in the scene" not in problem
    err = refused(metric=sp.eye(3), potential=sp.Symbol("t", positive=True) * y)
    assert "same name as the time t" in str(err) and "symmech.t" in str(err)


def test_a_plain_real_symbol_with_the_velocity_name_is_the_velocity():
    scene = sm.Scene(Q, metric=sp.eye(3), constraints=[sp.Symbol("ydot", real=True) + R * thd])
    assert scene.constraint_matrix == sp.Matrix([[0, 1, R]])
    assert scene.parameters == (R,)


def test_two_symbols_sharing_a_name_are_refused():
    a_pos, a = sp.Symbol("a", positive=True), sp.Symbol("a")
    err = refused(metric=sp.diag(1, 1, 1 + a_pos**2), potential=a * x)
    (problem,) = err.problems
    assert "symbol a (positive=True)" in problem and "symbol a (no assumptions)" in problem
    assert "metric" in problem and "potential" in problem
    assert "different assumptions" in problem


def test_declared_parameters_are_checked():
    err = refused(metric=sp.diag(m, m, I), parameters=(m, m, I))
    assert err.problems == ["parameters: m is listed more than once"]
    err = refused(metric=sp.diag(m, m, I), parameters=(m, sp.Symbol("m"), I))
    assert "share the name 'm'" in str(err)
    # a field using a symbol named like a declared parameter, with other assumptions
    err = refused(metric=sp.diag(sp.Symbol("m"), 1, 1), parameters=(m,))
    assert "same name as the parameter m (positive=True)" in str(err)
    err = refused(metric=sp.eye(3), parameters=(x,))
    assert "parameters: x is the coordinate x" in str(err)
    err = refused(metric=sp.eye(3), parameters=(sp.Symbol("x"),))
    assert "parameters: symbol x (no assumptions) has the same name as the coordinate x" in str(err)


def test_quasi_velocity_names_must_be_free():
    v = (sp.Symbol("x"), *sp.symbols("v2 v3", real=True))
    err = refused(metric=sp.eye(3), frame=sp.eye(3), quasi_velocities=v)
    assert "quasi_velocities" in str(err) and "distinct names" in str(err)


# -- deterministic default parameters -------------------------------------------------------

_DETERMINISM = textwrap.dedent(
    """
    import sympy as sp, symmech as sm
    x, y = sm.coordinates("x y")
    names = "a b c d e f"
    pos, plain = sp.symbols(names, positive=True), sp.symbols(names)
    # name ties: before names were made unique, their order followed the hash seed
    V = sum(p * x**k + r * y**k for k, (p, r) in enumerate(zip(pos, plain), 1))
    try:
        sm.Scene((x, y), metric=sp.eye(2), potential=V)
    except sm.SceneError as exc:
        print(exc)
    ok = sm.Scene((x, y), metric=sp.diag(*pos[:2]), potential=sum(pos[2:]) * x * y)
    print([sp.srepr(p) for p in ok.parameters])
    """
)


def test_default_parameter_order_does_not_depend_on_the_hash_seed():
    outputs = []
    for seed in ("1", "2"):
        env = {**os.environ, "PYTHONHASHSEED": seed, "PYTHONPATH": str(ROOT)}
        run = subprocess.run(
            [sys.executable, "-c", _DETERMINISM],
            capture_output=True,
            text=True,
            env=env,
            timeout=120,
            check=True,
        )
        outputs.append(run.stdout)
    assert outputs[0] == outputs[1]
    lines = outputs[0].splitlines()
    assert lines[0] == "6 problems in the scene:"
    assert all("same name as the symbol" in line for line in lines[1:7])
    assert lines[7] == str([sp.srepr(sp.Symbol(c, positive=True)) for c in "abcdef"])


# -- velocity symbols: printing, equality, pickling, code generation ----------------------


def test_velocity_latex_puts_the_dot_on_the_base_name():
    q = sm.coordinates("q1 x_1 theta omega_z")
    assert [sp.latex(s) for s in sm.velocities(q)] == [
        r"\dot{q}_{1}",
        r"\dot{x}_{1}",
        r"\dot{\theta}",
        r"\dot{\omega}_{z}",
    ]
    assert [str(s) for s in sm.velocities(q)] == ["q1dot", "x_1dot", "thetadot", "omega_zdot"]
    q1d = sm.velocities(q)[0]
    assert sp.latex(q1d**2 * q[0]) == r"q_{1} \dot{q}_{1}^{2}"
    assert sp.latex(q1d, symbol_names={q1d: "v"}) == "v"


def test_velocity_symbols_are_plain_real_symbols_for_sympy():
    q = sm.coordinates("q1 x_1")
    v1, v2 = sm.velocities(q)
    plain1, plain2 = sp.Symbol("q1dot", real=True), sp.Symbol("x_1dot", real=True)
    assert sm.velocities(q) == (v1, v2)  # repeated calls give equal symbols
    assert v1 == plain1 and plain1 == v1 and hash(v1) == hash(plain1)
    assert v1 != sp.Symbol("q1dot")  # other assumptions: another symbol
    assert type(v1).__name__ == "Symbol" and v1.is_real
    # canonical order and printing are those of the plain symbols
    e = q[0] * v1 + v2**2 - sp.sin(v1 * v2)
    e_plain = q[0] * plain1 + plain2**2 - sp.sin(plain1 * plain2)
    assert e == e_plain and str(e) == str(e_plain) and e.args == e_plain.args
    assert sp.srepr(v1) == "Symbol('q1dot', real=True)"
    assert sp.diff(e, plain1) == sp.diff(e, v1)
    # pickling keeps the class (and so the LaTeX)
    back = pickle.loads(pickle.dumps(e))
    assert back == e and sp.latex(back) == sp.latex(e)
    assert sp.latex(pickle.loads(pickle.dumps(v2))) == r"\dot{x}_{1}"


def test_generated_code_accepts_subscripted_velocities():
    q = sm.coordinates("x_1 q1")
    qd = sm.velocities(q)
    m1, m2 = sp.symbols("m_1 m2", positive=True)
    T = m1 * qd[0] ** 2 / 2 + m2 * (qd[1] ** 2 + qd[0] * qd[1] * sp.cos(q[1])) / 2
    scene = sm.Scene(q, kinetic_energy=T, potential=sp.cos(q[1]))
    mod = sm.codegen.generate(scene, target="numpy").load()
    state = {q[0]: 0.1, q[1]: 0.7, qd[0]: 0.3, qd[1]: -0.4, m1: 1.5, m2: 2.0}
    assert scene.parameters == (m2, m1)  # sorted by name: "m2" < "m_1"
    params = np.array([state[p] for p in scene.parameters])
    got = mod.acceleration(np.array([0.1, 0.7]), np.array([0.3, -0.4]), params)
    # reference: solve g qdd = f with g and f from the Lagrangian by sympy directly
    L = T - sp.cos(q[1])
    g = sp.hessian(T, qd)
    f = sp.Matrix(
        [
            sp.diff(L, qi)
            - sum(sp.diff(sp.diff(L, vi), qj) * vj for qj, vj in zip(q, qd, strict=True))
            for qi, vi in zip(q, qd, strict=True)
        ]
    )
    want = np.array(g.subs(state).evalf().LUsolve(f.subs(state).evalf()), dtype=float).ravel()
    np.testing.assert_allclose(got, want, rtol=1e-12)
