"""The simulator's steppers: tableaux against the order conditions (exact or mpmath), orders
of convergence and of the dense outputs by regression, error estimates against true local
errors, an adaptive driver on Kepler, Rodas4 on stiff problems, the controller, the first
step, the C coefficient tables and bad input."""

from __future__ import annotations

import math
from fractions import Fraction
from functools import cache

import mpmath
import numpy as np
import pytest

from symmech.errors import SymmechError
from symmech.simulate import tableaux as tb
from symmech.simulate.c_tableaux import c_tableau
from symmech.simulate.steppers import (
    METHODS,
    Controller,
    StepperError,
    initial_step,
    stepper,
)

EXPLICIT = ("dop853", "tsit5", "rk45", "rk4")
ADAPTIVE_EXPLICIT = ("dop853", "tsit5", "rk45")

# --- rooted trees and elementary weights (HNW I, section II.2) ---------------------------


def _key(t):
    return (_nodes(t), repr(t))


@cache
def _nodes(t) -> int:
    return 1 + sum(_nodes(c) for c in t)


@cache
def _trees(n: int) -> tuple:
    """Rooted trees with ``n`` nodes (a tree is the sorted tuple of its subtrees)."""
    if n == 1:
        return ((),)
    return tuple(sorted({tuple(sorted(f, key=_key)) for f in _forests(n - 1)}, key=_key))


@cache
def _forests(m: int) -> tuple:
    if m == 0:
        return ((),)
    out = set()
    for k in range(1, m + 1):
        for t in _trees(k):
            for rest in _forests(m - k):
                out.add(tuple(sorted((t, *rest), key=_key)))
    return tuple(out)


@cache
def _density(t) -> int:
    """gamma(t) = |t| prod gamma(subtrees): the order condition is b.Phi(t) = 1/gamma(t)."""
    return _nodes(t) * math.prod(_density(c) for c in t)


def _phi(A, t, memo):
    """Stage vector of the elementary weight: Phi(()) = 1, Phi(t) = prod_children A Phi(c)."""
    if t not in memo:
        g = [A[0][0] * 0 + 1] * len(A)
        for c in t:
            gc = _phi(A, c, memo)
            g = [g[i] * sum(A[i][j] * gc[j] for j in range(len(A))) for i in range(len(A))]
        memo[t] = g
    return memo[t]


def _residuals(A, w, order, theta=None):
    """``w.Phi(t) - theta^|t| / gamma(t)`` for every tree of 1..order nodes (theta = 1 of
    the weights' arithmetic by default)."""
    memo: dict = {}
    theta = A[0][0] * 0 + 1 if theta is None else theta
    return [
        sum(wi * gi for wi, gi in zip(w, _phi(A, t, memo), strict=True)) - theta**n / _density(t)
        for n in range(1, order + 1)
        for t in _trees(n)
    ]


def _mp(x: Fraction):
    return mpmath.mpf(x.numerator) / x.denominator


def _extended(tab):
    """``A`` with the row ``b`` of ``K_s = f(t0 + h, y1)`` appended (FSAL stage)."""
    s = tab.stages
    return [[*row, 0] for row in tab.a] + [[*tab.b, 0]], s


def test_rooted_tree_counts():
    # A000081: 1, 1, 2, 4, 9, 20, 48, 115 trees; 200 conditions up to order 8
    assert [len(_trees(n)) for n in range(1, 9)] == [1, 1, 2, 4, 9, 20, 48, 115]


