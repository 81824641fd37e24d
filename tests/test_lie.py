"""Tests of symmech.geometry.lie against hand derivations from slides 000.

Slides 000: "Computing Lie bracket in coordinates", "Frobenius integrability condition",
"Example: rolling ball", "Example: Driving a car", "Connection coefficients in a
nonholonomic basis".
"""

from __future__ import annotations

import dataclasses
import itertools

import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from symmech.errors import SceneError
from symmech.geometry.distributions import (
    BracketRankResult,
    InvolutivityResult,
    bracket_rank,
    is_involutive,
)
from symmech.geometry.lie import commutation_coefficients, hat, lie_bracket

x, y, z = sp.symbols("x y z", real=True)
XYZ = (x, y, z)
R = sp.Matrix(3, 3, sp.symbols("R0:9", real=True))
E1, E2, E3 = (1, 0, 0), (0, 1, 0), (0, 0, 1)


def is_zero(M: sp.MatrixBase) -> bool:
    return all(sp.simplify(e) == 0 for e in M)


def apply_field(X: sp.MatrixBase, f: sp.Expr, q) -> sp.Expr:
    """X f = X^i df/dq^i (the derivation X acting on a function; slides 000)."""
    return sp.Add(*[X[i] * sp.diff(f, qi) for i, qi in enumerate(q)])


# ---------------------------------------------------------------------------- lie_bracket


def test_slides_example_bracket():
    # Slides: X = (y, 0, 0), Y = (0, x, 0)  ->  [X, Y] = (-x, y, 0).
    Z = lie_bracket([y, 0, 0], [0, x, 0], XYZ)
    assert Z.shape == (3, 1)
    assert Z == sp.Matrix([-x, y, 0])


def test_bracket_accepts_columns_and_tuples_alike():
    Z1 = lie_bracket(sp.Matrix([y, 0, 0]), (0, x, 0), sp.Matrix(XYZ))
    assert Z1 == sp.Matrix([-x, y, 0])


def test_bracket_hand_computed():
    # X = (xy, z, 0), Y = (0, x^2, y):
    # X.grad Y = (0, 2x^2 y, z), Y.grad X = (x^3, y, 0)  ->  Z = (-x^3, 2x^2 y - y, z).
    Z = lie_bracket([x * y, z, 0], [0, x**2, y], XYZ)
    assert sp.expand(Z - sp.Matrix([-(x**3), 2 * x**2 * y - y, z])) == sp.zeros(3, 1)


def test_heisenberg_bracket():
    X = [1, 0, -y / 2]
    Y = [0, 1, x / 2]
    assert lie_bracket(X, Y, XYZ) == sp.Matrix([0, 0, 1])


def test_simplify_none_is_equivalent_raw_sum():
    X = [sp.cos(z), sp.sin(z), 0]
    Y = [0, 0, 1]
    raw = lie_bracket(X, Y, XYZ, simplify="none")
    assert raw == sp.Matrix([sp.sin(z), -sp.cos(z), 0])


def test_hat_is_cross_product():
    w = sp.Matrix(sp.symbols("w1:4"))
    v = sp.Matrix(sp.symbols("v1:4"))
    assert sp.expand(hat(w) * v - w.cross(v)) == sp.zeros(3, 1)
    assert hat((1, 2, 3)) == sp.Matrix([[0, -3, 2], [3, 0, -1], [-2, 1, 0]])
    assert hat(w).T == -hat(w)


def test_rolling_ball_bracket_slides():
    # Slides: [[e1 x] R, [e2 x] R] = -[e3 x] R.
    Z = lie_bracket(hat(E1) * R, hat(E2) * R, R)
    assert Z.shape == (3, 3)
    assert sp.expand(Z + hat(E3) * R) == sp.zeros(3, 3)
    assert Z != hat(E3) * R  # the sign matters


def test_right_invariant_and_left_invariant_brackets():
    # Right-invariant fields [a x] R: d_X Y = [b x][a x] R, so [X, Y] = -[(a x b) x] R.
    a, b = sp.Matrix([2, -1, 3]), sp.Matrix([0, 5, -2])
    Z = lie_bracket(hat(a) * R, hat(b) * R, R)
    assert sp.expand(Z + hat(a.cross(b)) * R) == sp.zeros(3, 3)
    # Left-invariant fields R [a x]: d_X Y = R [a x][b x], so [X, Y] = +R [(a x b) x].
    W = lie_bracket(R * hat(E1), R * hat(E2), R)
    assert sp.expand(W - R * hat(E3)) == sp.zeros(3, 3)


