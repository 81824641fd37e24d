"""More of the table of :mod:`mechanics_table`: models from sympy's docstrings (the
joints' and System's examples, their equations formed as a user then forms them) and the
models of issue 25 (actuators, bodies' potential energies, a hinge's inertia, loads
without a frame)."""

# The builders are copied as their sources write them, unused names included.
# ruff: noqa: RUF059

from __future__ import annotations

import sympy as sm
import sympy.physics.mechanics as me
from mechanics_entry import Entry

T = me.dynamicsymbols._t

# ----------------------------------------------------------- sympy's docstrings


def docstring_system_cart_pendulum(constrained: bool = False):
    # sympy/physics/mechanics/system.py, the docstring of System (a cart on a rail and a
    # pendulum, joints without given coordinates; then the bob held at x = 0 by a
    # holonomic constraint, the slider's speed dependent)
    g, l = sm.symbols("g l")
    F = me.dynamicsymbols("F")
    rail = me.RigidBody("rail")
    cart = me.RigidBody("cart")
    bob = me.Particle("bob")
    bob_frame = me.ReferenceFrame("bob_frame")
    system = me.System.from_newtonian(rail)
    system.add_joints(
        me.PrismaticJoint("slider", rail, cart, joint_axis=rail.x),
        me.PinJoint(
            "pin",
            cart,
            bob,
            joint_axis=cart.z,
            child_interframe=bob_frame,
            child_point=l * bob_frame.y,
        ),
    )
    system.apply_uniform_gravity(-g * system.y)
    system.add_loads((cart.masscenter, F * rail.x))
    system.validate_system()
    system.form_eoms()
    if constrained:
        system.add_holonomic_constraints(bob.masscenter.pos_from(rail.masscenter).dot(system.x))
        system.q_ind = system.get_joint("pin").coordinates
        system.q_dep = system.get_joint("slider").coordinates
        system.u_ind = system.get_joint("pin").speeds
        system.u_dep = system.get_joint("slider").speeds
        system.validate_system()
        system.form_eoms()
    return system


def docstring_system_form_eoms():
    # sympy/physics/mechanics/system.py, the docstring of System.form_eoms (LagrangesMethod,
    # a prismatic joint whose speed is the q_dot, a potential_energy, a damper in q_dot)
    q = me.dynamicsymbols("q")
    qd = me.dynamicsymbols("q", 1)
    m, k, b = sm.symbols("m k b")
    wall = me.RigidBody("W")
    system = me.System.from_newtonian(wall)
    bob = me.Particle("P", mass=m)
    bob.potential_energy = sm.S.Half * k * q**2
    system.add_joints(me.PrismaticJoint("J", wall, bob, q, qd))
    system.add_loads((bob.masscenter, b * qd * system.x))
    system.form_eoms(me.LagrangesMethod)
    return system


def docstring_pin_double_pendulum():
    # sympy/physics/mechanics/joint.py, the docstring of PinJoint (a double pendulum of
    # rigid bodies), its equations formed by a System with gravity
    l1, l2, g = sm.symbols("l1 l2 g")
    ceiling = me.RigidBody("C")
    upper_bob = me.RigidBody("U")
    lower_bob = me.RigidBody("L")
    ceiling_joint = me.PinJoint(
        "P1",
        ceiling,
        upper_bob,
        child_point=-l1 * upper_bob.frame.x,
        joint_axis=ceiling.frame.z,
    )
    pendulum_joint = me.PinJoint(
        "P2",
        upper_bob,
        lower_bob,
        child_point=-l2 * lower_bob.frame.x,
        joint_axis=upper_bob.frame.z,
    )
    system = me.System.from_newtonian(ceiling)
    system.add_joints(ceiling_joint, pendulum_joint)
    system.apply_uniform_gravity(-g * ceiling.frame.x)
    system.form_eoms()
    return system


def docstring_cylindrical_flag():
    # sympy/physics/mechanics/joint.py, the docstring of CylindricalJoint (a tube sliding
    # and turning on a pole, a flag sliding and turning on the tube), equations formed
    # by a System with gravity
    r, l, w, g = sm.symbols("r l w g")
    floor = me.RigidBody("floor")
    tube = me.RigidBody("tube")
    flag = me.RigidBody("flag")
    floor_joint = me.CylindricalJoint("C1", floor, tube, joint_axis=floor.z)
    flag_joint = me.CylindricalJoint(
        "C2",
        tube,
        flag,
        parent_point=r * tube.y,
        child_point=-w * flag.y + l * flag.z,
        joint_axis=tube.y,
    )
    system = me.System.from_newtonian(floor)
    system.add_joints(floor_joint, flag_joint)
    system.apply_uniform_gravity(-g * floor.z)
    system.form_eoms()
    return system


