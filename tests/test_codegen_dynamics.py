"""``dynamics`` = (v_dot, lambda) from one solve, and acceleration and multipliers as its
parts when their code is large (codegen.sharing): the same doubles as the functions
generated apart, in C and NumPy, one state and batches, and the same failures."""

from __future__ import annotations

import importlib

import numpy as np
import pytest
import sympy as sp

import symmech as sm
from symmech import codegen
from symmech.codegen.callers import NumericalError
from symmech.examples import bouncing_ball

sharing = importlib.import_module("symmech.codegen.sharing")


def sleigh() -> sm.Scene:
    """A Chaplygin sleigh (knife edge at distance a from the mass centre) in a quadratic
    potential: non-zero multipliers and a full 3 x 3 metric."""
    m, I, a, k = sp.symbols("m I a k", positive=True)
    x, y, th = sm.coordinates("x y theta")
    xd, yd, _ = sm.velocities((x, y, th))
    g = sp.Matrix(
        [
            [m, 0, -m * a * sp.sin(th)],
            [0, m, m * a * sp.cos(th)],
            [-m * a * sp.sin(th), m * a * sp.cos(th), I + m * a**2],
        ]
    )
    return sm.Scene(
        (x, y, th),
        metric=g,
        potential=k * (x**2 + y**2) / 2 + k * sp.cos(th),
        constraints=[-sp.sin(th) * xd + sp.cos(th) * yd],
        name="sleigh",
    )


PARAMS = {"m": 1.3, "I": 0.7, "a": 0.4, "k": 2.1}
FUNCTIONS = ["acceleration", "multipliers", "rhs"]


def _states(n: int, count: int = 7) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(11)
    return rng.uniform(-2, 2, (count, n)), rng.uniform(-3, 3, (count, n))


def _generate(scene: sm.Scene, target: str) -> codegen.GeneratedCode:
    return codegen.generate(scene, target, strategy="linear_solve", functions=FUNCTIONS)


@pytest.fixture(scope="module")
def apart():
    """Acceleration and multipliers generated apart (the default for a small body)."""
    scene = sleigh()
    return {t: _generate(scene, t).load() for t in ("c", "numpy")}


@pytest.fixture(scope="module")
def shared():
    """The same, made parts of dynamics (every body counts as large)."""
    scene = sleigh()
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(sharing, "MAX_SPLIT_CHARACTERS", 0)
        codes = {t: _generate(scene, t) for t in ("c", "numpy")}
    return codes


def test_parts_of_dynamics_when_large(shared, apart):
    for code in shared.values():
        names = [f.name for f in code.functions]
        assert names.index("dynamics") < names.index("acceleration")
        parts = {f.name: f.part_of for f in code.functions}
        assert parts["acceleration"] == ("dynamics", 0)
        assert parts["multipliers"] == ("dynamics", 3)
        assert code.plan.function("multipliers").part_of == ("dynamics", 3)
    c_text = shared["c"].files[f"{shared['c'].stem}.c"]
    assert c_text.count("lam0") < apart["c"].code.files[f"{shared['c'].stem}.c"].count("lam0")


@pytest.mark.parametrize("target", ["c", "numpy"])
def test_parts_give_the_doubles_of_the_functions_apart(shared, apart, target, tmp_path):
    mod, ref = shared[target].load(cache=tmp_path), apart[target]
    q, v = _states(3)
    for name in ("acceleration", "multipliers"):
        got = getattr(mod, name)(q, v, PARAMS)
        assert np.array_equal(got, getattr(ref, name)(q, v, PARAMS)), name
        for i in range(len(q)):  # one state (the fast path) as well
            assert np.array_equal(getattr(mod, name)(q[i], v[i], PARAMS), got[i])
    both = mod.dynamics(q, v, PARAMS)
    assert both.shape == (len(q), 4)
    assert np.array_equal(both[:, :3], ref.acceleration(q, v, PARAMS))
    assert np.array_equal(both[:, 3:], ref.multipliers(q, v, PARAMS))
    y = np.concatenate([q, v], axis=1)
    assert np.array_equal(mod.rhs(y, PARAMS), ref.rhs(y, PARAMS))


