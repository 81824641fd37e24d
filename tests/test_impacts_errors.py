"""Degenerate and bad input, singular sets, wall lookup, the wall-velocity override and
the behaviour outside D."""

from __future__ import annotations

import pytest
import sympy as sp
from test_impacts_support import impact_map, is_zero, kkt

import symmech as sm
from symmech.impacts import ImpactMap, derive_impact_map

x, y, th = sm.coordinates("x y theta")
xd, yd, thd = sm.velocities((x, y, th))
m, R = sp.symbols("m R", positive=True)


def test_wall_gradient_in_the_span_of_the_constraints():
    scene = sm.Scene((x, y), metric=sp.eye(2), constraints=[xd], walls=[sm.Wall(x, name="w")])
    with pytest.raises(
        sm.ImpactError,
        match=r"gradient of psi = x lies in the span of the permanent constraints \['xdot'\]",
    ):
        impact_map(scene, "w")


def test_wall_gradient_in_the_span_of_state_dependent_constraints():
    """psi = x^2/2 + y: d psi = x dx + dy, exactly the constraint x xdot + ydot = 0."""
    scene = sm.Scene(
        (x, y), metric=sp.diag(1, 2), constraints=[x * xd + yd], walls=[sm.Wall(x**2 / 2 + y)]
    )
    with pytest.raises(sm.ImpactError, match="lies in the span of the permanent constraints"):
        impact_map(scene, 0)


def test_impulsive_constraint_dependent_on_the_wall():
    scene = sm.Scene((x, y), metric=sp.eye(2), walls=[sm.Wall(y, impulsive_constraints=[2 * yd])])
    with pytest.raises(sm.ImpactError, match=r"nu\^1 = 2\*ydot is linearly dependent on d psi"):
        impact_map(scene, 0)


def test_wall_gradient_in_the_constraint_span_only_on_the_wall():
    """Generic sample points see nothing wrong: d psi = dy and mu = y dx + dy are
    independent off the wall y = 0, the same one-form on it, where impacts happen."""
    scene = sm.Scene((x, y), metric=sp.eye(2), constraints=[y * xd + yd], walls=[sm.Wall(y)])
    with pytest.raises(
        sm.ImpactError,
        match=r"on the wall psi = y = 0 the gradient of psi lies in the span of the permanent"
        r" constraints \['xdot\*y \+ ydot'\].* e\.g\. \{y=0\}",
    ):
        impact_map(scene, 0)


def test_curved_wall_degenerate_only_on_the_wall():
    """psi = y - x^2 and mu = (y - x^2 - 2x) dx + dy: equal on the parabola only; the
    points of the wall are found by solving psi = 0 numerically."""
    scene = sm.Scene(
        (x, y),
        metric=sp.diag(1, 2 + x**2),
        constraints=[(y - x**2 - 2 * x) * xd + yd],
        walls=[sm.Wall(y - x**2)],
    )
    with pytest.raises(sm.ImpactError, match=r"on the wall psi = -x\*\*2 \+ y = 0"):
        impact_map(scene, 0)
    # the same constraint against a wall it crosses transversally is fine
    other = sm.Scene(
        (x, y),
        metric=sp.diag(1, 2 + x**2),
        constraints=[(y - x**2 - 2 * x) * xd + yd],
        walls=[sm.Wall(y - x**2 + 1)],
    )
    assert impact_map(other, 0).matrix.shape == (2, 2)


def test_impulsive_constraint_dependent_only_on_the_wall():
    scene = sm.Scene(
        (x, y), metric=sp.eye(2), walls=[sm.Wall(y, impulsive_constraints=[y * xd + yd])]
    )
    with pytest.raises(
        sm.ImpactError, match=r"on the wall psi = y = 0 the impulsive constraint nu\^1 = xdot\*y"
    ):
        impact_map(scene, 0)


def test_points_on_a_moving_wall_with_an_arbitrary_function_of_time():
    from symmech.algebra.sampling import sample_points
    from symmech.impacts.degeneracy import points_on_wall

    f = sp.Function("f")
    psi = y - sp.sin(x) - f(sm.t)
    base = sample_points([x, y, sm.t, f(sm.t)], count=4)
    found = points_on_wall(psi, (x, y), base)
    assert len(found) == 4
    for p in found:
        assert abs(sp.N(psi.xreplace(p), 30)) < 1e-30


