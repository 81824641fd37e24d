"""Gaits: modes, resets, the stride map, its fixed points and multipliers.

Independent routes: the rimless wheel's closed-form fixed point and multiplier (McGeer
1990, derived in :func:`symmech.gait.models.rimless_wheel`'s docstring by angular momentum
about the new foot and energy over one stance); Garcia et al.'s published equations of the
simplest walker and its published fixed point; central differences of the stride map
against the variational-saltation Jacobian.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

import symmech as sm
from symmech.errors import SceneError
from symmech.gait import (
    CompiledGait,
    Gait,
    GaitError,
    Reset,
    StrideOptions,
    Transition,
    impact_reset,
    stride,
)
from symmech.gait.models import compass_gait, rimless_wheel, simplest_walker_limit
from symmech.gait.periodic import difference_jacobian, fixed_point, multipliers

WHEEL = dict(m=1.0, r=0.3, l=1.0, g=9.81, alpha=math.pi / 10, gamma=0.1)


def wheel_closed_form(p: dict) -> tuple[float, float]:
    """McGeer's fixed point theta_dot* just after impact and the multiplier eta^2."""
    a, gm, r, l, g = p["alpha"], p["gamma"], p["r"], p["l"], p["g"]
    eta = (r * r + l * l * math.cos(2 * a)) / (r * r + l * l)
    K = 4 * g * l * math.sin(a) * math.sin(gm) / (r * r + l * l)
    return -math.sqrt(eta**2 * K / (1 - eta**2)), eta**2


@pytest.fixture(scope="module")
def wheel() -> Gait:
    return rimless_wheel()


@pytest.mark.parametrize("target", ["c", "numpy"])
def test_rimless_wheel_fixed_point_and_multiplier_equal_mcgeer(wheel, target):
    fns = CompiledGait(wheel, WHEEL, target=target)
    w, lam = wheel_closed_form(WHEEL)
    fp = fixed_point(fns, 0, [WHEEL["alpha"], 0.8 * w])
    assert fp.x[0] == pytest.approx(WHEEL["alpha"], abs=1e-14)
    assert abs(fp.x[1] - w) <= 1e-12 * abs(w)
    big, trivial = fp.multipliers
    assert abs(big - lam) <= 1e-12
    assert abs(trivial) <= 1e-12  # the state after impact has theta = alpha: rank 1
    # the monodromy matrix has the trivial multiplier 1 (the flow's direction) instead
    mono = sorted(abs(m) for m in multipliers(fp.stride.monodromy))
    assert mono == pytest.approx([lam, 1.0], abs=1e-11)
    assert fp.stable


def test_rimless_wheel_reset_is_angular_momentum_about_the_new_foot(wheel):
    """theta_dot+ = (r^2 + l^2 cos 2 alpha)/(r^2 + l^2) theta_dot- at theta- = -alpha."""
    tr = wheel.transitions[0]
    th = wheel.modes["stance"].coordinates[0]
    thd = wheel.modes["stance"].velocities[0]
    r, l, alpha = (next(p for p in wheel.parameters if p.name == s) for s in ("r", "l", "alpha"))
    at_strike = tr.reset.velocity[0].subs(th, -alpha)
    expected = (r**2 + l**2 * sp.cos(2 * alpha)) / (r**2 + l**2) * thd
    assert sp.simplify(at_strike - expected) == 0
    assert tr.reset.position[0].subs(th, -alpha) == alpha
    assert tr.reset.dissipative


def test_compass_gait_variational_jacobian_equals_central_differences():
    gait = compass_gait()
    p = dict(m=5.0, mH=10.0, a=0.5, b=0.5, g=9.81, gamma=3 * math.pi / 180)
    fns = CompiledGait(gait, p)
    fp = fixed_point(fns, 0, [0.27, -0.27, -1.1, -0.4])
    x = fp.x
    assert x[0] == pytest.approx(-x[1], abs=1e-12)  # just after heel strike
    # Goswami et al. (1996), the stable gait at 3 degrees, angles from the vertical
    # (theta_ns, theta_s, dtheta_ns, dtheta_s) = (-0.3234, 0.2187, -0.3772, -1.0918):
    # from the slope's normal, theta = theta_vertical + gamma
    gamma = p["gamma"]
    assert x[0] == pytest.approx(0.2187 + gamma, abs=2e-4)
    assert x[1] == pytest.approx(-0.3234 + gamma, abs=2e-4)
    assert x[2] == pytest.approx(-1.0918, abs=1e-3)
    assert x[3] == pytest.approx(-0.3772, abs=1e-3)
    fd = difference_jacobian(fns, 0, x, 1e-5)
    assert np.max(np.abs(fd - fp.DP)) <= 1e-7 * max(1.0, np.max(np.abs(fp.DP)))
    assert fp.stable


