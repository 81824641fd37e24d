"""Every bad input of the scene declaration is refused with a SceneError naming it.

Issue: "Validation collects every problem and raises one sm.SceneError naming each".
"""

from __future__ import annotations

import pytest
import sympy as sp

import symmech as sm

x, y, th = sm.coordinates("x y theta")
xd, yd, thd = sm.velocities((x, y, th))
m, I, R = sp.symbols("m I R", positive=True)
Q = (x, y, th)


def refused(**kwargs) -> sm.SceneError:
    with pytest.raises(sm.SceneError) as info:
        sm.Scene(Q, **kwargs)
    assert isinstance(info.value, ValueError)
    return info.value


@pytest.mark.parametrize(
    ("kwargs", "needles"),
    [
        (dict(metric=sp.Matrix([[1, 0, 0], [0, 1, 0]])), ["metric", "not square"]),
        (dict(metric=sp.eye(2)), ["metric", "does not match the 3 coordinates"]),
        (dict(metric=sp.Matrix([[m, 1, 0], [0, m, 0], [0, 0, I]])), ["metric", "not symmetric"]),
        (dict(metric=sp.Matrix([[1, 1, 0], [1, 1, 0], [0, 0, 1]])), ["metric", "singular"]),
        (dict(metric=sp.diag(m, -m, I)), ["metric", "not positive definite"]),
        (dict(metric=sp.diag(1, 1, sp.sin(th) ** 2 - 2)), ["metric", "not positive definite"]),
        (dict(metric=sp.Matrix([[1, 2, 0], [2, 1, 0], [0, 0, 1]])), ["not positive definite"]),
        # det = m^2 (1 - 4 cos^2 theta): indefinite wherever |cos theta| > 1/2
        (
            dict(
                metric=sp.Matrix(
                    [[m, 2 * m * sp.cos(th), 0], [2 * m * sp.cos(th), m, 0], [0, 0, I]]
                )
            ),
            ["metric", "not positive definite at the sampled point", "theta="],
        ),
        # det = m^2 (1 - cos^2 theta) - m^2 sin^2 theta = 0 identically: singular everywhere
        (
            dict(
                metric=sp.Matrix(
                    [
                        [m, m * sp.cos(th), 0],
                        [m * sp.cos(th), m * (1 - sp.sin(th) ** 2), 0],
                        [0, 0, I],
                    ]
                )
            ),
            ["metric", "singular (determinant identically 0)"],
        ),
        # det = x^2 y^2 (1 - 1) = 0 for all x, y, though every entry depends on q
        (
            dict(metric=sp.Matrix([[x**2, x * y, 0], [x * y, y**2, 0], [0, 0, 1]])),
            ["metric", "singular"],
        ),
        (dict(kinetic_energy=m * xd**3), ["kinetic_energy", "not a quadratic form"]),
        (dict(kinetic_energy=m * xd**2 / 2 + m * xd), ["kinetic_energy", "not a quadratic form"]),
        (
            dict(kinetic_energy=m * (xd**2 + yd**2 + thd**2) / 2 + 1),
            ["kinetic_energy", "does not depend on the velocities"],
        ),
        (
            dict(kinetic_energy=sp.sqrt(xd**2 + yd**2 + thd**2)),
            ["kinetic_energy", "not a quadratic form"],
        ),
        (
            dict(metric=sp.eye(3), constraints=[xd**2 + yd]),
            ["constraints[0]", "not linear in the velocities"],
        ),
        (dict(metric=sp.eye(3), constraints=[xd * yd]), ["constraints[0]", "not linear"]),
        (dict(metric=sp.eye(3), constraints=[xd + 1]), ["constraints[0]", "linear (homogeneous)"]),
        (
            dict(metric=sp.eye(3), constraints=[sp.sin(x)]),
            ["constraints[0]", "does not involve any velocity"],
        ),
        (
            dict(metric=sp.eye(3), constraints=[xd + R * thd, 2 * xd + 2 * R * thd]),
            ["constraints", "linearly dependent"],
        ),
        (
            dict(metric=sp.eye(3), constraints=[[1, 0, 0], [0, 1, 0], [0, 0, 1]]),
            ["constraints", "3 constraints for 3 coordinates"],
        ),
        (dict(metric=sp.eye(3), constraints=[[1, 0]]), ["constraints[0]", "needs 3 entries"]),
        (dict(metric=sp.diag(m, m, xd)), ["metric", "velocity symbols", "xdot"]),
        (dict(metric=sp.eye(3), potential=m * xd), ["potential", "velocity symbols"]),
        (
            dict(metric=sp.eye(3), potential=sp.Symbol("zdot")),
            ["potential", "zdot", "velocities of coordinates"],
        ),
        (dict(metric=sp.diag(1, 1, sp.Abs(x) + 1)), ["metric", "non-smooth", "Abs"]),
        (dict(metric=sp.eye(3), potential=sp.sign(x)), ["potential", "non-smooth", "sign"]),
        (
            dict(metric=sp.eye(3), potential=sp.Piecewise((x, x > 0), (0, True))),
            ["potential", "Piecewise"],
        ),
        (dict(metric=sp.eye(3), potential=sp.Heaviside(x)), ["potential", "Heaviside"]),
        (dict(metric=sp.eye(3), potential=sp.floor(x)), ["potential", "floor"]),
        (dict(metric=sp.eye(3), potential=sp.Max(x, y)), ["potential", "Max"]),
        (dict(metric=sp.eye(3), potential=sp.Min(x, y)), ["potential", "Min"]),
        (dict(metric=sp.eye(3), potential=sp.Mod(x, 1)), ["potential", "non-smooth", "Mod"]),
        (dict(metric=sp.eye(3), potential=sp.ceiling(x)), ["potential", "ceiling"]),
        (dict(metric=sp.eye(3), potential=sp.frac(x)), ["potential", "frac"]),
        (
            dict(metric=sp.diag(1, 1, 1 + 2 * sp.cos(th))),
            ["metric", "not positive definite", "theta="],
        ),
        (dict(metric=sp.diag(1, 1, 1 + sm.t**2)), ["metric", "depends on time"]),
        (dict(metric=sp.eye(3), constraints=[xd + sm.t * yd]), ["constraints", "depends on time"]),
        (
            dict(metric=sp.eye(3), kinetic_energy=xd**2),
            ["exactly one of 'metric' and 'kinetic_energy'"],
        ),
        (dict(), ["exactly one of 'metric' and 'kinetic_energy'"]),
    ],
)
def test_bad_input_is_named(kwargs, needles):
    err = refused(**kwargs)
    message = str(err)
    for needle in needles:
        assert needle in message, f"{needle!r} not in {message!r}"


