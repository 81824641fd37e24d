"""PyDy's example models for the table of :mod:`mechanics_table`: ``pydy-0.9.4.tar.gz``
from PyPI, ``docs/examples/*.rst``, each copied up to its equations (without the
simulation, plotting and visualisation).  Left out: ``rocket-car.rst`` (its equations are
formed by hand, not by a KanesMethod) and the two ``kane-levinson-1985`` chapters
(kinematics exercises, no model); ``pydy.models`` holds the same two functions as
``sympy.physics.mechanics.models``, which the table calls."""

# The builders are copied as their sources write them, unused names included.
# ruff: noqa: RUF059

from __future__ import annotations

import sympy as sm
import sympy.physics.mechanics as me
from mechanics_entry import Entry


def pydy_mass_spring_damper():
    # pydy-0.9.4 docs/examples/mass-spring-damper.rst
    x, v = me.dynamicsymbols("x v")
    m, c, k, g, t = sm.symbols("m c k g t")
    ceiling = me.ReferenceFrame("C")
    O = me.Point("O")
    P = me.Point("P")
    O.set_vel(ceiling, 0)
    P.set_pos(O, x * ceiling.x)
    P.set_vel(ceiling, v * ceiling.x)
    damping = -c * P.vel(ceiling)
    stiffness = -k * P.pos_from(O)
    gravity = m * g * ceiling.x
    forces = damping + stiffness + gravity
    mass = me.Particle("mass", P, m)
    kane = me.KanesMethod(ceiling, q_ind=[x], u_ind=[v], kd_eqs=[v - x.diff(t)])
    kane.kanes_equations([mass], loads=[(P, forces)])
    return kane


def pydy_chaos_pendulum():
    # pydy-0.9.4 docs/examples/chaos-pendulum.rst
    mA, mB, lB, w, h, g = sm.symbols("m_A, m_B, L_B, w, h, g")
    theta, phi = me.dynamicsymbols("theta, phi")
    omega, alpha = me.dynamicsymbols("omega, alpha")
    kin_diff = (omega - theta.diff(), alpha - phi.diff())
    N = me.ReferenceFrame("N")
    A = me.ReferenceFrame("A")
    B = me.ReferenceFrame("B")
    A.orient(N, "Axis", (theta, N.y))
    B.orient(A, "Axis", (phi, A.z))
    No = me.Point("No")
    Ao = me.Point("Ao")
    Bo = me.Point("Bo")
    lA = (lB - h / 2) / 2
    Ao.set_pos(No, lA * A.z)
    Bo.set_pos(No, lB * A.z)
    A.set_ang_vel(N, omega * N.y)
    B.set_ang_vel(A, alpha * A.z)
    No.set_vel(N, 0)
    Ao.v2pt_theory(No, N, A)
    Bo.v2pt_theory(No, N, A)
    IAxx = sm.S(1) / 12 * mA * (2 * lA) ** 2
    IAyy = IAxx
    IAzz = 0
    IA = (me.inertia(A, IAxx, IAyy, IAzz), Ao)
    IBxx = sm.S(1) / 12 * mB * h**2
    IByy = sm.S(1) / 12 * mB * (w**2 + h**2)
    IBzz = sm.S(1) / 12 * mB * w**2
    IB = (me.inertia(B, IBxx, IByy, IBzz), Bo)
    rod = me.RigidBody("rod", Ao, A, mA, IA)
    plate = me.RigidBody("plate", Bo, B, mB, IB)
    rod_gravity = (Ao, mA * g * N.z)
    plate_gravity = (Bo, mB * g * N.z)
    kane = me.KanesMethod(N, q_ind=(theta, phi), u_ind=(omega, alpha), kd_eqs=kin_diff)
    kane.kanes_equations((rod, plate), (rod_gravity, plate_gravity))
    return kane


