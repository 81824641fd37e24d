"""The knife edge at a wall: one P and Q for the scene, its impact map and its generated code.

Metric diag(m, m, J) on (x, y, theta), permanent constraint -sin(theta) xdot + cos(theta) ydot
= 0 (the blade rolls along its heading), wall y - 1 >= 0.  D = ker mu is spanned by
(cos theta, sin theta, 0) and (0, 0, 1), so the g-orthogonal projector onto D has
P_00 = cos^2(theta), P_01 = sin(theta) cos(theta) (Carnot paper 002, section 2.2), and the
elastic impact reverses the admissible velocity: v+ = -v- on the line of the blade, with
thetadot unchanged.  No entry may carry the spurious factor 1/(sin^2 + cos^2): not the
scene's P, not the impact map's, not the post-impact velocity, not the generated C.
"""

from __future__ import annotations

import re

import sympy as sp
from kkt_oracle import kkt_post_velocity

import symmech as sm
from symmech.codegen import generate

x, y, th = sp.symbols("x y theta", real=True)
m, J = sp.symbols("m J", positive=True)


def knife_edge() -> sm.Scene:
    return sm.Scene(
        coordinates=[x, y, th],
        metric=sp.diag(m, m, J),
        constraints=[[-sp.sin(th), sp.cos(th), 0]],
        walls=[sm.Wall(y - 1)],
        name="knife_edge",
    )


def pythagorean(e: sp.Expr) -> bool:
    """Whether e has a sum sin^2 + cos^2 anywhere (in any order, with any factor)."""
    for node in sp.preorder_traversal(e):
        if node.is_Add:
            squares = {a for a in node.args if a.is_Pow and a.exp == 2}
            if sp.sin(th) ** 2 in squares and sp.cos(th) ** 2 in squares:
                return True
    return False


def test_one_projector_for_the_scene_and_its_impact_map():
    scene = knife_edge()
    P, Q = scene.projectors()
    expected = sp.Matrix(
        [
            [sp.cos(th) ** 2, sp.sin(th) * sp.cos(th), 0],
            [sp.sin(th) * sp.cos(th), sp.sin(th) ** 2, 0],
            [0, 0, 1],
        ]
    )
    # exact, by form and not only by value: the printed entries are the textbook ones
    assert P[0, 0] == sp.cos(th) ** 2
    assert sp.simplify(P - expected) == sp.zeros(3, 3)
    imp = scene.impact_map(0)
    assert imp.projectors.P == P and imp.projectors.Q == Q
    for e in (*imp.projectors.P, *imp.projectors.PP, *imp.projectors.T, *imp.post_velocity):
        assert not pythagorean(e), e
        assert not sp.denom(sp.together(e)).has(th), e


def test_impact_map_agrees_with_the_kkt_oracle_and_reverses_the_blade():
    scene = knife_edge()
    imp = scene.impact_map(0)
    v = sp.Matrix(scene.velocities)
    mu = sp.Matrix(scene.constraint_matrix)
    kkt = kkt_post_velocity(scene.mass_matrix(), mu, sp.Matrix([[0, 1, 0]]), sp.zeros(0, 3), v, 1)
    for point in ({th: sp.Rational(1, 3)}, {th: sp.Rational(-7, 5)}, {th: 2}):
        s, w = sp.Rational(3, 2), sp.Rational(-1, 4)
        state = {v[0]: s * sp.cos(th), v[1]: s * sp.sin(th), v[2]: w, m: 2, J: sp.Rational(1, 3)}
        post = imp.post_velocity.xreplace(state).xreplace(point)
        oracle = kkt.xreplace(state).xreplace(point)
        assert all(abs(sp.N(a - b, 40)) < 1e-35 for a, b in zip(post, oracle, strict=True))
        want = sp.Matrix([-s * sp.cos(th), -s * sp.sin(th), w]).xreplace(point)
        assert all(abs(sp.N(a - b, 40)) < 1e-35 for a, b in zip(post, want, strict=True))


def test_generated_impact_function_divides_by_nothing():
    code = generate(knife_edge())
    source = next(
        text for name, text in code.files.items() if name.endswith(".c") and "python" not in name
    )
    start = source.index("impact_wall0(const double *q")
    body = source[start : source.index("\n}\n", start)]
    assert "out[0]" in body
    assert "/" not in re.sub(r"/\*.*?\*/", "", body, flags=re.S), body
