"""Benchmark: the simulator's steppers (symmech.simulate.steppers) against SciPy's solve_ivp.

Work-precision on Kepler (e = 0.5, one period, error against the closed form of Kepler's
equation) for dop853, tsit5, rk45 and rodas4 at rtol = 1e-4 .. 1e-12 (atol = rtol / 100),
each driven by a plain Python loop over ``Stepper.step`` with ``initial_step`` and
``Controller``; the baseline is ``scipy.integrate.solve_ivp`` in the same run (DOP853 for
dop853, RK45 for tsit5 and rk45, Radau with the exact Jacobian for rodas4).  Then the stiff
Robertson problem on [0, 1e5] (rtol 1e-6, error against Radau at rtol 1e-12): rodas4
against Radau and BDF.  Both sides call the same Python right-hand side, so the ratios
compare the integrators and their Python overheads, not generated code.

Run:  python benchmarks/steppers.py      (about 20 seconds; --quick: a smoke test, one
tolerance per method and Robertson on [0, 1])
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import numpy as np
from scipy.integrate import solve_ivp

from symmech.simulate.steppers import Controller, initial_step, stepper

E = 0.5


def kepler(t, y):
    r3 = (y[0] ** 2 + y[1] ** 2) ** 1.5
    return np.array([y[2], y[3], -y[0] / r3, -y[1] / r3])


def kepler_jac(t, y):
    x, z = y[0], y[1]
    r5 = (x * x + z * z) ** 2.5
    J = np.zeros((4, 4))
    J[0, 2] = J[1, 3] = 1.0
    J[2, 0] = (2 * x * x - z * z) / r5
    J[3, 1] = (2 * z * z - x * x) / r5
    J[2, 1] = J[3, 0] = 3 * x * z / r5
    return J


def kepler_exact(t):
    ecc = E
    u = t
    for _ in range(50):
        u -= (u - ecc * math.sin(u) - t) / (1 - ecc * math.cos(u))
    w, d = math.sqrt(1 - ecc * ecc), 1 - ecc * math.cos(u)
    return np.array([math.cos(u) - ecc, w * math.sin(u), -math.sin(u) / d, w * math.cos(u) / d])


def robertson(t, y):
    a, b, c = y
    return np.array([-0.04 * a + 1e4 * b * c, 0.04 * a - 1e4 * b * c - 3e7 * b * b, 3e7 * b * b])


def robertson_jac(t, y):
    _, b, c = y
    return np.array(
        [[-0.04, 1e4 * c, 1e4 * b], [0.04, -1e4 * c - 6e7 * b, -1e4 * b], [0.0, 6e7 * b, 0.0]]
    )


def drive(name, f, jac, y0, t_end, rtol, atol):
    """The loop the simulator runs, without events: returns y, steps, rhs calls."""
    st = stepper(name)
    t, y = 0.0, np.array(y0, dtype=float)
    fy = f(t, y)
    h = min(initial_step(f, t, y, fy, 1, st.error_order, rtol, atol), t_end)
    ctrl = Controller(st.error_order)
    steps, nfev = 0, 2
    while t < t_end:
        h = min(h, t_end - t)
        step = st.step(f, t, y, fy, h, rtol, atol, jac)
        nfev += step.nfev
        ok, factor = ctrl(step.error)
        if ok:
            t = t_end if h == t_end - t else t + h
            y, fy = step.y, step.f
            steps += 1
        h *= factor
    return y, steps, nfev


def timed(fn, repeat=3):
    times, out = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), out


BASELINE = {"dop853": "DOP853", "tsit5": "RK45", "rk45": "RK45", "rodas4": "Radau"}


def kepler_table(quick: bool = False) -> None:
    t_end = 2 * math.pi
    exact = kepler_exact(t_end)
    print("Kepler e = 0.5, one period; error = max |y - exact|; time = median of 3")
    print(
        f"{'method':7} {'rtol':>6} {'steps':>6} {'nfev':>7} {'error':>9} {'time s':>8} |"
        f" {'scipy':6} {'nfev':>7} {'error':>9} {'time s':>8} | {'time ratio':>10}"
    )
    for name in ("dop853", "tsit5", "rk45", "rodas4"):
        tols = (1e-4, 1e-6, 1e-8) if name == "rodas4" else (1e-4, 1e-6, 1e-8, 1e-10, 1e-12)
        tols = tols[1:2] if quick else tols
        for rtol in tols:
            atol = rtol * 1e-2
            jac = kepler_jac if name == "rodas4" else None
            ours_t, (y, steps, nfev) = timed(
                lambda rtol=rtol, atol=atol, jac=jac, name=name: drive(
                    name, kepler, jac, kepler_exact(0), t_end, rtol, atol
                )
            )
            method = BASELINE[name]
            extra = {"jac": kepler_jac} if method == "Radau" else {}
            base_t, sol = timed(
                lambda rtol=rtol, atol=atol, method=method, extra=extra: solve_ivp(
                    kepler,
                    (0, t_end),
                    kepler_exact(0),
                    method=method,
                    rtol=rtol,
                    atol=atol,
                    **extra,
                )
            )
            err = np.max(np.abs(y - exact))
            base_err = np.max(np.abs(sol.y[:, -1] - exact))
            print(
                f"{name:7} {rtol:6.0e} {steps:6d} {nfev:7d} {err:9.2e} {ours_t:8.4f} |"
                f" {method:6} {sol.nfev:7d} {base_err:9.2e} {base_t:8.4f} | {ours_t / base_t:10.2f}"
            )


def robertson_table(t_end: float = 1e5) -> None:
    y0 = [1.0, 0.0, 0.0]
    ref = solve_ivp(
        robertson, (0, t_end), y0, method="Radau", jac=robertson_jac, rtol=1e-12, atol=1e-18
    ).y[:, -1]
    rtol, atol = 1e-6, 1e-10
    print(
        f"\nRobertson on [0, {t_end:g}], rtol {rtol:g}, atol {atol:g};"
        " error = max |y - ref| / |ref|"
    )
    t_ours, (y, steps, nfev) = timed(
        lambda: drive("rodas4", robertson, robertson_jac, y0, t_end, rtol, atol)
    )
    rel = np.max(np.abs(y - ref) / np.abs(ref))
    print(f"rodas4  steps {steps:5d} nfev {nfev:6d} rel error {rel:9.2e} time {t_ours:8.4f} s")
    for method in ("Radau", "BDF"):
        t_b, sol = timed(
            lambda method=method: solve_ivp(
                robertson, (0, t_end), y0, method=method, jac=robertson_jac, rtol=rtol, atol=atol
            )
        )
        rel = np.max(np.abs(sol.y[:, -1] - ref) / np.abs(ref))
        print(
            f"{method:7} steps {sol.t.size - 1:5d} nfev {sol.nfev:6d} rel error {rel:9.2e}"
            f" time {t_b:8.4f} s  (rodas4 / {method} time: {t_ours / t_b:.2f})"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="a smoke test (see the docstring)")
    quick = ap.parse_args().quick
    kepler_table(quick)
    robertson_table(1.0 if quick else 1e5)


if __name__ == "__main__":
    main()