def test_stride_refuses_a_state_of_the_wrong_size(wheel):
    fns = CompiledGait(wheel, WHEEL, target="numpy")
    with pytest.raises(GaitError, match="2 entries"):
        stride(fns, 0, [0.1, 0.2, 0.3])


def test_no_strike_within_t_max_is_an_error_naming_the_mode(wheel):
    fns = CompiledGait(wheel, WHEEL, target="numpy")
    with pytest.raises(GaitError, match="mode 'stance': no transition fired within t_max"):
        stride(fns, 0, [WHEEL["alpha"], -1.5], options=StrideOptions(t_max=0.05))


def test_gait_declaration_errors_name_the_transition_and_the_reason(wheel):
    stance = wheel.modes["stance"]
    th = stance.coordinates[0]
    thd = stance.velocities[0]
    good = wheel.transitions[0].reset
    with pytest.raises(SceneError, match="not a wall of mode"):
        Gait("g", {"stance": stance}, (Transition("stance", "stance", "floor", good),))
    short = Reset(position=sp.ImmutableMatrix([th, th]), velocity=sp.ImmutableMatrix([thd, thd]))
    with pytest.raises(SceneError, match="the reset gives 2 coordinates"):
        Gait("g", {"stance": stance}, (Transition("stance", "stance", "heel", short),))
    with pytest.raises(SceneError, match="the condition depends on velocities"):
        Gait("g", {"stance": stance}, (Transition("stance", "stance", "heel", good, thd),))
    with pytest.raises(SceneError, match="must both be declared"):
        Gait("g", {"stance": stance}, (Transition("stance", "flight", "heel", good),))
    with pytest.raises(SceneError, match="no transition out of it"):
        Gait(
            "g", {"stance": stance, "other": stance}, (Transition("stance", "other", "heel", good),)
        )
    fns_params = dict(WHEEL)
    fns_params.pop("gamma")
    with pytest.raises(SceneError, match="missing \\['gamma'\\]"):
        CompiledGait(wheel, fns_params, target="numpy")
    with pytest.raises(SceneError, match="not finite"):
        CompiledGait(wheel, {**WHEEL, "g": float("nan")}, target="numpy")


def test_an_impact_that_gains_energy_is_refused():
    """Carnot paper 002, Theorem 3.9's counterexample (ImpactMap.energy_change): g = I,
    psi = q4 - q3 + 1, impulsive constraint q4dot = 0, alpha = 1: T can grow."""
    q = sm.coordinates("q1 q2 q3 q4 q5")
    qd = sm.velocities(q)
    wall = sm.Wall(q[3] - q[2] + 1, restitution=1, impulsive_constraints=[qd[3]], name="w")
    scene = sm.Scene(q, metric=sp.eye(5), walls=[wall], name="gainer")
    with pytest.raises(SceneError, match="gains energy"):
        impact_reset(scene, scene, "w", {s: s for s in q}, list(q))


@pytest.fixture(scope="module")
def walker() -> Gait:
    return simplest_walker_limit()


def test_simplest_walker_limit_is_garcias_model(walker):
    """Garcia et al. (1998), eqs. 3-5 with theta = theta1 and phi = theta1 - theta2:
    theta'' = sin(theta - gamma), phi'' = theta'' + theta'^2 sin(phi) - cos(theta -
    gamma) sin(phi); heel strike theta+ = -theta-, phi+ = -2 theta-, theta'+ =
    cos(2 theta-) theta'-, phi'+ = cos(2 theta-)(1 - cos(2 theta-)) theta'-."""
    mode = walker.modes["stance"]
    t1, t2 = mode.coordinates
    d1 = mode.velocities[0]
    (gamma,) = [p for p in walker.parameters if p.name == "gamma"]
    acc = sp.Matrix(mode.acceleration())
    theta, phi, theta_d = t1, t1 - t2, d1
    theta_dd = sp.sin(theta - gamma)
    phi_dd = theta_dd + theta_d**2 * sp.sin(phi) - sp.cos(theta - gamma) * sp.sin(phi)
    assert sp.simplify(acc[0] - theta_dd) == 0
    assert sp.simplify((acc[0] - acc[1]) - phi_dd) == 0
    reset = walker.transitions[0].reset
    at_strike = {t2: -t1}  # phi = 2 theta
    q_plus = reset.position.subs(at_strike)
    v_plus = reset.velocity.subs(at_strike)
    c = sp.cos(2 * t1)
    assert sp.simplify(q_plus[0] - (-t1)) == 0  # theta+ = -theta-
    assert sp.simplify((q_plus[0] - q_plus[1]) - (-2 * t1)) == 0  # phi+ = -2 theta-
    assert sp.simplify(v_plus[0] - c * d1) == 0
    assert sp.simplify((v_plus[0] - v_plus[1]) - c * (1 - c) * d1) == 0


