"""The stabilising step (symmech.algebra.stability): closed forms that keep their digits in
float64, checked against mpmath at 50 digits."""

from __future__ import annotations

import mpmath as mp
import pytest
import sympy as sp
from test_impacts_support import impact_map

import symmech as sm
from symmech.algebra.stability import stable_coefficient, stable_entry, stable_linear
from symmech.algebra.zero import evidently_nonzero
from symmech.impacts import derive_impact_map

I, m, R, k, a, b, x, y = sp.symbols("I m R k a b x y", positive=True)
theta = sp.Symbol("theta", real=True)
phi = sp.Symbol("phi", real=True)


def rel_err(value: float, exact) -> float:
    return float(abs((mp.mpf(value) - exact) / exact))


def test_text001_rebound_coefficient():
    I1 = I + m * R**2
    printed = I / m - I**2 * R**2 / I1**2 - I**3 / (m * I1**2)
    stable = stable_coefficient(printed)
    assert sp.simplify(stable - I * R**2 / I1) == 0
    f_stable = sp.lambdify((I, m, R), stable, "math")
    f_printed = sp.lambdify((I, m, R), printed, "math")
    with mp.workdps(50):
        exact = mp.mpf(1) * mp.mpf("1e-9") ** 2 / (1 + mp.mpf("1e-9") ** 2)
        assert rel_err(f_stable(1.0, 1.0, 1e-9), exact) < 1e-15
        assert rel_err(f_printed(1.0, 1.0, 1e-9), exact) > 0.5


def test_one_minus_a_fraction():
    assert stable_coefficient(1 - x / (x + y)) == y / (x + y)


def test_a_product_over_a_radical_of_the_state_is_written_stably():
    """A wall's gradient (the ellipse's support function), as a product or as a flat sum:
    (a^2 - b^2) sin cos / root becomes (a - b)(a + b) sin cos / root."""
    root = sp.sqrt(a**2 * sp.cos(theta) ** 2 + b**2 * sp.sin(theta) ** 2)
    expr = (a**2 - b**2) * sp.sin(theta) * sp.cos(theta) / root
    for written in (expr, sp.expand(expr)):
        stable = stable_entry(written, state=(theta,))
        assert stable.has(a - b) and stable.has(a + b)
        assert sp.simplify(stable - expr) == 0


def test_a_sum_over_a_radical_of_the_state_is_kept_or_proven_zero():
    """A sum of products of sums over a radical of the state (the bicycle's rolling
    constraints) is kept as written: over a common denominator, expanded, it would grow;
    one that is identically zero (by the circle relation here, which cancel does not
    know) becomes 0."""
    root = sp.sqrt(2 + sp.sin(theta) * sp.cos(phi))
    kept = a * sp.sin(theta) * sp.cos(phi) + b * (sp.cos(theta) + sp.sin(phi)) ** 2 / root
    assert stable_entry(kept, state=(theta, phi)) == kept
    assert sp.count_ops(stable_coefficient(kept, state=(theta, phi))) > sp.count_ops(kept)
    zero = (
        a * (sp.cos(phi) + 1) / root
        - a * (sp.cos(phi) + 1) * (sp.sin(theta) ** 2 + sp.cos(theta) ** 2) / root
    )
    assert isinstance(zero, sp.Add) and zero != 0
    assert stable_entry(zero, state=(theta, phi)) == 0
    assert evidently_nonzero(kept) and not evidently_nonzero(zero)


def test_state_monomials_get_factored_coefficients():
    """I + m (a^4 - 2 a^2 b^2 + b^4) sin^2: the coefficient of sin^2 becomes
    m (a - b)^2 (a + b)^2, which keeps its digits for a ~ b."""
    expr = I + m * sp.expand((a**2 - b**2) ** 2) * sp.sin(theta) ** 2
    stable = stable_coefficient(expr, state=(theta,))
    assert stable.has((a - b) ** 2)
    assert sp.expand(stable - expr) == 0
    f_stable = sp.lambdify((I, m, a, b, theta), stable, "math")
    f_plain = sp.lambdify((I, m, a, b, theta), sp.expand(expr), "math")
    args = (1e-24, 1.0, 1.0 + 1e-7, 1.0, 0.5)
    with mp.workdps(50):
        ap = mp.mpf(args[2])
        exact = mp.mpf(args[0]) + (ap**2 - 1) ** 2 * mp.sin(mp.mpf(0.5)) ** 2
        assert rel_err(f_stable(*args), exact) < 1e-12
        assert rel_err(f_plain(*args), exact) > 1e-6