def pydy_multidof_holonomic():
    # pydy-0.9.4 docs/examples/multidof-holonomic.rst (speeds that are not the q_dots,
    # velocities simplified and set by hand, inputs F(t) and T(t), a damper)
    q1, q2, q3 = me.dynamicsymbols("q1, q2, q3")
    u1, u2, u3 = me.dynamicsymbols("u1, u2, u3")
    F, T = me.dynamicsymbols("F, T")
    k, c, ma, mb, mc, IB_bo, l, kT, g = sm.symbols("k, c, m_a, m_b, m_c, I_{B_bo}, l, k_T, g")
    N = me.ReferenceFrame("N")
    B = N.orientnew("B", "Axis", (q2, N.z))
    C = B.orientnew("C", "Axis", (q3, N.z))
    O = me.Point("O")
    Pab = O.locatenew("P_{ab}", q1 * N.x)
    Bo = Pab.locatenew("B_o", -2 * l / 3 * B.y)
    Pbc = Pab.locatenew("P_{bc}", -l * B.y)
    Pc = Pbc.locatenew("P_c", -l * C.y)
    Pab.set_vel(N, Pab.pos_from(O).dt(N))
    Bo.v2pt_theory(Pab, N, B)
    Pbc.v2pt_theory(Pab, N, B)
    Pc.v2pt_theory(Pbc, N, C)
    u1_eq = sm.Eq(u1, Pab.vel(N).dot(N.x))
    u2_eq = sm.Eq(u2, Bo.vel(N).dot(B.x))
    u3_eq = sm.Eq(u3, C.ang_vel_in(B).dot(B.z))
    qdots = sm.solve([u1_eq, u2_eq, u3_eq], q1.diff(), q2.diff(), q3.diff())
    Pab.set_vel(N, Pab.vel(N).subs(qdots).simplify())
    Bo.set_vel(N, Bo.vel(N).subs(qdots).express(B).simplify())
    Pc.set_vel(N, Pc.vel(N).subs(qdots).simplify())
    B.set_ang_vel(N, B.ang_vel_in(N).subs(qdots).simplify())
    C.set_ang_vel(B, u3 * N.z)
    IB = me.inertia(B, 0, 0, IB_bo)
    Rab = (F - k * q1 - c * qdots[q1.diff()]) * N.x
    Rbo = -(mb * g) * N.y
    Rc = -(mc * g) * N.y
    TB = (T + kT * q3) * N.z
    TC = -kT * q3 * N.z
    kdes = [u1_eq.rhs - u1_eq.lhs, u2_eq.rhs - u2_eq.lhs, u3_eq.rhs - u3_eq.lhs]
    block = me.Particle("block", Pab, ma)
    pendulum = me.RigidBody("pendulum", Bo, B, mb, (IB, Bo))
    bob = me.Particle("bob", Pc, mc)
    bodies = [block, pendulum, bob]
    loads = [(Pab, Rab), (Bo, Rbo), (Pc, Rc), (B, TB), (C, TC)]
    kane = me.KanesMethod(N, (q1, q2, q3), (u1, u2, u3), kd_eqs=kdes)
    kane.kanes_equations(bodies, loads=loads)
    return kane


def pydy_three_link_conical_pendulum():
    # pydy-0.9.4 docs/examples/three-link-conical-pendulum.rst (angular velocities set
    # as omega I.z + delta I.x, not the derivatives of the orientations)
    n = 3
    alpha = me.dynamicsymbols(f"alpha:{n}")
    beta = me.dynamicsymbols(f"beta:{n}")
    omega = me.dynamicsymbols(f"omega:{n}")
    delta = me.dynamicsymbols(f"delta:{n}")
    m_bob = sm.symbols(f"m:{n}")
    l = sm.symbols(f"l:{n}")
    m_link = sm.symbols(f"M:{n}")
    Ixx = sm.symbols(f"Ixx:{n}")
    Iyy = sm.symbols(f"Iyy:{n}")
    Izz = sm.symbols(f"Izz:{n}")
    g = sm.symbols("g")
    I = me.ReferenceFrame("I")
    A = me.ReferenceFrame("A")
    A.orient(I, "Space", [alpha[0], beta[0], 0], "ZXY")
    B = me.ReferenceFrame("B")
    B.orient(A, "Space", [alpha[1], beta[1], 0], "ZXY")
    C = me.ReferenceFrame("C")
    C.orient(B, "Space", [alpha[2], beta[2], 0], "ZXY")
    kinematic_differentials = []
    for i in range(n):
        kinematic_differentials.append(omega[i] - alpha[i].diff())
        kinematic_differentials.append(delta[i] - beta[i].diff())
    A.set_ang_vel(I, omega[0] * I.z + delta[0] * I.x)
    B.set_ang_vel(I, omega[1] * I.z + delta[1] * I.x)
    C.set_ang_vel(I, omega[2] * I.z + delta[2] * I.x)
    O = me.Point("O")
    O.set_vel(I, 0)
    P1 = O.locatenew("P1", -l[0] * A.y)
    P2 = P1.locatenew("P2", -l[1] * B.y)
    P3 = P2.locatenew("P3", -l[2] * C.y)
    P1.v2pt_theory(O, I, A)
    P2.v2pt_theory(P1, I, B)
    P3.v2pt_theory(P2, I, C)
    particles = [
        me.Particle("Pa1", P1, m_bob[0]),
        me.Particle("Pa2", P2, m_bob[1]),
        me.Particle("Pa3", P3, m_bob[2]),
    ]
    P_link1 = O.locatenew("P_link1", -l[0] / 2 * A.y)
    P_link2 = P1.locatenew("P_link2", -l[1] / 2 * B.y)
    P_link3 = P2.locatenew("P_link3", -l[2] / 2 * C.y)
    P_link1.v2pt_theory(O, I, A)
    P_link2.v2pt_theory(P1, I, B)
    P_link3.v2pt_theory(P2, I, C)
    links = [
        me.RigidBody(
            "link1", P_link1, A, m_link[0], (me.inertia(A, Ixx[0], Iyy[0], Izz[0]), P_link1)
        ),
        me.RigidBody(
            "link2", P_link2, B, m_link[1], (me.inertia(B, Ixx[1], Iyy[1], Izz[1]), P_link2)
        ),
        me.RigidBody(
            "link3", P_link3, C, m_link[2], (me.inertia(C, Ixx[2], Iyy[2], Izz[2]), P_link3)
        ),
    ]
    forces = [(p.point, -p.mass * g * I.y) for p in particles]
    forces += [(link.masscenter, -link.mass * g * I.y) for link in links]
    kane = me.KanesMethod(
        I, q_ind=alpha + beta, u_ind=omega + delta, kd_eqs=kinematic_differentials
    )
    kane.kanes_equations(links + particles, loads=forces)
    return kane


