"""Exponentials stay whole in generated code: the stable form must not split
exp(-(x - c)^2/s^2) into factors that overflow where the exponential itself is tiny."""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

import symmech as sm
from symmech.algebra.stability import stable_coefficient


def test_stable_coefficient_keeps_exponentials_whole():
    x, y, c, s, h = sp.symbols("x y c s h", positive=True)
    e = y - h * sp.exp(-(((x - c) / s) ** 2))
    out = stable_coefficient(e, (x, y))
    assert sp.simplify(out - e) == 0
    # every exponential of the result is the original one (no split of its argument)
    assert out.atoms(sp.exp) == e.atoms(sp.exp)
    f = sp.lambdify((x, y, c, s, h), out, "math")
    assert f(0.0, 0.5, 5.0, 0.01, 1.0) == 0.5


@pytest.mark.parametrize("target", ["c", "numpy"])
def test_a_narrow_gaussian_bump_wall_evaluates_far_from_its_centre(target):
    x, y = sm.coordinates("x y")
    h, c, s = sp.symbols("h c s", positive=True)
    scene = sm.Scene(
        (x, y),
        metric=sp.eye(2),
        walls=[sm.Wall(y - h * sp.exp(-(((x - c) / s) ** 2)), restitution=1, name="bump")],
        name="bump",
    )
    mod = sm.codegen.generate(scene, target).load()
    p = {"h": 1.0, "c": 5.0, "s": 0.01}
    for xv in (0.0, 4.99, 5.0, 5.005, 100.0):
        psi = float(mod.psi([xv, 0.5], p))
        assert psi == pytest.approx(0.5 - math.exp(-(((xv - 5.0) / 0.01) ** 2)), abs=1e-15)
        grad = mod.dpsi([xv, 0.5], p)
        assert np.all(np.isfinite(grad))
