"""The mpmath Gauss-Legendre reference stepper: coefficients against the Gauss quadrature
formulas, 30 correct digits on the harmonic oscillator and the pendulum (closed forms with
mpmath's elliptic functions), order by regression, error estimate, dense output, failure
and bad input."""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest

from symmech.simulate.precise import GaussLegendre, gauss_legendre_coefficients
from symmech.simulate.steppers import Controller, StepperError

mpf = mpmath.mpf


def _vec(*values) -> np.ndarray:
    return np.array([mpf(v) for v in values], dtype=object)


def _oscillator(t, y):
    return np.array([y[1], -y[0]], dtype=object)


def _pendulum(t, y):
    return np.array([y[1], -mpmath.sin(y[0])], dtype=object)


def _pendulum_exact(t, theta0=1):
    """theta(t) = 2 asin(k sn(K - t | k^2)), omega = -2 k cn(K - t | k^2), k = sin(theta0/2):
    the pendulum released from rest at theta0 (t = 0 is a turning point)."""
    k = mpmath.sin(mpf(theta0) / 2)
    m = k * k
    u = mpmath.ellipk(m) - t
    return _vec(
        2 * mpmath.asin(k * mpmath.ellipfun("sn", u, m=m)), -2 * k * mpmath.ellipfun("cn", u, m=m)
    )


def _drive(gl, f, y0, t_end, rtol, atol, h):
    """A plain adaptive loop with the float Controller; returns the final state and the
    number of accepted steps."""
    ctrl = Controller(gl.error_order)
    t, y = mpf(0), y0
    fy = f(t, y)
    accepted = 0
    while t < t_end:
        h = min(h, t_end - t)
        step = gl.step(f, t, y, fy, h, rtol, atol)
        ok, factor = ctrl(step.error)
        if ok:
            t, y, fy = t + h, step.y, step.f
            accepted += 1
        h = h * factor
    return y, accepted


def _err(y, ref) -> mpf:
    return max(abs(a - b) for a, b in zip(y, ref, strict=True))


@pytest.mark.parametrize("s", [6, 8])
def test_coefficients_are_the_gauss_rule(s):
    """Nodes: roots of P_s(2c - 1), symmetric; b equals the Gauss weights 1/((1 - x^2)
    P_s'(x)^2) (an independent formula); B(2s) and C(s) hold to the working precision and
    B(2s + 1) fails (the order is exactly 2s)."""
    with mpmath.workdps(50):
        c, A, b, W = gauss_legendre_coefficients(s)
        tol = mpf(10) ** -45
        for i in range(s):
            x = 2 * c[i] - 1
            assert abs(mpmath.legendre(s, x)) < tol
            assert abs(c[i] + c[s - 1 - i] - 1) < tol
            dP = mpmath.diff(lambda u: mpmath.legendre(s, u), x)
            assert abs(b[i] - 1 / ((1 - x * x) * dP**2)) < tol
            for k in range(1, s + 1):  # C(s): sum_j a_ij c_j^(k-1) = c_i^k / k
                assert abs(sum(A[i][j] * c[j] ** (k - 1) for j in range(s)) - c[i] ** k / k) < tol
        for k in range(1, 2 * s + 1):  # B(2s)
            assert abs(sum(b[j] * c[j] ** (k - 1) for j in range(s)) - mpf(1) / k) < tol
        assert abs(sum(b[j] * c[j] ** (2 * s) for j in range(s)) - mpf(1) / (2 * s + 1)) > 1e-12
        assert all(abs(sum(W[j]) - b[j]) < tol for j in range(s))


def test_harmonic_oscillator_to_30_digits():
    with mpmath.workdps(40):
        gl = GaussLegendre(8)
        t_end = mpf(6)
        y, steps = _drive(
            gl, _oscillator, _vec(1, 0), t_end, mpf(10) ** -33, mpf(10) ** -35, mpf("0.1")
        )
        assert _err(y, _vec(mpmath.cos(t_end), -mpmath.sin(t_end))) < mpf(10) ** -30
        assert steps < 60


def test_pendulum_to_30_digits_with_dense_output():
    """Against the elliptic-function closed form; the dense output's refine() is as
    accurate inside the last step, its collocation polynomial to its order s."""
    with mpmath.workdps(40):
        gl = GaussLegendre(8)
        t_end = mpf(3)
        y, steps = _drive(
            gl, _pendulum, _vec(1, 0), t_end, mpf(10) ** -33, mpf(10) ** -35, mpf("0.1")
        )
        assert _err(y, _pendulum_exact(t_end)) < mpf(10) ** -30
        assert steps < 60
        y0 = _pendulum_exact(mpf(2))
        step = gl.step(_pendulum, 2, y0, _pendulum(2, y0), mpf("0.1"), mpf(10) ** -33, 0)
        assert step.error <= 1  # an accepted step
        nfev = step.nfev
        for theta in ("0.3", "0.5", "0.8"):
            exact = _pendulum_exact(2 + mpf(theta) * mpf("0.1"))
            assert _err(step.dense.refine(theta), exact) < mpf(10) ** -30
            assert _err(step.dense(theta), exact) < mpf(10) ** -15
        assert step.nfev > nfev  # refine's calls are counted


