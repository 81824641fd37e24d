"""Walking models: the rimless wheel, the compass gait and the simplest walker.

All on a slope of angle ``gamma``, in the slope's frame: ``X`` downhill along the slope,
``Y`` normal to it, gravity ``g (sin gamma, -cos gamma)``, so a mass m at (X, Y) has
``V = m g (Y cos gamma - X sin gamma)``.  A leg at angle ``theta`` from the slope's
normal has its foot at ``hip + l (sin theta, -cos theta)``; with the stance foot pinned
at the origin the hip is at ``l (-sin theta, cos theta)`` (theta decreases as the walker
goes downhill).

Each model is declared as a mechanism with its feet free (the *impact scene*, where the
heel strike is the closed-form impact of the swing foot's wall with restitution 0 and its
tangential velocity held: Carnot paper eqs. 10 and 17) and a stance mode derived from it
by pinning the stance foot (:func:`~symmech.gait.modes.pinned_scene`); the reset is the
impact followed by the leg swap (:func:`~symmech.gait.modes.impact_reset`).  Heel strike
is the zero of the swing foot's height whose factor ``theta_stance + theta_swing``
vanishes (the other factor vanishes at mid-stance, where the foot scuffs: ignored, as in
the papers).

* :func:`rimless_wheel`: McGeer, "Passive dynamic walking", IJRR 9 (1990); a hub of mass m
  and inertia ``m r^2`` on massless spokes of length l, ``2 alpha`` apart.
* :func:`compass_gait`: Goswami, Thuilot and Espiau, INRIA RR-2996 (1996); legs of mass m
  at a from the foot and b from the hip, hip mass mH.
* :func:`simplest_walker`: Garcia, Chatterjee, Ruina and Coleman, J. Biomech. Eng. 120
  (1998); hip mass M = 1, feet of mass beta (the model is the limit beta -> 0), l = g = 1;
  :func:`simplest_walker_limit` is that limit, declared exactly.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import sympy as sp

from symmech.declaration.symbols import coordinates, velocities
from symmech.declaration.wall import Wall
from symmech.gait.limits import limit_gait
from symmech.gait.modes import Gait, Reset, Transition, impact_reset, pinned_scene
from symmech.scene import Scene

__all__ = [
    "GAITS",
    "GaitCase",
    "compass_gait",
    "hopper",
    "rimless_wheel",
    "simplest_walker",
    "simplest_walker_limit",
]


def _leg(theta: sp.Expr, length: sp.Expr) -> sp.Matrix:
    """From the hip to a point at ``length`` along a leg at angle ``theta``."""
    return sp.Matrix([length * sp.sin(theta), -length * sp.cos(theta)])


def _point_energy(m: sp.Expr, r: sp.Matrix, q: list, qd: list, g, gamma) -> tuple:
    v = r.jacobian(q) * sp.Matrix(qd)
    T = m * (v.T * v)[0, 0] / 2
    V = m * g * (r[1] * sp.cos(gamma) - r[0] * sp.sin(gamma))
    return T, V


def _foot_wall(foot: sp.Matrix, q: list, qd: list) -> Wall:
    """The swing foot's wall: its height, plastic, its tangential velocity held."""
    vx = (foot.jacobian(q) * sp.Matrix(qd))[0]
    return Wall(foot[1], restitution=0, impulsive_constraints=[vx], name="heel")


def rimless_wheel() -> Gait:
    """McGeer's rimless wheel: stance angle ``theta`` from ``alpha`` to ``-alpha``, heel
    strike of the next spoke at ``theta = -alpha``, then ``theta+ = theta + 2 alpha``.
    The return map of ``theta_dot`` just after impact is ``w -> eta sqrt(w^2 + K)`` with
    ``eta = (r^2 + l^2 cos 2 alpha)/(r^2 + l^2)`` (angular momentum about the new foot)
    and ``K = 4 g l sin(alpha) sin(gamma)/(r^2 + l^2)``: fixed point
    ``w*^2 = eta^2 K / (1 - eta^2)``, multiplier ``eta^2`` (McGeer 1990, section 2)."""
    x, y, th = coordinates("x y theta")
    xd, yd, thd = velocities((x, y, th))
    m, r, l, g, alpha, gamma = sp.symbols("m r l g alpha gamma", positive=True)
    Q, Qd = [x, y, th], [xd, yd, thd]
    hub = sp.Matrix([x, y])
    T, V = _point_energy(m, hub, Q, Qd, g, gamma)
    T += m * r**2 * thd**2 / 2
    next_foot = hub + _leg(th + 2 * alpha, l)
    wheel = Scene(
        Q,
        kinetic_energy=T,
        potential=V,
        walls=[_foot_wall(next_foot, Q, Qd)],
        parameters=[m, r, l, g, alpha, gamma],
        name="rimless_wheel_free",
    )
    (s,) = coordinates("theta")
    pin = {x: -l * sp.sin(s), y: l * sp.cos(s), th: s}
    stance = pinned_scene(wheel, pin, [s], name="rimless_wheel")
    reset = impact_reset(stance, wheel, "heel", pin, [th + 2 * alpha])
    return Gait(
        "rimless_wheel", {"stance": stance}, (Transition("stance", "stance", "heel", reset),)
    )