@pytest.mark.parametrize("name", EXPLICIT)
def test_order_conditions(name):
    """b satisfies every condition up to the order and fails one of the next order; the
    embedded weights (b - e) up to the error order (DOP853: e5 to 5 and e3 to 3); rows of
    a sum to c.  Exact for the rational rk4 and rk45, mpmath (60 digits) otherwise."""
    tab = tb.TABLEAUX[name]
    exact = name in ("rk4", "rk45")
    with mpmath.workdps(60):
        conv = (lambda x: x) if exact else _mp
        A = [[conv(x) for x in row] for row in tab.a]
        b = [conv(x) for x in tab.b]
        tol = 0 if exact else mpmath.mpf(10) ** (-26 if name == "dop853" else -50)
        for i, row in enumerate(A):
            assert abs(sum(row) - conv(tab.c[i])) <= tol
        assert max(abs(r) for r in _residuals(A, b, tab.order)) <= tol
        assert max(abs(r) for r in _residuals(A, b, tab.order + 1)) > 1e-6
        if name == "rk4":
            return
        Ae, s = _extended(tab)
        Ae = [[conv(x) for x in row] for row in Ae]
        bhat = [(b[i] if i < s else 0) - conv(tab.e[i]) for i in range(s + 1)]
        q = 5 if name == "dop853" else tab.error_order
        assert max(abs(r) for r in _residuals(Ae, bhat, q)) <= tol
        assert max(abs(r) for r in _residuals(Ae, bhat, q + 1)) > 1e-6  # a true estimate
        if name == "dop853":
            b3 = [(b[i] if i < s else 0) - _mp(tb.DOP853_EXTRAS.e3[i]) for i in range(s + 1)]
            assert max(abs(r) for r in _residuals(Ae, b3, 3)) <= tol
            assert max(abs(r) for r in _residuals(Ae, b3, 4)) > 1e-6


def _dop853_dense_weights(theta):
    """DOP853's dense weights b_i(theta) over the 16 stages, from the F formula (mpmath)."""
    x, tab = tb.DOP853_EXTRAS, tb.DOP853
    s = tab.stages
    b = [_mp(v) for v in tab.b] + [0] * 4
    e0 = [1] + [0] * 15
    e12 = [0] * 12 + [1] + [0] * 3
    F = [b, [e0[i] - b[i] for i in range(16)], [2 * b[i] - e0[i] - e12[i] for i in range(16)]]
    F += [[_mp(v) for v in row] for row in x.d]
    w = F[6]
    for k in range(5, -1, -1):
        m = (1 - theta) if k % 2 == 0 else theta
        w = [F[k][i] + m * w[i] for i in range(16)]
    A = [[_mp(v) for v in row] + [0] * 4 for row in tab.a]
    A += [[*(_mp(v) for v in tab.b), 0, 0, 0, 0]]
    A += [[_mp(v) for v in row] + [0] * (16 - len(row)) for row in x.a_extra]
    assert len(A) == 16 and s == 12
    return A, [theta * wi for wi in w]


@pytest.mark.parametrize("name", ["dop853", "tsit5", "rk45"])
@pytest.mark.parametrize("theta", ["1/4", "1/2", "4/5", "1"])
def test_dense_output_order_conditions(name, theta):
    """sum_i b_i(theta) Phi_i(t) = theta^|t| / gamma(t) up to the dense order; b_i(1) = b_i."""
    with mpmath.workdps(40):
        th = mpmath.mpf(Fraction(theta).numerator) / Fraction(theta).denominator
        tab = tb.TABLEAUX[name]
        if name == "dop853":
            A, w = _dop853_dense_weights(th)
            tol = 1e-25
        else:
            Ae, _ = _extended(tab)
            A = [[_mp(x) for x in row] for row in Ae]
            w = [sum(_mp(p) * th ** (k + 1) for k, p in enumerate(row)) for row in tab.dense]
            tol = 1e-14  # Tsitouras' r_ik are published to ~17 digits
        assert max(abs(r) for r in _residuals(A, w, tab.dense_order, th)) <= tol
        if theta == "1":
            b = [_mp(x) for x in tab.b]
            assert max(abs(w[i] - (b[i] if i < len(b) else 0)) for i in range(len(w))) <= tol