def test_simplest_walker_fixed_point_equals_garcias_published_gait(walker):
    """gamma = 0.009, long-period gait: theta* = 0.20031090049483, theta'* =
    -0.19983247291764 (Garcia et al. 1998, given to 1e-10)."""
    from symmech.gait.models import GAITS

    fns = CompiledGait(walker, {"gamma": 0.009})
    fp = fixed_point(fns, 0, GAITS["simplest_walker"].guess)
    assert abs(fp.x[0] - 0.20031090049483) <= 1e-10
    assert abs(fp.x[2] - -0.19983247291764) <= 1e-10
    big = fp.multipliers[:2]
    assert all(abs(m) < 1 for m in big) and abs(big[0].imag) > 0.5
    # central differences in float64 agree with the variational-saltation route to the
    # accuracy differences can have (h = 1e-6: about 1e-9 of error from O(h^2) and rounding)
    fd = difference_jacobian(fns, 0, fp.x, 1e-6)
    assert np.max(np.abs(fd - fp.DP)) <= 1e-7


def test_hopper_two_modes_of_different_sizes():
    """Flight (body and foot, 4 states) and stance (body, 2 states): the stride from one
    liftoff to the next crosses both transitions; its Jacobian (4 x 4, through a 2-state
    mode) equals central differences, and the plastic touchdown leaves the body's
    velocity unchanged (the metric is diagonal)."""
    from symmech.gait.models import GAITS

    case = GAITS["hopper"]
    gait = case.build()
    touchdown = gait.transition("touchdown").reset
    y = gait.modes["flight"].coordinates[0]
    yd = gait.modes["flight"].velocities[0]
    assert touchdown.position == sp.ImmutableMatrix([y])
    assert sp.simplify(touchdown.velocity[0] - yd) == 0
    fns = CompiledGait(gait, case.parameters)
    fp = fixed_point(fns, case.section, case.guess)
    assert [k for k, _, _ in fp.stride.events] == [0, 1]
    assert fp.x[1] == 0 and fp.x[3] == 0  # the foot leaves the ground at rest
    assert fp.DP.shape == (4, 4)
    fd = difference_jacobian(fns, case.section, fp.x, 1e-6)
    assert np.max(np.abs(fd - fp.DP)) <= 1e-7 * max(1.0, np.max(np.abs(fp.DP)))
    big = fp.multipliers[0]
    assert abs(big) < 1 and abs(big.imag) < 1e-12
    assert all(abs(m) <= 1e-10 for m in fp.multipliers[1:])


def test_feet_of_vanishing_mass_converge_to_the_exact_limit(walker):
    """The simplest walker with feet of mass beta (an Euler-Lagrange mode, a closed-form
    heel strike) tends to the limit declared exactly, linearly in beta: its fixed point
    extrapolated from beta = 1e-4 and 1e-5 to 0 meets the limit's to 1e-9."""
    from symmech.gait.models import GAITS

    limit = fixed_point(CompiledGait(walker, {"gamma": 0.009}), 0, GAITS["simplest_walker"].guess)
    case = GAITS["simplest_walker_feet"]
    with_feet = CompiledGait(case.build(), case.parameters)
    betas = (1e-4, 1e-5)
    xs = [
        fixed_point(with_feet.with_parameters({"beta": b, "gamma": 0.009}), 0, limit.x).x
        for b in betas
    ]
    for i in (0, 2):
        d1, d2 = xs[0][i] - limit.x[i], xs[1][i] - limit.x[i]
        assert 5 < d1 / d2 < 20  # first order in beta
        extrapolated = (betas[0] * d2 - betas[1] * d1) / (betas[0] - betas[1])
        assert abs(extrapolated) <= 1e-9
