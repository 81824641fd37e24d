"""Applied generalized forces, named run-time inputs and scenes written with dynamic symbols.

Independent routes: sympy's ``LagrangesMethod`` with a force list (the equations of a damped,
driven pendulum on a cart), the change of velocity basis ``q_dot = S v`` (a force given in
coordinates and in a frame gives the same motion), and the closed-form solution of the
damped oscillator for the simulated flow.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from sympy.physics import mechanics as me

import symmech as sm

RNG = np.random.default_rng(20261126)


def _cart_pendulum():
    """A pendulum on a cart, damped (c) at the pivot, the cart pushed by an input F(t)."""
    m1, m2, l, g, c = sp.symbols("m1 m2 l g c", positive=True)
    F = sp.Function("F", real=True)(sm.t)
    x, th = sm.coordinates("x theta")
    xd, thd = sm.velocities((x, th))
    T = m1 * xd**2 / 2 + m2 * (xd**2 + 2 * l * xd * thd * sp.cos(th) + l**2 * thd**2) / 2
    V = -m2 * g * l * sp.cos(th)
    scene = sm.Scene((x, th), kinetic_energy=T, potential=V, forces=[F, -c * thd], name="cart")
    return scene, (m1, m2, l, g, c), F


def _lagranges_method_rhs():
    """The same system built and solved by sympy.physics.mechanics (an independent route)."""
    m1, m2, l, g, c = sp.symbols("m1 m2 l g c", positive=True)
    x, th = me.dynamicsymbols("x theta")
    xd, thd = me.dynamicsymbols("x theta", 1)
    F = me.dynamicsymbols("F")
    N = me.ReferenceFrame("N")
    A = N.orientnew("A", "Axis", (th, N.z))
    O = me.Point("O")
    O.set_vel(N, 0)
    P1 = O.locatenew("P1", x * N.x)
    P1.set_vel(N, xd * N.x)
    P2 = P1.locatenew("P2", -l * A.y)
    P2.v2pt_theory(P1, N, A)
    cart = me.Particle("cart", P1, m1)
    bob = me.Particle("bob", P2, m2)
    L = me.Lagrangian(N, cart, bob)
    forces = [
        (P1, F * N.x),
        (P2, -m2 * g * N.y),
        (A, -c * thd * N.z),
        (N, c * thd * N.z),
    ]
    lm = me.LagrangesMethod(L, [x, th], forcelist=forces, frame=N)
    lm.form_lagranges_equations()
    return lm.rhs(), (x, th, xd, thd, F), (m1, m2, l, g, c)


def test_forces_match_lagranges_method_with_a_force_list():
    scene, params, F = _cart_pendulum()
    acc = scene.acceleration()
    rhs, (x, th, xd, thd, Fm), mparams = _lagranges_method_rhs()
    xs, ths, xds, thds = sm.coordinates("x theta") + sm.velocities(sm.coordinates("x theta"))
    for _ in range(5):
        vals = RNG.uniform(0.3, 2.0, 5)
        state = RNG.uniform(-1.5, 1.5, 4)
        u = RNG.uniform(-2, 2)
        sub = dict(zip(params, vals, strict=True)) | dict(
            zip((xs, ths, xds, thds), state, strict=True)
        )
        sub[F] = u
        ours = [float(e.xreplace(sub)) for e in acc]
        msub = dict(zip(mparams, vals, strict=True)) | dict(
            zip((x, th, xd, thd), state, strict=True)
        )
        msub[Fm] = u
        theirs = [float(e.xreplace(msub).evalf()) for e in rhs[2:]]
        np.testing.assert_allclose(ours, theirs, rtol=1e-12, atol=1e-12)


def test_a_force_in_a_frame_is_the_coordinate_force_times_S_transpose():
    """A planar body with body-frame velocities: F = S^T Q gives the coordinate motion."""
    m, J, c = sp.symbols("m J c", positive=True)
    x, y, th = sm.coordinates("x y theta")
    xd, yd, thd = sm.velocities((x, y, th))
    Q = sp.Matrix([-c * xd + sp.sin(th), -c * yd, -c * thd + x])
    coords = sm.Scene((x, y, th), metric=sp.diag(m, m, J), forces=list(Q))
    vx, vy, w = sp.symbols("v_x v_y omega", real=True)
    S = sp.Matrix([[sp.cos(th), -sp.sin(th), 0], [sp.sin(th), sp.cos(th), 0], [0, 0, 1]])
    qdot = S * sp.Matrix([vx, vy, w])
    F = (S.T * Q.xreplace(dict(zip((xd, yd, thd), qdot, strict=True)))).applyfunc(sp.expand)
    framed = sm.Scene(
        (x, y, th),
        kinetic_energy=(m * (vx**2 + vy**2) + J * w**2) / 2,
        frame=S,
        quasi_velocities=(vx, vy, w),
        forces=list(F),
    )
    a_q = coords.acceleration()
    a_v = framed.acceleration()
    for _ in range(4):
        pv = dict(zip((m, J, c), RNG.uniform(0.5, 2, 3), strict=True))
        q = dict(zip((x, y, th), RNG.uniform(-1, 1, 3), strict=True))
        vv = dict(zip((vx, vy, w), RNG.uniform(-1, 1, 3), strict=True))
        Sn = S.xreplace(q)
        qd_n = Sn * sp.Matrix([vv[vx], vv[vy], vv[w]])
        # q_ddot = S v_dot + S_dot v
        Sdot = S.diff(th) * qd_n[2]
        lhs = Sn * a_v.xreplace(pv | q | vv) + Sdot.xreplace(q) * sp.Matrix([vv[vx], vv[vy], vv[w]])
        rhs = a_q.xreplace(pv | q | dict(zip((xd, yd, thd), qd_n, strict=True)))
        np.testing.assert_allclose(
            np.array(lhs, dtype=float), np.array(rhs, dtype=float), rtol=1e-12, atol=1e-12
        )


@pytest.mark.parametrize("target", ["c", "numpy"])
def test_generated_forces_and_named_inputs(target):
    scene, _, F = _cart_pendulum()
    mod = sm.codegen.generate(scene, target=target).load()
    assert mod.inputs == ("F",)
    names = [str(p) for p in scene.parameters]
    acc = scene.acceleration()
    for _ in range(3):
        p = RNG.uniform(0.5, 2, len(names))
        q, v = RNG.uniform(-1, 1, 2), RNG.uniform(-1, 1, 2)
        u = RNG.uniform(-1, 1)
        sub = dict(zip(scene.parameters, p, strict=True))
        sub |= dict(zip(scene.coordinates + scene.velocities, [*q, *v], strict=True))
        sub[F] = u
        want = [float(e.xreplace(sub)) for e in acc]
        byname = dict(zip(names, p, strict=True))
        for inputs in ({"F": u}, [u], {F: u}, {"F(t)": u}):
            got = mod.acceleration(q, v, byname, t=0.0, inputs=inputs)
            np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-14)
    with pytest.raises(sm.codegen.CodegenError, match=r"missing \['F'\], unknown \['G'\]"):
        mod.acceleration(q, v, byname, t=0.0, inputs={"G": 1.0})
    with pytest.raises(sm.codegen.CodegenError, match="given twice"):
        mod.acceleration(q, v, byname, t=0.0, inputs={"F": 1.0, F: 2.0})
    with pytest.raises(sm.codegen.CodegenError, match="needs the inputs"):
        mod.acceleration(q, v, byname, t=0.0)
    # a batch of inputs by name broadcasts against the states
    batch = mod.acceleration(
        np.zeros((3, 2)), np.zeros((3, 2)), byname, t=0.0, inputs={"F": [0.0, 1.0, 2.0]}
    )
    assert batch.shape == (3, 2)
    assert batch[0, 0] == 0.0 and batch[2, 0] == pytest.approx(2 * batch[1, 0])


def test_simulated_damped_oscillator_follows_the_closed_form():
    m, k, c = 2.0, 3.0, 0.4
    (x,) = sm.coordinates("x")
    (xd,) = sm.velocities((x,))
    M, K, C = sp.symbols("M K C", positive=True)
    scene = sm.Scene((x,), metric=[[M]], potential=K * x**2 / 2, forces=[-C * xd], name="damped")
    assert not scene.conservative
    res = sm.simulate(
        scene, [1.0], [0.0], 5.0, params={"M": m, "K": k, "C": c}, rtol=1e-10, atol=1e-12
    )
    assert res.status == "finished" or res.success
    zeta_w = c / (2 * m)
    wd = math.sqrt(k / m - zeta_w**2)
    x_exact = math.exp(-zeta_w * 5.0) * (math.cos(wd * 5.0) + zeta_w / wd * math.sin(wd * 5.0))
    assert abs(res.y[-1, 0] - x_exact) < 1e-8
    assert res.stats.get("energy_drift") is None


def test_forces_refused_with_the_reason():
    x, y = sm.coordinates("x y")
    xd, _ = sm.velocities((x, y))
    with pytest.raises(sm.SceneError, match="forces: 1 entries for 2 velocities"):
        sm.Scene((x, y), metric=sp.eye(2), forces=[xd])
    with pytest.raises(sm.SceneError, match="forces: expected a sequence"):
        sm.Scene((x, y), metric=sp.eye(2), forces=xd)
    with pytest.raises(sm.SceneError, match=r"forces\[0\].*not allowed|forces\[0\]"):
        sm.Scene((x, y), metric=sp.eye(2), forces=["__import__('os')", 0])
    with pytest.raises(sm.SceneError, match=r"forces\[1\].*not real"):
        sm.Scene((x, y), metric=sp.eye(2), forces=[0, sp.sqrt(-1 - x**2)])
    vx, vy = sp.symbols("v_x v_y", real=True)
    with pytest.raises(sm.SceneError, match="forces: contains the coordinate velocities"):
        sm.Scene(
            (x, y),
            kinetic_energy=(vx**2 + vy**2) / 2,
            frame=sp.eye(2),
            quasi_velocities=(vx, vy),
            forces=[xd, 0],
        )


def test_scene_file_forces_round_trip():
    text = """