def _two_legs(name: str, hip_mass, leg_mass, b, l, g, gamma):
    """The impact scene of a two-legged walker: hip (x, y), leg angles (theta1 stance,
    theta2 swing), point masses at ``b`` from the hip on each leg."""
    x, y, t1, t2 = coordinates("x y theta1 theta2")
    Q = [x, y, t1, t2]
    Qd = list(velocities(tuple(Q)))
    hip = sp.Matrix([x, y])
    T, V = _point_energy(hip_mass, hip, Q, Qd, g, gamma)
    for leg in (t1, t2):
        Ti, Vi = _point_energy(leg_mass, hip + _leg(leg, b), Q, Qd, g, gamma)
        T, V = T + Ti, V + Vi
    scene = Scene(
        Q,
        kinetic_energy=T,
        potential=V,
        walls=[_foot_wall(hip + _leg(t2, l), Q, Qd)],
        name=f"{name}_free",
    )
    return scene, (x, y, t1, t2)


def _walker(name: str, free: Scene, Q, l) -> Gait:
    x, y, t1, t2 = Q
    s1, s2 = coordinates("theta1 theta2")
    pin = {x: -l * sp.sin(s1), y: l * sp.cos(s1), t1: s1, t2: s2}
    stance = pinned_scene(free, pin, [s1, s2], name=name)
    stance = stance.replace(walls=[Wall(s1 + s2, name="strike")])
    reset = impact_reset(stance, free, "heel", pin, [t2, t1])
    # heel strike counts with the hip ahead of the stance foot (theta1 < 0): not at the
    # start of a step, where theta1 + theta2 = 0 too, nor for a state moved off it
    tr = Transition("stance", "stance", "strike", reset, condition=-s1)
    return Gait(name, {"stance": stance}, (tr,))


def compass_gait() -> Gait:
    """Goswami, Thuilot and Espiau's compass gait: legs of length ``l = a + b`` with a
    point mass m at ``a`` from the foot, hip mass ``mH``; angles ``theta1`` (stance) and
    ``theta2`` (swing) from the slope's normal; heel strike at ``theta1 + theta2 = 0``
    with the hip ahead of the stance foot, then the legs swap."""
    m, mH, a, b, g, gamma = sp.symbols("m mH a b g gamma", positive=True)
    free, Q = _two_legs("compass_gait", mH, m, b, a + b, g, gamma)
    return _walker("compass_gait", free, Q, a + b)


def simplest_walker() -> Gait:
    """Garcia et al.'s simplest walker with feet of mass ``beta`` (hip mass 1, l = g = 1):
    a compass gait with its leg masses at the feet.  ``theta1`` is Garcia's theta and
    ``theta1 - theta2`` his phi."""
    beta, gamma = sp.symbols("beta gamma", positive=True)
    one = sp.Integer(1)
    free, Q = _two_legs("simplest_walker", one, beta, one, one, one, gamma)
    return _walker("simplest_walker", free, Q, one)


def simplest_walker_limit() -> Gait:
    """The simplest walker at ``beta -> 0``, declared exactly.

    As ``beta -> 0`` the swing leg's equation is divided by beta and the stance leg's
    loses the feet; the limit system is not the Euler-Lagrange system of any metric (the
    swing leg is driven by the stance leg, not the converse).  It is declared as a mode
    with unit metric and the limit field as its forces: ``q_ddot = lim_{beta->0}
    g_beta^-1 f_beta`` taken symbolically from :func:`simplest_walker`'s stance mode,
    and the reset as the limit of its closed-form heel strike.  (Garcia et al., eqs. 3-5,
    in their variables theta = theta1, phi = theta1 - theta2: ``theta'' = sin(theta -
    gamma)``, ``phi'' = theta'' + theta'^2 sin phi - cos(theta - gamma) sin phi``; heel
    strike ``theta+ = -theta-``, ``theta'+ = cos(2 theta-) theta'-``.)  The limit is
    :func:`symmech.gait.limits.limit_gait` of :func:`simplest_walker`."""
    return limit_gait(simplest_walker(), "beta", 0, name="simplest_walker_limit")


