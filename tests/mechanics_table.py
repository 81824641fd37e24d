"""A table of ``sympy.physics.mechanics`` models, each built as a user would build it:
the code copied from sympy's own tests, docstrings and ``sympy.physics.mechanics.models``
(sympy 1.14, the installed one) and from PyDy's examples (``pydy-0.9.4.tar.gz`` from
PyPI, ``docs/examples/*.rst``), the source named in each builder's comment.  Assertions,
printing and simulation are left out; the model is returned with its equations formed.

Each :class:`Entry` says what the import must do: agree with the model's own
``mass_matrix_full \\ forcing_full`` at random states (``refused`` None), or refuse it
with a message matching ``refused``.  ``tests/test_mechanics_table.py`` checks them;
``benchmarks/mechanics_roundtrip.py`` prints the counts.  (``tests/mechanics_harvest.py``
runs sympy's test functions themselves, unchanged, for the slow exhaustive round trip.)
"""

# The builders are copied as their sources write them, unused names included.
# ruff: noqa: RUF059, F841

from __future__ import annotations

import sympy as sp
from mechanics_entry import Entry
from mechanics_table_more import MORE
from mechanics_table_pydy import PYDY
from sympy import Matrix, cos, pi, sin, symbols
from sympy.physics import mechanics as me
from sympy.physics.mechanics import (
    KanesMethod,
    LagrangesMethod,
    Lagrangian,
    Particle,
    Point,
    ReferenceFrame,
    RigidBody,
    dynamicsymbols,
    inertia,
)

# ------------------------------------------------------------------ sympy's tests


def kane_one_dof():
    # sympy/physics/mechanics/tests/test_kane.py::test_one_dof
    q, u = dynamicsymbols("q u")
    qd, ud = dynamicsymbols("q u", 1)
    m, c, k = symbols("m c k")
    N = ReferenceFrame("N")
    P = Point("P")
    P.set_vel(N, u * N.x)
    kd = [qd - u]
    FL = [(P, (-k * q - c * u) * N.x)]
    pa = Particle("pa", P, m)
    BL = [pa]
    KM = KanesMethod(N, [q], [u], kd)
    KM.kanes_equations(BL, FL)
    return KM


def kane_two_dof():
    # sympy/physics/mechanics/tests/test_kane.py::test_two_dof
    q1, q2, u1, u2 = dynamicsymbols("q1 q2 u1 u2")
    q1d, q2d, u1d, u2d = dynamicsymbols("q1 q2 u1 u2", 1)
    m, c1, c2, k1, k2 = symbols("m c1 c2 k1 k2")
    N = ReferenceFrame("N")
    P1 = Point("P1")
    P2 = Point("P2")
    P1.set_vel(N, u1 * N.x)
    P2.set_vel(N, (u1 + u2) * N.x)
    kd = [q1d / 2 - u1 / 2, 2 * q2d - 2 * u2]
    FL = [
        (P1, (-k1 * q1 - c1 * u1 + k2 * q2 + c2 * u2) * N.x),
        (P2, (-k2 * q2 - c2 * u2) * N.x),
    ]
    pa1 = Particle("pa1", P1, m)
    pa2 = Particle("pa2", P2, m)
    BL = [pa1, pa2]
    KM = KanesMethod(N, q_ind=[q1, q2], u_ind=[u1, u2], kd_eqs=kd)
    KM.kanes_equations(BL, FL)
    return KM


def kane_pend():
    # sympy/physics/mechanics/tests/test_kane.py::test_pend
    q, u = dynamicsymbols("q u")
    qd, ud = dynamicsymbols("q u", 1)
    m, l, g = symbols("m l g")
    N = ReferenceFrame("N")
    P = Point("P")
    P.set_vel(N, -l * u * sin(q) * N.x + l * u * cos(q) * N.y)
    kd = [qd - u]
    FL = [(P, m * g * N.x)]
    pa = Particle("pa", P, m)
    BL = [pa]
    KM = KanesMethod(N, [q], [u], kd)
    KM.kanes_equations(BL, FL)
    return KM


def kane_rolling_disc():
    # sympy/physics/mechanics/tests/test_kane.py::test_rolling_disc
    q1, q2, q3, u1, u2, u3 = dynamicsymbols("q1 q2 q3 u1 u2 u3")
    q1d, q2d, q3d, u1d, u2d, u3d = dynamicsymbols("q1 q2 q3 u1 u2 u3", 1)
    r, m, g = symbols("r m g")
    N = ReferenceFrame("N")
    Y = N.orientnew("Y", "Axis", [q1, N.z])
    L = Y.orientnew("L", "Axis", [q2, Y.x])
    R = L.orientnew("R", "Axis", [q3, L.y])
    w_R_N_qd = R.ang_vel_in(N)
    R.set_ang_vel(N, u1 * L.x + u2 * L.y + u3 * L.z)
    C = Point("C")
    C.set_vel(N, 0)
    Dmc = C.locatenew("Dmc", r * L.z)
    Dmc.v2pt_theory(C, N, R)
    I = inertia(L, m / 4 * r**2, m / 2 * r**2, m / 4 * r**2)
    kd = [me.dot(R.ang_vel_in(N) - w_R_N_qd, uv) for uv in L]
    ForceList = [(Dmc, -m * g * Y.z)]
    BodyD = RigidBody("BodyD", Dmc, R, m, (I, Dmc))
    BodyList = [BodyD]
    KM = KanesMethod(N, q_ind=[q1, q2, q3], u_ind=[u1, u2, u3], kd_eqs=kd)
    KM.kanes_equations(BodyList, ForceList)
    return KM