def test_rodas4_order_conditions_and_l_stability():
    """Back to alpha, Gamma (Gamma^-1 = diag(1/gamma) - C, alpha = a Gamma, b = m Gamma):
    the Rosenbrock conditions of HNW II table VI.7.1 to order 4 (embedded: 3), c = row
    sums of alpha, d = row sums of Gamma; R(z) -> 0 as z -> -inf (L-stable)."""
    t = tb.RODAS4
    with mpmath.workdps(30):
        g = _mp(t.gamma)
        Ginv = mpmath.matrix(6, 6)
        for i in range(6):
            for j in range(6):
                Ginv[i, j] = (1 / g if i == j else 0) - _mp(t.C[i][j])
        G = Ginv**-1
        alpha = mpmath.matrix([[_mp(x) for x in r] for r in t.a]) * G
        beta = alpha + G - mpmath.diag([g] * 6)  # alpha_ij + gamma_ij, j < i
        one = mpmath.matrix([1] * 6)
        ai = alpha * one
        bi = beta * one
        for i in range(6):
            assert abs(ai[i] - _mp(t.c[i])) < 1e-14
            assert abs((G * one)[i] - _mp(t.d[i])) < 1e-14

        def conditions(weights):
            b = (mpmath.matrix([[_mp(x) for x in weights]]) * G).T
            dot = lambda u, v: sum(u[i] * v[i] for i in range(6))  # noqa: E731
            sq = lambda u: mpmath.matrix([u[i] ** 2 for i in range(6)])  # noqa: E731
            a3 = mpmath.matrix([ai[i] ** 3 for i in range(6)])
            return [
                dot(b, one) - 1,
                dot(b, bi) - (mpmath.mpf(1) / 2 - g),
                dot(b, sq(ai)) - mpmath.mpf(1) / 3,
                dot(b, beta * bi) - (mpmath.mpf(1) / 6 - g + g**2),
                dot(b, a3) - mpmath.mpf(1) / 4,
                dot(b, mpmath.matrix([ai[i] * (alpha * bi)[i] for i in range(6)]))
                - (mpmath.mpf(1) / 8 - g / 3),
                dot(b, beta * sq(ai)) - (mpmath.mpf(1) / 12 - g / 3),
                dot(b, beta * (beta * bi)) - (mpmath.mpf(1) / 24 - g / 2 + 1.5 * g**2 - g**3),
            ]

        assert max(abs(r) for r in conditions(t.b)) < 1e-13
        emb = conditions(t.bhat)
        assert max(abs(r) for r in emb[:4]) < 1e-13
        assert max(abs(r) for r in emb[4:]) > 1e-6
    st = stepper("rodas4")
    for lam_h in (-1e3, -1e6, -1e12):
        lam = lam_h / 0.1
        rhs = lambda t, y, lam=lam: lam * y  # noqa: E731
        jac = lambda t, y, lam=lam: np.array([[lam]])  # noqa: E731
        step = st.step(rhs, 0.0, np.ones(1), np.array([lam]), 0.1, 1e-6, 1e-6, jac)
        assert abs(step.y[0]) < 50 / abs(lam_h)  # R(z) = O(1/z), stiffly accurate


# --- test problems ---------------------------------------------------------------------


def _linear(t, y):
    return np.array([-y[0] + math.sin(5 * t)])


def _linear_exact(t):
    # y' = -y + sin 5t, y(0) = 1
    return np.array([(1 + 5 / 26) * math.exp(-t) + (math.sin(5 * t) - 5 * math.cos(5 * t)) / 26])


def _linear_jac(t, y):
    return np.array([[-1.0]])


E_KEPLER = 0.5


def _kepler(t, y):
    r3 = (y[0] ** 2 + y[1] ** 2) ** 1.5
    return np.array([y[2], y[3], -y[0] / r3, -y[1] / r3])


def _kepler_jac(t, y):
    x, z = y[0], y[1]
    r2 = x * x + z * z
    r5 = r2**2.5
    J = np.zeros((4, 4))
    J[0, 2] = J[1, 3] = 1.0
    J[2, 0] = (2 * x * x - z * z) / r5
    J[3, 1] = (2 * z * z - x * x) / r5
    J[2, 1] = J[3, 0] = 3 * x * z / r5
    return J


def _kepler_exact(t):
    """Closed form through Kepler's equation E - e sin E = t (Newton), period 2 pi,
    pericentre at t = 0."""
    e = E_KEPLER
    E = t
    for _ in range(50):
        E -= (E - e * math.sin(E) - t) / (1 - e * math.cos(E))
    w = math.sqrt(1 - e * e)
    d = 1 - e * math.cos(E)
    return np.array([math.cos(E) - e, w * math.sin(E), -math.sin(E) / d, w * math.cos(E) / d])


def _pendulum(t, y):
    return np.array([y[1], -math.sin(y[0])])


def _pendulum_jac(t, y):
    return np.array([[0.0, 1.0], [-math.cos(y[0]), 0.0]])