def test_matrix_fields_on_rectangular_matrix_space():
    # 2x2 coordinates, X = A M, Y = B M  ->  [X, Y] = (B A - A B) M.
    M = sp.Matrix(2, 2, sp.symbols("m0:4"))
    A = sp.Matrix([[1, 2], [0, -1]])
    B = sp.Matrix([[0, 1], [3, 1]])
    Z = lie_bracket(A * M, B * M, M)
    assert sp.expand(Z - (B * A - A * B) * M) == sp.zeros(2, 2)


# ------------------------------------------------------------------- random polynomial fields

# Monomials of total degree <= 2 keep the nested brackets of the Jacobi test small.
_MONOMIALS = [
    x**i * y**j * z**k for i in range(3) for j in range(3) for k in range(3) if i + j + k <= 2
]
polys = st.lists(
    st.tuples(st.integers(-3, 3), st.sampled_from(_MONOMIALS)), min_size=0, max_size=3
).map(lambda terms: sp.Add(*[c * m for c, m in terms]))
vfields = st.tuples(polys, polys, polys).map(lambda t: sp.Matrix(t))


@settings(max_examples=30, deadline=None)
@given(vfields, vfields)
def test_antisymmetry(X, Y):
    assert sp.expand(lie_bracket(X, Y, XYZ) + lie_bracket(Y, X, XYZ)) == sp.zeros(3, 1)


@settings(max_examples=30, deadline=None)
@given(vfields, vfields, vfields)
def test_jacobi_identity(X, Y, W):
    def br(A, B):
        return lie_bracket(A, B, XYZ)

    total = br(X, br(Y, W)) + br(Y, br(W, X)) + br(W, br(X, Y))
    assert sp.expand(total) == sp.zeros(3, 1)


@settings(max_examples=30, deadline=None)
@given(vfields, vfields, polys)
def test_bracket_is_commutator_of_derivations(X, Y, f):
    # Slides' definition: [X, Y] f = X(Y f) - Y(X f).
    Z = lie_bracket(X, Y, XYZ)
    lhs = apply_field(Z, f, XYZ)
    rhs = apply_field(X, apply_field(Y, f, XYZ), XYZ) - apply_field(Y, apply_field(X, f, XYZ), XYZ)
    assert sp.expand(lhs - rhs) == 0


@settings(max_examples=30, deadline=None)
@given(vfields, vfields, polys)
def test_leibniz_rule(X, Y, f):
    # [X, f Y] = (X f) Y + f [X, Y]
    lhs = lie_bracket(X, f * Y, XYZ)
    rhs = apply_field(X, f, XYZ) * Y + f * lie_bracket(X, Y, XYZ)
    assert sp.expand(lhs - rhs) == sp.zeros(3, 1)


# ----------------------------------------------------------------------- Frobenius / rank

th, ka, cx, cy = sp.symbols("theta kappa x y", real=True)
CAR_Q = (cx, cy, th, ka)
CAR = [[sp.cos(th), sp.sin(th), ka, 0], [0, 0, 0, 1]]
BALL = [hat(E1) * R, hat(E2) * R]


def test_car_not_involutive_with_certificate():
    res = is_involutive(CAR, CAR_Q)
    assert isinstance(res, InvolutivityResult)
    assert not res
    assert res.involutive is False
    assert res.pair == (0, 1)
    # [X1, X2] = -dX1/dkappa = (0, 0, -1, 0)
    assert res.bracket == sp.Matrix([0, 0, -1, 0])
    assert res.rank == 2
    assert res.dimension == 4
    assert "generic" in res.policy


def test_car_bracket_generating_at_depth_3():
    res = bracket_rank(CAR, CAR_Q, depth=3)
    assert isinstance(res, BracketRankResult)
    assert res.rank == 4
    assert res.bracket_generating
    assert res.dimension == res.manifold_dimension == 4
    assert len(res.fields) == len(res.words) == 4
    # Hand derivation: [X2, X1] = d/dtheta, [X1, d/dtheta] = (sin, -cos, 0, 0).
    assert res.words[2] == (1, 0)
    assert res.fields[2] == sp.Matrix([0, 0, 1, 0])
    assert res.words[3] == (0, 1, 0)
    assert sp.simplify(res.fields[3] - sp.Matrix([sp.sin(th), -sp.cos(th), 0, 0])) == sp.zeros(4, 1)