def kane_parallel_axis():
    # sympy/physics/mechanics/tests/test_kane.py::test_parallel_axis (inertia about
    # the hinge: positive definite for physical values only)
    gravity = symbols("g")
    k, ls = symbols("k ls")
    a, mA, mC = symbols("a mA mC")
    F = dynamicsymbols("F")
    Ix, Iy, Iz = symbols("Ix Iy Iz")
    q1, q2 = dynamicsymbols("q1 q2")
    q1d, q2d = dynamicsymbols("q1 q2", 1)
    u1, u2 = dynamicsymbols("u1 u2")
    N = ReferenceFrame("N")
    A = ReferenceFrame("A")
    A.orient(N, "Axis", [-q2, N.z])
    A.set_ang_vel(N, -u2 * N.z)
    O = Point("O")
    C = O.locatenew("C", q1 * N.x)
    Ao = C.locatenew("Ao", a * A.y)
    C.set_vel(N, u1 * N.x)
    Ao.v2pt_theory(C, N, A)
    Cart = Particle("Cart", C, mC)
    Pendulum = RigidBody("Pendulum", Ao, A, mA, (inertia(A, Ix, Iy, Iz), C))
    kindiffs = [q1d - u1, q2d - u2]
    bodyList = [Cart, Pendulum]
    forceList = [
        (Ao, -N.y * gravity * mA),
        (C, -N.y * gravity * mC),
        (C, -N.x * k * (q1 - ls)),
        (C, N.x * F),
    ]
    km = KanesMethod(N, [q1, q2], [u1, u2], kindiffs)
    km.kanes_equations(bodyList, forceList)
    return km


def kane_input_format():
    # sympy/physics/mechanics/tests/test_kane.py::test_input_format (bodies= and
    # forcelist= given to the constructor, kanes_equations() without arguments)
    q1, q2, u1, u2 = dynamicsymbols("q1 q2 u1 u2")
    q1d, q2d, u1d, u2d = dynamicsymbols("q1 q2 u1 u2", 1)
    m, c1, c2, k1, k2 = symbols("m c1 c2 k1 k2")
    N = ReferenceFrame("N")
    P1 = Point("P1")
    P2 = Point("P2")
    P1.set_vel(N, u1 * N.x)
    P2.set_vel(N, (u1 + u2) * N.x)
    kd = [q1d - u1, q2d - u2]
    FL = [
        (P1, (-k1 * q1 - c1 * u1 + k2 * q2 + c2 * u2) * N.x),
        (P2, (-k2 * q2 - c2 * u2) * N.x),
    ]
    BL = [Particle("pa1", P1, m), Particle("pa2", P2, m)]
    KM = KanesMethod(N, q_ind=[q1, q2], u_ind=[u1, u2], kd_eqs=kd, bodies=BL, forcelist=FL)
    KM.kanes_equations()
    return KM


def kane_issue_24887():
    # sympy/physics/mechanics/tests/test_kane.py::test_issue_24887 (spherical pendulum
    # of a particle: its orientation speed about A.y has no inertia)
    g, l, m, c = symbols("g l m c")
    q1, q2, q3, u1, u2, u3 = dynamicsymbols("q1:4 u1:4")
    N = ReferenceFrame("N")
    A = ReferenceFrame("A")
    A.orient_body_fixed(N, (q1, q2, q3), "zxy")
    N_w_A = A.ang_vel_in(N)
    kdes = [N_w_A.dot(A.x) - u1, N_w_A.dot(A.y) - u2, N_w_A.dot(A.z) - u3]
    O = Point("O")
    O.set_vel(N, 0)
    Po = O.locatenew("Po", -l * A.y)
    Po.set_vel(A, 0)
    P = Particle("P", Po, m)
    kane = KanesMethod(
        N, [q1, q2, q3], [u1, u2, u3], kdes, bodies=[P], forcelist=[(Po, -m * g * N.y)]
    )
    kane.kanes_equations()
    return kane


def kane_aux():
    # sympy/physics/mechanics/tests/test_kane.py::test_aux (the model with u_auxiliary)
    q1, q2, q3 = dynamicsymbols("q1 q2 q3")
    u1, u2, u3, u4, u5 = dynamicsymbols("u1 u2 u3 u4 u5")
    r, m, g = symbols("r m g")
    N = ReferenceFrame("N")
    Y = N.orientnew("Y", "Axis", [q1, N.z])
    L = Y.orientnew("L", "Axis", [q2, Y.x])
    R = L.orientnew("R", "Axis", [q3, L.y])
    w_R_N_qd = R.ang_vel_in(N)
    R.set_ang_vel(N, u1 * L.x + u2 * L.y + u3 * L.z)
    C = Point("C")
    C.set_vel(N, u4 * L.x + u5 * (Y.z ^ L.x))
    Dmc = C.locatenew("Dmc", r * L.z)
    Dmc.v2pt_theory(C, N, R)
    Dmc.a2pt_theory(C, N, R)
    I = inertia(L, m / 4 * r**2, m / 2 * r**2, m / 4 * r**2)
    kd = [me.dot(R.ang_vel_in(N) - w_R_N_qd, uv) for uv in L]
    ForceList = [(Dmc, -m * g * Y.z), (C, 0 * L.x)]
    BodyD = RigidBody("BodyD", Dmc, R, m, (I, Dmc))
    KM = KanesMethod(N, q_ind=[q1, q2, q3], u_ind=[u1, u2, u3], kd_eqs=kd, u_auxiliary=[u4, u5])
    KM.kanes_equations([BodyD], ForceList)
    return KM