def pydy_astrobee():
    # pydy-0.9.4 docs/examples/astrobee.rst (a free rigid body, Euler angles, force and
    # torque inputs)
    ISS = me.ReferenceFrame("N")
    B = me.ReferenceFrame("B")
    q1, q2, q3 = me.dynamicsymbols("q1:4")
    B.orient(ISS, "Body", (q1, q2, q3), "xyz")
    O = me.Point("O")
    O.set_vel(ISS, 0)
    x, y, z = me.dynamicsymbols("x, y, z")
    C = O.locatenew("C", x * ISS.x + y * ISS.y + z * ISS.z)
    ux = me.dynamicsymbols("u_x")
    uy = me.dynamicsymbols("u_y")
    uz = me.dynamicsymbols("u_z")
    u1 = me.dynamicsymbols("u_1")
    u2 = me.dynamicsymbols("u_2")
    u3 = me.dynamicsymbols("u_3")
    z1 = sm.Eq(ux, x.diff())
    z2 = sm.Eq(uy, y.diff())
    z3 = sm.Eq(uz, z.diff())
    z4 = sm.Eq(u1, q1.diff())
    z5 = sm.Eq(u2, q2.diff())
    z6 = sm.Eq(u3, q3.diff())
    u = sm.solve(
        [z1, z2, z3, z4, z5, z6], x.diff(), y.diff(), z.diff(), q1.diff(), q2.diff(), q3.diff()
    )
    C.set_vel(ISS, C.pos_from(O).dt(ISS).subs(u))
    B.set_ang_vel(ISS, B.ang_vel_in(ISS).subs(u))
    m = sm.symbols("m")
    Ix, Iy, Iz = sm.symbols("I_x, I_y, I_z")
    I = me.inertia(B, Ix, Iy, Iz)
    Fx_mag, Fy_mag, Fz_mag = me.dynamicsymbols("Fmag_x, Fmag_y, Fmag_z")
    T1_mag, T2_mag, T3_mag = me.dynamicsymbols("Tmag_1, Tmag_2, Tmag_3")
    kdes = [
        z1.rhs - z1.lhs,
        z2.rhs - z2.lhs,
        z3.rhs - z3.lhs,
        z4.rhs - z4.lhs,
        z5.rhs - z5.lhs,
        z6.rhs - z6.lhs,
    ]
    body = me.RigidBody("body", C, B, m, (I, C))
    loads = [
        (C, Fx_mag * ISS.x),
        (C, Fy_mag * ISS.y),
        (C, Fz_mag * ISS.z),
        (B, T1_mag * B.x),
        (B, T2_mag * B.y),
        (B, T3_mag * B.z),
    ]
    kane = me.KanesMethod(ISS, (x, y, z, q1, q2, q3), (ux, uy, uz, u1, u2, u3), kd_eqs=kdes)
    kane.kanes_equations([body], loads=loads)
    return kane


