"""Benchmark: generated C and NumPy code against sympy.lambdify(..., cse=True).

For the bouncing ellipse (text 001, its impact map), Carnot paper Example 3.13 (the
constrained acceleration and the impact map, quasi-velocities) and the n-link pendulum on
a cart (n = 2, 4, 8; the acceleration), one run prints:

* generation time (``symmech.codegen.generate``), compile time (gcc, empty cache);
* operations after CSE (``sympy.count_ops``) and the estimated flops per state;
* single-state call time of the loaded C and NumPy functions and of the lambdify
  baseline, and the ratio lambdify / C;
* batch throughput (states/s over ``--states`` states, default 10^6) of C, NumPy and
  lambdify (vectorised over arrays), with ratios;
* the flop bound: estimated flops per state / the scalar flop rate of this machine,
  measured in the same run by a C kernel (independent multiply-adds, gcc -O2), and the
  ratio of the measured batch time to it.

The lambdify baseline evaluates the same mathematics: the closed form where the
generated code uses one, else g and f from lambdify and ``numpy.linalg.solve`` (the
constrained and impact systems of Example 3.13 use their closed forms).

Flop estimate (an assumption, stated here): + - * count 1; a division 4; sqrt and hypot
4; sin, cos, tan, exp, log, atan, pow 20 (libm calls); the Cholesky steps add their
classical counts (n^3/3 + 2 n^2 r + ...).  Targets (issue 4): single-state C >= 20x
faster than lambdify for the 8-link pendulum; batch C within 3x of the flop bound.

Run:  python benchmarks/codegen.py [--states N]      (not run in CI)
"""

from __future__ import annotations

import argparse
import ctypes
import subprocess
import sys
import tempfile
import time
import timeit
from collections import Counter
from pathlib import Path

import numpy as np
import sympy as sp

import symmech as sm
from symmech.codegen.build import compile_library, find_compiler
from symmech.declaration.symbols import t as TIME
from symmech.examples import bouncing_ellipse, carnot_3_13, pendulum_on_cart

WEIGHTS = {"add": 1, "mul": 1, "div": 4, "sqrt": 4, "hypot": 4, "libm": 20}
_LIBM = (sp.sin, sp.cos, sp.tan, sp.exp, sp.log, sp.atan, sp.asin, sp.acos, sp.atan2)


def flop_profile(exprs) -> Counter:
    """Operation counts by kind along the expression DAGs (each node counted once)."""
    seen: set = set()
    out: Counter = Counter()

    def go(e: sp.Basic) -> None:
        if e in seen or e.is_Atom:
            return
        seen.add(e)
        for a in e.args:
            go(a)
        if e.is_Add:
            out["add"] += len(e.args) - 1
        elif e.is_Mul:
            out["mul"] += len(e.args) - 1
        elif e.is_Pow:
            k = e.exp
            if k.is_Integer:
                out["mul"] += max(abs(int(k)) - 1, 0)
                if k < 0:
                    out["div"] += 1
            elif k.is_Rational and k.q == 2:
                out["sqrt"] += 1
                out["mul"] += abs(int(k.p)) // 2
                if k < 0:
                    out["div"] += 1
            else:
                out["libm"] += 1
        elif isinstance(e, sp.Function):
            out["hypot" if e.func.__name__ == "hypot" else "libm"] += 1

    for e in exprs:
        go(sp.sympify(e))
    return out


def step_flops(fn) -> float:
    """Classical flop counts of the linear-algebra step of a lowered function."""
    if fn.step is None:
        return 0.0
    diag = fn.step_args[-1]

    def factor(n: int) -> float:  # Cholesky, or reciprocal square roots of a diagonal
        return 8 * n if diag else n**3 / 3 + 8 * n

    def solve(n: int, r: int) -> float:
        return 2 * n * r if diag else 2 * n**2 * r

    if fn.step == "spd_solve":
        n = fn.step_args[0]
        return factor(n) + solve(n, 1)
    if fn.step.startswith("constrained"):
        n, m, _ = fn.step_args
        return factor(n) + solve(n, m + 1) + 2 * m * m * n + m**3 / 3 + 2 * m * m + 2 * n * m
    n, k, _, _ = fn.step_args
    return factor(n) + solve(n, k) + 2 * k * k * n + k**3 / 3 + 2 * k * k + 4 * n * k


def estimated_flops(fn) -> float:
    prof = flop_profile(fn.expressions)
    return sum(WEIGHTS[k] * v for k, v in prof.items()) + step_flops(fn)


