"""The NumPy module's one-state variants ``_one_<name>`` (plain floats, ``math``): the same
results as the vectorised functions for every function of every built-in scene that has
one, failures and unusual arguments passed on to the general path (which raises or explains
as before), and the variant actually taken for plain one-state calls."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import symmech as sm
from symmech.codegen import CodegenError, NumericalError
from symmech.examples import carnot_3_7, carnot_3_13, carnot_4_4, pendulum_on_cart


@pytest.mark.parametrize(
    ("build", "strategy"),
    [
        (lambda: pendulum_on_cart(3), "linear_solve"),
        (lambda: pendulum_on_cart(2), "closed_form"),
        (carnot_3_7, "auto"),
        (carnot_3_13, "auto"),
        (carnot_4_4, "auto"),
    ],
)
def test_one_state_variant_matches_the_vectorised_function(build, strategy):
    code = sm.codegen.generate(build(), "numpy", strategy=strategy, projectors=True)
    mod = code.load()
    module = mod._raw  # the general callers
    with_variant = [f for f in code.functions if f.scalar is not None]
    assert with_variant, "no function got a one-state variant"
    rng = np.random.default_rng(11)
    p = 0.5 + rng.random(len(mod.parameters))
    for rule in code.parameter_rules:  # a restitution must lie in [0, 1]
        if rule.upper is not None:
            p[rule.index] = 0.5 * (rule.upper + (rule.lower or 0.0))
    for f in with_variant:
        assert f.name in mod._fast
        for _ in range(4):
            q, v = rng.normal(size=mod.n), rng.normal(size=mod.n)
            args = [np.concatenate([q, v])] if f.state == ("y",) else [q, v][: len(f.state)]
            try:
                general = module[f.name](tuple(args), p if f.takes_parameters else None, None, None)
            except NumericalError:
                continue  # (a random state may be singular for a closed form)
            one = mod._fast[f.name](tuple(args), p if f.takes_parameters else None)
            assert one is not None, f.name
            np.testing.assert_allclose(one, general, rtol=4e-15, atol=1e-300, err_msg=f.name)
            assert one.shape == general.shape


def test_plain_calls_take_the_variant_and_others_the_general_path(monkeypatch):
    mod = sm.codegen.generate(pendulum_on_cart(2), "numpy", strategy="linear_solve").load()
    assert "plain floats" in mod.fast_path
    q, v, p = np.zeros(3), np.ones(3), np.ones(len(mod.parameters))
    calls = []
    fast = mod._fast["acceleration"]
    monkeypatch.setitem(mod._fast, "acceleration", lambda s, pp: calls.append(1) or fast(s, pp))
    ref = mod.acceleration(q, v, p)
    assert calls
    np.testing.assert_array_equal(mod.acceleration(list(q), list(v), list(p)), ref)
    # unusual arguments: the general path converts or refuses them with its messages
    np.testing.assert_allclose(mod.acceleration(q.astype(np.float32), v, p), ref, rtol=1e-6)
    with pytest.raises(CodegenError):
        mod.acceleration([True, False, True], v, p)
    with pytest.raises(CodegenError):
        mod.acceleration(q + 1j, v, p)
    bad = p.copy()
    bad[0] = -1.0
    with pytest.raises(NumericalError, match="parameter"):
        mod.acceleration(q, v, bad)


def test_a_failure_in_the_variant_is_reported_by_the_general_path():
    x, y = sm.coordinates("x y")
    a = sp.Symbol("a")
    # g = [[4, a], [a, 4]]: positive definite for |a| < 4 only (a declared without a sign)
    scene = sm.Scene((x, y), metric=[[4, a], [a, 4]], potential=x**2 + y**2)
    mod = sm.codegen.generate(scene, "numpy", strategy="linear_solve").load()
    assert mod._fast["acceleration"]((np.ones(2), np.zeros(2)), np.array([5.0])) is None
    with pytest.raises(NumericalError, match="positive definite"):
        mod.acceleration(np.ones(2), np.zeros(2), [5.0])
    np.testing.assert_allclose(
        mod._fast["acceleration"]((np.ones(2), np.zeros(2)), np.array([1.0])),
        mod.acceleration(np.ones((1, 2)), np.zeros((1, 2)), [1.0])[0],
        rtol=1e-15,
    )
    # math raises where numpy returns inf: the general path reports the non-finite output
    s2 = sm.Scene((x,), metric=[[1]], potential=sp.exp(a * x))
    m2 = sm.codegen.generate(s2, "numpy").load()
    with pytest.raises(NumericalError, match="not finite"):
        m2.acceleration([1000.0], [0.0], [1.0])


@pytest.mark.parametrize("speed", [1e-300, 1e-150, 1.0, 1e150, 1e300])
def test_the_scaled_impact_variant_is_scale_invariant_as_the_vectorised_one(speed):
    """A static wall's impact map is evaluated for v / 2^e and scaled back, so that no
    intermediate under- or overflows (the energy law's map holds square roots of quadratic
    forms in v); its one-state variant scales by the same exponent."""
    from symmech.examples import spinning_disk

    mod = sm.codegen.generate(spinning_disk(), "numpy").load()
    (name,) = [f.name for f in mod.code.functions if f.scaled]
    assert name in mod._fast
    p = np.full(len(mod.parameters), 0.7)
    rng = np.random.default_rng(5)
    q, v = rng.normal(size=mod.n), speed * rng.normal(size=mod.n)
    one = mod._fast[name]((q, v), p)
    general = mod._raw[name]((q, v), p, None, None)
    assert one is not None and np.all(np.isfinite(one)), one
    np.testing.assert_allclose(one, general, rtol=4e-15, atol=0)
    unit = mod._fast[name]((q, v / speed), p)
    np.testing.assert_allclose(one / speed, unit, rtol=4e-15, atol=0)