def kane_implicit_kinematics():
    # sympy/physics/mechanics/tests/test_kane.py::test_implicit_kinematics (a rigid
    # body in space, its orientation a unit quaternion: 7 coordinates, 6 speeds)
    NED = ReferenceFrame("NED")
    NED_o = Point("NED_o")
    NED_o.set_vel(NED, 0)
    q_att = dynamicsymbols("lambda_0:4", real=True)
    B = NED.orientnew("B", "Quaternion", q_att)
    q_pos = dynamicsymbols("B_x:z")
    B_cm = NED_o.locatenew("B_cm", q_pos[0] * B.x + q_pos[1] * B.y + q_pos[2] * B.z)
    q_ind = q_att[1:] + q_pos
    q_dep = [q_att[0]]
    kinematic_eqs = []
    B_ang_vel = B.ang_vel_in(NED)
    P, Q, R = dynamicsymbols("P Q R")
    B.set_ang_vel(NED, P * B.x + Q * B.y + R * B.z)
    B_ang_vel_kd = (B.ang_vel_in(NED) - B_ang_vel).simplify()
    kinematic_eqs += [B_ang_vel_kd & B.x, B_ang_vel_kd & B.y, B_ang_vel_kd & B.z]
    B_cm_vel = B_cm.vel(NED)
    U, V, W = dynamicsymbols("U V W")
    B_cm.set_vel(NED, U * B.x + V * B.y + W * B.z)
    B_ref_vel_kd = B_cm.vel(NED) - B_cm_vel
    kinematic_eqs += [B_ref_vel_kd & B.x, B_ref_vel_kd & B.y, B_ref_vel_kd & B.z]
    u_ind = [U, V, W, P, Q, R]
    q_att_vec = Matrix(q_att)
    config_cons = [(q_att_vec.T * q_att_vec)[0] - 1]
    kinematic_eqs = [*kinematic_eqs, (q_att_vec.T * q_att_vec.diff())[0]]
    KM = KanesMethod(
        NED,
        q_ind,
        u_ind,
        q_dependent=q_dep,
        kd_eqs=kinematic_eqs,
        configuration_constraints=config_cons,
        velocity_constraints=[],
        u_dependent=[],
        u_auxiliary=[],
        explicit_kinematics=False,
    )
    M_B = symbols("M_B")
    J_B = inertia(
        B,
        *[
            sp.S(f"J_B_{ax}") * (1 if ax[0] == ax[1] else -1)
            for ax in ["xx", "yy", "zz", "xy", "yz", "xz"]
        ],
    )
    J_B = J_B.subs({sp.S("J_B_xy"): 0, sp.S("J_B_yz"): 0})
    RB = RigidBody("RB", B_cm, B, M_B, (J_B, B_cm))
    force_list = [(RB.masscenter, RB.mass * sp.S("g") * NED.z)]
    KM.kanes_equations([RB], force_list)
    return KM


def kane_replace_qdots_in_force():
    # sympy/physics/mechanics/tests/test_kane4.py::test_replace_qdots_in_force (loads
    # written in q_dot, which KanesMethod replaces by its kinematic equations)
    q1, q2 = dynamicsymbols("q1, q2")
    qd1, qd2 = dynamicsymbols("q1, q2", level=1)
    u1, u2 = dynamicsymbols("u1, u2")
    l, m = symbols("l, m")
    N = ReferenceFrame("N")
    A = N.orientnew("A", "Axis", (q1, N.z))
    B = A.orientnew("B", "Axis", (q2, N.z))
    O = Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", (l * A.x))
    P.v2pt_theory(O, N, A)
    Q = P.locatenew("Q", (l * B.x))
    Q.v2pt_theory(P, N, B)
    Ap = Particle("Ap", P, m)
    Bp = Particle("Bp", Q, m)
    sigma, delta = symbols("sigma, delta")
    Ta = (sigma * q2 + delta * qd2) * N.z
    forces = [(A, Ta), (B, -Ta)]
    kde1 = [u1 - qd1, u2 - qd2]
    KM1 = KanesMethod(N, [q1, q2], [u1, u2], kd_eqs=kde1)
    KM1.kanes_equations([Ap, Bp], forces)
    return KM1


def kane_replace_qdots_in_force_relative():
    # sympy/physics/mechanics/tests/test_kane4.py::test_replace_qdots_in_force (its
    # second set of kinematic equations: u2 the absolute rate of B)
    q1, q2 = dynamicsymbols("q1, q2")
    qd1, qd2 = dynamicsymbols("q1, q2", level=1)
    u1, u2 = dynamicsymbols("u1, u2")
    l, m = symbols("l, m")
    N = ReferenceFrame("N")
    A = N.orientnew("A", "Axis", (q1, N.z))
    B = A.orientnew("B", "Axis", (q2, N.z))
    O = Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", (l * A.x))
    P.v2pt_theory(O, N, A)
    Q = P.locatenew("Q", (l * B.x))
    Q.v2pt_theory(P, N, B)
    Ap = Particle("Ap", P, m)
    Bp = Particle("Bp", Q, m)
    sigma, delta = symbols("sigma, delta")
    Ta = (sigma * q2 + delta * qd2) * N.z
    forces = [(A, Ta), (B, -Ta)]
    kde2 = [u1 - qd1, u2 - (qd1 + qd2)]
    KM2 = KanesMethod(N, [q1, q2], [u1, u2], kd_eqs=kde2)
    KM2.kanes_equations([Ap, Bp], forces)
    return KM2