def test_impulsive_constraint_dependent_on_the_permanent_constraints():
    """Caught when the scene is declared (symmech.declaration.spec)."""
    with pytest.raises(sm.SceneError, match=r"impulsive_constraints .*linearly dependent"):
        sm.Scene(
            (x, y, th),
            metric=sp.eye(3),
            constraints=[xd - R * thd],
            walls=[sm.Wall(y, impulsive_constraints=[2 * xd - 2 * R * thd])],
        )


@pytest.mark.parametrize("alpha", [2, -sp.Rational(1, 2), 1.5])
def test_restitution_outside_unit_interval(alpha):
    with pytest.raises(sm.SceneError, match=r"restitution = .* is outside \[0, 1\]"):
        sm.Wall(y, restitution=alpha)


def test_restitution_symbol_known_to_be_negative():
    with pytest.raises(sm.SceneError, match="outside"):
        sm.Wall(y, restitution=sp.Symbol("e", negative=True))


def test_psi_without_coordinates():
    with pytest.raises(sm.SceneError, match="does not depend on the coordinates"):
        sm.Scene((x, y), metric=sp.eye(2), walls=[sm.Wall(sm.t - 1, name="clock")])


def test_unknown_law_and_unknown_wall():
    scene = sm.Scene((x, y), metric=sp.eye(2), walls=[sm.Wall(y, name="floor")])
    with pytest.raises(sm.ImpactError, match="law must be one of"):
        impact_map(scene, 0, law="plastic")
    # the scene resolves the wall (SceneError); derive_impact_map resolves it too
    with pytest.raises(sm.SceneError, match="no wall named 'ceiling'"):
        impact_map(scene, "ceiling")
    with pytest.raises(sm.SceneError, match="no wall with index 3"):
        impact_map(scene, 3)
    with pytest.raises(sm.ImpactError, match="no wall named 'ceiling'"):
        derive_impact_map(scene.declaration, "ceiling")
    with pytest.raises(sm.ImpactError, match="out of range"):
        derive_impact_map(scene.declaration, 3)
    with pytest.raises(sm.SceneError, match="law must be one of"):
        sm.Wall(y, law="plastic")


def test_wall_lookup_by_index_name_and_object():
    wall = sm.Wall(y, restitution=sp.Rational(1, 3), name="floor")
    scene = sm.Scene((x, y), metric=sp.eye(2), walls=[sm.Wall(x, name="side"), wall])
    maps = [impact_map(scene, 1), impact_map(scene, "floor"), impact_map(scene, wall)]
    assert all(isinstance(mp, ImpactMap) for mp in maps)
    expected = sp.Matrix([xd, -yd / 3])
    assert all(mp.post_velocity == expected for mp in maps)
    assert impact_map(scene, "side").post_velocity == sp.Matrix([-xd, yd])


def test_singular_states_are_listed():
    """D = span{(y, 1)} and the wall x = 0: C = y^2/(1 + y^2) vanishes at y = 0, where the
    motion allowed by the constraint is tangent to the wall."""
    scene = sm.Scene((x, y), metric=sp.eye(2), constraints=[xd - y * yd], walls=[sm.Wall(x)])
    imp = impact_map(scene, 0)
    exprs = [s.expression for s in imp.singularities]
    assert y in exprs
    assert any("det C^AB" in s.description for s in imp.singularities if s.expression == y)
    # the closed form indeed has y in a denominator
    assert any(sp.denom(sp.cancel(e)).has(y) for e in imp.matrix)
    # and it is still right away from y = 0 (route B)
    z = sp.Symbol("z", real=True)
    v_minus = sp.Matrix([y * z, z])  # in D
    assert is_zero((imp.apply(list(v_minus)) - kkt(scene, 0, v_minus)).norm() ** 2)