@cache
def _pendulum_reference(t_end: float) -> tuple[float, ...]:
    """The pendulum from (0.5, 0) by SciPy's DOP853 at its tightest tolerance (~1e-14)."""
    from scipy.integrate import solve_ivp

    sol = solve_ivp(_pendulum, (0, t_end), [0.5, 0.0], method="DOP853", rtol=2.3e-14, atol=1e-16)
    return tuple(sol.y[:, -1])


PROBLEMS = {
    "linear": (_linear, _linear_jac, _linear_exact(0.0), 2.0, lambda: _linear_exact(2.0)),
    "pendulum": (_pendulum, _pendulum_jac, np.array([0.5, 0.0]), 10.0,
                 lambda: np.array(_pendulum_reference(10.0))),
    "kepler": (_kepler, _kepler_jac, _kepler_exact(0.0), math.pi, lambda: _kepler_exact(math.pi)),
}  # fmt: skip

# Step counts in each method's asymptotic range, with global errors between ~1e-4 and
# ~1e-13.  DOP853 is not run on Kepler (e = 0.5): its h^8 regime there starts at the
# float64 rounding floor.
STEPS = {
    ("dop853", "linear"): (8, 12, 16, 24),
    ("dop853", "pendulum"): (16, 24, 32, 48),
    ("tsit5", "linear"): (48, 64, 96, 128),
    ("tsit5", "pendulum"): (64, 96, 128, 192),
    ("tsit5", "kepler"): (128, 192, 256, 384),
    ("rk45", "linear"): (48, 64, 96, 128),
    ("rk45", "pendulum"): (64, 96, 128, 192),
    ("rk45", "kepler"): (128, 192, 256, 384),
    ("rk4", "linear"): (16, 24, 32, 48),
    ("rk4", "pendulum"): (32, 48, 64, 96),
    ("rk4", "kepler"): (256, 384, 512, 768),
    ("rodas4", "linear"): (24, 32, 48, 64),
    ("rodas4", "pendulum"): (32, 48, 64, 96),
    ("rodas4", "kepler"): (512, 768, 1024, 1536),
}


def _fixed(st, f, jac, y0, t_end, n, t0=0.0):
    h = (t_end - t0) / n
    t, y = t0, np.array(y0, dtype=float)
    fy = f(t, y)
    for i in range(n):
        step = st.step(f, t, y, fy, h, 1e-6, 1e-6, jac)
        t, y, fy = t0 + (i + 1) * h, step.y, step.f
    return y


def _slope(hs, errors):
    return float(np.polyfit(np.log(hs), np.log(errors), 1)[0])


@pytest.mark.parametrize(("name", "problem"), list(STEPS))
def test_convergence_order(name, problem):
    """Global error over fixed steps: slope of log error on log h within 0.3 of the order
    (y' = -y + sin 5t on [0, 2] and Kepler with e = 0.5 from pericentre to apocentre
    against their closed forms, the pendulum on [0, 10] against a tight SciPy run)."""
    f, jac, y0, t_end, exact = PROBLEMS[problem]
    steps = STEPS[name, problem]
    st = stepper(name)
    ref = exact()
    errors = [np.max(np.abs(_fixed(st, f, jac, y0, t_end, n) - ref)) for n in steps]
    hs = [t_end / n for n in steps]
    assert min(errors) > 1e-13 and max(errors) < 1e-3, errors  # the method, not rounding
    assert abs(_slope(hs, errors) - st.order) <= 0.3, (errors, _slope(hs, errors))


@pytest.mark.parametrize("name", METHODS)
def test_backward_steps_converge_too(name):
    """h < 0 integrates backwards: the pendulum from t = 10 back to 0 at the method's order."""
    st = stepper(name)
    steps = STEPS[name, "pendulum"]
    y10 = np.array(_pendulum_reference(10.0))
    errors = [
        np.max(np.abs(_fixed(st, _pendulum, _pendulum_jac, y10, 0.0, n, t0=10.0) - [0.5, 0.0]))
        for n in steps
    ]
    assert min(errors) > 1e-13, errors
    assert abs(_slope([10.0 / n for n in steps], errors) - st.order) <= 0.3, errors


DENSE_H = {"dop853": (0.8, 0.6, 0.4, 0.3), "rk4": (0.4, 0.2, 0.1, 0.05)}