def kane_rolling_disc_lu():
    # sympy/physics/mechanics/tests/test_kane5.py::test_kane_rolling_disc_lu (the
    # dependent speeds of the contact point, which no body's velocity uses, by LU)
    from sympy.physics.mechanics.tests.test_kane5 import _create_rolling_disc

    props = _create_rolling_disc()
    kane = KanesMethod(
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
    return kane


def lagrange_disc_on_incline():
    # sympy/physics/mechanics/tests/test_lagrange.py::test_disc_on_an_incline_plane
    y, theta = dynamicsymbols("y theta")
    yd, thetad = dynamicsymbols("y theta", 1)
    m, g, R, l, alpha = symbols("m g R l alpha")
    N = ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [pi / 2 - alpha, N.z])
    B = A.orientnew("B", "Axis", [-theta, A.z])
    Do = Point("Do")
    Do.set_vel(N, yd * A.x)
    I = m * R**2 / 2 * B.z | B.z
    D = RigidBody("D", Do, B, m, (I, Do))
    D.potential_energy = m * g * (l - y) * sin(alpha)
    L = Lagrangian(N, D)
    q = [y, theta]
    hol_coneqs = [y - R * theta]
    lm = LagrangesMethod(L, q, hol_coneqs=hol_coneqs)
    lm.form_lagranges_equations()
    return lm


def lagrange_simp_pen():
    # sympy/physics/mechanics/tests/test_lagrange.py::test_simp_pen
    q, u = dynamicsymbols("q u")
    qd, ud = dynamicsymbols("q u ", 1)
    l, m, g = symbols("l m g")
    N = ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [q, N.z])
    A.set_ang_vel(N, qd * N.z)
    O = Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", l * A.x)
    P.v2pt_theory(O, N, A)
    Pa = Particle("Pa", P, m)
    Pa.potential_energy = -m * g * l * cos(q)
    L = Lagrangian(N, Pa)
    lm = LagrangesMethod(L, [q])
    lm.form_lagranges_equations()
    return lm


def lagrange_dub_pen(frame: bool = True):
    # sympy/physics/mechanics/tests/test_lagrange.py::test_dub_pen (bodies= whose
    # particles carry potential_energy; with and without frame=)
    q1, q2 = dynamicsymbols("q1 q2")
    q1d, q2d = dynamicsymbols("q1 q2", 1)
    m, l, g = symbols("m l g")
    N = ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [q1, N.z])
    B = N.orientnew("B", "Axis", [q2, N.z])
    A.set_ang_vel(N, q1d * A.z)
    B.set_ang_vel(N, q2d * A.z)
    O = Point("O")
    P = O.locatenew("P", l * A.x)
    R = P.locatenew("R", l * B.x)
    O.set_vel(N, 0)
    P.v2pt_theory(O, N, A)
    R.v2pt_theory(P, N, B)
    ParP = Particle("ParP", P, m)
    ParR = Particle("ParR", R, m)
    ParP.potential_energy = -m * g * l * cos(q1)
    ParR.potential_energy = -m * g * l * cos(q1) - m * g * l * cos(q2)
    L = Lagrangian(N, ParP, ParR)
    if frame:
        lm = LagrangesMethod(L, [q1, q2], bodies=[ParP, ParR], frame=N)
    else:
        lm = LagrangesMethod(L, [q1, q2], bodies=[ParP, ParR])
    lm.form_lagranges_equations()
    return lm


def lagrange_nonminimal_pendulum():
    # sympy/physics/mechanics/tests/test_lagrange.py::test_nonminimal_pendulum
    q1, q2 = dynamicsymbols("q1:3")
    q1d, q2d = dynamicsymbols("q1:3", level=1)
    L1, L2 = dynamicsymbols("L1:3")
    m, l, g = symbols("m l g")
    N = ReferenceFrame("N")
    pN = Point("N*")
    pN.set_vel(N, 0)
    theta1 = sp.atan(q2 / q1)
    A = N.orientnew("A", "axis", [theta1, N.z])
    P = pN.locatenew("P1", q1 * N.x + q2 * N.y)
    P.set_vel(N, P.pos_from(pN).dt(N))
    pP = Particle("pP", P, m)
    f_c = Matrix([q1**2 + q2**2 - l**2])
    R = m * g * N.x
    lm = LagrangesMethod(Lagrangian(N, pP), [q1, q2], hol_coneqs=f_c, forcelist=[(P, R)], frame=N)
    lm.form_lagranges_equations()
    return lm