def test_car_depth_2_is_not_enough():
    res = bracket_rank(CAR, CAR_Q, depth=2)
    assert res.rank == 3
    assert not res.bracket_generating


def test_rolling_ball_not_involutive():
    res = is_involutive(BALL, R)
    assert not res
    assert res.pair == (0, 1)
    assert res.bracket.shape == (3, 3)
    assert sp.expand(res.bracket + hat(E3) * R) == sp.zeros(3, 3)
    assert res.rank == 2
    assert res.dimension == 9


def test_rolling_ball_bracket_generating_on_so3():
    res = bracket_rank(BALL, R, depth=3, dim=3)
    assert res.rank == 3
    assert res.bracket_generating
    assert res.manifold_dimension == 3
    assert res.dimension == 9
    # As 9 entries (no dim given) it is not bracket generating: rank 3 < 9.
    assert not bracket_rank(BALL, R, depth=3).bracket_generating


def _cayley_rotation(a, b, c):
    """Rational rotation (I - K)^-1 (I + K) for K = [(a, b, c) x]."""
    K = hat((a, b, c))
    return (sp.eye(3) - K).inv() * (sp.eye(3) + K)


def test_rolling_ball_at_rotation_sample_points():
    rots = [_cayley_rotation(*v) for v in [(1, 2, 3), (sp.Rational(1, 2), -1, 2)]]
    for Q in rots:
        assert sp.simplify(Q.T * Q) == sp.eye(3)
    points = [dict(zip(R, Q, strict=True)) for Q in rots]
    assert not is_involutive(BALL, R, points=points)
    assert bracket_rank(BALL, R, dim=3, points=points).rank == 3
    # All three rotation fields: involutive (SO(3) itself), rank 3.
    res = is_involutive([*BALL, hat(E3) * R], R, points=points)
    assert res
    assert res.rank == 3


def test_holonomic_coordinate_plane():
    res = is_involutive([[1, 0, 0], [0, 1, 0]], XYZ)
    assert res
    assert res.pair is None and res.bracket is None
    assert res.rank == 2
    br = bracket_rank([[1, 0, 0], [0, 1, 0]], XYZ)
    assert br.rank == 2
    assert not br.bracket_generating


def test_holonomic_tangent_to_spheres():
    # Rotation fields x_i d_j - x_j d_i are tangent to |x| = const; any two span the
    # tangent plane generically, with [L1, L2] = -L3 = (x L1 + y L2) / z.
    L1 = [0, -z, y]
    L2 = [z, 0, -x]
    L3 = [-y, x, 0]
    assert sp.expand(lie_bracket(L1, L2, XYZ) + sp.Matrix(L3)) == sp.zeros(3, 1)
    res = is_involutive([L1, L2], XYZ)
    assert res
    assert res.rank == 2
    assert is_involutive([L1, L2, L3], XYZ).rank == 2
    assert bracket_rank([L1, L2], XYZ, depth=4).rank == 2


def test_heisenberg_not_involutive_but_generating():
    res = is_involutive([[1, 0, -y / 2], [0, 1, x / 2]], XYZ)
    assert not res
    assert res.bracket == sp.Matrix([0, 0, 1])
    assert bracket_rank([[1, 0, -y / 2], [0, 1, x / 2]], XYZ, depth=2).bracket_generating


def test_single_field_is_involutive():
    assert is_involutive([[x * y, sp.sin(z), 1]], XYZ)


def test_result_is_frozen():
    res = is_involutive(CAR, CAR_Q)
    with pytest.raises(dataclasses.FrozenInstanceError):
        res.involutive = True  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        bracket_rank(CAR, CAR_Q).rank = 0  # type: ignore[misc]


def test_numeric_check_catches_missed_zero():
    # sqrt(x^2 + 2x + 1) - x == 1 for x > 0, which sympy's simplify does not see.
    xp = sp.Symbol("xp", positive=True)
    e = sp.sqrt(xp**2 + 2 * xp + 1) - xp
    fields = [[e, 1], [1, 1]]  # both equal (1, 1): rank 1, trivially involutive
    res = is_involutive(fields, (xp, y))
    assert res
    assert res.rank == 1
    assert any("disagrees" in note for note in res.notes)
    br = bracket_rank(fields, (xp, y))
    assert br.rank == 1
    assert not br.bracket_generating


