"""The reference stepper for high-precision runs: Gauss-Legendre collocation in mpmath.

An ``s``-stage Gauss-Legendre method (order ``2s``, A-stable, symplectic; HNW I, section
II.7 and HNW II, section IV.5) with every coefficient computed at the current
``mpmath.mp`` precision from the roots of the Legendre polynomial, so a run at 40 digits
is a reference for float64 runs of the same algorithm.  Same :class:`Step` / ``Dense``
interface as :mod:`symmech.simulate.steppers`, with states as 1-d NumPy object arrays of
``mpmath.mpf`` (``f(t, y)`` must return one).
"""

from __future__ import annotations

import math

import mpmath
import numpy as np

from .steppers import Step, Stepper, StepperError

__all__ = ["GaussLegendre", "gauss_legendre_coefficients"]


def gauss_legendre_coefficients(stages: int) -> tuple[list, list, list, list]:
    """``(c, A, b, W)`` of the ``stages``-stage Gauss-Legendre method at the current
    precision (computed with 20 guard bits).

    ``c_i = (1 + x_i)/2`` with ``x_i`` the roots of the Legendre polynomial ``P_s``
    (Newton from the float64 Gauss nodes); with the Lagrange basis ``l_j`` on the nodes,
    ``W[j][k]`` is the coefficient of ``tau^(k+1)`` in ``integral_0^tau l_j``, so
    ``a_ij = integral_0^(c_i) l_j``, ``b_j = integral_0^1 l_j`` (the collocation
    conditions C(s) and B(2s), HNW I, eq. II.(7.15)).
    """
    s = int(stages)
    with mpmath.workprec(mpmath.mp.prec + 20):
        guesses = np.polynomial.legendre.leggauss(s)[0]
        dP = lambda x: mpmath.diff(lambda u: mpmath.legendre(s, u), x)  # noqa: E731
        roots = []
        for g in guesses:
            x = mpmath.mpf(float(g))
            for _ in range(200):
                step = mpmath.legendre(s, x) / dP(x)
                x -= step
                if abs(step) <= mpmath.eps * 4:
                    break
            roots.append(x)
        c = sorted((1 + x) / 2 for x in roots)
        M = mpmath.matrix([[ci**m for m in range(s)] for ci in c])
        Minv = M**-1  # L[j][m] = Minv[m, j]: l_j(tau) = sum_m L[j][m] tau^m
        W = [[Minv[k, j] / (k + 1) for k in range(s)] for j in range(s)]
        A = [[sum(W[j][k] * c[i] ** (k + 1) for k in range(s)) for j in range(s)] for i in range(s)]
        b = [sum(W[j]) for j in range(s)]
    return [+x for x in c], [[+x for x in row] for row in A], [+x for x in b], W


def _rms_float(values) -> float:
    return math.sqrt(float(sum(v * v for v in values)) / len(values)) if len(values) else 0.0


class _CollocationDense:
    """The collocation polynomials of the two half steps, joined at ``theta = 1/2``:
    ``u(t_a + tau h/2) = y_a + (h/2) sum_j K_j sum_k W_jk tau^(k+1)`` (order ``s``).

    :meth:`refine` gives ``y(t0 + theta h)`` to the method's full order ``2s`` by a fresh
    collocation step from ``(t0, y0)`` over ``theta h`` (for polishing an event time found
    on the polynomial); its calls of ``f`` are added to the step's ``nfev``.
    """

    def __init__(self, t0, h, pieces, W, refiner=None):
        self.t0, self.h = t0, h
        self._pieces, self._W = pieces, W
        self._refiner = refiner
        self.owner: Step | None = None

    def __call__(self, theta) -> np.ndarray:
        theta = mpmath.mpf(theta)
        first = theta <= mpmath.mpf(1) / 2
        y_a, K, hh = self._pieces[0 if first else 1]
        tau = 2 * theta if first else 2 * theta - 1
        out = y_a.copy()
        for j, row in enumerate(self._W):
            w = sum(coef * tau ** (k + 1) for k, coef in enumerate(row))
            out = out + (hh * w) * K[j]
        return out

    def refine(self, theta) -> np.ndarray:
        """``y(t0 + theta h)`` to order ``2s`` (one collocation solve; ``theta`` in (0, 1])."""
        theta = mpmath.mpf(theta)
        if theta == 0 or self._refiner is None:
            return self(theta)
        y, nfev = self._refiner(theta * self.h)
        if self.owner is not None:
            self.owner.nfev += nfev
        return y


