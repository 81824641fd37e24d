"""Tiny and huge speeds at an impact (issue 10, class 7): the impact map of a static wall
is linear in v, and the generated code evaluates it scale-invariantly (for v 2^-e, scaled
back by 2^e), so |v-| = 1e-300, 1e300 or a subnormal speed with an ellipse of aspect 1e8
gives the mpmath answer, and a power-of-two speed gives exactly the scaled unit answer.

The reference is the impulse-momentum (KKT) system of the scene's metric and wall gradient
solved by LU in mpmath at 50 digits (``codegen_support.kkt_solution``), not the generated
code or its closed form.
"""

from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest
import sympy as sp
from codegen_support import kkt_solution, require_c_compiler

import symmech as sm
from symmech.examples import bouncing_ellipse, spinning_disk

U = 2.0**-53
TINY = 2.0**-1074  # the spacing of the subnormal doubles

#: (I, a, b, m): ellipses of aspect 1e8 with small and large masses and inertias.
SHAPES = [
    (1.0, 1.0, 1e-8, 1.0),
    (1.0, 1e-8, 1.0, 1.0),
    (1e-8, 1e-8, 1.0, 1.0),
    (1e8, 1e-8, 1.0, 1.0),
    (1.0, 1e4, 1e-4, 1e-8),
]
ANGLES = [0.0, 1e-9, 0.3, 1.5707963, 3.0]
SPEEDS = [1e-300, 1e300, 1e-310, 2.0**-1060, 1.0]
DIRECTION = np.array([0.3, -1.0, 0.7])


def _reference(scene: sm.Scene, q, v, params) -> list[mp.mpf]:
    """v+ of the Newton law at restitution alpha: g (v+ - v) = dpsi^T lam,
    dpsi v+ = -alpha dpsi v, by LU of the KKT system at 50 digits."""
    wall = scene.walls[0]
    env = {s: sp.Float(x, 60) for s, x in zip(scene.coordinates, q, strict=True)}
    env |= {p: sp.Float(params[p.name], 60) for p in scene.parameters}
    with mp.workdps(50):
        n = scene.n
        M = mp.matrix(n, n)
        for i in range(n):
            for j in range(n):
                M[i, j] = mp.mpf(str(sp.N(scene.mass_matrix()[i, j].subs(env), 50)))
        A = mp.matrix(1, n)
        for i, qi in enumerate(scene.coordinates):
            A[0, i] = mp.mpf(str(sp.N(sp.diff(wall.psi, qi).subs(env), 50)))
        vv = mp.matrix([mp.mpf(float(x)) for x in v])
        alpha = mp.mpf(str(sp.N(wall.restitution.subs(env), 50)))
        b = mp.matrix([-alpha * (A * vv)[0]])
        x, _ = kkt_solution(M, M * vv, A, b)
        return [x[i] for i in range(n)]


@pytest.fixture(scope="module")
def modules():
    scene = bouncing_ellipse()
    out = {}
    for target in ("c", "numpy"):
        if target == "c":
            require_c_compiler()
        for strategy in ("closed_form", "linear_solve"):
            code = sm.codegen.generate(scene, target, strategy=strategy)
            out[target, strategy] = code.load()
            if target == "c":
                out["c-ctypes", strategy] = code.load(extension=False)
    return scene, out