_KERNEL = r"""
double symmech_flop_kernel(long iters, double x)
{
    double a0 = x, a1 = x + 1e-3, a2 = x + 2e-3, a3 = x + 3e-3;
    double a4 = x + 4e-3, a5 = x + 5e-3, a6 = x + 6e-3, a7 = x + 7e-3;
    const double c = 0.999999, d = 1e-7;
    for (long i = 0; i < iters; ++i) {
        a0 = a0*c + d; a1 = a1*c + d; a2 = a2*c + d; a3 = a3*c + d;
        a4 = a4*c + d; a5 = a5*c + d; a6 = a6*c + d; a7 = a7*c + d;
    }
    return a0 + a1 + a2 + a3 + a4 + a5 + a6 + a7;
}
"""


def machine_flop_rate() -> float:
    """Scalar double flops/s of gcc -O2 code on this machine (16 flops per iteration)."""
    with tempfile.TemporaryDirectory() as tmp:
        lib_path = compile_library(
            {"kernel.c": _KERNEL},
            flags=("-std=c99", "-O2", "-fPIC", "-shared"),
            cache=tmp,
        )
        lib = ctypes.CDLL(str(lib_path))
        fn = lib.symmech_flop_kernel
        fn.argtypes = [ctypes.c_long, ctypes.c_double]
        fn.restype = ctypes.c_double
        iters = 50_000_000
        best = min(timeit.repeat(lambda: fn(iters, 0.5), number=1, repeat=3))
        return 16 * iters / best


def _time(call, min_time: float = 0.2) -> float:
    timer = timeit.Timer(call)
    number, _ = timer.autorange()
    number = max(number, 3)
    return min(timer.repeat(repeat=3, number=number)) / number


class Case:
    def __init__(
        self, label: str, scene: sm.Scene, function: str, kind: str, strategy: str = "auto"
    ):
        self.label, self.scene, self.function, self.kind = label, scene, function, kind
        self.strategy = strategy


def baseline(case: Case, code_fn):
    """lambdify(cse=True) of the same mathematics: (single-state callable, batch callable)."""
    scene = case.scene
    plan = case.code.plan
    atoms = {a: d for d, a in plan.inputs}
    args = [*scene.coordinates, *scene.velocities, *plan.parameters, TIME, *atoms.values()]
    n = scene.n
    if code_fn.step is None or case.kind in ("impact", "acceleration_closed"):
        if case.kind.startswith("impact"):
            wall = scene.walls[0]
            exprs = list(scene.impact_map(wall.index).post_velocity)
        else:
            exprs = list(scene.acceleration())
        exprs = [sp.sympify(e).xreplace(atoms) for e in exprs]
        f = sp.lambdify(args, exprs, modules="numpy", cse=True)

        def single(*a):
            return np.array(f(*a))

        def batch(*a):
            out = f(*a)
            return np.stack([np.broadcast_to(o, a[0].shape) for o in out], axis=-1)

        return single, batch
    M = sp.Matrix(scene.mass_matrix())
    fv = sp.Matrix(scene.forcing())
    g = sp.lambdify(args, [list(M), list(fv)], modules="numpy", cse=True)

    def single(*a):
        Mv, fvv = g(*a)
        return np.linalg.solve(np.array(Mv, dtype=float).reshape(n, n), np.array(fvv, dtype=float))

    def batch(*a):
        Mv, fvv = g(*a)
        shape = a[0].shape
        Mb = np.stack([np.broadcast_to(x, shape) for x in Mv], axis=-1).reshape(*shape, n, n)
        fb = np.stack([np.broadcast_to(x, shape) for x in fvv], axis=-1)
        return np.linalg.solve(Mb, fb[..., None])[..., 0]

    return single, batch