coordinates = ["x"]
metric = ["m"]
potential = "k*x**2/2"
forces = ["-c*xdot + u"]
[parameters]
m = 2
k = 1
c = 0.1
[functions]
u = {}
"""
    sf = sm.reads_scene(text, name="osc")
    (x,) = sf.scene.coordinates
    u = sp.Function("u", real=True)(sm.t)
    c, k = sp.symbols("c k", positive=True)
    assert sf.scene.forcing()[0] == -c * sp.Symbol("xdot", real=True) - k * x + u
    again = sm.reads_scene(sm.dump_scene(sf.scene)).scene
    assert again.forcing() == sf.scene.forcing()
    with pytest.raises(sm.SceneError, match=r"forces \(line 5\): expected an array of 1"):
        sm.reads_scene(text.replace('"-c*xdot + u"', '"-c*xdot", "1"'))


def test_dynamicsymbols_declare_the_same_scene():
    x, th = me.dynamicsymbols("x theta")
    xd, thd = me.dynamicsymbols("x theta", 1)
    Fin = me.dynamicsymbols("F")
    m1, m2, l, g, c = sp.symbols("m1 m2 l g c", positive=True)
    T = m1 * xd**2 / 2 + m2 * (xd**2 + 2 * l * xd * thd * sp.cos(th) + l**2 * thd**2) / 2
    dyn = sm.Scene(
        (x, th),
        kinetic_energy=T,
        potential=-m2 * g * l * sp.cos(th),
        forces=[Fin, -c * thd],
        walls=[sm.Wall(x + l * sp.sin(th) + 1)],
        name="cart",
    )
    plain, _, F = _cart_pendulum()
    assert dyn.coordinates == plain.coordinates
    assert dyn.velocities == plain.velocities
    assert dyn.mass_matrix() == plain.mass_matrix()
    assert dyn.forcing() == plain.forcing()
    assert F in dyn.forcing().atoms(sp.core.function.AppliedUndef)
    with pytest.raises(sm.SceneError, match="acceleration of coordinate x"):
        sm.Scene((x, th), kinetic_energy=T, forces=[x.diff(me.dynamicsymbols._t, 2), 0])


def test_scene_file_inputs_table():
    text = """