def test_dynamics_solves_the_kkt_system(apart):
    """g v_dot = f + mu^T lambda, mu v_dot = -mu_dot v, by numpy.linalg.solve."""
    scene = sleigh()
    code = codegen.generate(scene, "c", functions=["dynamics", "mass_matrix", "forcing"])
    mod = code.load()
    q, v = _states(3, 3)
    syms = [*scene.coordinates, *scene.velocities, *(sp.Symbol(k, positive=True) for k in PARAMS)]
    mu = sp.lambdify(syms, scene.constraint_matrix)
    rate = sp.lambdify(syms, sp.Matrix(scene.constraint_rate()))
    for i in range(len(q)):
        args = (*q[i], *v[i], *PARAMS.values())
        M, f = mod.mass_matrix(q[i], PARAMS), mod.forcing(q[i], v[i], PARAMS)
        A, r = np.array(mu(*args), dtype=float), np.array(rate(*args), dtype=float).ravel()
        kkt = np.block([[M, -A.T], [A, np.zeros((1, 1))]])
        expected = np.linalg.solve(kkt, np.concatenate([f, -r]))
        assert np.allclose(mod.dynamics(q[i], v[i], PARAMS), expected, rtol=1e-12, atol=1e-12)


def test_closed_form_dynamics_agrees_with_the_solve():
    scene = sleigh()
    closed = codegen.generate(scene, "numpy", strategy="closed_form", functions=["dynamics"])
    solved = codegen.generate(scene, "c", strategy="linear_solve", functions=["dynamics"])
    q, v = _states(3)
    np.testing.assert_allclose(
        closed.load().dynamics(q, v, PARAMS), solved.load().dynamics(q, v, PARAMS), rtol=1e-11
    )


@pytest.mark.parametrize("target", ["c", "numpy"])
def test_parts_fail_where_the_functions_apart_fail(shared, apart, target, tmp_path):
    mod, ref = shared[target].load(cache=tmp_path), apart[target]
    q, v = _states(3, 2)
    v[1, 0] = np.nan
    for name in ("acceleration", "multipliers"):
        for m in (mod, ref):
            with pytest.raises(NumericalError):
                getattr(m, name)(q[1], v[1], PARAMS)
    huge = dict(PARAMS, k=1e308)  # forces overflow: not finite
    for name in ("acceleration", "multipliers", "dynamics"):
        outcomes = []
        for m in (mod, ref) if name != "dynamics" else (mod,):
            try:
                outcomes.append(getattr(m, name)(q[0], v[0] * 1e200, huge))
            except NumericalError:
                outcomes.append("error")
        assert all(str(o) == str(outcomes[0]) for o in outcomes), name


def test_dynamics_of_a_scene_without_constraints_is_a_note():
    code = codegen.generate(bouncing_ball(), "numpy", functions=["dynamics", "rhs"])
    assert "dynamics" not in [f.name for f in code.functions]
    assert any(note.startswith("dynamics, multipliers") for note in code.omitted)


def test_asked_for_dynamics_is_the_whole_of_the_parts(tmp_path):
    """dynamics asked for by name, with acceleration and multipliers large: they become
    its parts, and it is emitted once."""
    scene = sleigh()
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(sharing, "MAX_SPLIT_CHARACTERS", 0)
        code = codegen.generate(
            scene, "c", strategy="linear_solve", functions=["dynamics", *FUNCTIONS]
        )
    names = [f.name for f in code.functions]
    assert names.count("dynamics") == 1
    assert [f.part_of for f in code.functions if f.part_of] == [("dynamics", 0), ("dynamics", 3)]
    mod = code.load(cache=tmp_path)
    q, v = _states(3)
    both = mod.dynamics(q, v, PARAMS)
    assert np.array_equal(
        both,
        np.concatenate([mod.acceleration(q, v, PARAMS), mod.multipliers(q, v, PARAMS)], axis=1),
    )