@pytest.mark.parametrize("name", METHODS)
def test_dense_output_order(name):
    """One step from the exact state: the dense output's error at interior points behaves
    like h^(dense_order + 1) (slope within 0.3), on the pendulum."""
    st = stepper(name)
    hs = DENSE_H.get(name, (0.4, 0.2, 0.1, 0.05))
    from scipy.integrate import solve_ivp

    y0 = np.array([1.0, 0.3])
    errors = []
    for h in hs:
        ts = [0.3 * h, 0.55 * h, 0.85 * h]
        ref = solve_ivp(_pendulum, (0, h), y0, method="DOP853", t_eval=ts, rtol=1e-13, atol=1e-16)
        step = st.step(_pendulum, 0.0, y0, _pendulum(0, y0), h, 1e-6, 1e-6, _pendulum_jac)
        errors.append(
            max(
                np.max(np.abs(step.dense(th) - ref.y[:, k]))
                for k, th in enumerate((0.3, 0.55, 0.85))
            )
        )
        assert np.allclose(step.dense(1.0), step.y, rtol=1e-13, atol=1e-14)
        assert np.allclose(step.dense(0.0), y0, rtol=0, atol=1e-15)
    assert abs(_slope(hs, errors) - (st.dense_order + 1)) <= 0.3, errors


@pytest.mark.parametrize("name", ["dop853", "tsit5", "rk45", "rodas4"])
def test_error_estimate_tracks_the_local_error(name):
    """Over random states and steps on Kepler, the error norm with rtol = 0, atol = 1
    (plain RMS) tracks the true local error of the solution it estimates: the ratio stays
    within a factor 10 band whose geometric mean lies in [0.5, 5].  tsit5, rk45 and rodas4
    estimate their embedded solution (they propagate the higher order); DOP853's blended
    estimate is compared with its propagated y1 and never under-estimates it."""
    st = stepper(name)
    rng = np.random.default_rng(7)
    ratios = []
    for _ in range(16):
        t0 = rng.uniform(0, 2 * math.pi)
        h = rng.uniform(0.05, 0.15) * (3 if name == "dop853" else 1)
        y0 = _kepler_exact(t0)
        step = st.step(_kepler, t0, y0, _kepler(t0, y0), h, 0.0, 1.0, _kepler_jac)
        exact = _kepler_exact(t0 + h)
        if name == "dop853":
            true = math.sqrt(np.mean((step.y - exact) ** 2))
            assert step.error >= true
        else:  # the embedded solution is y1 - (y1 - yhat)
            err_vec = _embedded_error_vector(tb.TABLEAUX[name], t0, y0, h)
            true = math.sqrt(np.mean((step.y - err_vec - exact) ** 2))
        ratios.append(step.error / true)
    assert max(ratios) / min(ratios) <= 10, ratios
    assert 0.5 <= math.exp(np.mean(np.log(ratios))) <= 5, ratios


def _embedded_error_vector(tab, t0, y0, h):
    """``y1 - yhat`` recomputed from the stages with the tableau's own weights."""
    if isinstance(tab, tb.RosenbrockTableau):
        n = y0.size
        x = tab.arrays
        J = _kepler_jac(t0, y0)
        W = np.eye(n) / (float(x["gamma"]) * h) - J
        U = np.zeros((6, n))
        f0 = _kepler(t0, y0)
        for i in range(6):
            fi = f0 if i == 0 else _kepler(t0 + x["c"][i] * h, y0 + x["a"][i, :i] @ U[:i])
            U[i] = np.linalg.solve(W, fi + (x["C"][i, :i] @ U[:i]) / h)  # autonomous: f_t = 0
        return (x["b"] - x["bhat"]) @ U
    x = tab.arrays
    s = tab.stages
    K = np.zeros((s + 1, y0.size))
    K[0] = _kepler(t0, y0)
    for i in range(1, s):
        K[i] = _kepler(t0 + x["c"][i] * h, y0 + h * (x["a"][i, :i] @ K[:i]))
    K[s] = _kepler(t0 + h, y0 + h * (x["b"] @ K[:s]))
    return h * (x["e"] @ K)


