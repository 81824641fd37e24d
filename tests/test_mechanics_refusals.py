"""What Scene.from_mechanics cannot import is refused with a SceneError that names the
model's attribute holding it and says what to do; no other exception leaves it."""

from __future__ import annotations

import pytest
import sympy as sp
from sympy.physics import mechanics as me

import symmech as sm
from symmech.mechanics import reading

T = me.dynamicsymbols._t


def _particle_on_a_line(position, velocity, kd_rhs=None):
    """A particle at ``position(q)`` with velocity ``velocity(q, u)`` (KanesMethod, one
    speed; ``kd_rhs(q, u)`` the kinematic equation's q_dot, u by default)."""
    q, u = me.dynamicsymbols("q u")
    m = sp.Symbol("m", positive=True)
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", position(q, N))
    P.set_vel(N, velocity(q, u, N))
    qd = kd_rhs(q, u) if kd_rhs is not None else u
    km = me.KanesMethod(N, [q], [u], kd_eqs=[q.diff(T) - qd])
    km.kanes_equations([me.Particle("bob", P, m)], [])
    return km


def test_a_body_velocity_through_abs_is_refused_as_non_smooth_naming_the_body():
    # the velocity of |q| N.x differentiated by sympy: re, im and sign of q, no speed
    km = _particle_on_a_line(
        lambda q, N: sp.Abs(q) * N.x + q * N.y,
        lambda q, u, N: (sp.Abs(q) * N.x + q * N.y).dt(N).xreplace({q.diff(T): u}),
    )
    with pytest.raises(
        sm.SceneError,
        match=r"bob: mass centre velocity contains the non-smooth functions \['im', 're',"
        r" 'sign'\]; .* write the positions and velocities without them",
    ):
        sm.Scene.from_mechanics(km)


def test_a_velocity_linear_in_the_speed_but_non_smooth_is_refused_naming_the_body():
    km = _particle_on_a_line(lambda q, N: q * N.x, lambda q, u, N: (2 + sp.sign(q)) * u * N.x)
    with pytest.raises(
        sm.SceneError, match=r"bob: mass centre velocity contains the non-smooth functions"
    ):
        sm.Scene.from_mechanics(km)


def test_non_smooth_kinematic_equations_are_refused_naming_kd_eqs():
    km = _particle_on_a_line(
        lambda q, N: q * N.x, lambda q, u, N: u * N.x, lambda q, u: (2 + sp.sign(q)) * u
    )
    with pytest.raises(
        sm.SceneError,
        match=r"KanesMethod\.kd_eqs \(q_dot = S\(q\) u\) contains the non-smooth functions"
        r" \['sign'\]",
    ):
        sm.Scene.from_mechanics(km)


def test_a_non_smooth_lagrangian_is_refused_naming_it():
    q = me.dynamicsymbols("q")
    m = sp.Symbol("m", positive=True)
    lm = me.LagrangesMethod(m * (2 + sp.Abs(q)) * q.diff(T) ** 2 / 2, [q])
    lm.form_lagranges_equations()
    with pytest.raises(
        sm.SceneError,
        match=r"the Lagrangian of the LagrangesMethod contains the non-smooth functions"
        r" \['Abs'\]",
    ):
        sm.Scene.from_mechanics(lm)


def test_a_frame_less_lagrange_model_without_loads_imports():
    """LagrangesMethod without frame=: nothing needs the frame when there are no loads;
    the pendulum's accelerations are those of its own equations."""
    q = me.dynamicsymbols("q")
    m, l, g = sp.symbols("m l g", positive=True)
    lm = me.LagrangesMethod(m * l**2 * q.diff(T) ** 2 / 2 + m * g * l * sp.cos(q), [q])
    lm.form_lagranges_equations()
    scene = sm.Scene.from_mechanics(lm)
    values = {m: 1.3, l: 0.7, g: 9.81, q: 0.4, q.diff(T): -0.2}
    theirs = (lm.mass_matrix_full.LUsolve(lm.forcing_full)).xreplace(values)[1]
    sub = {s: values[k] for k in (m, l, g) for s in scene.parameters if s.name == k.name}
    sub |= {scene.coordinates[0]: 0.4, scene.velocities[0]: -0.2}
    ours = scene.mass_matrix().LUsolve(scene.forcing())[0].xreplace(sub)
    assert abs(float(ours) - float(theirs)) < 1e-12
    assert abs(float(theirs) + 9.81 / 0.7 * float(sp.sin(0.4))) < 1e-12  # the pendulum's


@pytest.mark.parametrize(
    "error",
    [
        ValueError("x"),
        KeyError("x"),
        IndexError("x"),
        RecursionError("x"),
        sp.polys.polyerrors.PolynomialError("x"),
        sp.polys.polyerrors.CoercionFailed("x"),
    ],
)
def test_a_failure_of_sympy_while_reading_becomes_a_scene_error_naming_the_part(error):
    with pytest.raises(sm.SceneError, match=r"^from_mechanics: KanesMethod: reading its loads"):
        with reading("KanesMethod", "its loads"):
            raise error


def test_kinematic_equations_with_a_prescribed_part_are_refused_naming_kd_eqs():
    km = _particle_on_a_line(lambda q, N: q * N.x, lambda q, u, N: u * N.x, lambda q, u: u + 1)
    with pytest.raises(
        sm.SceneError,
        match=r"KanesMethod\.kd_eqs: the kinematic differential equations must read"
        r" q_dot = S\(q\) u; \[1\] is left over",
    ):
        sm.Scene.from_mechanics(km)


def test_a_velocity_constraint_with_a_prescribed_rate_is_refused_naming_it():
    q1, q2, u1, u2 = me.dynamicsymbols("q1 q2 u1 u2")
    m = sp.Symbol("m", positive=True)
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", q1 * N.x + q2 * N.y)
    P.set_vel(N, u1 * N.x + u2 * N.y)
    km = me.KanesMethod(
        N,
        [q1, q2],
        [u1],
        kd_eqs=[q1.diff(T) - u1, q2.diff(T) - u2],
        u_dependent=[u2],
        velocity_constraints=[u2 - 1],
    )
    km.kanes_equations([me.Particle("bob", P, m)], [])
    with pytest.raises(
        sm.SceneError,
        match=r"KanesMethod\.velocity_constraints / configuration_constraints: velocity"
        r" constraints with a part free of the speeds \[-1\]",
    ):
        sm.Scene.from_mechanics(km)


def test_a_system_without_coordinates_is_refused_as_such():
    with pytest.raises(sm.SceneError, match=r"^from_mechanics: the System has no generalized"):
        sm.Scene.from_mechanics(me.System())
