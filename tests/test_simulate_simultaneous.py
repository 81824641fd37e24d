"""Simultaneous impacts (issue 24, item 2): walls closed and approaching at one instant
are resolved together by the generalized Newton law, the others in cascade.

Independent routes: textbook closed forms (a rod landing flat rebounds straight up at
alpha sqrt(2 g h); a ball dropped into a symmetric V corner rebounds straight up at
alpha V), and a KKT solve built here from the scene's metric and the walls' gradients
(active sets tried by brute force), not from the generated impact maps the loop uses.
"""

from __future__ import annotations

import itertools
import math

import mpmath
import numpy as np
import pytest
import sympy as sp

import symmech as sm
from symmech.examples import newtons_cradle
from symmech.simulate.impulses import active_set_solution, solve_small
from symmech.simulate.reference import reference_run

ROD = {"alpha": 0.5, "g": 9.81, "l": 1.0, "m": 1.0}
BACKENDS = ["c", "numpy", "scipy"]


def rod(swapped: bool = False) -> sm.Scene:
    scene = sm.load_scene("falling_rod")
    if swapped:
        scene = scene.replace(walls=[w.as_wall() for w in reversed(scene.walls)])
    return scene


def first_impact(res: sm.SimulationResult) -> np.ndarray:
    return res.impacts()[0].v_plus


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("alpha", [0.0, 0.5, 1.0])
def test_a_rod_landing_flat_rebounds_straight_up_whatever_the_wall_order(backend, alpha):
    h, g = 1.0, ROD["g"]
    t_land = math.sqrt(2 * h / g)
    params = {**ROD, "alpha": alpha}
    outs = []
    for swapped in (False, True):
        res = sm.simulate(
            rod(swapped), [0.0, h, 0.0], [0.0, 0.0, 0.0], 1.2 * t_land, params=params,
            backend=backend, rtol=1e-10, atol=1e-12,
        )  # fmt: skip
        assert res.status == "finished", res.message
        impacts = res.impacts()
        assert len(impacts) == 2 and {e.wall_name for e in impacts} == {"endA", "endB"}
        assert impacts[0].time == impacts[1].time
        np.testing.assert_allclose(impacts[0].time, t_land, rtol=1e-9)
        v = first_impact(res)
        np.testing.assert_allclose(v, [0.0, alpha * math.sqrt(2 * g * h), 0.0], atol=1e-9)
        assert abs(v[2]) < 1e-12
        # the energy change of the set, carried once: -(1 - alpha^2) m ydot-^2 / 2
        dE = sum(e.energy_change for e in impacts)
        np.testing.assert_allclose(dE, -(1 - alpha**2) * g * h, rtol=1e-8, atol=1e-12)
        outs.append(v)
    np.testing.assert_allclose(outs[0], outs[1], atol=1e-12)


@pytest.mark.parametrize("backend", ["c", "numpy"])
def test_the_sequential_law_stays_selectable_and_its_spin_follows_the_wall_order(backend):
    spins = []
    for swapped in (False, True):
        res = sm.simulate(
            rod(swapped), [0.0, 1.0, 0.0], [0.0, 0.0, 0.0], 0.5, params=ROD, backend=backend,
            impact_law="sequential", max_events=2,
        )  # fmt: skip
        spins.append(res.impacts()[-1].v_plus[2])
    assert abs(spins[0]) > 1 and spins[0] == pytest.approx(-spins[1], rel=1e-12)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("beta", [math.pi / 4, math.pi / 6, 1.2])
def test_a_ball_dropped_into_a_v_corner_rebounds_straight_up(backend, beta):
    """Normals n = (+-sin b, cos b): both contacts active, Lambda = (1 + alpha) V m cos b /
    (1 + cos 2b) each, v+ = (0, alpha V)."""
    scene = sm.load_scene("ball_in_corner")
    params = {"alpha": 0.5, "beta": beta, "g": 9.81, "m": 2.0}
    h = 0.5
    res = sm.simulate(
        scene, [0.0, h], [0.0, 0.0], 1.1 * math.sqrt(2 * h / 9.81), params=params,
        backend=backend, rtol=1e-10, atol=1e-12,
    )  # fmt: skip
    V = math.sqrt(2 * 9.81 * h)
    np.testing.assert_allclose(first_impact(res), [0.0, 0.5 * V], atol=1e-9)
    assert len(res.impacts()) == 2


def _kkt_law(M: np.ndarray, G: np.ndarray, u: np.ndarray, alpha: np.ndarray, v: np.ndarray):
    """The generalized Newton law by brute force over active sets, each a KKT solve
    [[M, -G_A^T], [G_A, 0]] [v+; Lambda_A] = [M v-; -alpha_A u_A] (an independent route:
    the metric and the gradients, not the generated impact maps)."""
    n, k = len(v), len(u)
    found = []
    for size in range(1, k + 1):
        for act in itertools.combinations(range(k), size):
            A = G[list(act)]
            K = np.block([[M, -A.T], [A, np.zeros((size, size))]])
            rhs = np.concatenate([M @ v, -alpha[list(act)] * u[list(act)]])
            sol = np.linalg.solve(K, rhs)
            vp, lam = sol[:n], sol[n:]
            w = G @ vp + alpha * u
            if np.all(lam >= -1e-12) and np.all(w >= -1e-12):
                found.append(vp)
    assert len(found) >= 1
    return found[0]


