"""Hostile and extreme declarations (issue 10, classes 4 and 5): refused with a symmech
exception naming the field and the reason, or accepted with an UndecidedWarning saying
what was not decided; never a raw sympy or Python exception, never a silent wrong answer.

Every refusal is checked by an independent route: the point the declaration reports is
substituted into the user's expression with sympy/mpmath here, and a constant said to be
outside float64 is compared with ``sys.float_info`` in mpmath.
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import mpmath
import pytest
import sympy as sp

import symmech as sm
from symmech.algebra.sampling import sample_points
from symmech.declaration.constants import constant_out_of_range
from symmech.declaration.definiteness import definiteness, lower_bound
from symmech.declaration.expressions import parse_expression
from symmech.declaration.wallpoints import vanishing_gradient

x, y = sm.coordinates("x y")
Q = (x, y)
R = sp.Rational
POINTS = sample_points(Q, count=4, far=2)


def refused(**kwargs: object) -> sm.SceneError:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no stray warning either
        with pytest.raises(sm.SceneError) as info:
            sm.Scene(Q, **kwargs)
    return info.value


def accepted(**kwargs: object) -> sm.Scene:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return sm.Scene(Q, **kwargs)


def undecided(**kwargs: object) -> str:
    with pytest.warns(sm.UndecidedWarning) as record:
        sm.Scene(Q, **kwargs)
    return str(record[0].message)


def has(err: sm.SceneError, *needles: str) -> bool:
    return any(all(n in p for n in needles) for p in err.problems)


def file_refused(text: str, tmp_path: Path | None = None) -> sm.SceneFileError:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(sm.SceneFileError) as info:
            if tmp_path is None:
                sm.reads_scene(text)
            else:
                path = tmp_path / "hostile.toml"
                path.write_text(text)
                sm.load_scene(path)
    return info.value


BASE = 'coordinates = ["x", "y"]\nmetric = [1, 1]\n'


# -- class 4: metrics indefinite on part of the domain ----------------------------------------

# (g_yy, a point in the region where it is negative): the sampled points miss each region
INDEFINITE_SOMEWHERE = [
    (1 + R(101, 100) * sp.sin(x), "|x + pi/2| < 0.14"),
    (1 + R(1001, 1000) * sp.cos(x), "|x - pi| < 0.045"),
    (x**2 - R(1, 100), "|x| < 0.1"),
    ((x - 2) ** 2 - R(1, 100), "|x - 2| < 0.1"),
    (x**2 - R(1, 10**6), "|x| < 0.001"),
    (x**2 + y**2 - 2 * x * y - R(1, 10**4), "|x - y| < 0.01"),
]


@pytest.mark.parametrize(("entry", "region"), INDEFINITE_SOMEWHERE)
def test_metric_indefinite_away_from_the_samples_is_refused(entry: sp.Expr, region: str):
    g = sp.diag(1, entry)
    # the sampled points alone see a positive metric
    assert all(entry.xreplace(p) > 0 for p in POINTS), region
    err = refused(metric=g)
    # found by the search, or past the exact real roots of the entry (solveset, Sturm)
    assert has(err, "metric: not positive definite at the point", "a point found"), err.problems
    verdict = definiteness(g, Q, POINTS)
    assert verdict.status == "refuted"
    # independent route: the entry, evaluated by sympy at the reported point, is negative
    value = entry.xreplace({k: v for k, v in verdict.point.items() if k in Q})
    assert sp.N(value, 30) < 0, (region, verdict.point)


def test_off_diagonal_metric_indefinite_on_a_narrow_region_is_refused():
    c = R(101, 100) * sp.sin(x)
    g = sp.Matrix([[1, c], [c, 1]])
    err = refused(metric=g)
    assert has(err, "metric: not positive definite"), err.problems
    verdict = definiteness(g, Q, POINTS)
    if verdict.status == "refuted":  # else a sampled point saw it already
        det = g.det().xreplace({k: v for k, v in verdict.point.items() if k in Q})
        assert sp.N(det, 30) < 0


@pytest.mark.parametrize(
    "g",
    [
        sp.diag(1, 1 + R(99, 100) * sp.sin(x)),  # interval bound 1/100 > 0
        sp.diag(1, x**2 - 2 * x + R(1001, 1000)),  # (x - 1)^2 + 1/1000: exact roots
        sp.diag(1, x**2),  # singular at x = 0 only
        sp.diag(1, 1 / x**2),  # positive where defined
        sp.Matrix([[2, sp.cos(x)], [sp.cos(x), 2]]),  # minors 2 and 4 - cos^2 x >= 3
        sp.Matrix([[1 + y**2, 0], [0, sp.exp(x) + sp.cosh(y)]]),
    ],
)
def test_positive_metrics_are_proven_without_a_warning(g: sp.Matrix):
    accepted(metric=g)
    assert definiteness(sp.Matrix(g), Q, POINTS).status == "proven"


def test_kinetic_energy_as_a_sum_of_squares_proves_the_metric():
    xd, yd = sm.velocities(Q)
    T = (xd + sp.cos(y) * yd) ** 2 / 2 + (sp.sin(y) * yd) ** 2 / 2 + yd**2
    scene = accepted(kinetic_energy=T)
    assert definiteness(scene.mass_matrix(), Q, POINTS, kinetic_energy=T).status == "proven"


def test_undecided_definiteness_warns_and_says_what_was_not_decided():
    # 3 - 2 sin x - 2 cos x >= 3 - 2 sqrt 2 > 0: true, but beyond the interval bound
    # (-1) and not a polynomial in x
    message = undecided(metric=sp.diag(1, 3 - 2 * sp.sin(x) - 2 * sp.cos(x)))
    assert "metric: positive definiteness is undecided" in message
    assert "not proven nonnegative" in message
    # a dip too narrow for the search (indefinite for |x| < 0.01) is refused from the
    # exact real roots of the entry (+-sqrt(log(101/100))/100)
    err = refused(metric=sp.diag(1, 1 - R(101, 100) * sp.exp(-(10**4) * x**2)))
    assert has(err, "has the exact real roots", "found from the exact real roots")
    # negative near x = 70.7, beyond the search, with roots solveset cannot list: said
    # undecided, not accepted in silence
    message = undecided(metric=sp.diag(1, 2 - sp.exp(x / 100) * sp.sin(x)))
    assert "may be indefinite elsewhere" in message


def test_interval_lower_bounds_are_rigorous():
    # checked against the exact minimum (independent route: calculus by hand)
    assert lower_bound(2 + sp.sin(x), {}) == 1
    assert lower_bound(x**2 - R(1, 100), {}) <= -R(1, 100)
    assert lower_bound(sp.cos(x) ** 2 + 1, {}) == 1
    assert lower_bound(1 / (x - 1), {}) is None  # unbounded: no bound claimed
    assert lower_bound(sp.log(x), {}) is None  # log of a non-positive range
    k = sp.Symbol("k", positive=True)
    assert lower_bound(1 + k * sp.sin(x), {k: R(1, 2)}) == R(1, 2)
    assert lower_bound(1 + k * sp.sin(x), {}) < 0  # k unbounded: not proven


# -- class 4: walls whose gradient vanishes on the wall ---------------------------------------

DEGENERATE_WALLS = [
    x**2,
    x**3,
    x**4,
    sp.sin(x) ** 2,
    1 - sp.cos(x),
    sp.exp(x**2) - 1,
    (x - 1) ** 2 * (y + 2),
    (y - 1) ** 2 * (x + 2),
    (x - y) ** 2,
    x**2 * y,
    (x**2 + y**2 - 1) ** 2,
    sp.sinh(x) ** 2,
]


@pytest.mark.parametrize("psi", DEGENERATE_WALLS, ids=str)
def test_wall_with_vanishing_gradient_on_the_wall_is_refused(psi: sp.Expr):
    err = refused(metric=sp.eye(2), walls=[sm.Wall(psi)])
    assert has(err, "walls[0].psi", "gradient d psi/dq vanishes on the wall"), err.problems
    point, _ = vanishing_gradient(psi, Q, POINTS)
    assert point is not None
    # independent route: psi and both partial derivatives vanish there (sympy, 30 digits)
    at = {k: v for k, v in point.items() if k in Q}
    for e in (psi, sp.diff(psi, x), sp.diff(psi, y)):
        assert abs(sp.N(e.xreplace(at), 30)) < 1e-12, (psi, e, at)


@pytest.mark.parametrize(
    "psi",
    [
        x,
        y - x**2,
        x * y,  # d psi = 0 only at the origin, a single point of the wall
        y - sp.sin(x),
        x**2 + y**2 - 1,
        x**3 - y,
        x - y**3,  # d psi/dx = 1: regular everywhere, decided without solving
        sp.exp(x) - 2,
    ],
    ids=str,
)
def test_regular_walls_are_accepted(psi: sp.Expr):
    scene = accepted(metric=sp.eye(2), walls=[sm.Wall(psi)])
    assert scene.impact_map(0).matrix.shape == (2, 2)


def test_wall_never_reached_is_accepted_with_a_warning():
    message = undecided(metric=sp.eye(2), walls=[sm.Wall(x**2 + y**2)])
    assert "walls[0].psi = x**2 + y**2: no point of the wall psi = 0 was found" in message


def test_degenerate_walls_are_refused_in_scene_files(tmp_path: Path):
    for psi in ("x**2", "sin(x)**2", "(x-1)**2*(y+2)", "1 - cos(x)"):
        err = file_refused(BASE + f'[[walls]]\npsi = "{psi}"\n', tmp_path)
        assert err.details[0][:2] == ("walls[0].psi", 4), err.details
        assert "gradient d psi/dq vanishes on the wall" in str(err)


# -- class 4: fields that are not real, special functions -------------------------------------


def test_complex_fields_are_refused():
    xd, _ = sm.velocities(Q)
    err = refused(metric=sp.eye(2), potential=sp.I * x)
    assert has(err, "potential: is not real: it holds the imaginary unit I")
    err = refused(metric=sp.diag(1, 1 + sp.I * x))
    assert has(err, "metric: entry [1,1] = I*x + 1: is not real")
    err = refused(metric=sp.eye(2), constraints=[xd + sp.I * x * xd])
    assert has(err, "constraints[0]: is not real")
    with pytest.raises(sm.SceneError, match="wall: psi is not real"):
        sm.Wall(y - sp.I)


def test_symbols_declared_non_real_are_refused():
    z = sp.Symbol("z", imaginary=True)
    assert (1 + z**2).subs(z, 2 * sp.I) < 0  # independent: the entry can be negative
    err = refused(metric=sp.diag(1, 1 + z**2))
    assert has(err, "metric: entry [1,1] = z**2 + 1: is not real", "declared non-real (z")
    err = refused(metric=sp.eye(2), potential=z * x)
    assert has(err, "potential: is not real", "(z")


@pytest.mark.parametrize("bad", [sp.sqrt(-(x**2) - 1), sp.log(-1 - x**2), sp.asin(2 + x**2)])
def test_fields_never_real_are_refused(bad: sp.Expr):
    # independent route: complex at a few points by sympy's own evaluation
    for v in (0, 1, -3):
        assert sp.im(sp.N(bad.subs(x, v))) != 0
    err = refused(metric=sp.eye(2), potential=bad)
    assert has(err, "potential =", "not real at any sampled point"), err.problems
    err = refused(metric=sp.eye(2), walls=[sm.Wall(y + bad)])
    assert has(err, "walls[0].psi =", "not real at any sampled point"), err.problems


def test_field_real_on_part_of_the_domain_warns():
    message = undecided(metric=sp.eye(2), potential=sp.sqrt(x))
    assert "potential = sqrt(x): not real at the sampled point" in message
    assert "real domain is restricted" in message


def test_never_real_in_a_scene_file():
    err = file_refused(BASE + 'potential = "sqrt(-x**2 - 1)"\n')
    assert err.details[0][:2] == ("potential", 3)
    assert "not real at any sampled point" in str(err)


SPECIAL = [
    sp.zeta(x),
    sp.gamma(x),
    sp.besselj(0, x),
    sp.LambertW(x),
    sp.polylog(2, x),
    sp.hyper([1], [2], x),
    sp.erf(x),
    sp.Ei(x),
    sp.airyai(x),
    sp.elliptic_k(x),
    sp.loggamma(x),
    sp.dirichlet_eta(x),
    sp.factorial(x),
    sp.binomial(x, 2),
    sp.KroneckerDelta(x, y),
    sp.LeviCivita(x, y),
    sp.Ynm(1, 1, x, y),
]
UNEVALUATED = [
    sp.Integral(sp.exp(-(y**2)), (y, 0, x)),
    sp.Sum(x ** sp.Symbol("k", integer=True), (sp.Symbol("k", integer=True), 0, 3)),
    sp.Subs(sp.sin(x), x, y),
    sp.Derivative(sp.sin(x), x, evaluate=False),
]


@pytest.mark.parametrize("f", SPECIAL + UNEVALUATED, ids=lambda f: type(f).__name__)
def test_special_functions_are_refused_in_every_field(f: sp.Expr):
    name = type(f).__name__
    what = "calls" if f in SPECIAL else "holds an unevaluated"
    err = refused(metric=sp.eye(2), potential=f)
    assert has(err, "potential", what), err.problems
    err = refused(metric=sp.diag(1, 1 + f**2))
    assert has(err, "metric: entry [1,1]", what), err.problems
    with pytest.raises(sm.SceneError, match=f"wall: psi {what}"):
        sm.Wall(y - f)
    if f in SPECIAL:
        assert has(err, name)


def test_zeta_is_refused_before_any_derivation():
    # differentiating zeta(x) (the forcing) once ended in a raw sympy ArgumentIndexError
    # whose str() itself raises: the declaration refuses zeta before anything is derived
    err = refused(metric=sp.eye(2), potential=sp.zeta(x))
    assert err.problems == [
        "potential: calls zeta, which symmech does not support (not an elementary function:"
        " sin, cos, ..., exp, log, atan2 and their kin; an undefined sympy.Function can stand"
        " for it)"
    ]


def test_an_undefined_function_stands_for_a_special_one():
    G = sp.Function("G", positive=True)
    scene = accepted(metric=sp.eye(2), potential=G(x))
    assert scene.forcing()[0] == -sp.Derivative(G(x), x)


def test_special_functions_in_scene_files_are_refused():
    for f in ("zeta(x)", "gamma(x)", "besselj(0, x)", "LambertW(x)"):
        err = file_refused(BASE + f'potential = "{f}"\n')
        assert err.details[0][:2] == ("potential", 3)
        assert "is not allowed" in str(err)


# -- class 5: constants merged by sympy -----------------------------------------------------

F64_MAX = mpmath.mpf(sys.float_info.max)
F64_TINY = mpmath.mpf(2) ** -1074  # smallest subnormal

# (value built in Python, its exact magnitude for the independent check)
MERGED = [
    (sp.exp(709) * sp.exp(709) * x, mpmath.exp(1418)),
    (x * sp.exp(-745) * sp.exp(-745), mpmath.exp(-1490)),
    (sp.Mul(*[sp.pi**64] * 12) * x, mpmath.pi**768),
    (sp.exp(709) ** 2 * x, mpmath.exp(1418)),
    (x / sp.exp(745) / sp.exp(745), mpmath.exp(-1490)),
    (sp.Float(1e308) * 10 * x, mpmath.mpf(10) ** 309),
    (sp.Float(1e308) * x + sp.Float(1e308) * x, 2 * mpmath.mpf(1e308)),
    (3 * sp.exp(709) * x, 3 * mpmath.exp(709)),
    (sp.Float(1e-200) * sp.Float(1e-200) * x, mpmath.mpf(10) ** -400),
    (x**2 + sp.exp(-400) * sp.exp(-400), mpmath.exp(-800)),
    (sp.sin(x * sp.exp(400) * sp.exp(400)), mpmath.exp(800)),
]


@pytest.mark.parametrize(("value", "magnitude"), MERGED, ids=lambda v: str(v)[:30])
def test_merged_constants_outside_float64_are_refused_in_every_field(value, magnitude):
    assert magnitude > F64_MAX or magnitude < F64_TINY  # independent: outside float64
    assert constant_out_of_range(value) is not None
    err = refused(metric=sp.eye(2), potential=value)
    assert has(err, "potential: holds the", "float64"), err.problems
    err = refused(metric=sp.diag(1, 1 + value**2))
    assert has(err, "metric: entry [1,1]", "float64"), err.problems
    with pytest.raises(sm.SceneError, match="wall: psi holds the"):
        sm.Wall(y - value)


@pytest.mark.parametrize(
    "value",
    [
        sp.Integer(10) ** 308 * 10 * x,
        sp.Rational(10**400, 3) * x,
        sp.Rational(1, 10**400) + x,
        sp.Rational(10**150 + 1, 10**150) * x,
        sp.Mul(sp.Integer(10) ** 200, sp.Integer(10) ** 200, x, evaluate=False),
    ],
    ids=["10**308*10", "10**400/3", "1/10**400", "150 digits", "unevaluated product"],
)
def test_huge_exact_numbers_are_refused(value: sp.Expr):
    err = refused(metric=sp.eye(2), potential=value)
    assert has(err, "potential: holds the", "digits (limit 100)") or has(
        err, "potential: holds the", "float64"
    ), err.problems


def test_constants_of_other_fields_and_sympy_floats():
    # a sympy Float holds 1e400 (its exponent is unbounded); float64 does not
    assert mpmath.mpf(10) ** 400 > F64_MAX
    err = refused(metric=sp.eye(2), potential=sp.Float("1e400") * x)
    assert has(err, "potential: holds the constant", "outside the range of float64")
    err = refused(metric=sp.eye(2), walls=[sm.Wall(y, restitution=sp.exp(-800))])
    assert has(err, "walls[0].restitution: holds the constant exp(-800)", "underflows")
    xd, yd = sm.velocities(Q)
    err = refused(metric=sp.eye(2), constraints=[xd + sp.exp(709) * sp.exp(709) * yd])
    assert has(err, "constraints[0]: holds the", "exp(1418)", "float64")


@pytest.mark.parametrize(
    "value",
    [
        sp.exp(709) * x,  # 8.2e307
        sp.exp(-708) * x,  # 3.3e-308, normal
        sp.Float(1e-200) * x * sp.Float(1e-200) * sp.Float(1e300),  # 1e-100 (log space)
        sp.exp(709) * x + sp.exp(709) * y,  # each term in range
        sp.pi**128 * x,
    ],
    ids=str,
)
def test_constants_inside_float64_are_accepted(value: sp.Expr):
    accepted(metric=sp.eye(2), potential=value)


MERGED_TEXT = [
    "exp(709)*exp(709)*x",
    "x*exp(-745)*exp(-745)",
    "*".join(["pi**64"] * 12) + "*x",
    "exp(709)**2*x",
    "x/exp(745)/exp(745)",
    "1e308*x + 1e308*x",
    "3*exp(709)*x",
    "(exp(400)*x)**2",
    "x**2 + exp(-400)*exp(-400)",
    "sin(x*exp(400)*exp(400))",
    "(1 + x)*exp(709)*exp(709)",
]


@pytest.mark.parametrize("text", MERGED_TEXT)
def test_merged_constants_are_refused_by_the_parser_and_in_scene_files(text: str, tmp_path):
    with pytest.raises(sm.ExpressionError, match="float64"):
        parse_expression(text, {"x": x})
    err = file_refused(BASE + f'potential = "{text}"\n', tmp_path)
    assert err.details[0][:2] == ("potential", 3), err.details
    assert "float64" in str(err)
    err = file_refused(f'coordinates = ["x", "y"]\nmetric = [1, "1 + ({text})**2"]\n')
    assert err.details[0][:2] == ("metric[1,1]", 2), err.details


def test_merged_constants_in_a_wall_of_a_scene_file():
    err = file_refused(BASE + '[[walls]]\npsi = "y - exp(709)*exp(709)"\n')
    assert err.details[0][:2] == ("walls[0].psi", 4), err.details


def test_walls_given_as_strings_are_checked_like_sympy_walls():
    for text, needle in [
        ("x**2", "gradient d psi/dq vanishes on the wall"),
        ("zeta(x)", "function 'zeta' is not allowed"),
        ("y - exp(709)*exp(709)", "outside the range of float64"),
        ("sqrt(-x**2 - 1)", "not real at any sampled point"),
    ]:
        err = refused(metric=sp.eye(2), walls=[sm.Wall(text)])
        assert has(err, "walls[0].psi", needle), err.problems