def lagrange_2forces():
    # sympy/physics/mechanics/tests/test_lagrange2.py::test_lagrange_2forces
    q1, q2 = dynamicsymbols("q1, q2")
    q1d, q2d = dynamicsymbols("q1, q2", 1)
    m, k, nu = symbols("m, k, nu")
    N = ReferenceFrame("N")
    O = Point("O")
    P1 = O.locatenew("P1", q1 * N.x)
    P1.set_vel(N, q1d * N.x)
    P2 = O.locatenew("P1", q2 * N.x)
    P2.set_vel(N, q2d * N.x)
    pP1 = Particle("pP1", P1, m)
    pP1.potential_energy = k * q1**2 / 2
    pP2 = Particle("pP2", P2, m)
    pP2.potential_energy = k * (q1 - q2) ** 2 / 2
    forcelist = [(P1, -nu * q1d * N.x), (P2, -nu * q2d * N.x)]
    lag = Lagrangian(N, pP1, pP2)
    l_method = LagrangesMethod(lag, (q1, q2), forcelist=forcelist, frame=N)
    l_method.form_lagranges_equations()
    return l_method


def lagrange_rolling_disc():
    # sympy/physics/mechanics/tests/test_lagrange.py::test_rolling_disc
    q1, q2, q3 = dynamicsymbols("q1 q2 q3")
    q1d, q2d, q3d = dynamicsymbols("q1 q2 q3", 1)
    r, m, g = symbols("r m g")
    N = ReferenceFrame("N")
    Y = N.orientnew("Y", "Axis", [q1, N.z])
    L = Y.orientnew("L", "Axis", [q2, Y.x])
    R = L.orientnew("R", "Axis", [q3, L.y])
    C = Point("C")
    C.set_vel(N, 0)
    Dmc = C.locatenew("Dmc", r * L.z)
    Dmc.v2pt_theory(C, N, R)
    I = inertia(L, m / 4 * r**2, m / 2 * r**2, m / 4 * r**2)
    BodyD = RigidBody("BodyD", Dmc, R, m, (I, Dmc))
    BodyD.potential_energy = -m * g * r * cos(q2)
    Lag = Lagrangian(N, BodyD)
    q = [q1, q2, q3]
    lm = LagrangesMethod(Lag, q)
    lm.form_lagranges_equations()
    return lm


def linearize_pendulum_kane_nonminimal():
    # sympy/physics/mechanics/tests/test_linearize.py::test_linearize_pendulum_kane_nonminimal
    q1, q2 = dynamicsymbols("q1:3")
    q1d, q2d = dynamicsymbols("q1:3", level=1)
    u1, u2 = dynamicsymbols("u1:3")
    u1d, u2d = dynamicsymbols("u1:3", level=1)
    L, m, t = symbols("L, m, t")
    g = 9.8
    N = ReferenceFrame("N")
    pN = Point("N*")
    pN.set_vel(N, 0)
    theta1 = sp.atan(q2 / q1)
    A = N.orientnew("A", "axis", [theta1, N.z])
    P = pN.locatenew("P1", q1 * N.x + q2 * N.y)
    pP = Particle("pP", P, m)
    kde = Matrix([q1d - u1, q2d - u2])
    dq_dict = sp.solve(kde, [q1d, q2d])
    P.set_vel(N, P.pos_from(pN).dt(N).subs(dq_dict))
    f_c = Matrix([P.pos_from(pN).magnitude() - L])
    f_v = Matrix([P.vel(N).express(A).dot(A.x)])
    f_v.simplify()
    f_a = f_v.diff(t)
    R = m * g * N.x
    KM = KanesMethod(
        N,
        q_ind=[q2],
        u_ind=[u2],
        q_dependent=[q1],
        u_dependent=[u1],
        configuration_constraints=f_c,
        velocity_constraints=f_v,
        acceleration_constraints=f_a,
        kd_eqs=kde,
    )
    KM.kanes_equations([pP], [(P, R)])
    return KM


def linearize_pendulum_lagrange_minimal():
    # sympy/physics/mechanics/tests/test_linearize.py::test_linearize_pendulum_lagrange_minimal
    q1 = dynamicsymbols("q1")
    q1d = dynamicsymbols("q1", 1)
    L, m, t = symbols("L, m, t")
    g = 9.8
    N = ReferenceFrame("N")
    pN = Point("N*")
    pN.set_vel(N, 0)
    A = N.orientnew("A", "axis", [q1, N.z])
    A.set_ang_vel(N, q1d * N.z)
    P = pN.locatenew("P", L * A.x)
    P.v2pt_theory(pN, N, A)
    pP = Particle("pP", P, m)
    Lag = Lagrangian(N, pP)
    LM = LagrangesMethod(Lag, [q1], [(P, m * g * N.x)], frame=N)
    LM.form_lagranges_equations()
    return LM