def run_case(case: Case, rate: float, states: int, rng: np.random.Generator) -> str:
    """Measure one case; returns its table row."""
    scene = case.scene
    t0 = time.perf_counter()
    code_c = sm.codegen.generate(scene, "c", strategy=case.strategy)
    gen = time.perf_counter() - t0
    code_np = sm.codegen.generate(scene, "numpy", strategy=case.strategy)
    case.code = code_c
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        compile_library(dict(code_c.files), cache=tmp)
        cc = time.perf_counter() - t0
    mod_c = code_c.load()
    mod_np = code_np.load()
    fn = next(f for f in code_c.functions if f.name == case.function)
    flops = estimated_flops(fn)
    n = scene.n
    params = rng.uniform(0.5, 1.5, len(mod_c.parameters))
    restitution = {str(w.restitution) for w in scene.walls}
    for i, name in enumerate(mod_c.parameters):
        if name in restitution:
            params[i] = 0.7
    q = rng.uniform(-1, 1, n)
    for i, s in enumerate(scene.coordinates):
        if s.name == "theta" and scene.frame is not None:
            q[i] = 1.1
    v = rng.uniform(-1, 1, n)
    if case.kind == "impact" and scene.is_constrained:
        # impact maps are derived for pre-impact velocities in D (Carnot paper, 3.1)
        proj = sm.codegen.generate(scene, "numpy", functions=["projectors"]).load()
        v = proj.projectors(q, params)[0] @ v
    single_lam, batch_lam = baseline(case, fn)
    lam_args = (*q, *v, *params, 0.0)
    ref = single_lam(*lam_args)
    got = mod_c.call(case.function, q, v, params=params)
    assert np.allclose(got, ref, rtol=1e-9, atol=1e-12), (case.label, got, ref)
    t_c1 = _time(lambda: mod_c.call(case.function, q, v, params=params))
    t_np1 = _time(lambda: mod_np.call(case.function, q, v, params=params))
    t_l1 = _time(lambda: single_lam(*lam_args))
    N = states
    Q = rng.uniform(-1, 1, (N, n))
    for i, s in enumerate(scene.coordinates):
        if s.name == "theta" and scene.frame is not None:
            Q[:, i] = rng.uniform(0.5, 2.5, N)
    Vb = rng.uniform(-1, 1, (N, n))
    if case.kind == "impact" and scene.is_constrained:
        Vb = np.einsum("nij,nj->ni", proj.projectors(Q, params)[0], Vb)
    t_cb = min(
        timeit.repeat(lambda: mod_c.call(case.function, Q, Vb, params=params), number=1, repeat=3)
    )
    t_npb = min(
        timeit.repeat(lambda: mod_np.call(case.function, Q, Vb, params=params), number=1, repeat=2)
    )
    cols = [Q[:, i] for i in range(n)] + [Vb[:, i] for i in range(n)]
    t_lb = min(timeit.repeat(lambda: batch_lam(*cols, *params, 0.0), number=1, repeat=2))
    bound = flops * N / rate
    return (
        f"{case.label:32} {code_c.plan.strategy:12} {gen:7.2f} {cc:6.2f} {fn.operations:6d}"
        f" {flops:7.0f} | {t_c1 * 1e6:8.2f} {t_np1 * 1e6:8.1f} {t_l1 * 1e6:9.1f}"
        f" {t_l1 / t_c1:7.1f} | {N / t_cb:9.3g} {N / t_npb:9.3g} {N / t_lb:10.3g}"
        f" {t_npb / t_cb:6.1f} {t_lb / t_cb:6.1f} | {t_cb / bound:7.2f}"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--states", type=int, default=1_000_000, help="batch size (default 10^6)")
    args = ap.parse_args()
    find_compiler()
    rng = np.random.default_rng(0)
    rate = machine_flop_rate()
    print(f"scalar flop rate (gcc -O2 multiply-add kernel): {rate / 1e9:.2f} GFlop/s")
    print(
        f"batch size: {args.states} states; python {sys.version.split()[0]}, sympy {sp.__version__}"
    )
    cases = [
        Case(
            "bouncing ellipse: impact",
            bouncing_ellipse(sp.Symbol("alpha", nonnegative=True)),
            "impact_wall",
            "impact",
        ),
        Case("Example 3.13: acceleration", carnot_3_13(), "acceleration", "acceleration"),
        Case("Example 3.13: impact (KKT)", carnot_3_13(), "impact_rough_wall", "impact"),
        Case(
            "Example 3.13: impact (closed)",
            carnot_3_13(),
            "impact_rough_wall",
            "impact",
            "closed_form",
        ),
        *[
            Case(
                f"{k}-link pendulum: acceleration",
                pendulum_on_cart(k),
                "acceleration",
                "acceleration",
            )
            for k in (2, 4, 8)
        ],
    ]
    header = (
        f"{'case':32} {'strategy':12} {'gen[s]':>7} {'cc[s]':>6} {'ops':>6} {'flops':>7}"
        f" | {'C 1[us]':>8} {'np 1[us]':>8} {'lam 1[us]':>9} {'lam/C':>7}"
        f" | {'C [st/s]':>9} {'np [st/s]':>9} {'lam [st/s]':>10} {'C/np':>6} {'C/lam':>6}"
        f" | {'C/bound':>7}"
    )
    print(header)
    print("-" * len(header))
    for case in cases:
        print(run_case(case, rate, args.states, rng))
    print(
        "\nC 1, np 1, lam 1: one state through the loaded module (argument checks included)"
        " and through the lambdify baseline; lam/C = lambdify time / C time.\n"
        "st/s: states per second in one batch call; C/bound = measured C batch time /"
        " (estimated flops per state x states / scalar flop rate)."
    )
    cc_version = subprocess.run([find_compiler(), "--version"], capture_output=True, text=True)
    print(f"compiler: {cc_version.stdout.splitlines()[0]}")


if __name__ == "__main__":
    Path(__file__)  # run from anywhere
    main()