def _drive(st, f, jac, y0, t_end, rtol, atol, max_steps=100_000):
    """A plain adaptive loop: initial_step, then the Controller.  Returns (y, accepted,
    rejected, nfev); y is None, and nfev the time reached, when max_steps runs out."""
    t, y = 0.0, np.array(y0, dtype=float)
    fy = f(t, y)
    h = min(initial_step(f, t, y, fy, 1, st.error_order, rtol, atol), t_end)
    ctrl = Controller(st.error_order)
    accepted = rejected = nfev = 0
    while t < t_end:
        if accepted + rejected >= max_steps:
            return None, accepted, rejected, t
        h = min(h, t_end - t)
        step = st.step(f, t, y, fy, h, rtol, atol, jac)
        nfev += step.nfev
        ok, factor = ctrl(step.error)
        if ok:
            t = t_end if h == t_end - t else t + h
            y, fy = step.y, step.f
            accepted += 1
        else:
            rejected += 1
        h *= factor
    return y, accepted, rejected, nfev


@pytest.mark.parametrize(
    ("name", "rtol"), [("dop853", 1e-10), ("tsit5", 1e-10), ("rk45", 1e-10), ("rodas4", 1e-8)]
)
def test_adaptive_driver_reaches_tolerance_on_kepler(name, rtol):
    """One period of Kepler (e = 0.5, pericentre to pericentre) with atol = rtol / 100:
    the final error is within 100 rtol |y|_max (a global error: the local tolerance
    accumulated over the orbit; measured 19, 24, 45 and 0.5 for the four methods)."""
    st = stepper(name)
    atol = rtol * 1e-2
    y, accepted, rejected, _ = _drive(
        st, _kepler, _kepler_jac, _kepler_exact(0.0), 2 * math.pi, rtol, atol
    )
    exact = _kepler_exact(2 * math.pi)
    scaled = np.max(np.abs(y - exact)) / (rtol * np.max(np.abs(exact)))
    assert scaled <= 100, (scaled, accepted, rejected)
    assert accepted < {"dop853": 100, "tsit5": 500, "rk45": 500, "rodas4": 1000}[name]


@pytest.mark.parametrize(("name", "method"), [("dop853", "DOP853"), ("rk45", "RK45")])
def test_same_algorithm_as_scipy_step_for_step(name, method):
    """dop853 and rk45 with initial_step and the default Controller are SciPy's DOP853 and
    RK45 (same tables, error norms, first step and step rule), so one Kepler period takes
    the same right-hand-side calls and ends on the same state to rounding."""
    from scipy.integrate import solve_ivp

    for rtol in (1e-5, 1e-9):
        y0 = _kepler_exact(0.0)
        y, accepted, _, nfev = _drive(
            stepper(name), _kepler, None, y0, 2 * math.pi, rtol, rtol * 1e-2
        )
        sol = solve_ivp(_kepler, (0, 2 * math.pi), y0, method=method, rtol=rtol, atol=rtol * 1e-2)
        assert sol.nfev == nfev + 2  # SciPy also counts f(t0, y0) and initial_step's call
        assert sol.t.size - 1 == accepted
        assert np.allclose(y, sol.y[:, -1], rtol=1e-11, atol=1e-12)  # summation order


LAM = -1e6


def _prothero(t, y):
    """Prothero-Robinson: y' = lambda (y - cos t) - sin t, y = cos t; stiffness -lambda."""
    return np.array([LAM * (y[0] - math.cos(t)) - math.sin(t)])


def _robertson(t, y):
    a, b, c = y
    return np.array([-0.04 * a + 1e4 * b * c, 0.04 * a - 1e4 * b * c - 3e7 * b * b, 3e7 * b * b])


def _robertson_jac(t, y):
    _, b, c = y
    return np.array(
        [[-0.04, 1e4 * c, 1e4 * b], [0.04, -1e4 * c - 6e7 * b, -1e4 * b], [0.0, 6e7 * b, 0.0]]
    )