def test_components_outside_D_pass_through():
    """(PP - alpha T~) Q = Q: the D^perp part of v- is carried through unchanged."""
    a = sp.Symbol("alpha", nonnegative=True)
    scene = sm.Scene(
        (x, y, th),
        metric=sp.diag(m, m, 2 * m),
        constraints=[xd - R * thd],
        walls=[sm.Wall(y - R, restitution=a)],
    )
    imp = impact_map(scene, 0)
    Q = imp.projectors.Q
    assert (imp.matrix * Q - Q).applyfunc(sp.cancel).is_zero_matrix


def test_wall_velocity_override():
    """A conveyor-belt floor: psi = y - t (moving up with speed 1) with a tangential belt
    speed c, and rolling relative to the belt, nu = xdot - R thdot: nu(v+ - V) = 0."""
    c = sp.Symbol("c", real=True)
    a = sp.Symbol("alpha", nonnegative=True)
    wall = sm.Wall(y - sm.t, restitution=a, impulsive_constraints=[xd - R * thd])
    scene = sm.Scene((x, y, th), metric=sp.diag(m, m, m * R**2 / 2), walls=[wall])
    V = sp.Matrix([c, 1, 0])
    imp = impact_map(scene, 0, wall_velocity=V)
    assert imp.wall_velocity == V
    post = imp.post_velocity
    assert is_zero((post[0] - c) - R * post[2])  # rolling relative to the belt
    assert is_zero((post[1] - 1) + a * (yd - 1))  # restitution relative to the floor
    assert all(is_zero(e) for e in post - kkt(scene, 0, [xd, yd, thd], V=V))
    result = imp.carnot()
    assert result.theorem.startswith("Theorem 4.3") and is_zero(result.residual)
    # the default V (normal velocity only) gives a different map: the belt speed matters
    default = impact_map(scene, 0)
    assert default.wall_velocity == sp.Matrix([0, 1, 0])
    assert not is_zero(default.post_velocity[0] - post[0])


def test_wall_velocity_must_move_with_the_wall():
    scene = sm.Scene((x, y), metric=sp.eye(2), walls=[sm.Wall(y - 2 * sm.t)])
    with pytest.raises(sm.ImpactError, match="does not move with the wall"):
        impact_map(scene, 0, wall_velocity=[0, 1])
    with pytest.raises(sm.ImpactError, match="must have 2 components"):
        derive_impact_map(scene.declaration, 0, wall_velocity=[0, 2, 0])


def test_apply_checks_its_input_and_carnot_unpacks():
    scene = sm.Scene((x, y), metric=sp.eye(2), walls=[sm.Wall(y, restitution=sp.Rational(1, 2))])
    imp = impact_map(scene, 0)
    with pytest.raises(sm.ImpactError, match="expected 2 velocity components"):
        imp.apply([1, 2, 3])
    theorem, residual = imp.carnot()
    assert theorem == "Theorem 3.2" and residual == 0
    assert imp.apply({xd: 1, yd: -4}) == sp.Matrix([1, 2])
    assert "static" in repr(imp)


def test_unsimplified_and_stable_forms_agree():
    a = sp.Symbol("alpha", nonnegative=True)
    wall = sm.Wall(y - R, restitution=a, impulsive_constraints=[xd - R * thd])
    scene = sm.Scene((x, y, th), metric=sp.diag(m, m, m * R**2 / 3), walls=[wall])
    raw = derive_impact_map(scene.declaration, 0, simplify="none")
    stable = derive_impact_map(scene.declaration, 0)
    full = derive_impact_map(scene.declaration, 0, simplify="full")
    assert (raw.matrix - stable.matrix).applyfunc(sp.cancel).is_zero_matrix
    assert (full.matrix - stable.matrix).applyfunc(sp.cancel).is_zero_matrix
    with pytest.raises(sm.ImpactError, match="simplify must be"):
        derive_impact_map(scene.declaration, 0, simplify="maximal")


def test_singularity_where_d_psi_itself_vanishes():
    """psi = x^2 - 1 without impulsive constraints: C = 4 x^2 vanishes at x = 0 because
    d psi = 2 x dx does, not because of a dependence on impulsive constraints."""
    scene = sm.Scene((x, y), metric=sp.eye(2), walls=[sm.Wall(x**2 - 1)])
    (singular,) = impact_map(scene, 0).singularities
    assert singular.expression == x
    assert singular.description.startswith("d psi = 0")
    assert "impulsive" not in singular.description