def docstring_spherical_pendulum():
    # sympy/physics/mechanics/joint.py, the docstring of SphericalJoint (a rigid bob on a
    # ball joint, body-fixed ZXZ angles), equations formed by a System with gravity
    l1, g = sm.symbols("l1 g")
    floor = me.RigidBody("F")
    bob = me.RigidBody("B")
    joint = me.SphericalJoint(
        "S", floor, bob, child_point=l1 * bob.y, rot_type="body", rot_order="ZXZ"
    )
    system = me.System.from_newtonian(floor)
    system.add_joints(joint)
    system.apply_uniform_gravity(-g * floor.y)
    system.form_eoms()
    return system


def docstring_planar_block():
    # sympy/physics/mechanics/joint.py, the docstring of PlanarJoint (a block on a
    # slope), equations formed by a System with gravity
    a, d, h, g = sm.symbols("a d h g")
    ground = me.RigidBody("G")
    block = me.RigidBody("B")
    slope = me.ReferenceFrame("A")
    slope.orient_axis(ground.frame, ground.y, a)
    joint = me.PlanarJoint(
        "PC",
        ground,
        block,
        parent_point=d * ground.x,
        child_point=-h * block.x,
        parent_interframe=slope,
    )
    system = me.System.from_newtonian(ground)
    system.add_joints(joint)
    system.apply_uniform_gravity(-g * ground.x)
    system.form_eoms()
    return system


def docstring_coulomb_friction():
    # sympy/physics/mechanics/actuator.py, the docstring of CoulombKineticFriction (a
    # block on a spring with Coulomb friction: sign of the velocity)
    x, v = me.dynamicsymbols("x, v", real=True)
    m, g, k, mu_k, mu_s, v_s, sigma = sm.symbols("m, g, k, mu_k, mu_s, v_s, sigma")
    N = me.ReferenceFrame("N")
    O, P = me.Point("O"), me.Point("P")
    O.set_vel(N, 0)
    P.set_pos(O, x * N.x)
    pathway = me.LinearPathway(O, P)
    friction = me.CoulombKineticFriction(mu_k, m * g, pathway, v_s=v_s, sigma=sigma, mu_s=mu_k)
    spring = me.LinearSpring(k, pathway)
    block = me.Particle("block", point=P, mass=m)
    kane = me.KanesMethod(N, (x,), (v,), kd_eqs=(x.diff() - v,))
    friction_loads = friction.to_loads()
    spring_loads = spring.to_loads()
    kane.kanes_equations([block], [*friction_loads, *spring_loads])
    return kane


# ------------------------------------------------------------ the cases of issue 25


def issue_pendulum_with_actuators():
    # issue 25: a pendulum through System with a TorqueActuator (k q at the pin) and a
    # LinearSpring on a LinearPathway: actuators, which System.loads leaves out
    q, u = me.dynamicsymbols("q u")
    k, c, m, l, g = sm.symbols("k c m l g")
    ground = me.RigidBody("ground")
    bob = me.RigidBody("bob", mass=m)
    system = me.System.from_newtonian(ground)
    pin = me.PinJoint("pin", ground, bob, q, u, joint_axis=ground.z, child_point=l * bob.frame.y)
    system.add_joints(pin)
    anchor = ground.masscenter.locatenew("anchor", l * ground.x)
    spring = me.LinearSpring(c, me.LinearPathway(anchor, bob.masscenter))
    system.add_actuators(me.TorqueActuator(-k * q, ground.z, bob, ground), spring)
    system.apply_uniform_gravity(-g * ground.y)
    system.form_eoms()
    return system


def issue_system_lagrange_potential_energy():
    # issue 25: the double pendulum of test_dub_pen through System with
    # eom_method=LagrangesMethod, joints whose speeds are the q_dots, potential_energy
    q1, q2 = me.dynamicsymbols("q1 q2")
    q1d, q2d = me.dynamicsymbols("q1 q2", 1)
    m, l, g = sm.symbols("m l g")
    ceiling = me.RigidBody("ceiling")
    upper = me.Particle("upper", mass=m)
    lower = me.Particle("lower", mass=m)
    system = me.System.from_newtonian(ceiling)
    f1, f2 = me.ReferenceFrame("f1"), me.ReferenceFrame("f2")
    system.add_joints(
        me.PinJoint(
            "P1",
            ceiling,
            upper,
            q1,
            q1d,
            joint_axis=ceiling.z,
            child_interframe=f1,
            child_point=-l * f1.x,
        ),
        me.PinJoint(
            "P2",
            upper,
            lower,
            q2,
            q2d,
            joint_axis=f1.z,
            parent_interframe=f1,
            child_interframe=f2,
            child_point=-l * f2.x,
        ),
    )
    for body in (upper, lower):
        body.potential_energy = (
            -body.mass * g * body.masscenter.pos_from(system.fixed_point).dot(system.x)
        )
    system.form_eoms(eom_method=me.LagrangesMethod)
    return system