def test_rodas4_on_stiff_problems_where_explicit_methods_crawl():
    """Prothero-Robinson with lambda = -1e6 on [0, 2]: Rodas4 in under 60 steps to 1e-6,
    while rk45 and dop853 cover under 1% of the interval in 1000 steps (their stability
    bound is |h lambda| < ~3.3: they need over 1e5 steps, 2000 times more).  Robertson on
    [0, 1e3]: Rodas4 in under 200 steps matches SciPy's Radau (an independent implicit
    method) to 10 rtol relative."""
    jac = lambda t, y: np.array([[LAM]])  # noqa: E731
    y, acc, rej, _ = _drive(stepper("rodas4"), _prothero, jac, [1.0], 2.0, 1e-6, 1e-8)
    assert acc + rej < 60 and abs(y[0] - math.cos(2.0)) < 1e-6, (acc, rej, y)
    for name in ("rk45", "dop853"):
        y, acc, rej, reached = _drive(stepper(name), _prothero, None, [1.0], 2.0, 1e-6, 1e-8, 1000)
        assert y is None and reached < 0.01 * 2.0, (name, reached)
    from scipy.integrate import solve_ivp

    y0 = [1.0, 0.0, 0.0]
    y, acc, rej, _ = _drive(stepper("rodas4"), _robertson, _robertson_jac, y0, 1e3, 1e-6, 1e-12)
    ref = solve_ivp(
        _robertson, (0, 1e3), y0, method="Radau", jac=_robertson_jac, rtol=1e-9, atol=1e-15
    )
    assert acc + rej < 200, (acc, rej)
    assert np.allclose(y, ref.y[:, -1], rtol=1e-5, atol=0), (y, ref.y[:, -1])


# --- controller, first step, tables, bookkeeping, bad input -----------------------------


def test_controller_rule():
    c = Controller(4)
    ok, f = c(0.5)
    assert ok and f == pytest.approx(0.9 * 0.5 ** (-1 / 5))
    ok, f = c(0.0)
    assert ok and f == 10.0
    ok, f = c(1e-30)
    assert ok and f == 10.0  # capped at max_factor
    ok, f = c(1e6)
    assert not ok and f == 0.2  # floored at min_factor
    ok, f = c(2.0)
    assert not ok and f == pytest.approx(0.9 * 2.0 ** (-1 / 5))
    ok, f = c(1e-3)
    assert ok and f == 1.0  # after a rejection: no growth
    ok, f = c(1e-3)
    assert ok and f > 1.0
    assert c(float("nan")) == (False, 0.2) and c(float("inf")) == (False, 0.2)
    pi = Controller(4, beta=0.04)
    pi(0.5)
    ok, f = pi(0.25)
    assert ok and f == pytest.approx(0.9 * 0.25 ** (-(0.2 - 0.03)) * 0.5**0.04)
    pi.reset()
    assert pi.previous == 1e-4 and not pi.rejected


@pytest.mark.parametrize("direction", [1, -1])
def test_initial_step_matches_scipy(direction):
    from scipy.integrate._ivp.common import select_initial_step

    y0 = _kepler_exact(0.3)
    f0 = _kepler(0.3, y0)
    for order, rtol, atol in ((4, 1e-6, 1e-9), (7, 1e-10, np.full(4, 1e-12)), (3, 1e-3, 1e-6)):
        ours = initial_step(_kepler, 0.3, y0, f0, direction, order, rtol, atol)
        theirs = select_initial_step(
            _kepler, 0.3, y0, np.inf, np.inf, f0, direction, order, rtol, atol
        )
        assert ours == pytest.approx(theirs, rel=1e-12)