def pydy_n_body_pendulum(n: int = 2):
    # pydy-0.9.4 docs/examples/3d-n-body-pendulum.rst (n = 2, the smallest it allows; the
    # balls' contact force switched by Heaviside: not smooth)
    m, m1, g, r, l, reibung, k, t = sm.symbols("m, m1, g, r, l, reibung, k, t")
    iXX, iYY, iZZ = sm.symbols("iXX, iYY, iZZ")
    q, u, A, Dmc, P, punkt = [], [], [], [], [], []
    for i in range(n):
        for j in ("x", "y", "z"):
            q.append(me.dynamicsymbols("q" + j + str(i)))
            u.append(me.dynamicsymbols("u" + j + str(i)))
        A.append(me.ReferenceFrame("A" + str(i)))
        Dmc.append(me.Point("Dmc" + str(i)))
        P.append(me.Point("P" + str(i)))
        punkt.append(me.Point("punkt" + str(i)))
    N = me.ReferenceFrame("N")
    P0 = me.Point("P0")
    rot, rot1 = [], []
    A[0].orient_body_fixed(N, (q[0], q[1], q[2]), "123")
    rot.append(A[0].ang_vel_in(N))
    A[0].set_ang_vel(N, u[0] * A[0].x + u[1] * A[0].y + u[2] * A[0].z)
    rot1.append(A[0].ang_vel_in(N))
    for i in range(1, n):
        A[i].orient_body_fixed(A[i - 1], (q[3 * i], q[3 * i + 1], q[3 * i + 2]), "123")
        rot.append(A[i].ang_vel_in(N))
        A[i].set_ang_vel(N, u[3 * i] * A[i].x + u[3 * i + 1] * A[i].y + u[3 * i + 2] * A[i].z)
        rot1.append(A[i].ang_vel_in(N))
    P[0].set_pos(P0, 0.0)
    P[0].set_vel(N, 0.0)
    Dmc[0].set_pos(P[0], l / 2.0 * A[0].y)
    Dmc[0].v2pt_theory(P[0], N, A[0])
    punkt[0].set_pos(Dmc[0], r * A[0].z)
    punkt[0].v2pt_theory(Dmc[0], N, A[0])
    for i in range(1, n):
        P[i].set_pos(P[i - 1], l * A[i - 1].y)
        P[i].v2pt_theory(P[i - 1], N, A[i - 1])
        Dmc[i].set_pos(P[i], l / sm.S(2.0) * A[i].y)
        Dmc[i].v2pt_theory(P[i], N, A[i])
        punkt[i].set_pos(Dmc[i], r * A[i].z)
        punkt[i].v2pt_theory(Dmc[i], N, A[i])
    BODY = []
    for i in range(n):
        inertia = me.inertia(A[i], iXX, iYY, iZZ)
        BODY.append(me.RigidBody("body" + str(i), Dmc[i], A[i], m, (inertia, Dmc[i])))
        BODY.append(me.Particle("punct" + str(i), punkt[i], m1))
    FG = [(Dmc[i], -m * g * N.y) for i in range(n)] + [(punkt[i], -m1 * g * N.y) for i in range(n)]
    FB = []
    for i in range(n):
        for j in range(i + 1, n):
            aa = Dmc[j].pos_from(Dmc[i])
            bb = aa.magnitude()
            aa = aa.normalize()
            FB.append((Dmc[j], k * (2 * r - bb) * aa * sm.Heaviside(2.0 * r - bb)))
            FB.append((Dmc[i], -k * (2 * r - bb) * aa * sm.Heaviside(2.0 * r - bb)))
    kd = []
    for i in range(n):
        for uv in A[i]:
            kd.append(me.dot(rot[i] - rot1[i], uv))
    KM = me.KanesMethod(N, q_ind=q, u_ind=u, kd_eqs=kd)
    KM.kanes_equations(BODY, FG + FB)
    return KM


class _IndexedFrame(me.ReferenceFrame):
    """PyDy's Carvallo-Whipple example's ReferenceFrame: unit vectors indexed 1, 2, 3."""

    def __init__(self, *args, **kwargs):
        kwargs.pop("indices", None)
        kwargs.pop("latexs", None)
        lab = args[0].lower()
        tex = r"\hat{{{}}}_{}"
        super().__init__(
            *args,
            indices=("1", "2", "3"),
            latexs=(tex.format(lab, "1"), tex.format(lab, "2"), tex.format(lab, "3")),
            **kwargs,
        )