def hopper() -> Gait:
    """A vertical hopper with flight and stance modes: a body of mass ``m`` on a leg
    spring (stiffness ``k``, rest length ``l``) to a foot of mass ``mf``.  Flight: body and
    foot free, ``y`` and ``yf``.  Touchdown: the foot's wall ``yf >= 0``, a plastic impact
    (the foot stops; the body's velocity is unchanged, the metric being diagonal), then the
    stance mode in ``y`` alone, where an actuator in the leg pumps energy in with the
    force ``pump y' - sat y'^3`` (a van der Pol oscillator's: energy in at low speed, out
    at high speed, so the hop height settles).  Liftoff: the ground's force on the foot,
    ``mf g - k (y - l) + pump y' - sat y'^3``, reaches 0; the foot leaves at rest (a
    coordinate map, no impact).  The hopping gait is the fixed point of the map from one
    liftoff to the next (touchdown, stance, liftoff)."""
    y, yf = coordinates("y yf")
    m, mf, k, l, pump, sat, g = sp.symbols("m mf k l pump sat g", positive=True)
    flight = Scene(
        [y, yf],
        metric=sp.diag(m, mf),
        potential=m * g * y + mf * g * yf + k * (y - yf - l) ** 2 / 2,
        walls=[Wall(yf, restitution=0, name="touchdown")],
        name="hopper_flight",
    )
    (ys,) = coordinates("y")
    (ysd,) = velocities((ys,))
    stance = Scene(
        [ys],
        metric=sp.Matrix([[m]]),
        potential=m * g * ys + k * (ys - l) ** 2 / 2,
        forces=[pump * ysd - sat * ysd**3],
        walls=[Wall(mf * g - k * (ys - l), name="liftoff")],
        name="hopper_stance",
    )
    touchdown = impact_reset(flight, flight, "touchdown", {y: y, yf: yf}, [y])
    liftoff = Reset(
        position=sp.ImmutableMatrix([ys, 0]),
        velocity=sp.ImmutableMatrix([ysd, 0]),
    )
    return Gait(
        "hopper",
        {"flight": flight, "stance": stance},
        (
            Transition("flight", "stance", "touchdown", touchdown, name="touchdown"),
            Transition("stance", "flight", "liftoff", liftoff, name="liftoff"),
        ),
    )


@dataclass(frozen=True)
class GaitCase:
    """A built-in gait: its builder, default parameters, a start for Newton (the state
    just after the section transition, near the published gait), and the parameter a
    continuation follows by default."""

    name: str
    build: Callable[[], Gait]
    parameters: Mapping[str, float]
    guess: tuple[float, ...]
    description: str
    continue_in: str = "gamma"
    section: int = 0


def _simplest_guess(theta: float = 0.2, theta_dot: float = -0.2) -> tuple[float, ...]:
    """Just after heel strike from Garcia's (theta, theta'): theta2 = -theta1 and
    theta2' = theta' - phi' with phi' = cos(2 theta)(1 - cos(2 theta)) theta'-."""
    c = math.cos(2 * theta)
    phi_dot = c * (1 - c) * theta_dot / c
    return (theta, -theta, theta_dot, theta_dot - phi_dot)


GAITS: dict[str, GaitCase] = {
    case.name: case
    for case in (
        GaitCase(
            "rimless_wheel",
            rimless_wheel,
            {"m": 1.0, "r": 0.3, "l": 1.0, "g": 9.81, "alpha": math.pi / 10, "gamma": 0.1},
            (math.pi / 10, -1.5),
            "McGeer's rimless wheel (closed-form fixed point and multiplier)",
        ),
        GaitCase(
            "simplest_walker",
            simplest_walker_limit,
            {"gamma": 0.009},
            _simplest_guess(),
            "Garcia et al.'s simplest walker (feet of vanishing mass, declared exactly)",
        ),
        GaitCase(
            "simplest_walker_feet",
            simplest_walker,
            {"beta": 1e-3, "gamma": 0.009},
            _simplest_guess(),
            "the simplest walker with feet of mass beta (hip mass 1)",
        ),
        GaitCase(
            "compass_gait",
            compass_gait,
            {"m": 5.0, "mH": 10.0, "a": 0.5, "b": 0.5, "g": 9.81, "gamma": 3 * math.pi / 180},
            (0.27, -0.27, -1.09, -0.38),
            "Goswami, Thuilot and Espiau's compass gait (stable gait at 3 degrees)",
        ),
        GaitCase(
            "hopper",
            hopper,
            {"m": 1.0, "mf": 0.1, "k": 200.0, "l": 1.0, "pump": 4.0, "sat": 1.0, "g": 9.81},
            (1.004905, 0.0, 1.9, 0.0),
            "a vertical hopper: flight (body and foot) and stance (body) modes",
            continue_in="pump",
            section=1,
        ),
    )
}
