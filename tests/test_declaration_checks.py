"""Validation of a declaration: every stage runs, costs stay bounded, numbers never leak.

Issue 2: "Validation collects every problem and raises one sm.SceneError naming each:
metric not square / not symmetric / singular / not positive definite (checked symbolically
where cheap, else at sampled points respecting symbol assumptions) ...".
"""

from __future__ import annotations

import time
import warnings

import pytest
import sympy as sp

import symmech as sm
from symmech.examples import pendulum_on_cart

x, y, th = sm.coordinates("x y theta")
xd, yd, thd = sm.velocities((x, y, th))
m, I, R, g0 = sp.symbols("m I R g", positive=True)
Q = (x, y, th)


def refused(q=Q, **kwargs) -> sm.SceneError:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no numpy or sympy warning may escape
        with pytest.raises(sm.SceneError) as info:
            sm.Scene(q, **kwargs)
    return info.value


def accepted(q=Q, **kwargs) -> sm.Scene:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return sm.Scene(q, **kwargs)


def has(err: sm.SceneError, *needles: str) -> bool:
    return any(all(n in p for n in needles) for p in err.problems)


# -- problems of every stage are reported together ------------------------------------------


def test_problems_of_all_three_stages_in_one_error():
    err = refused(
        metric=sp.diag(m, -m, I),  # properties: indefinite
        potential="m*g*y +",  # structure: does not parse
        constraints=[xd**2, xd + sm.t * yd],  # properties: not linear; symbols: time
        walls=[sm.Wall(R + 1, name="w")],  # properties: psi free of the coordinates
    )
    assert len(err.problems) == 5, err.problems
    assert has(err, "potential")
    assert has(err, "metric", "not positive definite")
    assert has(err, "constraints[0]", "not linear")
    assert has(err, "constraints[1]", "depends on time")
    assert has(err, "walls[0] ('w').psi", "does not depend on the coordinates")


@pytest.mark.parametrize(
    ("kwargs", "needles"),
    [
        (
            dict(metric=sp.diag(m, -m, I), potential=sp.Abs(x)),
            [("metric", "not positive definite"), ("potential", "Abs")],
        ),
        (
            dict(metric=sp.eye(3), potential=xd, constraints=[xd**2]),
            [("potential", "velocity symbols"), ("constraints[0]", "not linear")],
        ),
        (
            dict(kinetic_energy=xd**3, potential=sp.Abs(x)),
            [("kinetic_energy", "not a quadratic form"), ("potential", "Abs")],
        ),
        (
            dict(metric=[[1, 0], [0, 1]], frame=sp.eye(3), potential=sp.sign(y)),
            [("metric", "does not match"), ("frame", "together"), ("potential", "sign")],
        ),
    ],
)
def test_independent_fields_are_all_checked(kwargs, needles):
    err = refused(**kwargs)
    assert len(err.problems) == len(needles), err.problems
    for needle in needles:
        assert has(err, *needle), (needle, err.problems)


def test_dependent_checks_are_skipped_not_misreported():
    # a constraint with a misnamed symbol is reported for its symbol only
    err = refused(metric=sp.eye(3), constraints=[xd + sp.Symbol("ydot")])
    (problem,) = err.problems
    assert "same name as the velocity ydot" in problem and "velocity-free" not in problem
    # a coordinate velocity in a constraint of a frame scene: written in v
    v = sp.symbols("v1:4", real=True)
    err = refused(metric=sp.eye(3), frame=sp.eye(3), quasi_velocities=v, constraints=[xd])
    (problem,) = err.problems
    assert "quasi-velocities ['v1', 'v2', 'v3']" in problem and "xdot" in problem
    assert "does not involve any velocity" not in problem


# -- bounded cost on hostile but small input ----------------------------------------------

_SINES = " + ".join(f"sin({k}*y)" for k in range(1, 199))


def test_large_constraint_with_a_velocity_free_part_is_refused_quickly():
    z = sp.Symbol("z", real=True)
    hostile = f"xdot + (1+x**2)**64*ydot + {_SINES} + sin(199*y)*zdot"
    start = time.perf_counter()
    err = refused((x, y, z), metric=sp.eye(3), constraints=[hostile])
    assert time.perf_counter() - start < 20  # a guard only: simplify took > 12 minutes
    (problem,) = err.problems
    assert problem.startswith("constraints[0]:") and "velocity-free part sin(y)" in problem


def test_large_constraint_that_is_a_one_form_is_accepted_quickly():
    z = sp.Symbol("z", real=True)
    start = time.perf_counter()
    scene = accepted(
        (x, y, z),
        metric=sp.eye(3),
        constraints=[f"xdot + (1+x**2)**64*ydot + ({_SINES} + sin(199*y))*zdot"],
    )
    assert time.perf_counter() - start < 20
    mu = scene.constraint_matrix
    assert mu[0, 0] == 1 and mu[0, 1] == (1 + x**2) ** 64
    assert mu[0, 2] == sum(sp.sin(k * y) for k in range(1, 200))


