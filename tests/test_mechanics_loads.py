"""Scene.from_mechanics reads everything a model carries, or refuses it naming the part.

Each model is built as sympy's tests and documentation build them; the imported scene's
accelerations are compared with the model's own ``mass_matrix_full \\ forcing_full`` at
random states (:func:`mechanics_support.worst_difference`).
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from codegen_support import require_c_compiler
from mechanics_support import (
    c_worst_difference,
    model_accelerations,
    model_basis,
    random_values,
    worst_difference,
)
from sympy.physics import mechanics as me

import symmech as sm

T = me.dynamicsymbols._t


def _pendulum_system_with_actuators():
    """A pendulum through ``System`` with a torsion spring (``TorqueActuator``, k q) at
    the pin and a linear spring (``LinearSpring`` on a ``LinearPathway``) from a wall
    point to the bob: both are actuators, which ``System.loads`` leaves out."""
    q, u = me.dynamicsymbols("q u")
    k, c, m, l, g = sp.symbols("k c m l g")
    ground = me.RigidBody("ground")
    bob = me.RigidBody("bob", mass=m)
    system = me.System.from_newtonian(ground)
    pin = me.PinJoint("pin", ground, bob, q, u, joint_axis=ground.z, child_point=l * bob.frame.y)
    system.add_joints(pin)
    anchor = ground.masscenter.locatenew("anchor", l * ground.x)
    spring = me.LinearSpring(c, me.LinearPathway(anchor, bob.masscenter))
    system.add_actuators(me.TorqueActuator(-k * q, ground.z, bob, ground), spring)
    system.apply_uniform_gravity(-g * ground.y)
    system.validate_system()
    system.form_eoms()
    values = {k: 2.0, c: 0.7, m: 1.5, l: 0.7, g: 9.81, sp.Symbol("bob_izz"): 0.3}
    return system, values


def test_system_actuators_enter_the_forces():
    system, values = _pendulum_system_with_actuators()
    scene = sm.Scene.from_mechanics(system)
    assert {"k", "c"} <= {p.name for p in scene.parameters}
    assert worst_difference(system, scene, values) < 1e-10


def _double_pendulum_potential_energies(frame: bool):
    """sympy's test_lagrange.py::test_dub_pen: Particles with ``potential_energy``,
    ``LagrangesMethod(L, [q1, q2], bodies=[ParP, ParR])`` (and ``frame=N`` if asked)."""
    q1, q2 = me.dynamicsymbols("q1 q2")
    q1d, q2d = me.dynamicsymbols("q1 q2", 1)
    l, m, g = sp.symbols("l m g")
    N = me.ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [q1, N.z])
    B = N.orientnew("B", "Axis", [q2, N.z])
    A.set_ang_vel(N, q1d * A.z)
    B.set_ang_vel(N, q2d * A.z)
    O = me.Point("O")
    P = O.locatenew("P", l * A.x)
    R = P.locatenew("R", l * B.x)
    O.set_vel(N, 0)
    P.v2pt_theory(O, N, A)
    R.v2pt_theory(P, N, B)
    ParP = me.Particle("ParP", P, m)
    ParR = me.Particle("ParR", R, m)
    ParP.potential_energy = -m * g * l * sp.cos(q1)
    ParR.potential_energy = -m * g * l * sp.cos(q1) - m * g * l * sp.cos(q2)
    L = me.Lagrangian(N, ParP, ParR)
    extra = {"frame": N} if frame else {}
    lm = me.LagrangesMethod(L, [q1, q2], bodies=[ParP, ParR], **extra)
    lm.form_lagranges_equations()
    return lm, {l: 0.8, m: 1.1, g: 9.81}


@pytest.mark.parametrize("frame", [True, False], ids=["frame", "no-frame"])
def test_lagrange_bodies_potential_energies_are_read(frame):
    lm, values = _double_pendulum_potential_energies(frame)
    scene = sm.Scene.from_mechanics(lm)
    q1, q2 = (sp.Symbol(n, real=True) for n in ("q1", "q2"))
    l, m, g = sp.symbols("l m g")
    expected = -2 * m * g * l * sp.cos(q1) - m * g * l * sp.cos(q2)
    assert sp.expand(scene.potential - expected) == 0
    assert worst_difference(lm, scene, values) < 1e-10


def _spring_system(form: bool):
    """The ``System.form_eoms`` docstring: a bob on a spring and damper, the speed the
    q_dot (a System built for LagrangesMethod), ``potential_energy`` on the bob."""
    q = me.dynamicsymbols("q")
    qd = q.diff(T)
    m, k, b = sp.symbols("m k b")
    wall = me.RigidBody("wall")
    bob = me.Particle("bob", mass=m)
    bob.potential_energy = sp.S.Half * k * q**2
    system = me.System.from_newtonian(wall)
    system.add_joints(me.PrismaticJoint("bob_joint", wall, bob, q, qd))
    system.add_loads((bob.masscenter, b * qd * system.x))
    if form:
        system.form_eoms(me.LagrangesMethod)
    return system, {m: 1.2, k: 3.0, b: 0.4}


@pytest.mark.parametrize("form", [True, False], ids=["formed", "not-formed"])
def test_system_for_lagranges_method(form):
    system, values = _spring_system(form)
    scene = sm.Scene.from_mechanics(system)
    if not form:  # the model's own equations, formed after the import
        system.form_eoms(me.LagrangesMethod)
    assert scene.potential != 0 and scene.frame is None
    assert worst_difference(system, scene, values) < 1e-10


def test_kane_loads_written_in_q_dot():
    """A double pendulum in KanesMethod, u1 = q1' and u2 = q1' + q2', with a viscous
    torque between the links written in q2' (KanesMethod substitutes the kinematic
    equations into the loads)."""
    q1, q2, u1, u2 = me.dynamicsymbols("q1 q2 u1 u2")
    m, l, g, c = sp.symbols("m l g c")
    N = me.ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [q1, N.z])
    B = A.orientnew("B", "Axis", [q2, A.z])
    A.set_ang_vel(N, u1 * N.z)
    B.set_ang_vel(N, u2 * N.z)
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", l * A.x)
    R = P.locatenew("R", l * B.x)
    P.v2pt_theory(O, N, A)
    R.v2pt_theory(P, N, B)
    kd = [q1.diff(T) - u1, q1.diff(T) + q2.diff(T) - u2]
    loads = [
        (P, m * g * N.x),
        (R, m * g * N.x),
        (B, -c * q2.diff(T) * N.z),
        (A, c * q2.diff(T) * N.z),
    ]
    km = me.KanesMethod(N, [q1, q2], [u1, u2], kd_eqs=kd)
    km.kanes_equations([me.Particle("p", P, m), me.Particle("r", R, m)], loads)
    scene = sm.Scene.from_mechanics(km)
    assert worst_difference(km, scene, {m: 1.1, l: 0.8, g: 9.81, c: 0.3}) < 1e-10


def _cart_with_hinged_pendulum():
    """A cart (m_C) with a pendulum whose inertia is given about the hinge (I_z, the
    RigidBody's inertia point the hinge), every symbol positive: the metric
    [[m_A + m_C, a m_A cos theta], [., I_z]] is positive definite for physical values only
    (I_z >= m_A a^2)."""
    x, th, u1, u2 = me.dynamicsymbols("x theta u1 u2")
    mA, mC, a, Iz, g = sp.symbols("m_A m_C a I_z g", positive=True)
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
    return km, {mA: 1.0, mC: 2.0, a: 0.5, Iz: 0.4, g: 9.81}


@pytest.mark.parametrize(
    ("target", "strategy"), [("numpy", "auto"), ("c", "closed_form"), ("c", "linear_solve")]
)
def test_metric_positive_for_physical_values_only_is_checked_at_run_time(target, strategy):
    """Accepted (every symbol positive=True, the sampler keeps them positive), and the
    generated code's Cholesky factorisation of g (SYMMECH_NOT_SPD in C) is the check:
    at physical values its rhs is the model's own, at I_z < m_A a^2 a NumericalError,
    whether g is inverted in closed form or factorised at run time."""
    if target == "c":
        require_c_compiler()
    km, values = _cart_with_hinged_pendulum()
    scene = sm.Scene.from_mechanics(km)
    assert scene.declaration.metric_checked_at_run_time
    assert "checked at run time" in repr(scene)
    assert worst_difference(km, scene, values) < 1e-10
    mod = sm.codegen.generate(scene, target=target, strategy=strategy).load()
    params = {str(k): v for k, v in values.items()}
    qs, us = [0.1, 0.2], [0.3, -0.4]
    theirs = model_accelerations(km, values, qs, us, model_basis(km))
    ours = mod.rhs(np.array([*qs, *us]), params)
    assert np.max(np.abs(ours[2:] - theirs)) < 1e-10
    # (m_A + m_C) I_z < (m_A a cos theta)^2: g indefinite, the Cholesky factorisation fails
    with pytest.raises(
        sm.codegen.NumericalError, match=r"^rhs: a matrix that must be positive definite is not"
    ):
        mod.rhs(np.array([0.1, 0.0, 0.3, -0.4]), {**params, "I_z": 0.05})


def test_a_declared_hinge_metric_with_positive_symbols_is_accepted_for_a_run_time_check():
    """The same metric declared by hand: positive symbols are sampled positive, and g is
    positive definite for some of their values (I_z >= m_A a^2), so it is accepted."""
    x, th = sm.coordinates("x theta")
    mA, mC, a, Iz = sp.symbols("m_A m_C a I_z", positive=True)
    g = sp.Matrix([[mA + mC, a * mA * sp.cos(th)], [a * mA * sp.cos(th), Iz]])
    scene = sm.Scene((x, th), metric=g, name="hinge")
    assert scene.declaration.metric_checked_at_run_time
    # and it is indefinite for other positive values: a run-time check is needed
    at = {mA: 1, mC: 1, a: 1, Iz: sp.Rational(1, 10), th: 0}
    assert g.xreplace(at).det() < 0


def test_a_metric_indefinite_for_every_parameter_value_is_still_refused():
    x, y = sm.coordinates("x y")
    k = sp.Symbol("k", positive=True)
    with pytest.raises(sm.SceneError, match="not positive definite"):
        sm.Scene((x, y), metric=sp.Matrix([[1, 2 + k], [2 + k, 1]]))
    with pytest.raises(sm.SceneError, match="not positive definite"):
        sm.Scene((x, y), metric=sp.diag(k, sp.cos(y)))


def test_rolling_disc_with_lu_solved_dependent_speeds():
    """sympy's test_kane5.py::test_kane_rolling_disc_lu, unchanged: no body's velocity
    uses the contact point's speeds u4, u5, so the bodies' metric is singular; it is
    definite on the no-slip constraints' kernel, and the import agrees."""
    from sympy.physics.mechanics.tests.test_kane5 import _create_rolling_disc

    props = _create_rolling_disc()
    kane = me.KanesMethod(
        props["frame"],
        props["q_ind"],
        props["u_ind"],
        props["kdes"],
        u_dependent=props["u_dep"],
        velocity_constraints=props["fnh"],
        bodies=props["bodies"],
        forcelist=props["loads"],
        explicit_kinematics=False,
        constraint_solver="LU",
    )
    kane.kanes_equations()
    scene = sm.Scene.from_mechanics(kane)
    g, r, m = sp.symbols("g r m")
    assert worst_difference(kane, scene, {g: 9.81, r: 0.26, m: 3.43}) < 1e-10


def test_singular_mass_matrix_is_refused_naming_the_speed():
    """sympy's test_kane.py::test_issue_24887: a particle with three orientation speeds;
    u2 (about the rod) carries no inertia, so Kane's mass matrix is singular."""
    g, l, m = sp.symbols("g l m")
    q1, q2, q3, u1, u2, u3 = me.dynamicsymbols("q1:4 u1:4")
    N = me.ReferenceFrame("N")
    A = me.ReferenceFrame("A")
    A.orient_body_fixed(N, (q1, q2, q3), "zxy")
    N_w_A = A.ang_vel_in(N)
    kdes = [N_w_A.dot(A.x) - u1, N_w_A.dot(A.y) - u2, N_w_A.dot(A.z) - u3]
    O = me.Point("O")
    O.set_vel(N, 0)
    Po = O.locatenew("Po", -l * A.y)
    Po.set_vel(A, 0)
    P = me.Particle("P", Po, m)
    kane = me.KanesMethod(
        N, [q1, q2, q3], [u1, u2, u3], kdes, bodies=[P], forcelist=[(Po, -m * g * N.y)]
    )
    kane.kanes_equations()
    with pytest.raises(
        sm.SceneError, match=r"singular: no body's kinetic energy fixes the velocities \[u2\(t\)\]"
    ):
        sm.Scene.from_mechanics(kane)


def test_auxiliary_speeds_are_refused_as_such():
    q, u, ua = me.dynamicsymbols("q u ua")
    m, g = sp.symbols("m g")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", q * N.x)
    P.set_vel(N, u * N.x + ua * N.y)  # ua: the auxiliary speed of the rail's reaction
    km = me.KanesMethod(N, [q], [u], kd_eqs=[q.diff(T) - u], u_auxiliary=[ua])
    km.kanes_equations([me.Particle("p", P, m)], [(P, -m * g * N.y)])
    with pytest.raises(sm.SceneError, match=r"KanesMethod.u_auxiliary \[ua\(t\)\]: auxiliary"):
        sm.Scene.from_mechanics(km)


def test_lagrange_loads_without_frame_are_refused_naming_frame():
    q = me.dynamicsymbols("q")
    m, c = sp.symbols("m c")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", q * N.x)
    P.set_vel(N, q.diff(T) * N.x)
    L = me.Lagrangian(N, me.Particle("p", P, m))
    lm = me.LagrangesMethod(L, [q], forcelist=[(P, -c * q.diff(T) * N.x)])
    with pytest.raises(sm.SceneError, match=r"no frame=; .* pass frame=N"):
        sm.Scene.from_mechanics(lm)


@pytest.mark.parametrize("which", ["pendulum_on_cart", "rolling_disc_lu", "actuators"])
def test_generated_c_rhs_equals_the_models_own_equations(which):
    """The generated C of a few imported models against the model's own equations."""
    from codegen_support import require_c_compiler
    from sympy.physics.mechanics import models

    require_c_compiler()
    if which == "pendulum_on_cart":
        model = models.n_link_pendulum_on_cart(2, True, True)
        values = random_values(model)
    elif which == "rolling_disc_lu":
        from sympy.physics.mechanics.tests.test_kane5 import _create_rolling_disc

        props = _create_rolling_disc()
        model = me.KanesMethod(
            props["frame"],
            props["q_ind"],
            props["u_ind"],
            props["kdes"],
            u_dependent=props["u_dep"],
            velocity_constraints=props["fnh"],
            bodies=props["bodies"],
            forcelist=props["loads"],
            explicit_kinematics=False,
            constraint_solver="LU",
        )
        model.kanes_equations()
        values = dict(zip(sp.symbols("g r m"), (9.81, 0.26, 3.43), strict=True))
    else:
        model, values = _pendulum_system_with_actuators()
    scene = sm.Scene.from_mechanics(model, name=which)
    assert c_worst_difference(model, scene, values) < 1e-10


def test_kane_ignores_potential_energy_as_kanes_method_does_and_says_so():
    """KanesMethod forms its equations from the loads: a body's potential_energy is not
    read (sympy's own equations have no spring here), and the import warns about it."""
    q, u = me.dynamicsymbols("q u")
    m, k = sp.symbols("m k")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", q * N.x)
    P.set_vel(N, u * N.x)
    particle = me.Particle("p", P, m)
    particle.potential_energy = k * q**2 / 2
    km = me.KanesMethod(N, [q], [u], kd_eqs=[q.diff(T) - u])
    km.kanes_equations([particle], [(P, -m * u * N.x)])
    with pytest.warns(sm.SymmechWarning, match=r"ignores the potential_energy of \['p'\]"):
        scene = sm.Scene.from_mechanics(km)
    assert scene.potential == 0
    assert worst_difference(km, scene, {m: 1.3, k: 2.0}) < 1e-12