@pytest.mark.parametrize("shape", SHAPES, ids=lambda s: "I={},a={},b={},m={}".format(*s))
def test_tiny_and_huge_speeds_against_mpmath(modules, shape):
    """Error within 2^-40 of the largest entry of the 50-digit KKT solution (plus the
    spacing 2^-1074 of a subnormal output) at every speed, on every route; at a tiny or huge
    normal speed no worse than 4 times the relative error at speed 1 plus a few roundings
    (the scaling itself is exact)."""
    scene, mods = modules
    params = dict(zip(("I", "a", "b", "m"), shape, strict=True))
    for theta in ANGLES:
        q = [-3.0, 0.5, theta]
        errors = {}
        for speed in SPEEDS:
            v = DIRECTION * speed
            ref = _reference(scene, q, v, params)
            scale = max(abs(r) for r in ref)
            for key, mod in mods.items():
                out = mod.impact(q, v, params)
                assert np.all(np.isfinite(out)), (key, speed, out)
                err = max(abs(mp.mpf(float(o)) - r) for o, r in zip(out, ref, strict=True))
                errors[key, speed] = float(err / scale)
                # a subnormal output is exact only to its spacing 2^-1074
                assert err <= 2.0**-40 * scale + TINY, (key, theta, speed, out, ref)
        for (key, speed), err in errors.items():
            if speed >= 1e-300:  # not a subnormal speed (its output has few digits)
                assert err <= 4 * errors[key, 1.0] + 8 * U, (key, theta, speed, errors)


@pytest.mark.parametrize("route", ["c", "c-ctypes", "numpy"])
def test_a_power_of_two_speed_gives_exactly_the_scaled_answer(modules, route):
    """v+(2^k v) = 2^k v+(v) bit for bit, from 2^-1000 to 2^1000 (the scaling is exact)."""
    _, mods = modules
    params = {"I": 1.0, "a": 1.0, "b": 1e-8, "m": 1.0}
    for strategy in ("closed_form", "linear_solve"):
        mod = mods[route, strategy]
        for theta in ANGLES:
            q = [-3.0, 0.5, theta]
            unit = mod.impact(q, DIRECTION, params)
            for k in (-1000, -300, -1, 1, 300, 1000):
                out = mod.impact(q, np.ldexp(DIRECTION, k), params)
                np.testing.assert_array_equal(out, np.ldexp(unit, k), err_msg=f"{strategy} {k}")


def test_a_batch_mixing_tiny_huge_and_zero_speeds(modules):
    """Each state is scaled by its own speed; a zero speed gives zero, a NaN is refused."""
    scene, mods = modules
    params = {"I": 1.0, "a": 1.0, "b": 1e-8, "m": 1.0}
    q = np.array([[-3.0, 0.5, 0.3]] * 4)
    v = np.array([DIRECTION * 1e-300, DIRECTION * 1e300, np.zeros(3), DIRECTION])
    for key, mod in mods.items():
        out = mod.impact(q, v, params)
        np.testing.assert_array_equal(out[2], np.zeros(3))
        for i in (0, 1, 3):
            ref = _reference(scene, q[i], v[i], params)
            scale = max(abs(r) for r in ref)
            err = max(abs(mp.mpf(float(o)) - r) for o, r in zip(out[i], ref, strict=True))
            assert err / scale < 2.0**-40, (key, i)
        bad = v.copy()
        bad[1, 0] = np.nan
        # the C batch names the failing state; NumPy's linear solve fails as a whole
        where = "state 1" if key[0] != "numpy" or key[1] == "closed_form" else "not finite"
        with pytest.raises(sm.codegen.NumericalError, match=where):
            mod.impact(q, bad, params)


@pytest.mark.parametrize("target", ["c", "numpy"])
def test_the_energy_law_is_scale_invariant_too(target):
    """The energy law's map is homogeneous of degree 1 in v (a square root of a quadratic
    form): also evaluated scale-invariantly."""
    if target == "c":
        require_c_compiler()
    mod = sm.codegen.generate(spinning_disk("energy"), target).load()
    assert mod._spec["impact_wall"].scaled
    p = np.full(len(mod.parameters), 0.5)
    q, v = np.array([-2.0, 0.1, 0.2]), np.array([1.0, -0.5, 0.25])
    unit = mod.impact(q, v, p)
    for k in (-1040, -1000, 1000):
        np.testing.assert_array_equal(mod.impact(q, np.ldexp(v, k), p), np.ldexp(unit, k))


def test_a_moving_wall_is_not_scaled():
    """A moving wall's map is affine in v (the psi_t term): evaluated as it is."""
    from symmech.examples import carnot_4_4

    code = sm.codegen.generate(carnot_4_4(), "numpy")
    assert not next(f for f in code.functions if f.kind == "impact").scaled