def pydy_carvallo_whipple():
    # pydy-0.9.4 docs/examples/carvallo-whipple.rst (the Carvallo-Whipple bicycle in
    # Moore's parametrization: a configuration constraint, five velocity constraints,
    # acceleration constraints given by hand with Baumgarte's alpha, input torques)
    import sympy.physics.mechanics as mec

    ReferenceFrame = _IndexedFrame
    N = ReferenceFrame("N")
    A = ReferenceFrame("A")
    B = ReferenceFrame("B")
    C = ReferenceFrame("C")
    D = ReferenceFrame("D")
    E = ReferenceFrame("E")
    F = ReferenceFrame("F")
    q1, q2, q3, q4 = mec.dynamicsymbols("q1 q2 q3 q4")
    q5, q6, q7, q8 = mec.dynamicsymbols("q5 q6 q7 q8")
    u1, u2, u3, u4 = mec.dynamicsymbols("u1 u2 u3 u4")
    u5, u6, u7, u8 = mec.dynamicsymbols("u5 u6 u7 u8")
    # rear frame yaw
    A.orient(N, "Axis", (q3, N["3"]))
    # rear frame roll
    B.orient(A, "Axis", (q4, A["1"]))
    # rear frame pitch
    C.orient(B, "Axis", (q5, B["2"]))
    # front frame steer
    E.orient(C, "Axis", (q7, C["3"]))
    # geometry
    rf, rr = sm.symbols("rf rr")
    d1, d2, d3 = sm.symbols("d1 d2 d3")
    l1, l2, l3, l4 = sm.symbols("l1 l2 l3 l4")
    # acceleration due to gravity
    g = sm.symbols("g")
    # mass
    mc, md, me, mf = sm.symbols("mc md me mf")
    # inertia
    ic11, ic22, ic33, ic31 = sm.symbols("ic11 ic22 ic33 ic31")
    id11, id22 = sm.symbols("id11 id22")
    ie11, ie22, ie33, ie31 = sm.symbols("ie11 ie22 ie33 ie31")
    if11, if22 = sm.symbols("if11 if22")
    T4, T6, T7 = mec.dynamicsymbols("T4 T6 T7")
    # inertial origin
    o = mec.Point("o")
    # rear wheel contact point
    dn = mec.Point("dn")
    dn.set_pos(o, q1 * N["1"] + q2 * N["2"])
    # rear wheel contact point to rear wheel center
    do = mec.Point("do")
    do.set_pos(dn, -rr * B["3"])
    # rear wheel center to bicycle frame center
    co = mec.Point("co")
    co.set_pos(do, l1 * C["1"] + l2 * C["3"])
    # rear wheel center to steer axis point
    ce = mec.Point("ce")
    ce.set_pos(do, d1 * C["1"])
    # steer axis point to the front wheel center
    fo = mec.Point("fo")
    fo.set_pos(ce, d2 * E["3"] + d3 * E["1"])
    # front wheel center to front frame center
    eo = mec.Point("eo")
    eo.set_pos(fo, l3 * E["1"] + l4 * E["3"])
    # locate the point fixed on the wheel which instantaneously touches the
    # ground
    fn = mec.Point("fn")
    fn.set_pos(fo, rf * E["2"].cross(A["3"]).cross(E["2"]).normalize())
    holonomic = fn.pos_from(dn).dot(A["3"])
    t = mec.dynamicsymbols._t
    kinematical = [
        q1.diff(t) - u1,  # x
        q2.diff(t) - u2,  # y
        q3.diff(t) - u3,  # yaw
        q4.diff(t) - u4,  # roll
        q5.diff(t) - u5,  # pitch
        q7.diff(t) - u7,
    ]  # steer
    A.set_ang_vel(N, u3 * N["3"])  # yaw rate
    B.set_ang_vel(A, u4 * A["1"])  # roll rate
    C.set_ang_vel(B, u5 * B["2"])  # pitch rate
    D.set_ang_vel(C, u6 * C["2"])  # rear wheel rate
    E.set_ang_vel(C, u7 * C["3"])  # steer rate
    F.set_ang_vel(E, u8 * E["2"])  # front wheel rate
    # origin is fixed in N
    o.set_vel(N, 0 * N["1"])
    # rear wheel contact stays in ground plane
    dn.set_vel(N, u1 * N["1"] + u2 * N["2"])
    # mass centers
    do.v2pt_theory(dn, N, D)
    co.v2pt_theory(do, N, C)
    ce.v2pt_theory(do, N, C)
    fo.v2pt_theory(ce, N, E)
    eo.v2pt_theory(fo, N, E)
    # wheel contact velocities
    fn.v2pt_theory(fo, N, F)  # supress output
    nonholonomic = [
        dn.vel(N).dot(A["1"]),
        dn.vel(N).dot(A["2"]),
        fn.vel(N).dot(A["1"]),
        fn.vel(N).dot(A["2"]),
        fn.vel(N).dot(A["3"]),
    ]
    Ic = mec.inertia(C, ic11, ic22, ic33, 0, 0, ic31)
    Id = mec.inertia(C, id11, id22, id11, 0, 0, 0)
    Ie = mec.inertia(E, ie11, ie22, ie33, 0, 0, ie31)
    If = mec.inertia(E, if11, if22, if11, 0, 0, 0)
    rear_frame = mec.RigidBody("Rear Frame", co, C, mc, (Ic, co))
    rear_wheel = mec.RigidBody("Rear Wheel", do, D, md, (Id, do))
    front_frame = mec.RigidBody("Front Frame", eo, E, me, (Ie, eo))
    front_wheel = mec.RigidBody("Front Wheel", fo, F, mf, (If, fo))
    bodies = [rear_frame, rear_wheel, front_frame, front_wheel]
    # gravity
    Fco = (co, mc * g * A["3"])
    Fdo = (do, md * g * A["3"])
    Feo = (eo, me * g * A["3"])
    Ffo = (fo, mf * g * A["3"])
    # input torques
    Tc = (C, T4 * A["1"] - T6 * B["2"] - T7 * C["3"])
    Td = (D, T6 * C["2"])
    Te = (E, T7 * C["3"])
    loads = [Fco, Fdo, Feo, Ffo, Tc, Td, Te]
    acc_constraints = [c.diff(t) for c in nonholonomic]
    alpha = sm.symbols("alpha")
    acc_constraints[-1] += 2 * alpha * nonholonomic[-1] + alpha**2 * holonomic
    kane = mec.KanesMethod(
        N,
        [q1, q2, q3, q4, q7],  # x, y, yaw, roll, steer
        [u4, u6, u7],  # roll rate, rear wheel rate, steer rate
        kd_eqs=kinematical,
        q_dependent=[q5],  # pitch angle
        configuration_constraints=[holonomic],
        u_dependent=[u1, u2, u3, u5, u8],  # x', y', yaw rate, pitch rate, front wheel rate
        velocity_constraints=nonholonomic,
        acceleration_constraints=acc_constraints,
        constraint_solver="CRAMER",
    )
    fr, frstar = kane.kanes_equations(bodies, loads)
    return kane


