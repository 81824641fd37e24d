"""Several walls hit at once (symmech.impacts.several): the closed-form map of a set of
walls against textbook closed forms and an independent numeric impulse-momentum (KKT)
solve written here; the LCP decision; the energy identity; one wall against the existing
single-wall map on every built-in scene; hostile input."""

from __future__ import annotations

import random

import numpy as np
import pytest
import sympy as sp

from symmech import Scene, Wall
from symmech.declaration.symbols import coordinates, t, velocities
from symmech.errors import ImpactError, SceneError
from symmech.examples import EXAMPLES, body_pendulum_rotor, newtons_cradle, trig_wall
from symmech.impacts import SeveralImpactMap, derive_several_impact_map, simultaneous_impulses
from symmech.scenefile import load_scene

m, l, R, I, c = sp.symbols("m l R I c", positive=True)
HALF = sp.Rational(1, 2)


# ---------------------------------------------------------------------------------------
# the independent route: g (v+ - v-) = A^T lam with mu v+ = 0, wall rows of the Newton
# law, nu (v+ - V) = 0, solved numerically as one linear system


def _value(e: sp.Expr, point: dict) -> float:
    """``e`` at ``point`` (arbitrary functions of t and their derivatives included)."""
    e = sp.sympify(e)
    e = e.xreplace({d: point[d] for d in e.atoms(sp.Derivative) if d in point})
    e = e.xreplace({f: point[f] for f in e.atoms(sp.core.function.AppliedUndef) if f in point})
    return float(e.xreplace(point))


def _point(scene: Scene, rng: random.Random) -> dict:
    """A random state: coordinates, parameters and t, f(t) and f'(t) for each f."""
    point: dict = {s: sp.Float(rng.uniform(0.3, 1.2)) for s in (*scene.coordinates, t)}
    point.update({s: sp.Float(rng.uniform(0.5, 1.5)) for s in scene.parameters})
    for w in scene.walls:
        for f in sp.sympify(w.psi).atoms(sp.core.function.AppliedUndef):
            point[sp.Derivative(f, t)] = sp.Float(rng.uniform(-1, 1))
            point[f] = sp.Float(rng.uniform(-1, 1))
    return point