def test_factors_without_real_zeros_are_not_listed():
    """D = span{(p, 1)} with p = 5 y^2 + y + 5 (no real root) or 2 + cos(y) (no zero) and
    the wall x = 0: C = p^2/(1 + p^2) never vanishes, so nothing is listed; with p = y the
    factor y is (the motion allowed is tangent to the wall at y = 0)."""
    from symmech.impacts.degeneracy import no_real_zeros, pythagorean

    for p in (5 * y**2 + y + 5, 2 + sp.cos(y)):
        scene = sm.Scene((x, y), metric=sp.eye(2), constraints=[xd - p * yd], walls=[sm.Wall(x)])
        assert impact_map(scene, 0).singularities == []
    scene = sm.Scene((x, y), metric=sp.eye(2), constraints=[xd - y * yd], walls=[sm.Wall(x)])
    (singular,) = impact_map(scene, 0).singularities
    assert singular.expression == y and "span of the permanent constraints" in singular.description
    assert no_real_zeros(5 * x**2 + x + 5) and no_real_zeros(m * x**2 + 3)
    assert not no_real_zeros(x**2 - 1) and not no_real_zeros(sp.S.Zero)
    assert not no_real_zeros(sp.cos(x) + 1) and no_real_zeros(sp.cos(x) + 2)
    assert pythagorean(m * sp.sin(x) ** 2 + m * sp.cos(x) ** 2 - m) == 0


def test_a_resolved_wall_of_another_scene_is_refused():
    other = sm.Scene((x, y), metric=sp.eye(2), walls=[sm.Wall(y, name="floor")])
    scene = sm.Scene((x, y), metric=sp.diag(2, 3), walls=[sm.Wall(y, name="floor")])
    foreign = other.declaration.walls[0]
    with pytest.raises(sm.ImpactError, match="does not belong to this scene"):
        derive_impact_map(scene.declaration, foreign)
    own = scene.declaration.walls[0]
    assert derive_impact_map(scene.declaration, own).post_velocity == sp.Matrix([xd, -yd])


def test_latex_of_names_with_special_characters():
    wall = sm.Wall(y, restitution=sp.Rational(1, 2), name="rough_wall #1")
    scene = sm.Scene((x, y), metric=sp.eye(2), walls=[wall])
    imp = impact_map(scene, 0)
    text = imp._repr_latex_()
    assert r"rough\_wall \#1" in text and "rough_wall" not in text
    assert r"\text{Theorem 3.2: }" in imp.carnot()._repr_latex_()


@pytest.mark.parametrize(
    "g",
    [
        sp.diag(10**6, 10**6, sp.Rational(1, 10**6)),
        sp.diag(1, 1, 10**12),
        sp.Matrix([[10**6, 1, 0], [1, 10**6, 0], [0, 0, sp.Rational(1, 10**6)]]),
    ],
    ids=["1e6-1e6-1e-6", "1-1-1e12", "coupled"],
)
def test_badly_scaled_metrics(g):
    """C^AB has entries 10^12 apart: the regularity test is scale-invariant (Hadamard
    ratio), so the map is derived, and it is the KKT map; a truly dependent impulsive
    constraint is still refused."""
    wall = sm.Wall(
        y - sp.cos(th) / 2, restitution=sp.Rational(1, 2), impulsive_constraints=[xd - thd]
    )
    scene = sm.Scene((x, y, th), metric=g, walls=[wall])
    imp = impact_map(scene, 0)
    v = [xd, yd, thd]
    assert (imp.post_velocity - kkt(scene, 0, v)).applyfunc(sp.cancel).is_zero_matrix
    assert imp.carnot().holds
    dependent = sm.Scene((x, y, th), metric=g, walls=[sm.Wall(y, impulsive_constraints=[3 * yd])])
    with pytest.raises(sm.ImpactError, match="linearly dependent on d psi"):
        impact_map(dependent, 0)