def test_many_symbols_take_the_gathered_route_and_stay_stable(monkeypatch):
    """Over STABLE_FACTOR_GENERATORS symbols nothing is factored as a whole, yet the
    difference of nearly equal terms is still combined: (1 - x/(x+y)) S, with S a sum of
    many symbols, becomes y S/(x + y); I + m (a^2 - b^2)^2 sin^2 + ... keeps its
    factored coefficient of sin^2."""
    from symmech.algebra import budget, stability

    calls = []
    real = stability._gathered
    monkeypatch.setattr(
        stability, "_gathered", lambda part, st: calls.append(part) or real(part, st)
    )
    extra = sp.symbols(f"s0:{budget.STABLE_FACTOR_GENERATORS}", positive=True)
    S = sp.Add(*extra)
    out = stable_coefficient((1 - x / (x + y)) * S)
    assert calls, "the expression did not take the gathered route"
    assert sp.simplify(out - y * S / (x + y)) == 0
    f_out = sp.lambdify((x, y, *extra), out, "math")
    args = (1.0, 1e-12, *([1.0] * len(extra)))
    with mp.workdps(50):
        exact = mp.mpf(len(extra)) * (1 - mp.mpf(1) / (1 + mp.mpf(1e-12)))
        assert rel_err(f_out(*args), exact) < 1e-14
    calls.clear()
    expr = (
        I
        + m * sp.expand((a**2 - b**2) ** 2) * sp.sin(theta) ** 2
        + sp.expand(S * sp.cos(theta) * (x + y))
    )
    stable = stable_coefficient(expr, state=(theta,))
    assert calls
    assert stable.has((a - b) ** 2)
    assert sp.expand(stable - expr) == 0


def test_stable_linear_keeps_velocity_coefficients_apart():
    v1, v2 = sp.symbols("v1 v2", real=True)
    expr = (1 - x / (x + y)) * v1 + (x + y) * v2 / (x + y) ** 2 + 3
    out = stable_linear(expr, (v1, v2))
    assert out == y * v1 / (x + y) + v2 / (x + y) + 3
    with pytest.raises(ValueError, match="not affine"):
        stable_linear(v1 * v2, (v1, v2))


def test_impact_map_entries_are_stable_and_the_raw_form_is_not():
    """Example 3.7's theta_dot+ coefficient k^2/(R^2 + k^2): built as 1 - R^2/(R^2 + k^2)
    (simplify='none') it loses every digit when k << R."""
    X, Y, TH = sm.coordinates("x y theta")
    xd, _yd, thd = sm.velocities((X, Y, TH))
    wall = sm.Wall(Y - R, impulsive_constraints=[xd - R * thd])
    scene = sm.Scene((X, Y, TH), metric=sp.diag(m, m, m * k**2), walls=[wall])
    stable = impact_map(scene, 0).matrix[2, 2]
    raw = derive_impact_map(scene.declaration, 0, simplify="none").matrix[2, 2]
    assert sp.cancel(stable - raw) == 0
    f_stable = sp.lambdify((m, k, R), stable, "math")
    f_raw = sp.lambdify((m, k, R), raw, "math")
    with mp.workdps(50):
        kk = mp.mpf("1e-9")
        exact = kk**2 / (1 + kk**2)
        assert rel_err(f_stable(1.0, 1e-9, 1.0), exact) < 1e-15
        assert rel_err(f_raw(1.0, 1e-9, 1.0), exact) > 0.5