@pytest.mark.parametrize("s", [3, 4])
def test_order_by_regression(s):
    """Fixed steps on the oscillator over [0, 2]: slope of log error on log h is 2s +- 0.3."""
    with mpmath.workdps(40):
        gl = GaussLegendre(s)
        errors, hs = [], []
        for n in (4, 6, 8, 12):
            h = mpf(2) / n
            t, y = mpf(0), _vec(1, 0)
            for i in range(n):
                y = gl.step(_oscillator, t, y, _oscillator(t, y), h, mpf(10) ** -40, 0).y
                t = (i + 1) * h
            errors.append(float(_err(y, _vec(mpmath.cos(2), -mpmath.sin(2)))))
            hs.append(2 / n)
        slope = np.polyfit(np.log(hs), np.log(errors), 1)[0]
        assert abs(slope - 2 * s) <= 0.3, (errors, slope)


def test_dense_polynomial_order_by_regression():
    """The collocation polynomial at interior points: local error ~ h^(s+1)."""
    with mpmath.workdps(50):
        gl = GaussLegendre(4)
        errors, hs = [], []
        for h in ("0.4", "0.2", "0.1", "0.05"):
            step = gl.step(_pendulum, 0, _vec(1, 0), _pendulum(0, _vec(1, 0)), mpf(h), 1e-30, 0)
            errors.append(
                max(
                    float(_err(step.dense(th), _pendulum_exact(mpf(th) * mpf(h))))
                    for th in ("0.3", "0.7")
                )
            )
            hs.append(float(h))
        slope = np.polyfit(np.log(hs), np.log(errors), 1)[0]
        assert abs(slope - (gl.dense_order + 1)) <= 0.3, (errors, slope)


def test_error_estimate_tracks_the_true_error():
    """Richardson's estimate against the true error of the propagated solution, over
    steps of several sizes on the pendulum: within a factor 10 band around 1."""
    with mpmath.workdps(40):
        gl = GaussLegendre(6)
        ratios = []
        for t0, h in (("0.3", "0.2"), ("1.1", "0.35"), ("2.0", "0.5"), ("0.7", "0.8")):
            y0 = _pendulum_exact(mpf(t0))
            step = gl.step(_pendulum, mpf(t0), y0, _pendulum(t0, y0), mpf(h), 0, 1)
            true = _err(step.y, _pendulum_exact(mpf(t0) + mpf(h)))
            rms_true = float(true) / math.sqrt(2)
            ratios.append(step.error / rms_true)
        assert max(ratios) / min(ratios) < 10 and 0.1 < min(ratios) and max(ratios) < 10, ratios


def test_stiff_divergence_is_a_rejected_step_not_an_exception():
    """Fixed-point iteration on y' = -1e6 y with h = 1 diverges: error = inf, the
    controller rejects with its minimum factor, and a small step succeeds."""
    with mpmath.workdps(30):
        gl = GaussLegendre(6, max_iterations=30)
        f = lambda t, y: np.array([-(10**6) * y[0]], dtype=object)  # noqa: E731
        y0 = _vec(1)
        step = gl.step(f, 0, y0, f(0, y0), 1, 1e-20, 1e-20)
        assert step.error == math.inf
        assert Controller(gl.error_order)(step.error) == (False, 0.2)
        small = gl.step(f, 0, y0, f(0, y0), mpf(10) ** -8, 1e-20, 1e-20)
        assert small.error <= 1 and abs(small.y[0] - mpmath.exp(-(mpf(10) ** -2))) < 1e-20


def test_bad_input():
    with mpmath.workdps(20):
        y0 = _vec(1, 0)
        for call, text in [
            (lambda: GaussLegendre(0), "GaussLegendre(stages=0)"),
            (lambda: GaussLegendre(True), "GaussLegendre(stages=True)"),
            (lambda: GaussLegendre(4).step(_oscillator, 0, y0, y0, 0, 1e-10, 0), "h = 0"),
            (lambda: GaussLegendre(4).step(_oscillator, 0, np.ones((2, 2)), y0, 1, 1, 0), "1-d"),
            (lambda: GaussLegendre(4).step(lambda t, y: y[:1], 0, y0, y0, 1, 1, 0), "(1,)"),
        ]:  # fmt: skip
            with pytest.raises(StepperError) as info:
                call()
            assert text in str(info.value)
