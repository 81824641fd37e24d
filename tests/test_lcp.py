"""The small exact LCP solver (symmech.algebra.lcp) against independent routes: the
quadratic program of a symmetric positive definite W solved by scipy's NNLS, brute force
over the active sets written here, and the two methods of the solver against each other;
degenerate problems; refusals."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize

from symmech.algebra.lcp import ENUMERATION_MAX_SIZE, LCPError, solve_lcp
from symmech.errors import SymmechError


def _spd(rng: np.random.Generator, k: int, eps: float = 1e-2) -> np.ndarray:
    B = rng.standard_normal((k, k))
    return B @ B.T + eps * np.eye(k)


def _nnls_route(W: np.ndarray, q: np.ndarray) -> np.ndarray:
    """For W = L L^T the LCP is the KKT system of min 1/2 x^T W x + q^T x, x >= 0, i.e.
    min ||L^T x + L^-1 q|| over x >= 0 (scipy.optimize.nnls)."""
    L = np.linalg.cholesky(W)
    b = -scipy.linalg.solve_triangular(L, q, lower=True)
    x, _ = scipy.optimize.nnls(L.T, b, maxiter=50 * len(q))
    return x


def _brute_force(W: np.ndarray, q: np.ndarray) -> list[np.ndarray]:
    """Every solution over the 2^k active sets (independent of the solver's code)."""
    k = len(q)
    out = []
    for mask in itertools.product([False, True], repeat=k):
        S = [i for i in range(k) if mask[i]]
        x = np.zeros(k)
        if S:
            block = W[np.ix_(S, S)]
            if abs(np.linalg.det(block)) < 1e-12:
                continue
            x[S] = np.linalg.solve(block, -q[S])
        w = W @ x + q
        if np.all(x >= -1e-9) and np.all(w >= -1e-9):
            out.append(x)
    return out


def _assert_complementary(W: np.ndarray, q: np.ndarray, x: np.ndarray, w: np.ndarray) -> None:
    scale = 1 + np.abs(q).max() + np.abs(W).max() * (1 + np.abs(x).max())
    assert np.all(x >= 0) and np.all(w >= 0)
    np.testing.assert_allclose(w, W @ x + q, atol=1e-10 * scale)
    assert abs(float(x @ w)) <= 1e-10 * scale * (1 + np.abs(x).max())


@pytest.mark.parametrize("k", range(1, 9))
def test_random_p_matrices_agree_with_the_quadratic_program(k):
    rng = np.random.default_rng(1000 + k)
    for _ in range(25):
        W = _spd(rng, k)
        q = rng.standard_normal(k)
        reference = _nnls_route(W, q)
        for method in ("auto", "enumerate", "murty"):
            if method == "enumerate" and k > 6:
                continue
            sol = solve_lcp(W, q, method=method)
            _assert_complementary(W, q, sol.x, sol.w)
            np.testing.assert_allclose(sol.x, reference, rtol=1e-7, atol=1e-7)
        assert solve_lcp(W, q).method == ("enumerate" if k <= ENUMERATION_MAX_SIZE else "murty")


def test_nonsymmetric_p_matrix_against_brute_force():
    rng = np.random.default_rng(7)
    for k in (2, 3, 5):
        for _ in range(20):
            U = np.triu(rng.standard_normal((k, k)), 1) * 3
            W = U + np.diag(rng.uniform(0.5, 2.0, k))  # triangular, positive diagonal: P
            q = rng.standard_normal(k)
            (expected,) = _brute_force(W, q)
            for method in ("enumerate", "murty"):
                sol = solve_lcp(W, q, method=method)
                np.testing.assert_allclose(sol.x, expected, rtol=1e-9, atol=1e-12)


def test_textbook_two_by_two():
    # w = W x + q with W = [[2, 1], [1, 2]], q = (-5, -6): both active, x = W^-1 (5, 6)
    sol = solve_lcp([[2.0, 1.0], [1.0, 2.0]], [-5.0, -6.0])
    np.testing.assert_allclose(sol.x, [4 / 3, 7 / 3])
    assert sol.active == (0, 1) and list(sol.w) == [0.0, 0.0]
    # q >= 0: x = 0, w = q
    sol = solve_lcp([[2.0, 1.0], [1.0, 2.0]], [1.0, 0.0])
    assert list(sol.x) == [0.0, 0.0] and list(sol.w) == [1.0, 0.0] and sol.active == ()


def test_zeros_are_exact_where_the_active_set_says_so():
    rng = np.random.default_rng(3)
    for _ in range(50):
        W = _spd(rng, 4)
        q = rng.standard_normal(4)
        sol = solve_lcp(W, q)
        inactive = [i for i in range(4) if i not in sol.active]
        assert all(sol.x[i] == 0.0 for i in inactive)
        assert all(sol.w[i] == 0.0 for i in sol.active)


def test_degenerate_problems():
    # q = 0: x = 0 is the solution of a P-matrix LCP
    W = _spd(np.random.default_rng(1), 3)
    sol = solve_lcp(W, np.zeros(3))
    assert not sol.x.any() and not sol.w.any()
    # w_i = 0 and x_i = 0 at once (a contact exactly at the switch): both methods agree
    W = np.array([[2.0, 1.0], [1.0, 2.0]])
    q = np.array([-2.0, -1.0])  # x = (1, 0) and w = (0, 0): x_1 = w_1 = 0
    for method in ("enumerate", "murty"):
        sol = solve_lcp(W, q, method=method)
        np.testing.assert_allclose(sol.x, [1.0, 0.0])
        np.testing.assert_allclose(sol.w, [0.0, 0.0], atol=1e-15)
    # a singular positive semi-definite W (two identical contacts) with a solution: the
    # enumeration returns the first admissible set of its order
    sol = solve_lcp([[1.0, 1.0], [1.0, 1.0]], [-1.0, -1.0], method="enumerate")
    assert sol.active == (0,) and list(sol.x) == [1.0, 0.0]
    # the empty problem
    sol = solve_lcp(np.zeros((0, 0)), np.zeros(0))
    assert sol.x.shape == (0,) and sol.active == ()


def test_no_solution_is_refused():
    with pytest.raises(LCPError, match="no active set is admissible"):
        solve_lcp([[0.0]], [-1.0])  # w = -1 for every x >= 0
    with pytest.raises(LCPError, match="no active set is admissible"):
        solve_lcp([[-1.0]], [-1.0])
    with pytest.raises(LCPError, match="singular block"):
        solve_lcp([[0.0]], [-1.0], method="murty")
    with pytest.raises(LCPError, match="no active set"):
        solve_lcp([[1.0, -1.0], [-1.0, 1.0]], [-1.0, -1.0])  # singular and infeasible


@pytest.mark.parametrize(
    ("W", "q", "match"),
    [
        ([[np.nan]], [1.0], "finite"),
        ([[1.0]], [np.inf], "finite"),
        ([[1.0, 0.0]], [1.0], "square"),
        ([1.0, 2.0], [1.0, 2.0], "square"),
        ([[1.0, 0.0], [0.0, 1.0]], [1.0, 2.0, 3.0], "length 2"),
        ([["a"]], [1.0], "real arrays"),
        ([[1j]], [1.0], "real arrays"),
    ],
)
def test_refusals(W, q, match):
    with pytest.raises(LCPError, match=match) as info:
        solve_lcp(W, q)
    assert isinstance(info.value, SymmechError) and isinstance(info.value, ValueError)


def test_options_are_checked():
    with pytest.raises(LCPError, match="method"):
        solve_lcp([[1.0]], [1.0], method="lemke")  # type: ignore[arg-type]
    with pytest.raises(LCPError, match="rtol"):
        solve_lcp([[1.0]], [1.0], rtol=0.0)
    with pytest.raises(LCPError, match="rtol"):
        solve_lcp([[1.0]], [1.0], rtol=float("nan"))


def test_deterministic():
    rng = np.random.default_rng(11)
    W, q = _spd(rng, 7), rng.standard_normal(7)
    a, b = solve_lcp(W, q), solve_lcp(W.copy(), q.copy())
    assert a.active == b.active and np.array_equal(a.x, b.x) and np.array_equal(a.w, b.w)