def linearize_rolling_disc_kane():
    # sympy/physics/mechanics/tests/test_linearize.py::test_linearize_rolling_disc_kane
    # (a configuration constraint, dependent speeds, velocity constraints, an angular
    # acceleration set with set_ang_acc)
    t, r, m, g, v = symbols("t r m g v")
    q1, q2, q3, q4, q5, q6 = q = dynamicsymbols("q1:7")
    q1d, q2d, q3d, q4d, q5d, q6d = qd = [qi.diff(t) for qi in q]
    u1, u2, u3, u4, u5, u6 = u = dynamicsymbols("u1:7")
    N = ReferenceFrame("N")
    NO = Point("NO")
    A = N.orientnew("A", "Axis", [q1, N.z])
    B = A.orientnew("B", "Axis", [q2, A.x])
    C = B.orientnew("C", "Axis", [q3, B.y])
    CO = NO.locatenew("CO", q4 * N.x + q5 * N.y + q6 * N.z)
    w_c_n_qd = C.ang_vel_in(N)
    w_b_n_qd = B.ang_vel_in(N)
    C.set_ang_vel(N, u1 * B.x + u2 * B.y + u3 * B.z)
    v_co_n_qd = CO.pos_from(NO).dt(N)
    CO.set_vel(N, u4 * C.x + u5 * C.y + u6 * C.z)
    P = CO.locatenew("P", r * B.z)
    P.v2pt_theory(CO, N, C)
    f_c = Matrix([q6 - me.dot(CO.pos_from(P), N.z)])
    f_v = Matrix([me.dot(P.vel(N), uv) for uv in C])
    kindiffs = Matrix(
        [me.dot(w_c_n_qd - C.ang_vel_in(N), uv) for uv in B]
        + [me.dot(v_co_n_qd - CO.vel(N), uv) for uv in N]
    )
    qdots = sp.solve(kindiffs, qd)
    B.set_ang_vel(N, w_b_n_qd.subs(qdots))
    C.set_ang_acc(N, C.ang_vel_in(N).dt(B) + me.cross(B.ang_vel_in(N), C.ang_vel_in(N)))
    F_CO = m * g * A.z
    I = (m * r**2) / 4
    J = (m * r**2) / 2
    I_C_CO = inertia(C, I, J, I)
    Disc = RigidBody("Disc", CO, C, m, (I_C_CO, CO))
    BL = [Disc]
    FL = [(CO, F_CO)]
    KM = KanesMethod(
        N,
        [q1, q2, q3, q4, q5],
        [u1, u2, u3],
        kd_eqs=kindiffs,
        q_dependent=[q6],
        configuration_constraints=f_c,
        u_dependent=[u4, u5, u6],
        velocity_constraints=f_v,
    )
    KM.kanes_equations(BL, FL)
    return KM


def system_cart_pendulum_kanes():
    # sympy/physics/mechanics/tests/test_system_class.py::TestSystemExamples::
    # test_cart_pendulum_kanes (a System of joints; a load and an actuator)
    g, l, mc, mp, k = symbols("g l mc mp k")
    F, qp, qc, up, uc = dynamicsymbols("F qp qc up uc")
    rail = RigidBody("rail")
    cart = RigidBody("cart", mass=mc)
    bob = Particle("bob", mass=mp)
    bob_frame = ReferenceFrame("bob_frame")
    system = me.System.from_newtonian(rail)
    slider = me.PrismaticJoint("slider", rail, cart, qc, uc, joint_axis=rail.x)
    pin = me.PinJoint(
        "pin",
        cart,
        bob,
        qp,
        up,
        joint_axis=cart.z,
        child_interframe=bob_frame,
        child_point=l * bob_frame.y,
    )
    system.add_joints(slider, pin)
    system.apply_uniform_gravity(-g * system.y)
    system.add_loads((cart.masscenter, F * rail.x))
    system.add_actuators(me.TorqueActuator(k * qp, cart.z, bob_frame, cart))
    system.validate_system()
    system.form_eoms()
    return system


def system_cart_pendulum_lagrange():
    # sympy/physics/mechanics/tests/test_system_class.py::TestSystemExamples::
    # test_cart_pendulum_lagrange (joints whose speeds are the q_dots, the bodies'
    # potential_energy, a load and an actuator; LagrangesMethod)
    g, l, mc, mp, k = symbols("g l mc mp k")
    F, qp, qc = dynamicsymbols("F qp qc")
    qpd, qcd = dynamicsymbols("qp qc", 1)
    rail = RigidBody("rail")
    cart = RigidBody("cart", mass=mc)
    bob = Particle("bob", mass=mp)
    bob_frame = ReferenceFrame("bob_frame")
    system = me.System.from_newtonian(rail)
    slider = me.PrismaticJoint("slider", rail, cart, qc, qcd, joint_axis=rail.x)
    pin = me.PinJoint(
        "pin",
        cart,
        bob,
        qp,
        qpd,
        joint_axis=cart.z,
        child_interframe=bob_frame,
        child_point=l * bob_frame.y,
    )
    system.add_joints(slider, pin)
    for body in system.bodies:
        body.potential_energy = (
            body.mass * g * body.masscenter.pos_from(system.fixed_point).dot(system.y)
        )
    system.add_loads((cart.masscenter, F * rail.x))
    system.add_actuators(me.TorqueActuator(k * qp, cart.z, bob_frame, cart))
    system.validate_system(LagrangesMethod)
    system.form_eoms(LagrangesMethod)
    return system


def system_box_on_ground():
    # sympy/physics/mechanics/tests/test_system_class.py::TestSystemExamples::test_box_on_ground
    g, m, mu = symbols("g m mu")
    q, u, ua = dynamicsymbols("q u ua")
    N, F = dynamicsymbols("N F", positive=True)
    P = Particle("P", mass=m)
    system = me.System()
    system.add_bodies(P)
    P.masscenter.set_pos(system.fixed_point, q * system.x)
    P.masscenter.set_vel(system.frame, u * system.x + ua * system.y)
    system.q_ind, system.u_ind, system.u_aux = [q], [u], [ua]
    system.kdes = [q.diff(me.dynamicsymbols._t) - u]
    system.apply_uniform_gravity(-g * system.y)
    system.add_loads(me.Force(P, N * system.y), me.Force(P, F * system.x - mu * N * system.x))
    system.validate_system()
    system.form_eoms()
    return system