@pytest.mark.parametrize("name", METHODS)
def test_c_tableau_matches_the_steppers(name):
    """c_tableau gives correctly rounded floats of the exact tables, with the documented
    shapes: a C loop using them reproduces one step of the Python stepper."""
    d = c_tableau(name)
    assert all(isinstance(v, float) for vals in d.values() for v in vals)
    tab = tb.TABLEAUX[name]
    s = tab.stages
    assert len(d["c"]) == s and len(d["a"]) == s * (s - 1) // 2
    assert d["c"] == [float(x) for x in tab.c]
    if name == "rodas4":
        assert len(d["C"]) == 15 and len(d["h"]) == 12 and d["gamma"] == [0.25]
        return
    assert len(d["b"]) == s and sum(d["b"]) == pytest.approx(1.0, abs=1e-15)
    # a loop written from the flat lists only, as the C port will be
    y0 = _kepler_exact(0.2)
    h = 0.1
    K = [_kepler(0.2, y0)]
    for i in range(1, s):
        row = d["a"][i * (i - 1) // 2 : i * (i + 1) // 2]
        K.append(
            _kepler(0.2 + d["c"][i] * h, y0 + h * sum(r * k for r, k in zip(row, K, strict=True)))
        )
    y1 = y0 + h * sum(bi * k for bi, k in zip(d["b"], K, strict=True))
    step = stepper(name).step(_kepler, 0.2, y0, K[0], h, 1e-6, 1e-6)
    assert np.allclose(y1, step.y, rtol=0, atol=1e-15)
    if name == "dop853":
        assert len(d["e"]) == len(d["e3"]) == 13 and len(d["a_extra"]) == 42 and len(d["d"]) == 64
    elif name in ("tsit5", "rk45"):
        assert len(d["e"]) == s + 1 and len(d["dense"]) == (s + 1) * 4


def test_rhs_call_counts_and_lazy_dense_output():
    calls = [0]

    def f(t, y):
        calls[0] += 1
        return _kepler(t, y)

    y0 = _kepler_exact(0.0)
    for name, n in (("dop853", 12), ("tsit5", 6), ("rk45", 6), ("rk4", 4), ("rodas4", 7)):
        calls[0] = 0
        step = stepper(name).step(f, 0.0, y0, _kepler(0, y0), 0.1, 1e-6, 1e-6, _kepler_jac)
        assert step.nfev == calls[0] == n
        step.dense(0.5)
        step.dense(0.7)
        extra = 3 if name == "dop853" else 0
        assert step.nfev == calls[0] == n + extra


def test_non_finite_steps_report_infinite_error():
    def blow(t, y):
        return np.array([np.inf if t > 0 else 1.0])

    for name in METHODS:
        with np.errstate(invalid="ignore", over="ignore"):
            step = stepper(name).step(
                blow, 0.0, np.ones(1), np.ones(1), 0.1, 1e-6, 1e-6, _linear_jac
            )
        assert step.error == math.inf  # rk4 too: a fixed step still reports its failure
        assert Controller(4)(step.error) == (False, 0.2)


def test_bad_input_raises_stepper_errors():
    y0 = np.ones(1)
    rodas, tsit5 = stepper("rodas4"), stepper("tsit5")
    eye2 = lambda t, y: np.eye(2)  # noqa: E731
    two = lambda t, y: np.ones(2)  # noqa: E731
    cases = [
        (lambda: stepper("euler"), "unknown integration method 'euler'"),
        (lambda: c_tableau("rk23"), "unknown integration method 'rk23'"),
        (lambda: stepper("rk45").step(_linear, 0.0, y0, y0, 0.0, 1e-6, 1e-6), "h = 0.0"),
        (lambda: stepper("rk45").step(_linear, 0.0, y0, y0, math.nan, 1e-6, 1e-6), "h = nan"),
        (lambda: tsit5.step(two, 0.0, y0, y0, 0.1, 1e-6, 1e-6), "shape (2,)"),
        (lambda: stepper("rodas4").step(_linear, 0.0, y0, y0, 0.1, 1e-6, 1e-6), "needs jac"),
        (lambda: rodas.step(_linear, 0.0, y0, y0, 0.1, 1e-6, 1e-6, eye2), "returned shape (2, 2)"),
        (lambda: initial_step(_linear, 0.0, y0, y0, 1, 4, 1e-20, 1e-6), "rtol = 1e-20"),
        (lambda: initial_step(_linear, 0.0, y0, y0, 1, 4, 1e-6, -1.0), "atol = -1.0"),
        (lambda: initial_step(_linear, 0.0, y0, y0, 1, 4, 1e-6, [1e-6] * 2), "atol of shape (2,)"),
        (lambda: initial_step(_linear, 0.0, y0, y0, 0, 4, 1e-6, 1e-6), "direction = 0"),
        (lambda: Controller(4, min_factor=2.0), "min_factor"),
    ]  # fmt: skip
    for call, text in cases:
        with pytest.raises(StepperError, match=None) as info:
            call()
        assert isinstance(info.value, SymmechError) and isinstance(info.value, ValueError)
        assert text in str(info.value), (text, str(info.value))