def test_unsimplified_trig_identity():
    a = sp.Symbol("a", real=True)
    fields = [[sp.cos(a) ** 2 + sp.sin(a) ** 2, 1], [1, 1]]
    assert is_involutive(fields, (a, y), simplify=False).rank == 1
    assert bracket_rank(fields, (a, y), simplify=False).rank == 1


def test_symbolic_fallback_is_reported():
    f = sp.Function("f")
    res = is_involutive([[f(x), 0], [0, 1]], (x, y))
    assert res
    assert res.rank == 2
    assert any("could not evaluate numerically" in note for note in res.notes)


# ------------------------------------------------------------------------------- frames


def _recombine(c, S, k, l):
    n = S.rows
    return sp.Matrix([sp.Add(*[c[m, k, l] * S[i, m] for m in range(n)]) for i in range(n)])


def test_polar_orthonormal_frame():
    r = sp.Symbol("r", positive=True)
    t = sp.Symbol("theta", real=True)
    S = sp.diag(1, 1 / r)  # u1 = d/dr, u2 = (1/r) d/dtheta
    c = commutation_coefficients(S, (r, t))
    assert c.shape == (2, 2, 2)
    # [u1, u2] = d/dr (1/r) d/dtheta = -(1/r^2) d/dtheta = -(1/r) u2.
    assert sp.simplify(c[1, 0, 1] + 1 / r) == 0
    assert sp.simplify(c[1, 1, 0] - 1 / r) == 0
    for m, k, l in itertools.product(range(2), repeat=3):
        if (m, k, l) not in ((1, 0, 1), (1, 1, 0)):
            assert c[m, k, l] == 0


def test_rotating_planar_frame():
    # u1 = (cos, sin, 0), u2 = (-sin, cos, 0), u3 = d/dtheta on (x, y, theta):
    # [u3, u1] = u2, [u3, u2] = -u1, [u1, u2] = 0.
    S = sp.Matrix([[sp.cos(th), -sp.sin(th), 0], [sp.sin(th), sp.cos(th), 0], [0, 0, 1]])
    c = commutation_coefficients(S, (cx, cy, th))
    expected = sp.MutableDenseNDimArray.zeros(3, 3, 3)
    expected[1, 2, 0], expected[1, 0, 2] = 1, -1
    expected[0, 2, 1], expected[0, 1, 2] = -1, 1
    for idx in itertools.product(range(3), repeat=3):
        assert sp.simplify(c[idx] - expected[idx]) == 0, idx


def test_coordinate_frame_has_zero_coefficients():
    c = commutation_coefficients(sp.eye(3), XYZ)
    assert c.shape == (3, 3, 3)
    assert all(v == 0 for v in sp.flatten(c.tolist()))


def _unit_triangular(entries, lower):
    M = sp.eye(3)
    slots = [(1, 0), (2, 0), (2, 1)] if lower else [(0, 1), (0, 2), (1, 2)]
    for (i, j), e in zip(slots, entries, strict=True):
        M[i, j] = e
    return M


small_polys = st.lists(
    st.tuples(st.integers(-2, 2), st.sampled_from([x, y, z, x * y, z**2, sp.S.One])),
    max_size=2,
).map(lambda terms: sp.Add(*[c * m for c, m in terms]))
frames = st.tuples(
    st.tuples(small_polys, small_polys, small_polys),
    st.tuples(small_polys, small_polys, small_polys),
).map(lambda lu: _unit_triangular(lu[0], True) * _unit_triangular(lu[1], False))


@settings(max_examples=10, deadline=None)
@given(frames)
def test_random_frame_coefficients(S):
    # det S = 1, so S is a frame everywhere.
    c = commutation_coefficients(S, XYZ)
    n = 3
    for m, k, l in itertools.product(range(n), repeat=3):
        assert sp.expand(c[m, k, l] + c[m, l, k]) == 0  # antisymmetry
    for k, l in itertools.product(range(n), repeat=2):
        bracket = lie_bracket(S[:, k], S[:, l], XYZ)
        assert sp.expand(_recombine(c, S, k, l) - bracket) == sp.zeros(3, 1)
    # Jacobi identity in frame form: sum_cyc u_k(c^m_lp) + c^r_lp c^m_kr = 0.
    for m in range(n):
        for k, l, p in [(0, 1, 2)]:
            total = 0
            for a, b, d in [(k, l, p), (l, p, k), (p, k, l)]:
                total += apply_field(S[:, a], c[m, b, d], XYZ)
                total += sp.Add(*[c[r, b, d] * c[m, a, r] for r in range(n)])
            assert sp.expand(total) == 0