def jointsmethod_chaos_pendulum():
    # sympy/physics/mechanics/tests/test_jointsmethod.py::test_chaos_pendulum, with
    # RigidBody and System where sympy's test uses the deprecated Body and JointsMethod
    mA, mB, lA, lB, IAxx, IBxx, IByy, IBzz, g = symbols("mA, mB, lA, lB, IAxx, IBxx, IByy, IBzz, g")
    theta, phi, omega, alpha = dynamicsymbols("theta phi omega alpha")
    A = ReferenceFrame("A")
    B = ReferenceFrame("B")
    rod = RigidBody("rod", mass=mA, frame=A)
    rod.central_inertia = inertia(A, IAxx, IAxx, 0)
    plate = RigidBody("plate", mass=mB, frame=B)
    plate.central_inertia = inertia(B, IBxx, IByy, IBzz)
    C = RigidBody("C")
    system = me.System.from_newtonian(C)
    J1 = me.PinJoint(
        "J1", C, rod, coordinates=theta, speeds=omega, child_point=-lA * rod.z, joint_axis=C.y
    )
    J2 = me.PinJoint(
        "J2",
        rod,
        plate,
        coordinates=phi,
        speeds=alpha,
        parent_point=(lB - lA) * rod.z,
        joint_axis=rod.z,
    )
    system.add_joints(J1, J2)
    system.add_loads((rod.masscenter, mA * g * C.z), (plate.masscenter, mB * g * C.z))
    system.form_eoms()
    return system


def four_bar_linkage_manual_constraints():
    # sympy/physics/mechanics/tests/test_jointsmethod.py::
    # test_four_bar_linkage_with_manual_constraints, with RigidBody and the joints'
    # kinematic equations where sympy's test uses the deprecated Body and JointsMethod
    q1, q2, q3, u1, u2, u3 = dynamicsymbols("q1:4, u1:4")
    l1, l2, l3, l4, rho = symbols("l1:5, rho")
    N = ReferenceFrame("N")
    inertias = [inertia(N, 0, 0, rho * l**3 / 12) for l in (l1, l2, l3, l4)]
    link1 = RigidBody("Link1", frame=N, mass=rho * l1)
    link2 = RigidBody("Link2", mass=rho * l2)
    link3 = RigidBody("Link3", mass=rho * l3)
    link4 = RigidBody("Link4", mass=rho * l4)
    link1.central_inertia = inertias[0]
    link2.central_inertia = inertia(link2.frame, 0, 0, rho * l2**3 / 12)
    link3.central_inertia = inertia(link3.frame, 0, 0, rho * l3**3 / 12)
    link4.central_inertia = inertia(link4.frame, 0, 0, rho * l4**3 / 12)
    joint1 = me.PinJoint(
        "J1",
        link1,
        link2,
        coordinates=q1,
        speeds=u1,
        joint_axis=link1.z,
        parent_point=l1 / 2 * link1.x,
        child_point=-l2 / 2 * link2.x,
    )
    joint2 = me.PinJoint(
        "J2",
        link2,
        link3,
        coordinates=q2,
        speeds=u2,
        joint_axis=link2.z,
        parent_point=l2 / 2 * link2.x,
        child_point=-l3 / 2 * link3.x,
    )
    joint3 = me.PinJoint(
        "J3",
        link3,
        link4,
        coordinates=q3,
        speeds=u3,
        joint_axis=link3.z,
        parent_point=l3 / 2 * link3.x,
        child_point=-l4 / 2 * link4.x,
    )
    loop = link4.masscenter.pos_from(link1.masscenter) + l1 / 2 * link1.x + l4 / 2 * link4.x
    fh = Matrix([loop.dot(link1.x), loop.dot(link1.y)])
    kdes = [*joint1.kdes, *joint2.kdes, *joint3.kdes]
    t = dynamicsymbols._t
    qdots = sp.solve(kdes, [q1.diff(t), q2.diff(t), q3.diff(t)])
    fhd = fh.diff(t).subs(qdots)
    link1.masscenter.set_vel(N, 0)  # (JointsMethod fixes its root body so)
    kane = KanesMethod(
        N,
        q_ind=[q1],
        u_ind=[u1],
        q_dependent=[q2, q3],
        u_dependent=[u2, u3],
        kd_eqs=kdes,
        configuration_constraints=fh,
        velocity_constraints=fhd,
        forcelist=[],
        bodies=[link1, link2, link3, link4],
    )
    kane.kanes_equations()
    return kane


def models_entries() -> list[Entry]:
    """``sympy.physics.mechanics.models``, called as a user calls it."""
    from sympy.physics.mechanics import models

    out = []
    for n in (1, 2, 3):
        out += [
            Entry(
                f"models.multi_mass_spring_damper({n})",
                "sympy.physics.mechanics.models.multi_mass_spring_damper",
                lambda n=n: models.multi_mass_spring_damper(n),
            ),
            Entry(
                f"models.multi_mass_spring_damper({n}, True, True)",
                "sympy.physics.mechanics.models.multi_mass_spring_damper",
                lambda n=n: models.multi_mass_spring_damper(n, True, True),
            ),
            Entry(
                f"models.n_link_pendulum_on_cart({n})",
                "sympy.physics.mechanics.models.n_link_pendulum_on_cart",
                lambda n=n: models.n_link_pendulum_on_cart(n),
                c=n == 2,
            ),
            Entry(
                f"models.n_link_pendulum_on_cart({n}, True, True)",
                "sympy.physics.mechanics.models.n_link_pendulum_on_cart",
                lambda n=n: models.n_link_pendulum_on_cart(n, True, True),
                slow=n == 3,
            ),
        ]
    return out


