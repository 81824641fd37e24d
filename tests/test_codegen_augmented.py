"""``augmented_rhs``: the simulator's right-hand side with the walls' gaps, ``(q_dot,
v_dot, r_1 .. r_W)`` with ``r_w = dpsi_w(q) q_dot + psi_t`` (the chain rule), in one
call.

Checked against independent routes: the derivative of psi along the motion by central
differences (psi at ``(t +- h, q +- h q_dot)``) and by sympy's own d/dt of psi(t, q(t)) at
40 digits; the first 2n entries are ``rhs``'s, bit for bit (the same call of
acceleration); one state and a batch, NumPy and C, on a scene whose kinematics is not the
identity (the rolling ball's frame) with a moving wall and a static one."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from codegen_support import require_c_compiler

import symmech as sm
from symmech import codegen
from symmech.scenefile import read_scene

PARAMS = {"a": 0.7, "m": 1.3, "I": 0.4, "g": 9.81}


def _scene() -> sm.Scene:
    """The rolling ball (q_dot = S(q) v, S its frame), with a cone theta >= 0.3 + sin(t)/10
    that moves and a stop phi >= -2 that does not."""
    ball = read_scene("rolling_ball").scene
    phi, theta, _ = ball.coordinates
    walls = [
        sm.Wall(theta - sp.Rational(3, 10) - sp.sin(sm.t) / 10, restitution=1, name="cone"),
        sm.Wall(phi + 2, restitution=1, name="stop"),
    ]
    return ball.replace(walls=walls, name="ball_cone")


def _values(scene: sm.Scene) -> dict[str, float]:
    return {str(p): PARAMS.get(str(p), 0.9) for p in scene.parameters}


def _rates_by_sympy(scene: sm.Scene, t: float, y: np.ndarray, values: dict) -> list:
    """d/dt psi(t, q(t)) with q_dot = S(q) v, each symbol replaced by its value, at 40
    digits."""
    subs = {p: values[str(p)] for p in scene.parameters}
    state = dict(zip([*scene.coordinates, *scene.velocities], y.tolist(), strict=True))
    qdot = list(scene.kinematics())
    out = []
    for w in scene.walls:
        psi = w.psi
        rate = sum(sp.diff(psi, qi) * qd for qi, qd in zip(scene.coordinates, qdot, strict=True))
        rate += sp.diff(psi, sm.t)
        expr = rate.subs(subs).subs(state).subs(sm.t, t)
        out.append(float(sp.N(expr, 40)))
    return out


@pytest.mark.parametrize("target", ["numpy", "c"])
def test_augmented_rhs_is_rhs_and_the_rates_of_the_gaps(target):
    if target == "c":
        require_c_compiler()
    scene = _scene()
    values = _values(scene)
    code = codegen.generate(scene, target, functions=["rhs", "augmented_rhs", "psi"])
    mod = code.load()
    p = np.array([values[str(s)] for s in mod.parameters])
    n, walls = scene.n, len(scene.walls)
    rng = np.random.default_rng(7)
    Y = np.column_stack([rng.uniform(0.5, 1.2, (6, n)), rng.normal(size=(6, n))])
    t = 0.37
    batch = mod.call("augmented_rhs", Y, params=p, t=t)
    assert batch.shape == (6, 2 * n + walls)
    for k, y in enumerate(Y):
        one = mod.call("augmented_rhs", y, params=p, t=t)
        assert np.array_equal(one, batch[k])
        rhs = mod.call("rhs", y, params=p, t=t)
        assert np.array_equal(one[: 2 * n], rhs)
        exact = _rates_by_sympy(scene, t, y, values)
        np.testing.assert_allclose(one[2 * n :], exact, rtol=1e-13, atol=1e-14)
        # and by central differences of the generated psi along the motion
        h, qdot = 1e-5, rhs[:n]
        for w, name in enumerate(["psi_cone", "psi_stop"]):
            up = mod.call(name, y[:n] + h * qdot, params=p, t=t + h)
            down = mod.call(name, y[:n] - h * qdot, params=p, t=t - h)
            assert abs((up - down) / (2 * h) - one[2 * n + w]) < 1e-8


def test_augmented_rhs_is_asked_for_by_name():
    """Not in the default set (the simulator asks for it); asked for alone it brings
    acceleration and says so; a scene without walls has none and says why."""
    scene = _scene()
    assert "augmented_rhs" not in [f.name for f in codegen.generate(scene, "numpy").functions]
    alone = codegen.generate(scene, "numpy", functions=["augmented_rhs"])
    assert [f.name for f in alone.functions] == ["acceleration", "augmented_rhs"]
    assert any("augmented_rhs calls it" in o for o in alone.omitted)
    free = read_scene("rolling_ball").scene
    none = codegen.generate(free, "numpy", functions=["rhs", "augmented_rhs"])
    assert "augmented_rhs" not in [f.name for f in none.functions]
    assert any(o.startswith("augmented_rhs: the scene has no walls") for o in none.omitted)


def test_the_python_loops_take_it(monkeypatch):
    """A run of the NumPy loop through augmented_rhs gives what the path without it (rhs,
    then each wall's gradient) gives, to rounding."""
    from symmech.bench.cases import CASES
    from symmech.simulate import functions

    def run():
        return CASES["ellipse_gravity_flight"].simulate(backend="numpy")

    made = []
    kernel = functions._generated_kernel
    monkeypatch.setattr(functions, "_generated_kernel", lambda *a: made.append(a) or kernel(*a))
    fused = run()
    assert made  # the free flight went through augmented_rhs
    monkeypatch.setattr(functions.Functions, "_direct", _no_fused(functions.Functions._direct))
    general = run()
    assert [e.kind for e in fused.events] == [e.kind for e in general.events]
    np.testing.assert_allclose(
        [e.time for e in fused.events], [e.time for e in general.events], rtol=0, atol=1e-12
    )
    np.testing.assert_allclose(fused.y[-1], general.y[-1], rtol=0, atol=1e-10)


def _no_fused(direct):
    def without(self, mode, name):
        return None if name == "augmented_rhs" else direct(self, mode, name)

    return without