def test_identically_zero_parts_are_recognised():
    # velocity-free part sin^2 + cos^2 - 1 = 0: a homogeneous constraint
    scene = accepted(metric=sp.eye(3), constraints=[xd + sp.sin(x) ** 2 + sp.cos(x) ** 2 - 1])
    assert scene.constraint_matrix == sp.Matrix([[1, 0, 0]])
    # nonlinear terms that cancel: R (x + y)^2 - R x^2 - 2 R x y - R y^2 = 0
    scene = accepted(
        metric=sp.eye(3),
        constraints=[R * (xd + yd) ** 2 - R * xd**2 - 2 * R * xd * yd - R * yd**2 + thd],
    )
    assert scene.constraint_matrix == sp.Matrix([[0, 0, 1]])
    # a coefficient that vanishes identically leaves no velocity
    err = refused(metric=sp.eye(3), constraints=[(sp.sin(x) ** 2 + sp.cos(x) ** 2 - 1) * xd])
    assert has(err, "constraints[0]", "does not involve any velocity")
    # a large metric, symmetric up to a trigonometric identity
    A = sp.Add(*[sp.sin(k * y) for k in range(1, 199)]) / 1000  # |A| < 0.2
    G = sp.Matrix([[1, A, 0], [A + sp.sin(x) ** 2 + sp.cos(x) ** 2 - 1, 1, 0], [0, 0, 1]])
    start = time.perf_counter()
    accepted(metric=G)
    assert time.perf_counter() - start < 20
    err = refused(metric=sp.Matrix([[1, A, 0], [A + x / 1000, 1, 0], [0, 0, 1]]))
    assert has(err, "metric", "not symmetric", "(0, 1)")


# -- metric: what singular and indefinite mean ------------------------------------------------


def test_metric_definiteness_depends_on_the_coordinates():
    c = sp.cos(x)
    # det = 1 - (2 cos x + 3)^2 <= 0, < 0 except at cos x = -1: indefinite
    err = refused(metric=sp.Matrix([[1, 2 * c + 3, 0], [2 * c + 3, 1, 0], [0, 0, 1]]))
    assert has(err, "metric", "not positive definite at the sampled point")
    # det = cos^2 x - cos^2 x = 0 identically: singular everywhere
    err = refused(metric=sp.Matrix([[1, c, 0], [c, c**2, 0], [0, 0, 1]]))
    assert has(err, "metric", "singular (determinant identically 0)")
    # det = 4 + 2 sin x - cos^2 x >= 1: positive definite everywhere
    accepted(metric=sp.Matrix([[2 + sp.sin(x), c, 0], [c, 2, 0], [0, 0, 1]]))
    # singular only on x = 0 (like polar coordinates at the origin): accepted
    accepted(metric=sp.diag(1, x**2, 1))
    # diag(1, x): x is real, indefinite for x < 0; a positive coordinate makes it a metric
    err = refused(metric=sp.diag(1, x, 1))
    assert has(err, "metric", "not positive definite", "x=-")
    r = sp.Symbol("r", positive=True)
    accepted((r, y), metric=sp.diag(1, r))


def test_metric_of_a_kinetic_energy_is_checked():
    err = refused(kinetic_energy=m * (xd**2 - yd**2 + thd**2) / 2)
    assert has(err, "kinetic_energy", "its metric", "not positive definite")
    err = refused(kinetic_energy=m * (xd + yd) ** 2 / 2 + I * thd**2 / 2)
    assert has(err, "kinetic_energy", "singular")


# -- overflow and non-finite values ---------------------------------------------------------


def test_huge_entries_are_handled_without_warnings():
    e = sp.exp
    # entries that overflow float64 at every sampled point are judged in mpmath
    big = 1000 + x**2
    accepted((x,), metric=[[e(big)]])
    accepted((x,), metric=[[1e308]])
    accepted((x, y), metric=[[1e308, 0], [0, 1e-308]])  # scale-free: positive definite
    accepted((x,), metric=[[e(e(e(big)))]])  # exp of a real number is positive
    # det = e^(1000 + x^2) - 1 > 0 and e^(1000 + x^2) > 0: positive definite (in mpmath)
    accepted((x, y), metric=[[e(big), 1], [1, 1]])
    accepted((x, y), metric=[[1e308, 1e307], [1e307, 1e308]])
    # det = e^(1000 + x^2) - e^(1200 + 2 x^2) < 0: indefinite
    err = refused((x, y), metric=[[e(big), e(600 + x**2)], [e(600 + x**2), 1]])
    assert has(err, "metric", "not positive definite")
    # no finite value in any arithmetic: said so, naming the entry
    err = refused((x, y), metric=[[e(e(e(big))), 1], [1, 1]])
    assert has(err, "metric: entry [0,0] = exp(exp(exp(x**2 + 1000)))", "overflows float64")
    assert has(err, "positive definiteness cannot be checked")
    # a constant float64 cannot hold is refused whatever its sign (generated code holds it)
    err = refused((x,), metric=[[e(1000)]])
    assert has(err, "metric: entry [0,0] = exp(1000): holds the constant exp(1000)", "float64")
    for bad in (sp.zoo, sp.oo, sp.nan):
        err = refused((x, y), metric=[[bad, 0], [0, 1]])
        assert has(err, f"metric: entry [0,0] = {bad}", "cannot be checked"), err.problems