_AUX = r"u_auxiliary \[.*\]: auxiliary speeds .* not supported; build the KanesMethod without"
_TESTS = "sympy/physics/mechanics/tests/"

SYMPY: list[Entry] = [
    Entry("kane one dof", _TESTS + "test_kane.py::test_one_dof", kane_one_dof, c=True),
    Entry("kane two dof", _TESTS + "test_kane.py::test_two_dof", kane_two_dof),
    Entry("kane pendulum", _TESTS + "test_kane.py::test_pend", kane_pend),
    Entry("kane rolling disc", _TESTS + "test_kane.py::test_rolling_disc", kane_rolling_disc),
    Entry("kane parallel axis", _TESTS + "test_kane.py::test_parallel_axis", kane_parallel_axis),
    Entry("kane input format", _TESTS + "test_kane.py::test_input_format", kane_input_format),
    Entry(
        "kane issue 24887",
        _TESTS + "test_kane.py::test_issue_24887",
        kane_issue_24887,
        refused=r"singular: no body's kinetic energy fixes the velocities \[u2\(t\)\]"
        r" \(sympy issue 24887",
    ),
    Entry("kane u_auxiliary", _TESTS + "test_kane.py::test_aux", kane_aux, refused=_AUX),
    Entry(
        "kane quaternion",
        _TESTS + "test_kane.py::test_implicit_kinematics",
        kane_implicit_kinematics,
        refused=r"7 coordinates .* and only 6 speeds: .*unit quaternion.* use as many"
        r" coordinates as speeds",
    ),
    Entry(
        "kane forces in q_dot",
        _TESTS + "test_kane4.py::test_replace_qdots_in_force",
        kane_replace_qdots_in_force,
    ),
    Entry(
        "kane forces in q_dot, absolute speeds",
        _TESTS + "test_kane4.py::test_replace_qdots_in_force",
        kane_replace_qdots_in_force_relative,
    ),
    Entry(
        "kane rolling disc, LU",
        _TESTS + "test_kane5.py::test_kane_rolling_disc_lu",
        kane_rolling_disc_lu,
        c=True,
    ),
    Entry(
        "lagrange disc on incline",
        _TESTS + "test_lagrange.py::test_disc_on_an_incline_plane",
        lagrange_disc_on_incline,
    ),
    Entry("lagrange pendulum", _TESTS + "test_lagrange.py::test_simp_pen", lagrange_simp_pen),
    Entry(
        "lagrange double pendulum, bodies=, frame=",
        _TESTS + "test_lagrange.py::test_dub_pen",
        lagrange_dub_pen,
    ),
    Entry(
        "lagrange double pendulum, bodies=, no frame",
        _TESTS + "test_lagrange.py::test_dub_pen (without frame=)",
        lambda: lagrange_dub_pen(frame=False),
    ),
    Entry(
        "lagrange nonminimal pendulum",
        _TESTS + "test_lagrange.py::test_nonminimal_pendulum",
        lagrange_nonminimal_pendulum,
    ),
    Entry(
        "lagrange rolling disc",
        _TESTS + "test_lagrange.py::test_rolling_disc",
        lagrange_rolling_disc,
    ),
    Entry(
        "lagrange 2 forces", _TESTS + "test_lagrange2.py::test_lagrange_2forces", lagrange_2forces
    ),
    Entry(
        "kane nonminimal pendulum",
        _TESTS + "test_linearize.py::test_linearize_pendulum_kane_nonminimal",
        linearize_pendulum_kane_nonminimal,
        refused=r"a velocity or configuration constraint \(KanesMethod\.velocity_constraints"
        r" / configuration_constraints\) contains the non-smooth functions \['Abs'\]",
    ),
    Entry(
        "lagrange minimal pendulum",
        _TESTS + "test_linearize.py::test_linearize_pendulum_lagrange_minimal",
        linearize_pendulum_lagrange_minimal,
    ),
    Entry(
        "kane rolling disc, contact speeds",
        _TESTS + "test_linearize.py::test_linearize_rolling_disc_kane",
        linearize_rolling_disc_kane,
    ),
    Entry(
        "System cart pendulum (Kane, actuator)",
        _TESTS + "test_system_class.py::TestSystemExamples::test_cart_pendulum_kanes",
        system_cart_pendulum_kanes,
        c=True,
    ),
    Entry(
        "System cart pendulum (Lagrange, q_dot speeds)",
        _TESTS + "test_system_class.py::TestSystemExamples::test_cart_pendulum_lagrange",
        system_cart_pendulum_lagrange,
    ),
    Entry(
        "System box on ground (u_aux)",
        _TESTS + "test_system_class.py::TestSystemExamples::test_box_on_ground",
        system_box_on_ground,
        refused=r"System\.u_aux \[ua\(t\)\]: auxiliary speeds are not supported; build the"
        r" System without them",
    ),
    Entry(
        "four-bar linkage, manual constraints",
        _TESTS + "test_jointsmethod.py::test_four_bar_linkage_with_manual_constraints",
        four_bar_linkage_manual_constraints,
    ),
    Entry(
        "System chaos pendulum",
        _TESTS + "test_jointsmethod.py::test_chaos_pendulum",
        jointsmethod_chaos_pendulum,
    ),
]

#: every model of the table
TABLE: list[Entry] = [*SYMPY, *models_entries(), *MORE, *PYDY]