def test_the_law_matches_a_kkt_solve_built_from_the_metric_for_random_rod_landings():
    """The rod touching the floor with both ends (theta = 0) at random velocities that
    bring both ends in: the loop's rule (directions from the generated maps, active sets
    by impulses.active_set_solution) equals the KKT route; no energy is gained."""
    rng = np.random.default_rng(7)
    scene = rod()
    l, m = ROD["l"], ROD["m"]
    M = np.diag([m, m, m * l**2 / 3])
    G = np.array([[0.0, 1.0, -l], [0.0, 1.0, l]])  # d psi at theta = 0
    for alpha in (0.0, 0.3, 1.0):
        for _ in range(20):
            v = np.array([rng.normal(), -abs(rng.normal()) - 0.1, rng.normal()])
            u = G @ v
            if not np.all(u < -1e-3):
                continue
            want = _kkt_law(M, G, u, np.full(2, alpha), v)
            params = {**ROD, "alpha": alpha}
            res = sm.simulate(scene, [0.0, 0.0, 0.0], v, 1e-3, params=params, backend="numpy")
            got = first_impact(res)
            np.testing.assert_allclose(got, want, atol=1e-12 * max(1, np.abs(v).max()))
            T = lambda w: 0.5 * w @ M @ w  # noqa: E731
            assert T(got) <= T(v) * (1 + 1e-14)


def test_the_mpmath_reference_applies_the_same_law():
    with mpmath.workdps(30):
        res = reference_run(rod(), [0.0, 1.0, 0.0], [0.0, 0.0, 0.0], 0.5, params=ROD, dps=30)
        v = res.impacts()[0].v_plus
        want = ROD["alpha"] * mpmath.sqrt(2 * mpmath.mpf(ROD["g"]))
        assert abs(v[1] - want) < mpmath.mpf(10) ** -18
        assert abs(v[2]) < mpmath.mpf(10) ** -20


def test_three_balls_two_closing_at_once_match_the_kkt_law():
    """Balls 0 and 2 close on ball 1 at one instant (alpha = 0.5): both contacts are
    resolved together, as the KKT route says."""
    scene = newtons_cradle(3).replace(
        walls=[w.as_wall(restitution=sp.Rational(1, 2)) for w in newtons_cradle(3).walls]
    )
    v = np.array([1.0, 0.0, -2.0])
    M = np.eye(3)
    G = np.array([[-1.0, 1.0, 0.0], [0.0, -1.0, 1.0]])
    want = _kkt_law(M, G, G @ v, np.full(2, 0.5), v)
    for backend in ("c", "numpy"):
        res = sm.simulate(scene, [0.0, 0.2, 0.4], v, 1e-3, params={"m": 1.0, "r": 0.1},
                          backend=backend)  # fmt: skip
        np.testing.assert_allclose(first_impact(res), want, atol=1e-14)


def test_active_set_solution_is_the_lcp_solution_on_random_p_matrices():
    """Against brute force over sign patterns with numpy (w = K m - g, K = W D^-1)."""
    rng = np.random.default_rng(3)
    for k in range(1, 6):
        for _ in range(30):
            B = rng.normal(size=(k, k))
            W = B @ B.T + 0.1 * np.eye(k)
            K = W / np.diag(W)
            g = rng.normal(size=k)
            m = np.array(active_set_solution(K.tolist(), g.tolist(), 1e-12))
            w = K @ m - g
            assert np.all(m >= 0) and np.all(w >= -1e-10)
            assert abs(m @ w) < 1e-9
    assert solve_small([[0.0, 0.0], [0.0, 0.0]], [1.0, 1.0]) is None
    # no feasible set: K not a P-matrix, g such that nothing works
    assert active_set_solution([[-1.0]], [1.0], 1e-12) is None


def test_the_loop_agrees_with_the_closed_form_map_of_the_set():
    """Where both ends take an impulse, the loop's v+ (Newton directions from the one-wall
    generated maps) equals the closed-form several-wall map scene.impact_map([A, B])
    (Carnot framework with both wall rows at once), evaluated at the same state."""
    scene = rod()
    both = scene.impact_map(["endA", "endB"])
    rng = np.random.default_rng(11)
    checked = 0
    for _ in range(30):
        v = np.array([rng.normal(), -abs(rng.normal()) - 0.5, 0.3 * rng.normal()])
        params = {**ROD, "alpha": 0.5}
        res = sm.simulate(scene, [0.0, 0.0, 0.0], v, 1e-3, params=params, backend="c")
        impacts = res.impacts()
        if len(impacts) != 2 or impacts[0].time != impacts[1].time:
            continue  # one end only took an impulse: another active set
        closed = both.apply(list(v)).xreplace(
            {p: params[str(p)] for p in both.post_velocity.free_symbols if str(p) in params}
        )
        closed = closed.xreplace({q: 0 for q in scene.declaration.coordinates})
        np.testing.assert_allclose(
            impacts[0].v_plus, np.array(closed, dtype=float).ravel(), atol=1e-12
        )
        checked += 1
    assert checked >= 10