def test_unknown_symbols_with_declared_parameters():
    z = sp.Symbol("z")
    err = refused(metric=sp.diag(m, m, I), potential=z * y, parameters=(m, I))
    assert "potential" in str(err) and "unknown symbols ['z']" in str(err)


def test_all_problems_are_collected_in_one_error():
    err = refused(metric=sp.diag(m, m, xd), potential=sp.Abs(x), constraints=[])
    assert len(err.problems) == 2
    assert any("metric" in p for p in err.problems)
    assert any("potential" in p and "Abs" in p for p in err.problems)


def test_hostile_strings_are_refused_not_run(tmp_path):
    sentinel = tmp_path / "pwned"
    hostile = f"__import__('os').system('touch {sentinel}')"
    err = refused(metric=sp.eye(3), potential=hostile)
    assert "potential" in str(err)
    assert not sentinel.exists()
    err = refused(metric=sp.eye(3), constraints=["().__class__.__bases__"])
    assert "constraints[0]" in str(err)


def test_strings_are_parsed_safely():
    scene = sm.Scene(
        Q,
        metric=[["m", 0, 0], [0, "m", 0], [0, 0, "I"]],
        potential="m*9.81*y",
        constraints=["ydot + R*thetadot"],
        parameters=(m, I, R),
    )
    assert scene.mass_matrix() == sp.diag(m, m, I)
    assert scene.constraint_matrix == sp.Matrix([[0, 1, R]])


def test_coordinates_and_frames_are_checked():
    with pytest.raises(sm.SceneError, match="not sympy Symbols"):
        sm.Scene([x, 2], metric=sp.eye(2))
    with pytest.raises(sm.SceneError, match="repeated"):
        sm.Scene([x, x], metric=sp.eye(2))
    with pytest.raises(sm.SceneError, match="given together"):
        sm.Scene(Q, metric=sp.eye(3), frame=sp.eye(3))
    v = sp.symbols("v1:4", real=True)
    with pytest.raises(sm.SceneError, match=r"frame.*singular"):
        sm.Scene(Q, metric=sp.eye(3), frame=sp.zeros(3, 3), quasi_velocities=v)
    with pytest.raises(sm.SceneError, match="quasi_velocities"):
        sm.Scene(Q, metric=sp.eye(3), frame=sp.eye(3), quasi_velocities=v[:2])