def issue_hinge_positive_symbols():
    # issue 25: a cart with a pendulum whose inertia is given about the hinge, every
    # symbol positive: the metric [[mA + mC, a mA cos q2], [., Iz]] is positive definite
    # only for physical values (Iz >= mA a^2)
    x, th, u1, u2 = me.dynamicsymbols("x theta u1 u2")
    mA, mC, a, Iz, g = sm.symbols("m_A m_C a I_z g", positive=True)
    N = me.ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [th, N.z])
    O = me.Point("O")
    O.set_vel(N, 0)
    H = O.locatenew("H", x * N.x)
    H.set_vel(N, u1 * N.x)
    A.set_ang_vel(N, u2 * N.z)
    Ao = H.locatenew("Ao", -a * A.y)
    Ao.v2pt_theory(H, N, A)
    pendulum = me.RigidBody("pendulum", Ao, A, mA, (me.inertia(A, 0, 0, Iz), H))
    km = me.KanesMethod(N, [x, th], [u1, u2], kd_eqs=[x.diff(T) - u1, th.diff(T) - u2])
    km.kanes_equations([me.Particle("cart", H, mC), pendulum], [(Ao, -mA * g * N.y)])
    return km


def issue_lagrange_loads_without_frame():
    # issue 25: LagrangesMethod with loads (forcelist) but no frame=
    q = me.dynamicsymbols("q")
    m, c = sm.symbols("m c")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", q * N.x)
    P.set_vel(N, q.diff(T) * N.x)
    L = me.Lagrangian(N, me.Particle("p", P, m))
    # (sympy's form_lagranges_equations fails without the frame: the import is what
    # the user tries)
    return me.LagrangesMethod(L, [q], forcelist=[(P, -c * q.diff(T) * N.x)])


def issue_kane_potential_energy():
    # issue 25: a KanesMethod whose bodies carry potential_energy (test_pend's pendulum
    # with one): KanesMethod does not read it, nor does the import (it warns)
    q, u = me.dynamicsymbols("q u")
    m, l, g = sm.symbols("m l g")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    A = N.orientnew("A", "Axis", [q, N.z])
    A.set_ang_vel(N, u * N.z)
    P = O.locatenew("P", l * A.x)
    P.v2pt_theory(O, N, A)
    bob = me.Particle("bob", P, m)
    bob.potential_energy = -m * g * l * sm.cos(q)
    km = me.KanesMethod(N, [q], [u], kd_eqs=[q.diff(T) - u])
    km.kanes_equations([bob], [(P, m * g * N.x)])
    return km


MORE: list[Entry] = [
    Entry(
        "System docstring cart pendulum",
        "sympy/physics/mechanics/system.py: System",
        docstring_system_cart_pendulum,
    ),
    Entry(
        "System docstring cart pendulum, held at x = 0",
        "sympy/physics/mechanics/system.py: System (holonomic constraint)",
        lambda: docstring_system_cart_pendulum(constrained=True),
    ),
    Entry(
        "System.form_eoms docstring (Lagrange)",
        "sympy/physics/mechanics/system.py: System.form_eoms",
        docstring_system_form_eoms,
    ),
    Entry(
        "PinJoint docstring double pendulum",
        "sympy/physics/mechanics/joint.py: PinJoint",
        docstring_pin_double_pendulum,
        c=True,
    ),
    Entry(
        "CylindricalJoint docstring flag",
        "sympy/physics/mechanics/joint.py: CylindricalJoint",
        docstring_cylindrical_flag,
    ),
    Entry(
        "SphericalJoint docstring pendulum",
        "sympy/physics/mechanics/joint.py: SphericalJoint",
        docstring_spherical_pendulum,
    ),
    Entry(
        "PlanarJoint docstring block on slope",
        "sympy/physics/mechanics/joint.py: PlanarJoint",
        docstring_planar_block,
    ),
    Entry(
        "CoulombKineticFriction docstring",
        "sympy/physics/mechanics/actuator.py: CoulombKineticFriction",
        docstring_coulomb_friction,
        refused=r"the load on O contains the non-smooth functions \[.*'sign'\]; .* tanh",
    ),
    Entry(
        "issue 25: System actuators",
        "issue 25 (TorqueActuator, LinearSpring)",
        issue_pendulum_with_actuators,
    ),
    Entry(
        "issue 25: System for LagrangesMethod, potential_energy",
        "issue 25 (test_dub_pen through System)",
        issue_system_lagrange_potential_energy,
    ),
    Entry(
        "issue 25: hinge inertia, positive symbols",
        "issue 25 (test_parallel_axis, positive)",
        issue_hinge_positive_symbols,
    ),
    Entry(
        "issue 25: LagrangesMethod loads without frame=",
        "issue 25",
        issue_lagrange_loads_without_frame,
        refused=r"LagrangesMethod has loads \(forcelist\) but no frame=; .* pass frame=N",
    ),
    Entry(
        "issue 25: KanesMethod with potential_energy",
        "issue 25 (test_pend with a potential_energy)",
        issue_kane_potential_energy,
    ),
]