def _kkt(
    scene: Scene, names: list[str], point: dict, v_minus: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """v+ and the multipliers of the walls' rows and their impulsive constraints, from the
    impulse-momentum equations (Carnot paper eqs. 6, 9, 15, 19, 20)."""
    decl = scene.declaration
    n = decl.n
    S = sp.eye(n) if decl.frame is None else sp.Matrix(decl.frame)
    g = np.array([[_value(e, point) for e in row] for row in sp.Matrix(decl.metric).tolist()])
    rows, rhs = [], []
    for a in range(decl.constraint_matrix.rows):
        rows.append([_value(e, point) for e in decl.constraint_matrix.row(a)])
        rhs.append(0.0)
    walls = [scene.wall(name) for name in names]
    for w in walls:
        psi = sp.sympify(w.psi)
        d = np.array(
            [_value(e, point) for e in sp.Matrix([[psi.diff(q) for q in decl.coordinates]]) * S]
        )
        psi_t = _value(psi.diff(t), point)
        rows.append(list(d))
        rhs.append(-float(w.restitution.xreplace(point)) * (d @ v_minus + psi_t) - psi_t)
    for w in walls:
        psi = sp.sympify(w.psi)
        d = np.array(
            [_value(e, point) for e in sp.Matrix([[psi.diff(q) for q in decl.coordinates]]) * S]
        )
        psi_t = _value(psi.diff(t), point)
        V = -psi_t * np.linalg.solve(g, d) / (d @ np.linalg.solve(g, d))  # g-normal
        nu = sp.Matrix(w.impulsive_matrix)
        for a in range(nu.rows):
            row = np.array([_value(e, point) for e in nu.row(a)])
            rows.append(list(row))
            rhs.append(float(row @ V))
    A = np.array(rows).reshape(len(rows), n)
    big = np.block([[g, -A.T], [A, np.zeros((len(rows), len(rows)))]])
    sol = np.linalg.solve(big, np.concatenate([g @ v_minus, rhs]))
    m_rows = decl.constraint_matrix.rows
    return sol[:n], sol[n + m_rows :]  # v+ and the multipliers of the walls and the nu


def _in_D(scene: Scene, point: dict, v: np.ndarray) -> np.ndarray:
    """The g-orthogonal projection of v onto D = ker mu at the point."""
    decl = scene.declaration
    if not decl.constraint_matrix.rows:
        return v
    g = np.array([[_value(e, point) for e in row] for row in sp.Matrix(decl.metric).tolist()])
    mu = np.array([[_value(e, point) for e in row] for row in decl.constraint_matrix.tolist()])
    gi_mu = np.linalg.solve(g, mu.T)
    return v - gi_mu @ np.linalg.solve(mu @ gi_mu, mu @ v)


def _map_at(M, point: dict, v_minus: np.ndarray, what: str = "post_velocity") -> np.ndarray:
    rule = dict(zip(M.velocities, [sp.Float(x) for x in v_minus], strict=True))
    return np.array([_value(e.xreplace(rule), point) for e in getattr(M, what)])


def _against_kkt(
    scene: Scene, names: list[str], samples: int = 4, seed: int = 5, simplify: str = "light"
) -> None:
    if simplify == "light":
        M = scene.impact_map(names)
    else:
        M = derive_several_impact_map(scene.declaration, names, simplify=simplify)
    rng = random.Random(seed)
    for _ in range(samples):
        point = _point(scene, rng)
        v = _in_D(scene, point, np.array([rng.uniform(-2, 2) for _ in range(scene.n)]))
        v_plus, multipliers = _kkt(scene, names, point, v)
        np.testing.assert_allclose(_map_at(M, point, v), v_plus, atol=1e-9)
        np.testing.assert_allclose(_map_at(M, point, v, "multipliers"), multipliers, atol=1e-9)
        k = len(names)
        np.testing.assert_allclose(_map_at(M, point, v, "impulses"), multipliers[:k], atol=1e-9)


# ---------------------------------------------------------------------------------------
# scenes


def _rod(alpha: object = HALF, order: tuple[str, str] = ("endA", "endB")) -> Scene:
    x, y, th = coordinates("x y theta")
    walls = {
        "endA": Wall(y - l * sp.sin(th), restitution=alpha, name="endA"),
        "endB": Wall(y + l * sp.sin(th), restitution=alpha, name="endB"),
    }
    return Scene(
        (x, y, th), metric=sp.diag(m, m, m * l**2 / 3), walls=[walls[o] for o in order], name="rod"
    )


def _ball_in_corner(slopes: tuple[object, object], alphas=(HALF, HALF)) -> Scene:
    """A point mass (x, y) above the walls ``a_i x + b_i y >= 0``, ``slopes = ((a1, b1),
    (a2, b2))``."""
    x, y = coordinates("x y")
    walls = [
        Wall(a * x + b * y, restitution=alpha, name=name)
        for (a, b), alpha, name in zip(slopes, alphas, ("left", "right"), strict=True)
    ]
    return Scene((x, y), metric=sp.eye(2) * m, walls=walls, name="corner")


# ---------------------------------------------------------------------------------------
# the rod landing flat


@pytest.mark.parametrize("alpha", [0, HALF, 1])
def test_rod_landing_flat_rebounds_straight_up_whatever_the_order(alpha):
    v = sp.Symbol("v", positive=True)
    maps = [
        _rod(alpha, order).impact_map(["endA", "endB"])
        for order in [("endA", "endB"), ("endB", "endA")]
    ]
    maps.append(_rod(alpha).impact_map(["endB", "endA"]))
    th = maps[0].declaration.coordinates[2]
    for M in maps:
        assert isinstance(M, SeveralImpactMap)
        post = M.apply([0, -v, 0]).subs(th, 0)
        assert list(post) == [0, alpha * v, 0]  # ydot+ = -alpha ydot-, thetadot+ = 0
        # the impulses: each end takes half of (1 + alpha) m v (momentum, by symmetry)
        impulses = M.impulses_at([0, -v, 0]).subs(th, 0)
        assert [sp.simplify(e - (1 + alpha) * m * v / 2) for e in impulses] == [0, 0]
        # energy: T+ - T- = m/2 (alpha^2 - 1) v^2
        dT = M.energy_change().subs(th, 0).subs({M.velocities[1]: -v, M.velocities[0]: 0})
        dT = dT.subs(M.velocities[2], 0)
        assert sp.simplify(dT - m * (alpha**2 - 1) * v**2 / 2) == 0
        assert M.carnot().holds
    # every order gives the same post-impact velocity for every state
    a, b = (sp.Matrix(M.post_velocity) for M in maps[:2])
    assert sp.simplify(a - b) == sp.zeros(3, 1)


def test_rod_elastic_conserves_energy_identically():
    M = _rod(1).impact_map(["endA", "endB"])
    assert M.energy_change() == 0
    assert sp.simplify(M.energy_change(in_D=True)) == 0


def test_rod_lcp_decision_takes_both_ends():
    scene = _rod(HALF)
    M = scene.impact_map(["endA", "endB"])
    point = {scene.coordinates[2]: 0, m: 2, l: 1}
    W = np.array(M.delassus.subs(point), dtype=float)
    np.testing.assert_allclose(W, [[2.0, -1.0], [-1.0, 2.0]])  # (1/m) [[4, -2], [-2, 4]]
    decision = simultaneous_impulses(W, [-3.0, -3.0], 0.5)
    assert decision.active == (0, 1)
    np.testing.assert_allclose(decision.impulses, [4.5, 4.5])  # (1 + alpha) m v / 2
    np.testing.assert_allclose(decision.post_rates, [1.5, 1.5])


def test_rod_against_kkt_at_random_states():
    _against_kkt(_rod(sp.Rational(3, 10)), ["endA", "endB"])


# ---------------------------------------------------------------------------------------
# a ball in a corner


def test_ball_in_a_right_angled_corner():
    scene = _ball_in_corner(((1, 0), (0, 1)), alphas=(sp.Rational(1, 3), sp.Rational(3, 4)))
    M = scene.impact_map(["left", "right"])
    a, b = sp.symbols("a b", positive=True)
    # orthogonal normals: each wall reverses its own component (every law agrees)
    assert list(M.apply([-a, -b])) == [a / 3, sp.Rational(3, 4) * b]
    assert M.carnot().holds
    # the energy loss is the sum of the two one-wall losses
    assert (
        sp.expand(
            M.energy_change()
            - (
                -(1 - sp.Rational(1, 9)) * m * M.velocities[0] ** 2 / 2
                - (1 - sp.Rational(9, 16)) * m * M.velocities[1] ** 2 / 2
            )
        )
        == 0
    )


@pytest.mark.parametrize("alpha", [0, HALF, 1])
def test_ball_in_a_v_corner_falling_straight_down(alpha):
    k = sp.Rational(1, 2)  # walls y = k |x|: psi = y - k x, y + k x
    scene = _ball_in_corner(((-k, 1), (k, 1)), alphas=(alpha, alpha))
    M = scene.impact_map(["left", "right"])
    v = sp.Symbol("v", positive=True)
    assert list(M.apply([0, -v])) == [0, alpha * v]
    _against_kkt(scene, ["left", "right"], samples=3)


def test_v_corner_lcp_decides_one_wall_when_the_other_separates():
    k = sp.Rational(1, 2)
    scene = _ball_in_corner(((-k, 1), (k, 1)), alphas=(HALF, HALF))
    M = scene.impact_map(["left", "right"])
    W = np.array(M.delassus.subs({m: 1}), dtype=float)  # [[1 + k^2, 1 - k^2], ...]
    np.testing.assert_allclose(W, [[1.25, 0.75], [0.75, 1.25]])
    # moving fast to the right: approaches 'left' (y - x/2) hard, 'right' barely
    v = np.array([2.0, -0.2])
    u = np.array([v[1] - 0.5 * v[0], v[1] + 0.5 * v[0]])  # (-1.2, 0.8): only 'left' closes
    d = simultaneous_impulses(W, u, 0.5)
    assert d.active == (0,)
    # the one-wall law on 'left' (text 001 Thm 2.12 with alpha): u+ = -alpha u-
    n1 = np.array([-0.5, 1.0])
    v_plus = v - (1.5 * (n1 @ v) / (n1 @ n1)) * n1
    np.testing.assert_allclose(v + d.impulses[0] * n1, v_plus)
    assert d.post_rates[0] == pytest.approx(0.6) and d.post_rates[1] > 0


# ---------------------------------------------------------------------------------------
# three touching balls


def test_three_touching_balls_simultaneous_law():
    scene = newtons_cradle(3)
    M = scene.impact_map(["contact0", "contact1"])
    assert list(M.apply([1, 0, 0])) == [sp.Rational(-1, 3), sp.Rational(2, 3), sp.Rational(2, 3)]
    assert list(M.impulses_at([1, 0, 0])) == [sp.Rational(4, 3) * m, sp.Rational(2, 3) * m]
    assert M.energy_change() == 0 and M.carnot().holds
    # the cascade (one contact at a time, with the existing one-wall maps) gives (0, 0, 1)
    after_first = scene.impact_map("contact0").apply([1, 0, 0])
    assert list(scene.impact_map("contact1").apply(list(after_first))) == [0, 0, 1]


def test_three_touching_balls_lcp_decision():
    scene = newtons_cradle(3)
    M = scene.impact_map(["contact0", "contact1"])
    W = np.array(M.delassus.subs({m: 1}), dtype=float)
    np.testing.assert_allclose(W, [[2.0, -1.0], [-1.0, 2.0]])
    d = simultaneous_impulses(W, [-1.0, 0.0], [1.0, 1.0])
    assert d.active == (0, 1)
    np.testing.assert_allclose(d.impulses, [4 / 3, 2 / 3])
    A = np.array([[-1.0, 1.0, 0.0], [0.0, -1.0, 1.0]])
    np.testing.assert_allclose(np.array([1.0, 0, 0]) + A.T @ d.impulses, [-1 / 3, 2 / 3, 2 / 3])
    np.testing.assert_allclose(d.post_rates, [1.0, 0.0], atol=1e-15)


# ---------------------------------------------------------------------------------------
# permanent constraints, impulsive constraints, frames, moving walls


def test_knife_edge_scene_with_two_walls_against_kkt():
    x, y, th = coordinates("x y theta")
    xd, yd, _ = velocities((x, y, th))
    scene = Scene(
        (x, y, th),
        metric=sp.diag(m, m, I),
        constraints=[-sp.sin(th) * xd + sp.cos(th) * yd],
        walls=[
            Wall(x + l * sp.cos(th), restitution=HALF, name="front"),
            Wall(y - l * sp.sin(th) - c * t, restitution=sp.Rational(1, 5), name="lift"),
        ],
        name="sleigh",
    )
    _against_kkt(scene, ["front", "lift"])
    assert scene.impact_map(["front", "lift"]).carnot().holds


def test_every_route_of_the_projectors_against_kkt():
    """The sympy route (simplify="none"), the rational route (every entry a number) and
    the adjugate route (the tests above) build the same map."""
    x, y, th, z, w = coordinates("x y theta z w")
    xd, yd, thd, zd, _ = velocities((x, y, th, z, w))
    metric = sp.Matrix(5, 5, lambda i, j: 3 if i == j else (1 if abs(i - j) == 1 else 0))
    numeric = Scene(
        (x, y, th, z, w),
        metric=metric,
        constraints=[xd - yd + thd],
        walls=[
            Wall(x + 2 * y + w, restitution=sp.Rational(1, 3), name="a"),
            Wall(y - th, restitution=sp.Rational(2, 3), impulsive_constraints=[zd], name="b"),
        ],
        name="numeric",
    )
    _against_kkt(numeric, ["a", "b"], samples=2)
    assert numeric.impact_map(["a", "b"]).projectors.denominators is None  # rational route
    _against_kkt(_rod(sp.Rational(3, 10)), ["endA", "endB"], samples=2, simplify="none")
    _against_kkt(_rod(sp.Rational(3, 10)), ["endA", "endB"], samples=1, simplify="full")


def test_delassus_with_impulsive_constraints_is_the_doubly_constrained_inverse():
    """W = G M^-1 G^T with M^-1 the inverse constrained by mu and the set's nu (numeric,
    from g, mu, nu and the walls' one-forms at random states)."""
    x, y, ph, s = coordinates("x y phi s")
    xd, _, phd, sd = velocities((x, y, ph, s))
    scene = Scene(
        (x, y, ph, s),
        metric=sp.Matrix([[m, 0, 0, 1], [0, m, 0, 0], [0, 0, I, 0], [1, 0, 0, 3]]),
        constraints=[sd - xd - phd],
        walls=[
            Wall(
                y - R * sp.cos(ph),
                restitution=HALF,
                impulsive_constraints=[xd + R * phd],
                name="floor",
            ),
            Wall(x + y - R, restitution=1, name="side"),
        ],
        name="delassus",
    )
    M = scene.impact_map(["floor", "side"])
    rng = random.Random(3)
    decl = scene.declaration
    for _ in range(3):
        point = _point(scene, rng)
        g = np.array(sp.Matrix(decl.metric).xreplace(point), dtype=float)
        B = np.array(
            sp.Matrix(decl.constraint_matrix)
            .col_join(sp.Matrix(scene.wall("floor").impulsive_matrix))
            .xreplace(point),
            dtype=float,
        )
        G = np.array(
            sp.Matrix(
                [[sp.diff(w.psi, q) for q in decl.coordinates] for w in scene.walls]
            ).xreplace(point),
            dtype=float,
        )
        gi = np.linalg.inv(g)
        constrained = gi - gi @ B.T @ np.linalg.solve(B @ gi @ B.T, B @ gi)
        expected = G @ constrained @ G.T
        np.testing.assert_allclose(
            np.array(M.delassus.xreplace(point), dtype=float), expected, rtol=1e-10
        )


def test_rough_floor_and_side_wall_with_impulsive_constraint_against_kkt():
    x, y, ph = coordinates("x y phi")
    xd, _, phd = velocities((x, y, ph))
    scene = Scene(
        (x, y, ph),
        metric=sp.diag(m, m, I),
        walls=[
            Wall(
                y - R - c * t, restitution=HALF, impulsive_constraints=[xd + R * phd], name="floor"
            ),
            Wall(x - R, restitution=1, name="side"),
        ],
        name="disc_in_corner",
    )
    _against_kkt(scene, ["floor", "side"])
    M = scene.impact_map(["side", "floor"])
    assert M.carnot().holds and M.rows[-1].startswith("the impulsive constraint")


def test_frame_scene_sphere_in_a_corner_against_kkt():
    base = load_scene("carnot_3_13")
    y = base.coordinates[1]
    scene = base.replace(
        walls=[*[w.as_wall() for w in base.walls], Wall(y, restitution=HALF, name="side")]
    )
    _against_kkt(scene, ["rough_wall", "side"], samples=3)
    assert scene.impact_map(["rough_wall", "side"]).carnot().holds


# ---------------------------------------------------------------------------------------
# one wall: the existing map


def _builtin_scenes() -> list[tuple[str, Scene]]:
    scenes = [(name, build()) for name, (build, _) in sorted(EXAMPLES.items())]
    return [*scenes, ("trig_wall", trig_wall()), ("body_pendulum_rotor", body_pendulum_rotor())]


@pytest.mark.parametrize(
    ("name", "scene"), _builtin_scenes(), ids=lambda x: x if isinstance(x, str) else ""
)
def test_one_wall_is_the_existing_map(name, scene):
    rng = random.Random(17)
    for wall in scene.walls:
        single = scene.impact_map(wall.index, law="newton")
        assert scene.impact_map([wall.name], law="newton") is single  # the cached object
        several = derive_several_impact_map(
            scene.declaration,
            [wall.index],
            law="newton",
            projectors=scene.projectors(),
        )
        for _ in range(2):
            point = _point(scene, rng)
            v = _in_D(scene, point, np.array([rng.uniform(-2, 2) for _ in range(scene.n)]))
            np.testing.assert_allclose(
                _map_at(several, point, v), _map_at(single, point, v), rtol=1e-9, atol=1e-9
            )


# ---------------------------------------------------------------------------------------
# energy with unequal restitutions


def test_unequal_restitutions_loss_form_is_indefinite_but_the_lcp_never_gains_on_approach():
    k = sp.Rational(1, 2)
    scene = _ball_in_corner(((-k, 1), (k, 1)), alphas=(1, 0))
    M = scene.impact_map(["left", "right"])
    loss = np.array(M.loss_form.subs({m: 1}), dtype=float)
    assert np.linalg.eigvalsh(loss).min() < 0  # K - D K D indefinite (module docstring)
    W = np.array(M.delassus.subs({m: 1}), dtype=float)
    rng = np.random.default_rng(2)
    for _ in range(200):
        v = rng.standard_normal(2)
        u = np.array([v[1] - 0.5 * v[0], v[1] + 0.5 * v[0]])
        if np.any(u > 0):
            continue
        d = simultaneous_impulses(W, u, [1.0, 0.0])
        A = np.array([[-0.5, 1.0], [0.5, 1.0]])
        v_plus = v + A.T @ d.impulses
        dT = 0.5 * (v_plus @ v_plus - v @ v)
        assert dT == pytest.approx(0.5 * (0.0 * d.impulses[0] * u[0] + d.impulses[1] * u[1]))
        assert dT <= 1e-12


# ---------------------------------------------------------------------------------------
# hostile input


def test_hostile_sets():
    scene = _rod()
    with pytest.raises(ImpactError, match="given twice"):
        scene.impact_map(["endA", "endA"])
    with pytest.raises(ImpactError, match="given twice"):
        scene.impact_map(["endA", 0])
    with pytest.raises(SceneError, match="no wall named 'endC'"):
        scene.impact_map(["endA", "endC"])
    with pytest.raises(ImpactError, match="empty"):
        scene.impact_map([])
    with pytest.raises(ImpactError, match="Newton's law only"):
        scene.impact_map(["endA", "endB"], law="energy")
    with pytest.raises(ImpactError, match="wall_velocity"):
        scene.impact_map(["endA", "endB"], wall_velocity=[0, 0, 0])
    with pytest.raises(ImpactError, match="list or tuple"):
        derive_several_impact_map(scene.declaration, "endA")


def test_dependent_walls_are_refused():
    with pytest.raises(ImpactError, match="wall 'right' is linearly dependent"):
        _ball_in_corner(((0, 1), (0, 2))).impact_map(["left", "right"])
    # three walls in the plane: the third depends on the first two
    xs, ys = coordinates("x y")
    scene = Scene(
        (xs, ys),
        metric=sp.eye(2),
        walls=[Wall(xs, name="a"), Wall(ys, name="b"), Wall(xs + ys, name="c")],
        name="three",
    )
    with pytest.raises(ImpactError, match="wall 'c' is linearly dependent"):
        scene.impact_map(["a", "b", "c"])
    # a wall in the span of the permanent constraints together with another wall
    q1, q2, q3 = coordinates("q1 q2 q3")
    d1, d2, _ = velocities((q1, q2, q3))
    constrained = Scene(
        (q1, q2, q3),
        metric=sp.eye(3),
        constraints=[d1 - d2],
        walls=[Wall(q1 - q2, name="tangent"), Wall(q3, name="floor")],
        name="dep",
    )
    with pytest.raises(ImpactError, match="linearly dependent"):
        constrained.impact_map(["floor", "tangent"])


def test_energy_law_walls_need_newton_explicitly():
    scene = load_scene("spinning_disk")
    (w,) = scene.walls
    two = scene.replace(walls=[w.as_wall(), Wall(scene.coordinates[1] + 5, name="other")])
    with pytest.raises(ImpactError, match="energy law"):
        two.impact_map([w.name, "other"])


@pytest.mark.parametrize(
    ("W", "u", "alpha", "match"),
    [
        ([[1.0]], [np.nan], 1.0, "finite"),
        ([[np.inf]], [-1.0], 1.0, "finite"),
        ([[1.0]], [-1.0], np.nan, "finite"),
        ([[1.0]], [-1.0], 1.5, r"\[0, 1\]"),
        ([[1.0, 0.0]], [-1.0], 1.0, "square"),
        ([[1.0, -1.0], [-1.0, 1.0]], [-1.0, -1.0], 0.0, "no active set"),
    ],
)
def test_hostile_lcp_data(W, u, alpha, match):
    with pytest.raises(ImpactError, match=match):
        simultaneous_impulses(W, u, alpha)


def test_apply_refuses_text_and_wrong_lengths():
    M = _rod().impact_map(["endA", "endB"])
    with pytest.raises(ImpactError, match="not a number"):
        M.apply(["__import__('os')", 0, 0])
    with pytest.raises(ImpactError, match="expected 3"):
        M.impulses_at([0, 1])


def test_non_real_or_mismatched_lcp_data():
    with pytest.raises(ImpactError, match="real numbers"):
        simultaneous_impulses([[1.0]], ["a"], 1.0)
    with pytest.raises(ImpactError, match="real numbers"):
        simultaneous_impulses([[1.0, 0.0], [0.0, 1.0]], [-1.0, -1.0], [1.0, 1.0, 1.0])