def test_wall_validation():
    with pytest.raises(sm.SceneError, match="outside \\[0, 1\\]"):
        sm.Wall(y, restitution=1.5)
    with pytest.raises(sm.SceneError, match="outside \\[0, 1\\]"):
        sm.Wall(y, restitution=-0.1)
    with pytest.raises(sm.SceneError, match="restitution"):
        sm.Wall(y, restitution="0.5")
    with pytest.raises(sm.SceneError, match="law"):
        sm.Wall(y, law="magic")
    err = refused(metric=sp.eye(3), walls=[sm.Wall(R + 1, name="w")])
    assert "does not depend on the coordinates" in str(err) and "'w'" in str(err)


def test_scene_is_immutable_and_lazy():
    scene = sm.Scene(Q, metric=sp.diag(m, m, I))
    with pytest.raises(AttributeError, match="immutable"):
        scene.foo = 1
    assert scene._cache == {}
    f1 = scene.forcing()
    assert scene.forcing() is f1  # computed once


def test_default_parameters_are_sorted_and_deterministic():
    g = sp.Symbol("g", positive=True)
    scene = sm.Scene(Q, metric=sp.diag(m, m, I), potential=m * g * y, constraints=[yd + R * thd])
    assert scene.parameters == (I, R, g, m)
    # a name tie (two symbols named g) has no deterministic order: it is refused, with
    # the same message whatever order the symbols are met in
    g2 = sp.Symbol("g")
    messages = set()
    for V in (m * g * y + g2 * x, g2 * x + m * g * y, m * g * (y + g2 * x)):
        with pytest.raises(sm.SceneError) as info:
            sm.Scene(Q, metric=sp.diag(m, m, I), potential=V)
        messages.add(str(info.value))
    (message,) = messages
    assert "symbol g (positive=True)" in message and "symbol g (no assumptions)" in message


def test_metrics_positive_definite_off_a_small_set_are_accepted():
    # singular only at x = 0 (like polar coordinates at the origin)
    sm.Scene(Q, metric=sp.diag(1, x**2, 1))
    # det = (2 + sin theta) 2 - cos^2 theta >= 1: positive definite everywhere
    c = sp.cos(th)
    sm.Scene(Q, metric=sp.Matrix([[2 + sp.sin(th), c, 0], [c, 2, 0], [0, 0, I]]))


def test_example_arguments_are_symmech_errors():
    from symmech.examples import pendulum_on_cart

    with pytest.raises(sm.SceneError, match="pendulum_on_cart: n"):
        pendulum_on_cart(0)


def test_problems_name_their_field_as_a_path_not_in_prose():
    """Every problem of a declaration carries the field it is about (a path the scene-file
    reader looks up), and the label its message uses; the message itself is unchanged."""
    x, y = sm.coordinates("x y")
    xd, yd = sm.velocities((x, y))
    m = sp.Symbol("m", positive=True)
    wall = sm.Wall(y + x**0, impulsive_constraints=[xd * yd], name="floor")
    with pytest.raises(sm.SceneError) as info:
        sm.Scene(
            (x, y),
            metric=sp.diag(m, -m),
            constraints=[xd + yd, 2 * xd + 2 * yd],
            forces=[0, "q + 1"],
            walls=[wall],
        )
    records = {r.field: r for r in info.value.records}
    assert [r.message for r in info.value.records] == info.value.problems
    assert "metric" in records and records["metric"].message.startswith("metric")
    assert "forces[1]" in records
    nu = records["walls[0].impulsive_constraints[0]"]
    assert nu.label == "walls[0] ('floor').impulsive_constraints[0]"
    assert nu.message.startswith(nu.label) and not nu.reason.startswith("walls")
    with pytest.raises(sm.SceneError) as info:
        sm.Scene((x, y), metric=sp.eye(2) * m, constraints=[xd + yd, 2 * xd + 2 * yd])
    assert [r.field for r in info.value.records] == ["constraints"]