class GaussLegendre(Stepper):
    """``s``-stage Gauss-Legendre collocation (order ``2s``) in mpmath arithmetic.

    Stages ``K_i = f(t0 + c_i h, y0 + h sum_j a_ij K_j)`` by fixed-point iteration from
    ``K_i = f0`` (for non-stiff problems: it converges while ``|h| L rho(A) < 1``) until
    the update is below ``2^-prec`` relative; ``y1 = y0 + h sum_j b_j K_j``.  A step is two
    half steps; one full step beside them gives the error by Richardson's estimate
    ``(y_half,half - y_full) / (2^(2s) - 1)`` (HNW I, section II.4), scaled as the float
    steppers do.  The dense output is the collocation polynomial of each half step (order
    ``s``; ``dense.refine(theta)`` to order ``2s``).  When the iteration does not
    converge in ``max_iterations`` the step reports ``error = inf`` (the caller shrinks
    ``h``).
    """

    implicit = False
    adaptive = True

    def __init__(self, stages: int = 8, *, max_iterations: int = 100):
        if isinstance(stages, bool) or not isinstance(stages, int) or not 1 <= stages <= 32:
            raise StepperError(f"GaussLegendre(stages={stages!r}): need an integer in 1..32")
        self.stages = stages
        self.name = f"gauss_legendre{stages}"
        self.order = 2 * stages
        self.error_order = 2 * stages
        self.dense_order = stages
        self.max_iterations = int(max_iterations)
        self._cache: dict[int, tuple] = {}

    def coefficients(self) -> tuple[list, list, list, list]:
        """``(c, A, b, W)`` at the current ``mpmath.mp.prec`` (cached per precision)."""
        prec = mpmath.mp.prec
        if prec not in self._cache:
            self._cache[prec] = gauss_legendre_coefficients(self.stages)
        return self._cache[prec]

    def _call(self, f, t, y: np.ndarray) -> np.ndarray:
        out = np.asarray(f(t, y), dtype=object)
        if out.shape != y.shape:
            raise StepperError(
                f"the right-hand side f(t, y) returned shape {out.shape} for a state of"
                f" shape {y.shape}"
            )
        return out

    def _solve(self, f, t0, y0, f0, h, guess=None):
        """Collocation from ``(t0, y0)`` over ``h``: ``(y1, K, nfev)``, ``y1`` None if the
        fixed-point iteration does not converge.  ``guess``: starting stage derivatives
        (default ``f0`` at every stage)."""
        c, A, b, _ = self.coefficients()
        s, n = self.stages, len(y0)
        K = [list(k) for k in guess] if guess is not None else [list(f0)] * s
        nfev = 0
        tol = mpmath.mpf(2) ** (-mpmath.mp.prec + 4) * (1 + max((abs(v) for v in y0), default=0))
        fdot = mpmath.fdot
        for _ in range(self.max_iterations):
            new = []
            for i in range(s):
                hA = [h * a for a in A[i]]
                z = np.array(
                    [y0[m] + fdot(hA, [K[j][m] for j in range(s)]) for m in range(n)], dtype=object
                )
                new.append(list(self._call(f, t0 + c[i] * h, z)))
            nfev += s
            delta = abs(h) * max(
                (abs(new[i][m] - K[i][m]) for i in range(s) for m in range(n)), default=0
            )
            K = new
            if not mpmath.isfinite(delta):
                return None, K, nfev
            if delta <= tol:
                hb = [h * w for w in b]
                y1 = np.array(
                    [y0[m] + fdot(hb, [K[j][m] for j in range(s)]) for m in range(n)], dtype=object
                )
                return y1, [np.array(k, dtype=object) for k in K], nfev
        return None, K, nfev

    def _derivatives(self, K, taus) -> list[list]:
        """``u'`` of a half step's collocation polynomial at ``tau`` (in half-step units):
        ``sum_j K_j l_j(tau)`` with ``l_j(tau) = sum_k (k + 1) W_jk tau^k``; starting
        values for the next solves, accurate to O(h^s)."""
        W = self.coefficients()[3]
        out = []
        for tau in taus:
            weights = [sum((k + 1) * w * tau**k for k, w in enumerate(row)) for row in W]
            out.append([mpmath.fdot(weights, [Kj[m] for Kj in K]) for m in range(len(K[0]))])
        return out

    def step(self, f, t0, y0, f0, h, rtol, atol, jac=None) -> Step:
        """Two half steps and the full step; see the class docstring."""
        h = mpmath.mpf(h)
        if not mpmath.isfinite(h) or h == 0:
            raise StepperError(f"step size h = {h}: it must be finite and non-zero")
        t0 = mpmath.mpf(t0)
        if np.ndim(y0) != 1:
            raise StepperError(f"the state y0 must be 1-d, got shape {np.shape(y0)}")
        y0 = np.array([mpmath.mpf(v) for v in y0], dtype=object)
        f0 = np.array([mpmath.mpf(v) for v in np.asarray(f0, dtype=object).ravel()], dtype=object)
        half = h / 2
        c = self.coefficients()[0]
        y_a, K_a, n1 = self._solve(f, t0, y0, f0, half)
        nfev = n1
        y_b = y_full = None
        if y_a is not None:
            f_a = self._call(f, t0 + half, y_a)
            guess = self._derivatives(K_a, [1 + ci for ci in c])
            y_b, K_b, n2 = self._solve(f, t0 + half, y_a, f_a, half, guess)
            nfev += 1 + n2
        if y_b is not None:
            guess = [
                self._derivatives(K_a, [2 * ci])[0] if 2 * ci <= 1 else
                self._derivatives(K_b, [2 * ci - 1])[0]
                for ci in c
            ]  # fmt: skip
            y_full, _, n3 = self._solve(f, t0, y0, f0, h, guess)
            nfev += n3
        if y_b is None or y_full is None:
            dense = _CollocationDense(t0, h, [(y0, [0 * f0] * self.stages, half)] * 2, [])
            return Step(y0.copy(), f0.copy(), math.inf, dense, nfev)
        f1 = self._call(f, t0 + h, y_b)
        nfev += 1
        est = (y_b - y_full) / (2 ** (2 * self.stages) - 1)
        atol_ = np.broadcast_to(np.asarray(atol, dtype=object), y0.shape)
        scale = [
            mpmath.mpf(a) + mpmath.mpf(rtol) * max(abs(u), abs(v))
            for a, u, v in zip(atol_, y0, y_b, strict=True)
        ]
        ratios = [
            e / sc if sc else (0 if e == 0 else mpmath.inf)
            for e, sc in zip(est, scale, strict=True)
        ]
        error = _rms_float(ratios)

        def refiner(h_new):
            """Two half steps over ``h_new``, as the step itself (same accuracy)."""
            y_m, _, n1 = self._solve(f, t0, y0, f0, h_new / 2)
            y_new, _, n2 = (
                (None, None, 0)
                if y_m is None
                else self._solve(
                    f, t0 + h_new / 2, y_m, self._call(f, t0 + h_new / 2, y_m), h_new / 2
                )
            )
            if y_new is None:  # cannot happen for |h_new| <= |h| (the step converged)
                raise StepperError(f"refine: no convergence over {h_new}")
            return y_new, n1 + n2 + 1

        pieces = [(y0, K_a, half), (y_a, K_b, half)]
        dense = _CollocationDense(t0, h, pieces, self.coefficients()[3], refiner)
        step = Step(y_b, f1, error, dense, nfev)
        dense.owner = step
        return step