def test_entries_undefined_at_some_sampled_points_are_fine():
    accepted((x, y), metric=sp.diag(1 / x**2, 1))


# -- undefined functions ----------------------------------------------------------------------


def test_undefined_functions_of_the_coordinates_are_accepted():
    f = sp.Function("g")
    scene = accepted((x, y), metric=sp.diag(1 + f(x) ** 2, 1), potential=sp.Function("V")(x, y))
    assert scene.parameters == ()
    # metric diag(h, 1): Gamma^x_xx = h'/(2h) (slides 000), h = 1 + g^2
    h = 1 + f(x) ** 2
    assert sp.simplify(scene.christoffel()[0, 0, 0] - sp.diff(h, x) / (2 * h)) == 0
    # the same with declared parameters: functions are never parameters
    scene = accepted((x, y), metric=sp.diag(m * (1 + f(x) ** 2), 1), parameters=(m,))
    assert scene.parameters == (m,)
    accepted((x, y), metric=sp.eye(2), potential=f(x), parameters=())


def test_undefined_functions_obey_the_rules_of_their_field():
    f = sp.Function("g")
    err = refused((x, y), metric=sp.diag(1 + f(xd) ** 2, 1))
    assert has(err, "metric", "velocity symbols", "xdot")
    z = sp.Symbol("z")
    err = refused((x, y), metric=sp.eye(2), potential=f(z * x), parameters=())
    assert has(err, "potential", "unknown symbols ['z']")
    # a generic g(x) may be negative: diag(g(x), 1) is refused, unless g is positive
    err = refused((x, y), metric=sp.diag(f(x), 1))
    assert has(err, "metric", "not positive definite", "g(x)=-")
    accepted((x, y), metric=sp.diag(sp.Function("g", positive=True)(x), 1))


# -- examples --------------------------------------------------------------------------------


@pytest.mark.parametrize("n", [0, -2, 2.5, True, "3"])
def test_example_arguments_are_checked(n):
    with pytest.raises(sm.SceneError, match=r"pendulum_on_cart: n .* integer >= 1"):
        pendulum_on_cart(n)


# -- the numerical helpers on their own -------------------------------------------------------


def test_classify_symmetric_is_scale_free():
    import mpmath

    from symmech.algebra.numeric import classify_symmetric

    assert classify_symmetric([[1e308, 0.0], [0.0, 1e-308]])[0] == "positive definite"
    assert classify_symmetric([[1.0, 1.0], [1.0, 1.0]])[0] == "singular"
    assert classify_symmetric([[1.0, 2.0], [2.0, 1.0]])[0] == "indefinite"
    assert classify_symmetric([[0.0, 1.0], [1.0, 1.0]])[0] == "indefinite"  # det = -1
    assert classify_symmetric([[0.0, 0.0], [0.0, 1.0]])[0] == "singular"
    big = mpmath.mpf("1e500")
    assert classify_symmetric([[big, big / 2], [big / 2, big]])[0] == "positive definite"
    assert classify_symmetric([[big, 2 * big], [2 * big, big]])[0] == "indefinite"


def test_vanishes_compares_with_the_cancelling_terms():
    from symmech.algebra.numeric import vanishes

    pts = [{x: sp.Rational(-3, 7), y: sp.Rational(5, 3)}, {x: sp.Rational(2, 9), y: 1}]
    assert vanishes(sp.sin(x + y) - sp.sin(x) * sp.cos(y) - sp.cos(x) * sp.sin(y), pts)
    assert vanishes(sp.exp(sp.log(x**2 + 1)) - x**2 - 1, pts)
    # tiny but not zero: 1e-40 x is small only in absolute terms
    assert vanishes(x**-3 - 1 / x**3 + sp.Float("1e-40") * x, pts) is False
    assert vanishes(sp.exp(1000 * x) * (sp.sin(y) ** 2 + sp.cos(y) ** 2 - 1), pts)
    assert vanishes(sp.Function("g")(x), pts) is None  # no value for g(x) at any point