PYDY: list[Entry] = [
    Entry(
        "PyDy mass-spring-damper",
        "pydy-0.9.4 docs/examples/mass-spring-damper.rst",
        pydy_mass_spring_damper,
    ),
    Entry(
        "PyDy chaos pendulum", "pydy-0.9.4 docs/examples/chaos-pendulum.rst", pydy_chaos_pendulum
    ),
    Entry(
        "PyDy multidof holonomic",
        "pydy-0.9.4 docs/examples/multidof-holonomic.rst",
        pydy_multidof_holonomic,
        c=True,
    ),
    Entry(
        "PyDy three-link conical pendulum",
        "pydy-0.9.4 docs/examples/three-link-conical-pendulum.rst",
        pydy_three_link_conical_pendulum,
        slow=True,
    ),
    Entry(
        "PyDy Carvallo-Whipple bicycle",
        "pydy-0.9.4 docs/examples/carvallo-whipple.rst",
        pydy_carvallo_whipple,
        slow=True,
        # alpha = 0: the model's acceleration constraints are then the derivative of its
        # velocity constraints (with alpha they add alpha**2 times the configuration
        # constraint, not zero at the random states, which do not satisfy it)
        values=(("alpha", 0.0),),
    ),
    Entry("PyDy astrobee", "pydy-0.9.4 docs/examples/astrobee.rst", pydy_astrobee),
    Entry(
        "PyDy 3d n-body pendulum (n = 2)",
        "pydy-0.9.4 docs/examples/3d-n-body-pendulum.rst",
        pydy_n_body_pendulum,
        slow=True,
        refused=r"the load on Dmc1 contains the non-smooth functions \['Heaviside'\]",
    ),
]
