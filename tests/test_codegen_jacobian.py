"""The emitted Jacobian d(rhs)/dy (``generate(..., jacobian=True)``) against central
differences of the emitted rhs, and its absence unless asked for."""

from __future__ import annotations

import numpy as np
import pytest

import symmech as sm
from symmech.examples import carnot_3_7, ellipse_gravity, pendulum_wall, stiff_dumbbell


@pytest.mark.parametrize("target", ["c", "numpy"])
@pytest.mark.parametrize("build", [stiff_dumbbell, ellipse_gravity, pendulum_wall, carnot_3_7])
def test_jacobian_matches_central_differences_of_rhs(build, target):
    scene = build()
    mod = sm.codegen.generate(scene, target, jacobian=True).load()
    rng = np.random.default_rng(7)
    params = {str(p): float(rng.uniform(0.5, 2.0)) for p in scene.parameters}
    if "alpha" in params:
        params["alpha"] = 0.5
    for _ in range(5):
        y = rng.uniform(-1.0, 1.0, 2 * scene.n)
        J = mod.call("jacobian", y, params=params)
        h = 1e-5
        cols = [
            (mod.rhs(y + h * e, params) - mod.rhs(y - h * e, params)) / (2 * h)
            for e in np.eye(2 * scene.n)
        ]
        numeric = np.column_stack(cols)
        scale = max(1.0, float(np.max(np.abs(J))))
        assert np.max(np.abs(J - numeric)) < 1e-7 * scale


def test_jacobian_is_emitted_only_when_asked_for():
    code = sm.codegen.generate(stiff_dumbbell(), "numpy")
    assert "jacobian" not in [f.name for f in code.functions]
