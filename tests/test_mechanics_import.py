"""Scene.from_mechanics: models built as sympy's own tests and documentation build them.

Round trip: the imported scene's accelerations (symmech's M, f and constraints, solved
numerically) equal the model's own equations (its ``mass_matrix_full`` and
``forcing_full``, solved numerically) at random states; the Whipple bicycle's linearized
generated rhs has the eigenvalues of the benchmark of Meijaard et al. (2007).
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from mechanics_support import worst_difference
from sympy.physics import mechanics as me

import symmech as sm

T = me.dynamicsymbols._t


def _disc_from_contact_point():
    """sympy's test_kane.py::test_rolling_disc: the disc built from its contact point up
    (C.set_vel(N, 0): the rolling is in the kinematics, no contact coordinates)."""
    q1, q2, q3, u1, u2, u3 = me.dynamicsymbols("q1 q2 q3 u1 u2 u3")
    r, m, g = sp.symbols("r m g")
    N = me.ReferenceFrame("N")
    Y = N.orientnew("Y", "Axis", [q1, N.z])
    L = Y.orientnew("L", "Axis", [q2, Y.x])
    R = L.orientnew("R", "Axis", [q3, L.y])
    w_R_N_qd = R.ang_vel_in(N)
    R.set_ang_vel(N, u1 * L.x + u2 * L.y + u3 * L.z)
    C = me.Point("C")
    C.set_vel(N, 0)
    Dmc = C.locatenew("Dmc", r * L.z)
    Dmc.v2pt_theory(C, N, R)
    inertia = me.inertia(L, m / 4 * r**2, m / 2 * r**2, m / 4 * r**2)
    kd = [me.dot(R.ang_vel_in(N) - w_R_N_qd, uv) for uv in L]
    KM = me.KanesMethod(N, q_ind=[q1, q2, q3], u_ind=[u1, u2, u3], kd_eqs=kd)
    KM.kanes_equations([me.RigidBody("BodyD", Dmc, R, m, (inertia, Dmc))], [(Dmc, -m * g * Y.z)])
    return KM, {r: 0.7, m: 1.3, g: 9.81}


def _disc_with_contact_coordinates():
    """A rolling disc with its contact point's position (x, y) as coordinates and the
    no-slip conditions as velocity constraints with dependent speeds, a damping torque on
    the spin and a motor torque T(t) about the axle: KanesMethod with u_dependent."""
    q1, q2, q3, x, y = me.dynamicsymbols("q1 q2 q3 x y")
    u1, u2, u3, u4, u5 = me.dynamicsymbols("u1 u2 u3 u4 u5")
    tau = me.dynamicsymbols("tau")
    r, m, g, c = sp.symbols("r m g c")
    N = me.ReferenceFrame("N")
    Y = N.orientnew("Y", "Axis", [q1, N.z])
    L = Y.orientnew("L", "Axis", [q2, Y.x])
    R = L.orientnew("R", "Axis", [q3, L.y])
    O = me.Point("O")
    O.set_vel(N, 0)
    C = O.locatenew("C", x * N.x + y * N.y)
    Dmc = C.locatenew("Dmc", r * L.z)
    R.set_ang_vel(N, u1 * L.x + u2 * L.y + u3 * L.z)
    w_qd = (
        q1.diff(T) * N.z + q2.diff(T) * Y.x + q3.diff(T) * L.y
    )  # the angular velocity of R in q_dot
    kd = [me.dot(R.ang_vel_in(N) - w_qd, uv) for uv in L] + [x.diff(T) - u4, y.diff(T) - u5]
    C.set_vel(N, u4 * N.x + u5 * N.y)  # the contact point's velocity: its coordinates' rates
    Dmc.set_vel(N, C.vel(N) + (r * L.z).dt(N))
    Cc = Dmc.locatenew("Cc", -r * L.z)  # the material contact point of the disc
    Cc.v2pt_theory(Dmc, N, R)
    nonslip = [me.dot(Cc.vel(N), N.x), me.dot(Cc.vel(N), N.y)]
    inertia = me.inertia(L, m / 4 * r**2, m / 2 * r**2, m / 4 * r**2)
    disc = me.RigidBody("disc", Dmc, R, m, (inertia, Dmc))
    loads = [(Dmc, -m * g * N.z), (R, (-c * u2 + tau) * L.y), (L, (c * u2 - tau) * L.y)]
    KM = me.KanesMethod(
        N,
        q_ind=[q1, q2, q3, x, y],
        u_ind=[u1, u2, u3],
        u_dependent=[u4, u5],
        velocity_constraints=nonslip,
        kd_eqs=kd,
    )
    KM.kanes_equations([disc], loads)
    return KM, {r: 0.6, m: 2.0, g: 9.81, c: 0.3}


def _double_pendulum_lagrange():
    """sympy's documentation: a double pendulum with LagrangesMethod and a force list,
    plus a viscous torque at the middle joint."""
    q1, q2 = me.dynamicsymbols("q1 q2")
    q1d, q2d = me.dynamicsymbols("q1 q2", 1)
    m, l, g, c = sp.symbols("m l g c")
    N = me.ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [q1, N.z])
    B = N.orientnew("B", "Axis", [q2, N.z])
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", l * A.x)
    R = P.locatenew("R", l * B.x)
    P.v2pt_theory(O, N, A)
    R.v2pt_theory(P, N, B)
    ParP = me.Particle("ParP", P, m)
    ParR = me.Particle("ParR", R, m)
    L = me.Lagrangian(N, ParP, ParR)
    forces = [
        (P, m * g * N.x),
        (R, m * g * N.x),
        (B, -c * (q2d - q1d) * N.z),
        (A, c * (q2d - q1d) * N.z),
    ]
    lm = me.LagrangesMethod(L, [q1, q2], forcelist=forces, frame=N)
    lm.form_lagranges_equations()
    return lm, {m: 1.1, l: 0.8, g: 9.81, c: 0.2}


def _cart_pendulum_system():
    """The System class with joints (sympy's documentation style): a cart on a rail with a
    pendulum, uniform gravity, a force F(t) on the cart and viscous friction on the rail."""
    q, th = me.dynamicsymbols("q theta")
    u, w = me.dynamicsymbols("u omega")
    F = me.dynamicsymbols("F")
    m1, m2, l, g, c = sp.symbols("m1 m2 l g c")
    rail = me.RigidBody("rail")
    cart = me.RigidBody("cart", mass=m1)
    bob = me.RigidBody("bob", mass=m2)
    bob.inertia = (me.inertia(bob.frame, 0, 0, 0), bob.masscenter)  # a point mass
    system = me.System.from_newtonian(rail)
    slider = me.PrismaticJoint("slider", rail, cart, q, u, joint_axis=rail.x)
    pin = me.PinJoint("pin", cart, bob, th, w, joint_axis=cart.z, child_point=l * bob.frame.y)
    system.add_joints(slider, pin)
    system.apply_uniform_gravity(-g * rail.y)
    system.add_loads(me.Force(cart.masscenter, (F - c * u) * rail.x))
    system.validate_system()
    system.form_eoms()
    return system, {m1: 1.0, m2: 0.4, l: 0.9, g: 9.81, c: 0.15}


@pytest.mark.parametrize(
    "build",
    [
        _disc_from_contact_point,
        _disc_with_contact_coordinates,
        _double_pendulum_lagrange,
        _cart_pendulum_system,
    ],
)
def test_imported_accelerations_equal_the_models_own(build):
    model, values = build()
    scene = sm.Scene.from_mechanics(model, name=build.__name__.strip("_"))
    assert worst_difference(model, scene, values) < 1e-10


def test_import_reads_potential_forces_and_frame():
    model, _ = _disc_from_contact_point()
    scene = sm.Scene.from_mechanics(model)
    q2 = sp.Symbol("q2", real=True)
    m, g, r = (sp.Symbol(s) for s in "mgr")
    assert sp.simplify(scene.potential - m * g * r * sp.cos(q2)) == 0
    assert scene.frame is not None
    assert [str(u) for u in scene.velocities] == ["u1", "u2", "u3"]
    assert "m > 0" in repr(scene)  # declared without a sign, needed positive
    pend, _ = _double_pendulum_lagrange()
    s2 = sm.Scene.from_mechanics(pend)
    assert s2.frame is None and s2.potential != 0  # gravity from a fixed point: a potential
    assert any(e != 0 for e in s2.forces)  # the viscous torque stays a force


def test_import_with_a_wall_gives_an_impact_map_and_code():
    system, values = _cart_pendulum_system()
    q, th = me.dynamicsymbols("q theta")
    l = sp.Symbol("l")
    wall = sm.Wall(1 - q - l * sp.sin(th), restitution=sp.Rational(1, 2), name="stop")
    scene = sm.Scene.from_mechanics(system, walls=[wall], name="cart")
    imp = scene.impact_map("stop")
    assert imp is not None
    mod = sm.codegen.generate(scene, target="numpy").load()
    assert mod.inputs == ("F",)
    params = {str(k): v for k, v in values.items()}
    v_plus = mod.impact([0.2, 0.3], [1.0, -0.5], params, wall="stop", t=0.0, inputs={"F": 0.0})
    assert np.all(np.isfinite(v_plus))


def test_import_refuses_what_it_cannot_represent():
    with pytest.raises(sm.SceneError, match="expected a KanesMethod"):
        sm.Scene.from_mechanics(object())
    q, u = me.dynamicsymbols("q u")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", q * N.x)
    P.set_vel(N, (u + 1) * N.x)  # a prescribed drift: rheonomic
    km = me.KanesMethod(N, [q], [u], kd_eqs=[q.diff(T) - u])
    km.kanes_equations([me.Particle("p", P, 1)], [])
    with pytest.raises(sm.SceneError, match="scleronomic"):
        sm.Scene.from_mechanics(km)