# ------------------------------------------------------------------------------- errors


def test_error_shape_mismatch_names_argument():
    with pytest.raises(SceneError, match=r"lie_bracket: Y has 2 components but q has 3"):
        lie_bracket([y, 0, 0], [0, x], XYZ)
    with pytest.raises(SceneError, match=r"X has shape 1x3 .* 3x1 column"):
        lie_bracket(sp.Matrix([[y, 0, 0]]), [0, x, 0], XYZ)


def test_error_non_expression_component():
    with pytest.raises(SceneError, match=r"component Y\[1\] = 'x' \(str\) is not a sympy"):
        lie_bracket([y, 0, 0], [0, "x", 0], XYZ)
    with pytest.raises(SceneError, match=r"component X\[0\] = None"):
        lie_bracket([None, 0, 0], [0, x, 0], XYZ)
    with pytest.raises(SceneError, match=r"X must be .* sequence of 3 expressions, got str"):
        lie_bracket("y00", [0, x, 0], XYZ)


def test_error_bad_coordinates():
    with pytest.raises(SceneError, match=r"q\[1\] = x\*\*2 is not a sympy Symbol"):
        lie_bracket([1, 0], [0, 1], (x, x**2))
    with pytest.raises(SceneError, match=r"coordinate x appears twice"):
        lie_bracket([1, 0], [0, 1], (x, x))
    with pytest.raises(SceneError, match=r"q is empty"):
        lie_bracket([], [], ())
    with pytest.raises(SceneError, match=r"single symbol x"):
        lie_bracket([1], [x], x)


def test_error_matrix_field_shapes():
    with pytest.raises(SceneError, match=r"Y has shape 2x2 but q is a 3x3 matrix"):
        lie_bracket(hat(E1) * R, sp.eye(2), R)
    with pytest.raises(SceneError, match=r"X must be a 3x3 sympy Matrix"):
        lie_bracket([1] * 9, hat(E1) * R, R)
    with pytest.raises(SceneError, match=r"pass q as a matrix of symbols"):
        lie_bracket(hat(E1) * R, hat(E2) * R, list(R))


def test_error_hat_and_frames_and_rank_arguments():
    with pytest.raises(SceneError, match=r"hat: w must be a 3-vector"):
        hat((1, 2))
    with pytest.raises(SceneError, match=r"S has shape 2x2 but q has 3"):
        commutation_coefficients(sp.eye(2), XYZ)
    with pytest.raises(SceneError, match=r"S is degenerate: .* generic rank 2 < 3"):
        commutation_coefficients(sp.Matrix([[1, x, 0], [0, 0, 0], [0, 0, 1]]), XYZ)
    with pytest.raises(SceneError, match=r"S must be a 2x2 sympy Matrix, got list"):
        commutation_coefficients([[1, 0], [0, 1]], (x, y))
    with pytest.raises(SceneError, match=r"bracket_rank: depth must be an integer >= 1"):
        bracket_rank(CAR, CAR_Q, depth=0)
    with pytest.raises(SceneError, match=r"bracket_rank: dim must be an integer in 1\.\.4"):
        bracket_rank(CAR, CAR_Q, dim=5)
    with pytest.raises(SceneError, match=r"is_involutive: fields is empty"):
        is_involutive([], XYZ)
    with pytest.raises(SceneError, match=r"is_involutive: fields\[1\] has 2 components"):
        is_involutive([[1, 0, 0], [0, 1]], XYZ)


@pytest.mark.parametrize(
    "bad", [float("nan"), float("inf"), 1j, sp.zoo, sp.oo * sp.Symbol("x"), sp.I]
)
def test_components_that_are_not_finite_and_real_are_refused(bad):
    with pytest.raises(
        SceneError, match=r"lie_bracket: component X\[0\] = .* is not finite and real"
    ):
        lie_bracket([bad, 0], [0, x], [x, y])
    with pytest.raises(SceneError, match=r"hat: component w\[1\] = .* is not finite and real"):
        hat([x, bad, 0])