coordinates = ["x"]
metric = ["m"]
forces = ["-c*xdot + tau"]
[parameters]
m = 2
c = 0.1
[inputs]
tau = { description = "the push" }
"""
    scene = sm.reads_scene(text, name="pushed").scene
    tau = sp.Function("tau", real=True)(sm.t)
    assert tau in scene.forcing()[0].atoms(sp.core.function.AppliedUndef)
    mod = sm.codegen.generate(scene, target="numpy").load()
    assert mod.inputs == ("tau",)
    np.testing.assert_allclose(
        mod.acceleration([0.0], [1.0], {"m": 2, "c": 0.1}, inputs={"tau": 0.5}), [0.2]
    )
    with pytest.raises(sm.SceneError, match=r"inputs.tau \(line 9\): an input is a table"):
        sm.reads_scene(text.replace('tau = { description = "the push" }', "tau = 3"))
    with pytest.raises(sm.SceneError, match="declared both in"):
        sm.reads_scene(text + "[functions]\ntau = {}\n")
    with pytest.raises(sm.SceneError, match=r"expected a table \[inputs\]"):
        sm.reads_scene(
            "inputs = 3\n" + text.replace('[inputs]\ntau = { description = "the push" }\n', "")
        )


def test_scene_replace_declares_the_same_system_again():
    """Scene.replace rebuilds a scene from its resolved declaration (frame, constraints,
    forces, walls with velocity) and applies only the changes asked for."""
    from symmech.examples import carnot_3_13

    sphere = carnot_3_13()
    again = sphere.replace()
    assert again.mass_matrix() == sphere.mass_matrix()
    assert again.constraint_matrix == sphere.constraint_matrix
    assert again.parameters == sphere.parameters
    assert again.impact_map(0).post_velocity == sphere.impact_map(0).post_velocity
    scene, _, _ = _cart_pendulum()
    x, th = scene.coordinates
    l = sp.Symbol("l", positive=True)
    walled = scene.replace(walls=[sm.Wall(x + l * sp.sin(th) - 1, velocity=[0, 0], name="w")])
    assert walled.forcing() == scene.forcing()
    moved = walled.replace(name="moved")
    assert moved.name == "moved" and moved.walls[0].velocity == walled.walls[0].velocity
    alpha = sp.Symbol("alpha", nonnegative=True)
    softer = walled.replace(walls=[walled.walls[0].as_wall(restitution=alpha)], parameters=None)
    assert softer.walls[0].restitution == alpha and alpha in softer.parameters
