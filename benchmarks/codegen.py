"""Benchmark: generated C and NumPy code against ``sympy.lambdify(..., cse=True)``.

Scenes and functions: the bouncing ellipse of text 001 (its acceleration, identically 0
in free flight, and its impact map), Carnot paper Example 3.13 (the rolling sphere: the constrained
acceleration and the impact map at the rough wall, in quasi-velocities) and the pendulum
on a cart with n = 2, 4, 8 links (n + 1 coordinates; the acceleration).  Each is run with
both strategies of ``sm.codegen.generate``, ``closed_form`` and ``linear_solve`` (a
closed form whose generation does not finish within ``--limit`` seconds is reported as
such).  One run prints four tables and the issue's targets:

1. build: operations after CSE (``GeneratedCode.operation_counts()``, sympy.count_ops)
   of the C and NumPy code and of lambdify's CSE output (``sympy.cse`` + count_ops of
   the same expressions); the flops of the linear-algebra step (the header of the
   generated function; for the baseline the LU count 2/3 N^3 + 2 N^2); generation time
   (C and NumPy) and lambdify creation time, each from a fresh scene with sympy's cache
   cleared, so each includes deriving its expressions; compile + load time (gcc into an
   empty cache) and the NumPy import time.
2. run time: one state through the loaded module (``mod.acceleration`` / ``mod.impact``,
   argument checks included), through the bare C function of the same library by ctypes,
   and through the baseline; batch throughput in states/s over ``--states`` states
   (default 10^6; NumPy and lambdify in chunks of ``--chunk`` states).
3. error against run time: the worst relative error (infinity norm) of C, NumPy and the
   baseline over ``--error-states`` random states against an mpmath reference at 50
   digits, next to the batch time per state (a work-precision table per strategy).
4. the flop bound of the C batch (below).

The baseline (lambdify with its default modules, scipy and numpy) evaluates the same
mathematics as the row's strategy: for ``closed_form``, lambdify of the scene's closed
form (``scene.acceleration()``, the constrained one for Example 3.13, or
``scene.impact_map(0).post_velocity``); for ``linear_solve``, lambdify of the symbolic
blocks (M, f, mu, mu_dot v for an acceleration; M, A = [mu; dpsi; nu],
alpha for an impact) and ``numpy.linalg.solve`` (LU) of the full KKT system
``[[M, -A^T], [A, 0]] [x; lambda] = [rhs; b]`` (Carnot paper eqs. 5 and 6).  The
reference is that KKT system solved by mpmath's LU at 50 digits: an algorithm shared
with neither the closed forms nor the generated Cholesky / Schur-complement code.

Flop bound (table 4): flops per state = operations after CSE + the flops of the
linear-algebra step, each operation (including each libm call) counted as one flop; the
bound is flops x states / the peak rate of scalar double adds and multiplies of this
machine, measured in the same run by a C kernel of 12 independent multiply-add chains
(gcc -O2 -fno-tree-vectorize: the generated batch code evaluates one state at a time).
The counts are those of the one-state function: the batch evaluates the locals that read
only the parameters once per batch (``symmech.codegen.batch_split``), so it may do fewer
operations per state than it is charged.
C/bound is the measured C batch time over that bound (issue 4 target: <= 3).  A second
bound counts each libm call of the C function (sin, cos, hypot, ...) at its cost
measured in the same run (a throughput kernel per function) instead of one flop.  A third
bound, the roofline, also charges each division its measured cost and takes the larger of
that compute time and the memory time of the state: the bytes of the state arrays the
function reads and of its output, at the streaming rate of a C copy kernel measured in the
same run (a batch of a few flops per state is limited by memory, not arithmetic).  The
copy kernel writes into memory it has touched before, so the C batch is timed against the
roofline with ``out=`` (a preallocated output, touched once before); the allocating call,
which also pays the first touch of its fresh output (page faults and zeroing), is shown
beside it.

All ratios are "baseline / symmech" for times and operation counts and "symmech /
baseline" for throughput, so a ratio > 1 always means symmech is better.  Figures are
indicative (timings on a shared machine); they are never asserted by the tests.

Issue 13 table (printed first; ``--issue13-only`` prints only it): C generation time of
the n-link pendulum on a cart with ``linear_solve`` (n = 8, 16, 32; declaration included,
sympy's cache cleared) against what PyDy users do, measured in the same run: KanesMethod
forming M and f, ``sympy.cse`` of both, and C99 printing of the result
(``sympy.ccode`` of every replacement and reduced expression); the 4-link pendulum on a
cart with a wall at its tip (``linear_solve``; and the time for ``closed_form`` to be
refused by its budget); the NumPy module's one-state call of the 8-link acceleration
against lambdify of M, f and ``numpy.linalg.solve`` (best of many calls, argument checks
included).

Run:  python3 benchmarks/codegen.py [--states N] [--chunk N] [--limit S]   (not run in CI)
"""

from __future__ import annotations

import argparse
import ctypes
import os
import re
import shlex
import signal
import subprocess
import sys
import tempfile
import time
import timeit
from collections import Counter
from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import mpmath as mp
import numpy as np
import sympy as sp
from sympy.core.cache import clear_cache
from sympy.physics import mechanics as sm_mechanics

import symmech as sm
from symmech.algebra.budget import BudgetExceeded
from symmech.examples import bouncing_ellipse, carnot_3_13, pendulum_on_cart

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from derive import _mechanics_model  # the PyDy model of benchmarks/derive.py
from scale_support import cart_with_tip_wall

DPS = 50
KERNEL_FLAGS = ("-std=c99", "-O2", "-fno-tree-vectorize", "-fPIC", "-shared")
LIBM_UNARY = ("sin", "cos", "tan", "exp", "log", "expm1", "log1p", "sqrt", "atan", "asin", "acos")
LIBM_BINARY = ("pow", "hypot", "atan2")
_LIBM = re.compile(rf"\b({'|'.join(LIBM_UNARY + LIBM_BINARY)})\(")


# --------------------------------------------------------------------------- the cases


@dataclass(frozen=True)
class Case:
    """One scene and one generated function (``acceleration`` or ``impact``)."""

    label: str
    make: Callable[[], sm.Scene]
    function: str
    family: str = ""  # cases of one family grow in size: a timed-out closed form stops it
    links: int = 0  # the pendulum on a cart: its number of links


def cases() -> list[Case]:
    alpha = sp.Symbol("alpha", nonnegative=True)
    out = [
        Case("ellipse accel. n=3", lambda: bouncing_ellipse(alpha), "acceleration"),
        Case("ellipse impact n=3", lambda: bouncing_ellipse(alpha), "impact"),
        Case("Ex. 3.13 accel. n=6 m=3", carnot_3_13, "acceleration"),
        Case("Ex. 3.13 impact n=6 m=3", carnot_3_13, "impact"),
    ]
    if QUICK:
        out = out[1:2]
    for k in (2,) if QUICK else (2, 4, 8):
        out.append(
            Case(
                f"cart + {k}-link pend. n={k + 1}",
                lambda k=k: pendulum_on_cart(k),
                "acceleration",
                "pendulum",
                k,
            )
        )
    return out


# ------------------------------------------------------------------------------- timing


class TimeLimit(Exception):
    """A timed step did not finish within its limit."""


@contextmanager
def time_limit(seconds: float) -> Iterator[None]:
    """Interrupt the (pure Python, sympy) block after ``seconds`` with TimeLimit."""

    def handler(signum, frame):
        raise TimeLimit

    old = signal.signal(signal.SIGALRM, handler)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


#: ``--quick``: every table at its smallest size, timings short (a smoke test: the figures
#: are not meaningful, only that every step runs)
QUICK = False


def single_time(call: Callable[[], object]) -> float:
    """Seconds per call: timeit's autorange (>= 0.2 s per repeat), best of 3 repeats (with
    ``--quick`` 100 calls once)."""
    timer = timeit.Timer(call)
    if QUICK:
        return timer.timeit(number=100) / 100
    number, _ = timer.autorange()
    return min(timer.repeat(repeat=3, number=number)) / number


def best_time(call: Callable[[], object], budget: float = 6.0) -> float:
    """Best of up to 3 runs of a long call, stopping once ``budget`` seconds are spent."""
    times: list[float] = []
    while len(times) < (1 if QUICK else 3) and sum(times) < budget:
        t0 = time.perf_counter()
        call()
        times.append(time.perf_counter() - t0)
    return min(times)


def best_times(calls: Sequence[Callable[[], object]], budget: float = 6.0) -> list[float]:
    """The best time of each call, timed in turn (so that each sees the same load of a
    shared machine): at least 3 rounds and, within ``budget`` seconds, until 1 s is spent
    (a batch of a few milliseconds then gets tens of runs)."""
    best = [float("inf")] * len(calls)
    rounds, spent = 0, 0.0
    while rounds < (1 if QUICK else 3) or (spent < 1.0 and spent < budget and not QUICK):
        for k, call in enumerate(calls):
            t0 = time.perf_counter()
            call()
            elapsed = time.perf_counter() - t0
            best[k] = min(best[k], elapsed)
            spent += elapsed
        rounds += 1
    return best


def chunked_time(call: Callable[[int, int], object], states: int, chunk: int, budget: float):
    """Evaluate ``call(start, stop)`` over the states in chunks until all are done or
    ``budget`` seconds are spent; returns (states evaluated, seconds)."""
    done, spent = 0, 0.0
    while done < states and spent < budget:
        stop = min(done + chunk, states)
        t0 = time.perf_counter()
        call(done, stop)
        spent += time.perf_counter() - t0
        done = stop
    return done, spent


# --------------------------------------------------------------------- machine flop rate

_KERNEL = r"""
double bench_flop_kernel(long iters, double x, double c, double d)
{
    double a0 = x, a1 = x + 1e-3, a2 = x + 2e-3, a3 = x + 3e-3, a4 = x + 4e-3, a5 = x + 5e-3;
    double a6 = x + 6e-3, a7 = x + 7e-3, a8 = x + 8e-3, a9 = x + 9e-3, a10 = x + 1e-2;
    double a11 = x + 1.1e-2;
    for (long i = 0; i < iters; ++i) {
        a0 = a0*c + d; a1 = a1*c + d; a2 = a2*c + d; a3 = a3*c + d;
        a4 = a4*c + d; a5 = a5*c + d; a6 = a6*c + d; a7 = a7*c + d;
        a8 = a8*c + d; a9 = a9*c + d; a10 = a10*c + d; a11 = a11*c + d;
    }
    return a0 + a1 + a2 + a3 + a4 + a5 + a6 + a7 + a8 + a9 + a10 + a11;
}
"""


_STREAM = r"""
double bench_stream(long n, const double *a, double *b)
{
    for (long i = 0; i < n; ++i) b[i] = a[i]*1.0000001;
    return b[n - 1];
}

double bench_div(long iters, const double *x)
{
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    for (long i = 0; i < iters; i += 4) {
        s0 += 1.0/x[i & 1023]; s1 += 1.0/x[(i + 1) & 1023];
        s2 += 1.0/x[(i + 2) & 1023]; s3 += 1.0/x[(i + 3) & 1023];
    }
    return s0 + s1 + s2 + s3;
}
"""


def _libm_kernel(name: str) -> str:
    """Four independent sums of name(x) over 1024 arguments in [0.1, 0.9] (throughput)."""
    arg = (
        (lambda j: f"x[(i + {j}) & 1023], x[(i + {j + 5}) & 1023]")
        if name in LIBM_BINARY
        else (lambda j: f"x[(i + {j}) & 1023]")
    )
    sums = " ".join(f"s{j} += {name}({arg(j)});" for j in range(4))
    return f"""
double bench_{name}(long iters, const double *x)
{{
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    for (long i = 0; i < iters; i += 4) {{ {sums} }}
    return s0 + s1 + s2 + s3;
}}
"""


def _compile(compiler: str, folder: Path, source: str, stem: str) -> ctypes.CDLL:
    """Compile ``source`` into folder/stem.so (a distinct name: dlopen caches by path)."""
    (folder / f"{stem}.c").write_text(source)
    lib_path = folder / f"{stem}.so"
    cmd = [compiler, *KERNEL_FLAGS, "-o", str(lib_path), str(folder / f"{stem}.c"), "-lm"]
    subprocess.run(cmd, check=True, capture_output=True)
    return ctypes.CDLL(str(lib_path))


class Machine:
    """Peak scalar flop rate and libm costs of this machine, measured on demand (the
    machine is shared: table 4 re-measures them next to each C batch)."""

    def __init__(self, compiler: str, folder: Path):
        self._flop = _compile(compiler, folder, _KERNEL, "flop_kernel").bench_flop_kernel
        self._flop.argtypes = [ctypes.c_long, ctypes.c_double, ctypes.c_double, ctypes.c_double]
        self._flop.restype = ctypes.c_double
        source = "#include <math.h>\n" + "".join(map(_libm_kernel, LIBM_UNARY + LIBM_BINARY))
        lib = _compile(compiler, folder, source, "libm_kernel")
        self._libm = {}
        for name in LIBM_UNARY + LIBM_BINARY:
            fn = getattr(lib, f"bench_{name}")
            fn.argtypes = [ctypes.c_long, ctypes.c_void_p]
            fn.restype = ctypes.c_double
            self._libm[name] = fn
        self._x = np.linspace(0.1, 0.9, 1024)
        lib = _compile(compiler, folder, _STREAM, "stream_kernel")
        self._stream, self._div = lib.bench_stream, lib.bench_div
        self._stream.argtypes = [ctypes.c_long, ctypes.c_void_p, ctypes.c_void_p]
        self._div.argtypes = [ctypes.c_long, ctypes.c_void_p]
        self._stream.restype = self._div.restype = ctypes.c_double

    def rate(self) -> float:
        """Scalar double flops/s: 24 flops per iteration of the kernel, best of 3."""
        iters = 100_000 if QUICK else 10_000_000
        best = min(
            timeit.repeat(lambda: self._flop(iters, 0.5, 0.999999, 1e-7), number=1, repeat=3)
        )
        return 24 * iters / best

    def libm(self, names: Iterable[str]) -> dict[str, float]:
        """Seconds per call of each libm function (throughput, best of 3)."""
        iters = 10_000 if QUICK else 1_000_000
        out = {}
        ptr = self._x.ctypes.data
        for name in names:
            fn = self._libm[name]
            best = min(timeit.repeat(lambda fn=fn: fn(iters, ptr), number=1, repeat=3))
            out[name] = best / iters
        return out

    def bandwidth(self) -> float:
        """Bytes/s read plus written by a copy kernel over 2 x 128 MB (best of 3)."""
        n = 1024 * 1024 if QUICK else 16 * 1024 * 1024
        a, b = np.ones(n), np.zeros(n)
        best = min(
            timeit.repeat(lambda: self._stream(n, a.ctypes.data, b.ctypes.data), number=1, repeat=3)
        )
        return 16 * n / best

    def division(self) -> float:
        """Seconds per double division (throughput, best of 3)."""
        iters = 10_000 if QUICK else 1_000_000
        ptr = self._x.ctypes.data
        return min(timeit.repeat(lambda: self._div(iters, ptr), number=1, repeat=3)) / iters


def blas_flop_rate() -> float:
    """numpy's 1000 x 1000 matmul (2 N^3 flops), best of 3: a vectorised reference only."""
    size = 100 if QUICK else 1000
    a = np.random.default_rng(1).standard_normal((size, size))
    best = min(timeit.repeat(lambda: a @ a, number=1, repeat=3))
    return 2 * size**3 / best


# --------------------------------------------------------------------------- the blocks


@dataclass
class Blocks:
    """The symbolic KKT blocks of a case, flattened: ``[[M, -A^T], [A, 0]] [x; lam] =
    [top; b]``.  Acceleration: A = mu, top = f, b = -mu_dot v.  Impact (static wall): A =
    [mu; dpsi; nu], top = M v, b = (0_m, -alpha dpsi(v), 0_l)."""

    kind: str
    n: int
    k: int
    m: int
    exprs: list[sp.Expr]  # M (n*n), A (k*n), then f and rate, or alpha

    def assemble(self, vals: np.ndarray, v: np.ndarray, lib=np):
        """KKT matrix and right-hand side from values of ``exprs`` (leading batch axes
        allowed) in NumPy; or, with ``lib=mp``, one state at 50 digits."""
        n, k = self.n, self.k
        N = n + k
        if lib is mp:
            K = mp.zeros(N, N)
            rhs = mp.zeros(N, 1)
            for i in range(n):
                for j in range(n):
                    K[i, j] = vals[i * n + j]
            for a in range(k):
                for i in range(n):
                    K[n + a, i] = vals[n * n + a * n + i]
                    K[i, n + a] = -vals[n * n + a * n + i]
            tail = vals[n * n + k * n :]
            if self.kind == "acceleration":
                for i in range(n):
                    rhs[i] = tail[i]
                for a in range(k):
                    rhs[n + a] = -tail[n + a]
            else:
                for i in range(n):
                    rhs[i] = mp.fsum(K[i, j] * v[j] for j in range(n))
                rhs[n + self.m] = -tail[0] * mp.fsum(K[n + self.m, j] * v[j] for j in range(n))
            return K, rhs
        lead = vals.shape[:-1]
        K = np.zeros((*lead, N, N))
        M = vals[..., : n * n].reshape(*lead, n, n)
        A = vals[..., n * n : n * n + k * n].reshape(*lead, k, n)
        K[..., :n, :n] = M
        K[..., n:, :n] = A
        K[..., :n, n:] = -np.swapaxes(A, -1, -2)
        tail = vals[..., n * n + k * n :]
        rhs = np.zeros((*lead, N))
        if self.kind == "acceleration":
            rhs[..., :n] = tail[..., :n]
            rhs[..., n:] = -tail[..., n:]
        else:
            rhs[..., :n] = np.einsum("...ij,...j->...i", M, v)
            rhs[..., n + self.m] = -tail[..., 0] * np.einsum("...j,...j->...", A[..., self.m, :], v)
        return K, rhs


def kkt_blocks(scene: sm.Scene, function: str) -> Blocks:
    """The KKT blocks of ``function`` from the scene's metric, forcing, constraint
    one-forms and walls (Carnot paper eqs. 5 and 6)."""
    n = scene.n
    M = list(scene.mass_matrix())
    mu = sp.Matrix(scene.constraint_matrix)
    m = mu.rows
    if function == "acceleration":
        exprs = M + list(mu) + list(scene.forcing()) + list(scene.constraint_rate())
        return Blocks("acceleration", n, m, m, exprs)
    wall = scene.walls[0]
    if wall.moving:
        raise ValueError("the benchmark's impact baseline assumes a static wall")
    grad = sp.Matrix([[sp.diff(wall.psi, qi) for qi in scene.coordinates]])
    dpsi = grad * scene.frame if scene.frame is not None else grad
    A = mu.col_join(dpsi).col_join(sp.Matrix(wall.impulsive_matrix))
    return Blocks("impact", n, A.rows, m, M + list(A) + [sp.sympify(wall.restitution)])


def closed_form_exprs(scene: sm.Scene, function: str) -> list[sp.Expr]:
    if function == "acceleration":
        return list(scene.acceleration())
    return list(scene.impact_map(0).post_velocity)


def scene_args(scene: sm.Scene) -> list[sp.Symbol]:
    if scene.time_dependent:
        raise ValueError("the benchmark's scenes do not depend on time")
    return [*scene.coordinates, *scene.velocities, *scene.parameters]


def cse_operations(exprs: Sequence[sp.Expr]) -> int:
    """count_ops after sympy.cse with its defaults (what lambdify(cse=True) runs)."""
    replacements, reduced = sp.cse(list(exprs))
    return sum(sp.count_ops(e) for _, e in replacements) + sum(sp.count_ops(e) for e in reduced)


# ---------------------------------------------------------------------------- baseline


@dataclass
class Baseline:
    """lambdify(cse=True) of the same mathematics as a strategy (module docstring)."""

    what: str
    make_time: float
    ops: int
    solve_flops: float
    single: Callable[[list[float], np.ndarray], np.ndarray]  # (scalar args, v) -> out
    batch: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]  # (Q, V, p) -> out


def _stack(outputs: Sequence, count: int) -> np.ndarray:
    vals = np.empty((count, len(outputs)))
    for i, o in enumerate(outputs):
        vals[:, i] = o
    return vals


def make_baseline(case: Case, strategy: str) -> Baseline:
    """Create the baseline from a fresh scene (timed: derivation + lambdify)."""
    scene = case.make()
    clear_cache()
    t0 = time.perf_counter()
    args = scene_args(scene)
    if strategy == "closed_form":
        exprs = closed_form_exprs(scene, case.function)
        blocks = None
    else:
        blocks = kkt_blocks(scene, case.function)
        exprs = blocks.exprs
    f = sp.lambdify(args, exprs, cse=True)
    make = time.perf_counter() - t0
    ops = cse_operations(exprs)
    n = scene.n

    def columns(Q: np.ndarray, V: np.ndarray, p: np.ndarray) -> list:
        return [*Q.T, *V.T, *p]

    if blocks is None:

        def single(a: list[float], v: np.ndarray) -> np.ndarray:
            return np.asarray(f(*a), dtype=float)

        def batch(Q: np.ndarray, V: np.ndarray, p: np.ndarray) -> np.ndarray:
            return _stack(f(*columns(Q, V, p)), len(Q))

        return Baseline("lambdify closed form", make, ops, 0.0, single, batch)
    N = n + blocks.k

    def single(a: list[float], v: np.ndarray) -> np.ndarray:
        K, rhs = blocks.assemble(np.asarray(f(*a), dtype=float), v)
        return np.linalg.solve(K, rhs)[:n]

    def batch(Q: np.ndarray, V: np.ndarray, p: np.ndarray) -> np.ndarray:
        K, rhs = blocks.assemble(_stack(f(*columns(Q, V, p)), len(Q)), V)
        return np.linalg.solve(K, rhs[..., None])[..., :n, 0]

    what = "lambdify blocks + LU(KKT)" if blocks.k else "lambdify M, f + LU"
    return Baseline(what, make, ops, 2 * N**3 / 3 + 2 * N**2, single, batch)


# ------------------------------------------------------------------------ the reference


class Reference:
    """The KKT system of the case at 50 digits (mpmath LU), from the scene's blocks."""

    def __init__(self, case: Case):
        scene = case.make()
        self.blocks = kkt_blocks(scene, case.function)
        self.f = sp.lambdify(scene_args(scene), self.blocks.exprs, modules="mpmath")
        self.n = scene.n

    def __call__(self, q: np.ndarray, v: np.ndarray, p_scene: np.ndarray) -> list:
        with mp.workdps(DPS):
            vm = [mp.mpf(float(x)) for x in v]
            vals = self.f(*[mp.mpf(float(x)) for x in (*q, *v, *p_scene)])
            K, rhs = self.blocks.assemble(vals, vm, lib=mp)
            x = mp.lu_solve(K, rhs)
            return [x[i] for i in range(self.n)]


def worst_error(got: np.ndarray, refs: Sequence[list]) -> tuple[float, bool]:
    """max over states of ||got - ref||_inf / ||ref||_inf; the absolute error (flag True)
    when every reference is 0 to 30 digits (an identically zero output)."""
    with mp.workdps(DPS):
        scale = max(max(abs(r) for r in ref) for ref in refs)
        absolute = scale < mp.mpf(10) ** -30
        worst = mp.mpf(0)
        for row, ref in zip(got, refs, strict=True):
            err = max(abs(mp.mpf(float(g)) - r) for g, r in zip(row, ref, strict=True))
            norm = mp.mpf(1) if absolute else max(abs(r) for r in ref)
            worst = max(worst, err / norm)
        return float(worst), absolute


# --------------------------------------------------------------------------- one row


@dataclass
class Row:
    case: Case
    strategy: str
    note: str = ""
    baseline: str = ""
    ops: dict[str, int] = field(default_factory=dict)  # c, numpy, lam
    solve: dict[str, float] = field(default_factory=dict)  # c, lam
    libm: Counter = field(default_factory=Counter)  # libm calls per state in the C code
    gen: dict[str, float] = field(default_factory=dict)  # c, numpy, lam
    load: dict[str, float] = field(default_factory=dict)  # c, numpy
    single: dict[str, float] = field(default_factory=dict)  # c, raw, numpy, lam
    rate: dict[str, float] = field(default_factory=dict)  # c, numpy, lam (states/s)
    counted: dict[str, int] = field(default_factory=dict)  # states evaluated
    error: dict[str, tuple[float, bool]] = field(default_factory=dict)
    bound: dict[str, float] = field(default_factory=dict)  # states/s: flops, libm, roofline
    peak: float = 0.0  # flops/s measured next to the C batch
    divisions: int = 0  # divisions per state in the C code
    traffic: int = 0  # bytes per state: state arrays read and output written
    bandwidth: float = 0.0  # bytes/s of the copy kernel measured next to the C batch


def timed_generate(case: Case, target: str, strategy: str, limit: float):
    scene = case.make()
    clear_cache()
    t0 = time.perf_counter()
    with time_limit(limit):
        code = sm.codegen.generate(scene, target, strategy=strategy, functions=[case.function])
    return code, time.perf_counter() - t0


_DIVISION = re.compile(r"(?<![/*])/(?![/*])")


def memory_traffic(code, name: str, n: int) -> tuple[int, int]:
    """(divisions, bytes per state) of function ``name`` from the generated C: the
    divisions in its body (comments left out), and the bytes of the state arrays it reads
    (those not marked ``(void)``) plus those of its output."""
    (text,) = [t for f, t in code.files.items() if f.endswith(".c")]
    start = re.search(rf"^int \w+_{re.escape(name)}\(([^)]*)\)\n\{{", text, re.M)
    if start is None:
        raise RuntimeError(f"no definition of {name} in the generated C")
    end = text.index("\n}\n", start.end())
    body = re.sub(r"/\*.*?\*/", "", text[start.end() : end], flags=re.S)
    params = [a.split("*")[-1].strip() for a in start.group(1).split(",")]
    states = [a for a in params if a in ("q", "v", "y") and f"(void){a};" not in body]
    read = sum(2 * n if a == "y" else n for a in states)
    (out,) = [f.out_size for f in code.functions if f.name == name]
    return len(_DIVISION.findall(body)), 8 * (read + out)


def header_costs(code, name: str) -> tuple[int, int, Counter]:
    """(operations, solve flops, libm calls) of function ``name`` read from the generated
    C file: the function's header comment states its operations and its solve flops; the
    libm calls are those of the one-state function (up to its batch loop's functions,
    which repeat its body)."""
    (text,) = [t for f, t in code.files.items() if f.endswith(".c")]
    start = re.search(rf"^ \* {re.escape(name)}: ", text, re.M)
    if start is None:
        raise RuntimeError(f"no header comment for {name} in the generated C")
    body = text[start.start() :]
    batch = re.search(r"^(static \w+ sm_(once|each|scale_down)_|long \w+_batch\()", body, re.M)
    body = body[: batch.start()] if batch else body
    line = re.search(r"Operations after CSE: (\d+)[^\n]*", body)
    if line is None:
        raise RuntimeError(f"the header of {name} does not state its operation count")
    solve = re.search(r"solve: (\d+) flops", line.group(0))
    return int(line.group(1)), int(solve.group(1)) if solve else 0, Counter(_LIBM.findall(body))


def raw_c_call(code, mod, name: str, q, v, p) -> Callable[[], int] | None:
    """The bare C function of the loaded library by ctypes, on preallocated arrays (its
    prototype read from the generated header); None if it takes more than q, v, p, out."""
    path = getattr(mod, "path", None)
    (hdr,) = [t for f, t in code.files.items() if f.endswith(".h")]
    proto = re.search(rf"^int (\w+_{re.escape(name)})\(([^)]*)\);", hdr, re.M)
    if path is None or proto is None:
        return None
    names = [a.split("*")[-1].strip() for a in proto.group(2).split(",")]
    arrays = {"q": q, "v": v, "p": p, "out": np.empty(len(q))}
    if any(a not in arrays for a in names):
        return None
    fn = getattr(ctypes.CDLL(str(path)), proto.group(1))
    fn.argtypes = [ctypes.c_void_p] * len(names)
    fn.restype = ctypes.c_int
    keep = [np.ascontiguousarray(arrays[a], dtype=np.float64) for a in names]
    ptrs = [a.ctypes.data for a in keep]

    def call() -> int:
        return fn(*ptrs)

    call.keep = keep  # type: ignore[attr-defined]
    call.out = keep[names.index("out")]  # type: ignore[attr-defined]
    return call


class States:
    """Random states of a case (fixed seed): q, v, parameters; v in D for an impact of a
    constrained scene (projected in float64 as a user would)."""

    def __init__(self, case: Case, ref: Reference, seed: int):
        scene = case.make()
        rng = np.random.default_rng(seed)
        restitutions = {str(w.restitution) for w in scene.walls}
        self.names = [str(s) for s in scene.parameters]
        self.values = {
            s: rng.uniform(0.2, 0.9) if s in restitutions else rng.uniform(0.5, 1.5)
            for s in self.names
        }
        self.p_scene = np.array([self.values[s] for s in self.names])
        self.n = scene.n
        # Euler angle theta of a frame away from the frame's singular set sin(theta) = 0
        self.theta = [
            i
            for i, s in enumerate(scene.coordinates)
            if scene.frame is not None and s.name == "theta"
        ]
        self.project = case.function == "impact" and scene.is_constrained
        self.blocks = ref.blocks
        self.f = sp.lambdify(scene_args(scene), ref.blocks.exprs, modules="numpy")
        self.rng = rng

    def draw(self, count: int) -> tuple[np.ndarray, np.ndarray]:
        Q = self.rng.uniform(-1, 1, (count, self.n))
        for i in self.theta:
            Q[:, i] = self.rng.uniform(0.5, 2.5, count)
        V = self.rng.uniform(-1, 1, (count, self.n))
        if self.project:  # v - M^-1 mu^T (mu M^-1 mu^T)^-1 mu v
            b, n = self.blocks, self.n
            vals = _stack(self.f(*Q.T, *V.T, *self.p_scene), count)
            M = vals[:, : n * n].reshape(count, n, n)
            mu = vals[:, n * n : n * n + b.m * n].reshape(count, b.m, n)
            Z = np.linalg.solve(M, np.swapaxes(mu, 1, 2))
            lam = np.linalg.solve(mu @ Z, np.einsum("nai,ni->na", mu, V)[..., None])
            V = V - (Z @ lam)[..., 0]
        return Q, V


def run_row(case: Case, strategy: str, opts, machine: Machine, work: Path, log) -> Row:
    row = Row(case, strategy)
    try:
        code_c, row.gen["c"] = timed_generate(case, "c", strategy, opts.limit)
        code_np, row.gen["numpy"] = timed_generate(case, "numpy", strategy, opts.limit)
    except TimeLimit:
        row.note = f"generation did not finish within {opts.limit:g} s"
        return row
    except sm.codegen.CodegenError as exc:
        if not isinstance(exc.__cause__, BudgetExceeded):
            raise
        c = exc.__cause__
        row.note = f"refused by its budget ({c.stage}: {c.budget} = {c.limit:g} {c.measure})"
        return row
    (name,) = code_c.operation_counts()
    row.ops["c"] = code_c.operation_counts()[name]
    row.ops["numpy"] = code_np.operation_counts()[name]
    ops, row.solve["c"], row.libm = header_costs(code_c, name)
    if ops != row.ops["c"]:
        raise RuntimeError(f"{name}: header states {ops} operations, operation_counts {row.ops}")
    row.divisions, row.traffic = memory_traffic(code_c, name, code_c.plan.n)
    base = make_baseline(case, strategy)
    row.baseline, row.gen["lam"], row.ops["lam"] = base.what, base.make_time, base.ops
    row.solve["lam"] = base.solve_flops
    log(f"  generated and lambdified ({row.gen['c']:.1f} s, {row.gen['lam']:.1f} s)")

    folder = work / f"{case.label}-{strategy}".replace(" ", "_").replace(".", "")
    t0 = time.perf_counter()
    mod_c = code_c.load(cache=folder / "c")
    row.load["c"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    mod_np = code_np.load(cache=folder / "numpy")
    row.load["numpy"] = time.perf_counter() - t0

    ref = Reference(case)
    states = States(case, ref, opts.seed)
    p = np.array([states.values[s] for s in mod_c.parameters])

    def ours(mod, Q, V, out=None):  # mod.acceleration(q, v, params) or mod.impact(...)
        return getattr(mod, case.function)(Q, V, p, out=out)

    # error against the 50-digit reference on a fixed set of states
    Qe, Ve = states.draw(opts.error_states)
    refs = [ref(q, v, states.p_scene) for q, v in zip(Qe, Ve, strict=True)]
    lam_e = np.array(
        [
            base.single([*map(float, q), *map(float, v), *states.p_scene], v)
            for q, v in zip(Qe, Ve, strict=True)
        ]
    )
    row.error = {
        "c": worst_error(ours(mod_c, Qe, Ve), refs),
        "numpy": worst_error(ours(mod_np, Qe, Ve), refs),
        "lam": worst_error(lam_e, refs),
    }

    # one state
    q, v = Qe[0], Ve[0]
    scalars = [*map(float, q), *map(float, v), *map(float, states.p_scene)]
    row.single["c"] = single_time(lambda: ours(mod_c, q, v))
    raw = raw_c_call(code_c, mod_c, name, q, v, p)
    if raw is not None:
        if raw() != 0 or not np.array_equal(raw.out, ours(mod_c, q, v)):
            raise RuntimeError(f"{name}: the bare C call disagrees with the loaded module")
        row.single["raw"] = single_time(raw)
    row.single["numpy"] = single_time(lambda: ours(mod_np, q, v))
    row.single["lam"] = single_time(lambda: base.single(scalars, v))

    # batch throughput
    N = opts.states
    Q, V = states.draw(N)
    # the C batch, with the peak flop rate and the libm costs measured just before and
    # after it (best of both: the machine is shared)
    peak, libm = machine.rate(), machine.libm(row.libm)
    div, bandwidth = machine.division(), machine.bandwidth()
    # allocating, and into a preallocated output touched once before (as the copy kernel's)
    dest = np.ones((N, *ours(mod_c, Q[:1], V[:1]).shape[1:]))
    alloc, into = best_times([lambda: ours(mod_c, Q, V), lambda: ours(mod_c, Q, V, dest)])
    row.rate["c"], row.rate["c_out"] = N / alloc, N / into
    if not np.array_equal(dest, ours(mod_c, Q, V)):
        raise RuntimeError(f"{name}: the batch with out= disagrees with the allocating batch")
    row.counted["c"] = N
    peak = max(peak, machine.rate())
    libm = {k: min(t, libm[k]) for k, t in machine.libm(row.libm).items()}
    div, row.bandwidth = min(div, machine.division()), max(bandwidth, machine.bandwidth())
    done, spent = chunked_time(
        lambda a, b: ours(mod_np, Q[a:b], V[a:b]), N, opts.chunk, opts.budget
    )
    row.rate["numpy"], row.counted["numpy"] = done / spent, done
    P = states.p_scene
    done, spent = chunked_time(
        lambda a, b: base.batch(Q[a:b], V[a:b], P), N, opts.chunk, opts.budget
    )
    row.rate["lam"], row.counted["lam"] = done / spent, done
    flops = row.ops["c"] + row.solve["c"]
    row.peak = peak
    calls = sum(row.libm.values())
    timed = (flops - calls) / peak + sum(k * libm[name] for name, k in row.libm.items())
    row.bound["flops"] = peak / flops if flops else float("inf")
    row.bound["libm"] = 1 / timed if timed else float("inf")
    divs = min(row.divisions, max(flops - calls, 0))
    compute = (flops - calls - divs) / peak + sum(k * libm[name] for name, k in row.libm.items())
    compute += divs * div
    row.bound["roofline"] = 1 / max(compute, row.traffic / row.bandwidth)
    return row


# ------------------------------------------------------------------------------ output


def _g(x: float, width: int, digits: int = 3) -> str:
    return f"{x:{width}.{digits}g}"


def _err(e: tuple[float, bool]) -> str:
    return f"{e[0]:8.1e}{'*' if e[1] else ' '}"


def _table(title: str, columns: str, rows: list[Row], line: Callable[[Row], str]) -> None:
    head = f"{'case':24} {'strategy':12} {columns}"
    print(f"\n{title}")
    print(head)
    print("-" * len(head))
    for r in rows:
        lead = f"{r.case.label:24} {r.strategy:12}"
        print(f"{lead} {r.note}" if r.note else f"{lead} {line(r)}")


def _build_line(r: Row) -> str:
    return (
        f"{r.ops['c']:6d} {r.ops['numpy']:6d} {r.ops['lam']:7d}"
        f" {r.ops['lam'] / max(r.ops['c'], 1):6.2f} {r.solve['c']:7.0f} {r.solve['lam']:9.0f} |"
        f" {r.gen['c']:6.2f} {r.gen['numpy']:6.2f} {r.gen['lam']:6.2f}"
        f" {r.gen['lam'] / r.gen['c']:6.2f} {r.gen['lam'] / r.gen['numpy']:7.2f} |"
        f" {r.load['c']:6.2f} {r.load['numpy']:6.2f}"
    )


def _run_line(r: Row, states: int) -> str:
    s = {k: v * 1e6 for k, v in r.single.items()}
    raw = s.get("raw", float("nan"))
    mark = {k: "+" if r.counted[k] < states else " " for k in ("numpy", "lam")}
    return (
        f"{s['c']:6.2f} {raw:6.2f} {s['numpy']:7.1f} {s['lam']:7.1f}"
        f" {s['lam'] / s['c']:6.1f} {s['lam'] / raw:7.1f} {s['lam'] / s['numpy']:6.2f} |"
        f" {_g(r.rate['c'], 8)} {_g(r.rate['numpy'], 8)}{mark['numpy']}"
        f"{_g(r.rate['lam'], 8)}{mark['lam']} {r.rate['c'] / r.rate['lam']:6.1f}"
        f" {r.rate['numpy'] / r.rate['lam']:6.2f}"
    )


def _error_line(r: Row) -> str:
    ns = {k: 1e9 / v for k, v in r.rate.items()}
    return (
        f"{_err(r.error['c'])}{_err(r.error['numpy'])}{_err(r.error['lam'])}|"
        f" {ns['c']:8.1f} {ns['numpy']:8.1f} {ns['lam']:8.1f}   {r.baseline}"
    )


def _bound_line(r: Row) -> str:
    calls = ", ".join(f"{k} {n}" for n, k in sorted(r.libm.items())) or "-"
    return (
        f"{r.peak / 1e9:5.2f} {r.ops['c'] + r.solve['c']:7.0f} {_g(r.rate['c'], 8)} |"
        f" {_g(r.bound['flops'], 8)}"
        f" {r.bound['flops'] / r.rate['c']:7.2f} | {_g(r.bound['libm'], 8)}"
        f" {r.bound['libm'] / r.rate['c']:7.2f} | {r.divisions:4d} {r.traffic:5d}"
        f" {_g(r.bound['roofline'], 8)} {_g(r.rate['c_out'], 8)}"
        f" {r.bound['roofline'] / r.rate['c_out']:7.2f} {r.bound['roofline'] / r.rate['c']:7.2f}"
        f"   {calls}"
    )


def print_tables(rows: list[Row], states: int) -> None:
    _table(
        "1. Build: operations after CSE, flops of the linear-algebra step, seconds",
        f"{'ops C':>6} {'ops np':>6} {'ops lam':>7} {'lam/C':>6} {'solve C':>7} {'solve lam':>9} |"
        f" {'gen C':>6} {'gen np':>6} {'lam':>6} {'lam/gC':>6} {'lam/gnp':>7} |"
        f" {'gcc C':>6} {'imp np':>6}",
        rows,
        _build_line,
    )
    print(
        "ops: sympy.count_ops after CSE (C, NumPy: code.operation_counts(); lam: sympy.cse"
        " of the baseline's expressions, as lambdify(cse=True) runs it).\n"
        "solve: flops of the linear-algebra step (C: the generated function's header; lam:"
        " LU of the KKT matrix of order N, 2/3 N^3 + 2 N^2).\n"
        "gen: generate(scene, target, strategy=..., functions=[...]) from a fresh scene with"
        " sympy's cache cleared (the derivation is included); lam: deriving the\n"
        "baseline's expressions + lambdify(cse=True), same conditions; lam/gC, lam/gnp ="
        " lambdify time / generation time.  gcc C: code.load() into an empty\n"
        "cache (gcc + dlopen); imp np: code.load() of the NumPy module."
    )
    _table(
        f"2. Run time: one state [us]; batch [states/s] over {states} states",
        f"{'C mod':>6} {'C raw':>6} {'np':>7} {'lam':>7} {'lam/C':>6} {'lam/raw':>7}"
        f" {'lam/np':>6} | {'C':>8} {'np':>8}  {'lam':>8}  {'C/lam':>6} {'np/lam':>6}",
        rows,
        lambda r: _run_line(r, states),
    )
    print(
        "C mod: mod.acceleration / mod.impact of the loaded C module (argument checks, output"
        " allocation); C raw: the bare C function of the same library by\n"
        "ctypes on preallocated arrays (its prototype from the generated header); np: the"
        " loaded NumPy module; lam: the baseline (Python floats in, array out).\n"
        "Batch: one call for C; NumPy and lambdify in chunks of --chunk states."
    )
    if any(r.counted.get(k, states) < states for r in rows for k in ("numpy", "lam")):
        print(
            "+ fewer states than requested: the chunks ran until the time budget (--budget);"
            " states/s = states evaluated / their time."
        )
    _table(
        "3. Error against run time: worst relative error (inf-norm) vs mpmath; ns per state"
        " (batch)",
        f"{'err C':>9} {'err np':>9} {'err lam':>9} | {'C':>8} {'np':>8} {'lam':>8}   baseline",
        rows,
        _error_line,
    )
    print(
        "Reference: the KKT system at 50 digits (mpmath LU) from the scene's blocks, on"
        " --error-states random states (seed --seed).  * absolute error: the exact\n"
        "output is identically 0 (the rolling sphere's velocities are constant).  Impact"
        " states have v in D only to float64 accuracy (projected as a user would);\n"
        "the closed form (derived for v in D) and the KKT differ at that level."
    )
    _table(
        "4. Flop bound of the C batch [states/s]",
        f"{'peak':>5} {'flops':>7} {'C':>8} | {'bound':>8} {'C/bound':>7} | {'bound2':>8}"
        f" {'C/bound2':>7} | {'divs':>4} {'bytes':>5} {'roofline':>8} {'C out=':>8}"
        f" {'C/roof':>7} {'alloc':>7}   libm calls per state",
        rows,
        _bound_line,
    )
    print(
        "peak: scalar flop rate [GFlop/s] measured just before and after the C batch (the"
        " better); flops = ops C + solve C per state; bound = peak / flops;\n"
        "C/bound = C batch time / (flops x states / peak) (issue 4 target: <= 3).  bound2"
        " charges each libm call its cost measured next to the C batch instead of\n"
        "one flop (the other operations at the peak rate).  roofline: bound2 with each"
        " division (divs per state) at its measured cost, or the memory time of\n"
        "the bytes per state (state arrays read + output) at the copy kernel's rate,"
        " whichever is longer.  C out=: the C batch writing into a preallocated output\n"
        "(out=, touched before, as the copy kernel's destination); C/roof = its time / the"
        " roofline time; alloc: the same ratio for the allocating batch (column C)."
    )
    _targets(rows)


def _targets(rows: list[Row]) -> None:
    print("\nTargets (issue 4)")
    for r in rows:
        if r.case.links == 8 and r.strategy == "linear_solve" and not r.note:
            s = r.single
            print(
                f"  single-state C >= 20x faster than lambdify, 8-link pendulum ({r.strategy}):"
                f" {s['lam'] / s['c']:.1f}x through the loaded module,"
                f" {s['lam'] / s.get('raw', float('nan')):.1f}x through the bare C function"
            )
    done = [r for r in rows if not r.note and r.ops["c"] + r.solve["c"] > 0]
    for key, what in (
        ("flops", "each op one flop"),
        ("libm", "libm calls at measured cost"),
        ("roofline", "roofline: libm and divisions at measured cost, memory traffic"),
    ):
        ok = [r for r in done if r.bound[key] / r.rate["c"] <= 3]
        print(
            f"  batch C within 3x of the flop bound ({what}): {len(ok)} of {len(done)} rows"
            " (rows with no flops left out);"
            f" worst {max(r.bound[key] / r.rate['c'] for r in done):.1f}x"
        )
    measured = [r for r in rows if not r.note]
    if measured:
        for key, what in (("c_out", "out="), ("c", "allocating")):
            ratios = [r.bound["roofline"] / r.rate[key] for r in measured]
            print(
                f"  issue 27: batch C ({what}) within 2x of its roofline on every row"
                " (memory-bound rows with no flops included):"
                f" {sum(x <= 2 for x in ratios)} of {len(ratios)} rows; worst {max(ratios):.1f}x"
            )


def pydy_generation(n: int) -> float:
    """What PyDy users do: KanesMethod's M and f, one ``sympy.cse`` over both, C printing."""
    clear_cache()
    t0 = time.perf_counter()
    q, u, frame, particles, forces, kindiffs = _mechanics_model(n)
    kane = sm_mechanics.KanesMethod(frame, q_ind=q, u_ind=u, kd_eqs=kindiffs)
    kane.kanes_equations(particles, forces)
    plain = {s: sp.Symbol(f"s{k}") for k, s in enumerate((*q, *u))}
    pydy_print(kane.mass_matrix.xreplace(plain), kane.forcing.xreplace(plain))
    return time.perf_counter() - t0


def pydy_print(M: sp.Matrix, f: sp.Matrix) -> list[str]:
    """PyDy's generation step: one ``sympy.cse`` over M and f, then C printing of every
    temporary and entry."""
    replacements, reduced = sp.cse([M, f])
    text = [sp.ccode(e, assign_to=str(x)) for x, e in replacements]
    for block in reduced:
        text.extend(sp.ccode(e) for e in block)
    return text


def issue13_table() -> None:
    """Generation time against PyDy, the 4-link cart with a tip wall, NumPy one-state."""
    print("\nissue 13: generation time (C, linear_solve) against PyDy's route, same run")
    head = f"{'case':34s} {'symmech [s]':>11s} {'PyDy [s]':>9s} {'PyDy/sm':>8s}"
    print(head)
    print("-" * len(head))
    for n in (2,) if QUICK else (8, 16, 32):
        clear_cache()
        t0 = time.perf_counter()
        sm.codegen.generate(pendulum_on_cart(n), "c", strategy="linear_solve")
        t_sm = time.perf_counter() - t0
        t_py = pydy_generation(n)
        print(
            f"{f'cart + {n}-link pend.':34s} {t_sm:11.2f} {t_py:9.2f} {t_py / t_sm:8.1f}",
            flush=True,
        )
    tip = 2 if QUICK else 4
    clear_cache()
    t0 = time.perf_counter()
    sm.codegen.generate(cart_with_tip_wall(tip), "c", strategy="linear_solve")
    t_tip = time.perf_counter() - t0
    t0 = time.perf_counter()
    try:
        sm.codegen.generate(cart_with_tip_wall(tip), "c", strategy="closed_form")
        refused = "generated"
    except sm.codegen.CodegenError:
        refused = "refused by its budget"
    t_refuse = time.perf_counter() - t0
    print(f"{f'cart + {tip}-link pend., tip wall':34s} {t_tip:11.2f}  (linear_solve; target < 5 s)")
    print(f"{'  same, closed_form':34s} {t_refuse:11.2f}  ({refused})")
    links = 2 if QUICK else 8
    scene = pendulum_on_cart(links)
    code = sm.codegen.generate(scene, "numpy", strategy="linear_solve")
    mod = code.load()
    params = np.linspace(0.5, 1.5, len(code.plan.parameters))
    rng = np.random.default_rng(8)
    qv, vv = rng.normal(size=links + 1), rng.normal(size=links + 1)
    ours = best_time(lambda: mod.acceleration(qv, vv, params))
    syms = [*scene.coordinates, *scene.velocities, *code.plan.parameters]
    lam = sp.lambdify(syms, [sp.Matrix(scene.mass_matrix()), sp.Matrix(scene.forcing())], cse=True)

    def baseline() -> np.ndarray:
        G, F = lam(*qv, *vv, *params)
        return np.linalg.solve(np.asarray(G, float), np.asarray(F, float).ravel())

    base = best_time(baseline)
    np.testing.assert_allclose(mod.acceleration(qv, vv, params), baseline(), rtol=1e-10)
    print(
        f"{f'NumPy one state, {links}-link accel.':34s} {ours * 1e6:9.1f} us  lambdify + solve"
        f" {base * 1e6:.1f} us  (ratio {ours / base:.1f}; target <= 2)"
    )


def one_state_table(links: int) -> None:
    """Issue 27: one call of the pendulum's rhs, the way a user's own integrator, MPC loop
    or optimiser makes it, against lambdify of M, f and ``numpy.linalg.solve``."""
    scene = pendulum_on_cart(links)
    mod = sm.codegen.generate(scene, "c", functions=["rhs"]).load()
    rng = np.random.default_rng(27)
    y = 0.3 * rng.normal(size=2 * mod.n)
    p = np.linspace(0.5, 1.5, len(mod.parameters))
    named = dict(zip(mod.parameters, p.tolist(), strict=True))
    rhs = mod.bind(p).rhs
    syms = [*scene.coordinates, *scene.velocities, *(sp.Symbol(k) for k in mod.parameters)]
    lam = sp.lambdify(syms, [sp.Matrix(scene.mass_matrix()), sp.Matrix(scene.forcing())], cse=True)
    n = mod.n

    def baseline() -> np.ndarray:
        G, F = lam(*y, *p)
        vdot = np.linalg.solve(np.asarray(G, float), np.asarray(F, float).ravel())
        return np.concatenate([y[n:], vdot])

    np.testing.assert_allclose(rhs(y), baseline(), rtol=1e-9, atol=1e-12)
    routes = {
        "bound = mod.bind(p).rhs; bound(y)": (lambda: rhs(y), 1.5),
        "mod.rhs(y, p_array, t=0.0)": (lambda: mod.rhs(y, p, t=0.0), 3.0),
        "mod.rhs(y, p_dict, t=0.0)": (lambda: mod.rhs(y, named, t=0.0), 5.0),
        "lambdify(M, f) + numpy.linalg.solve": (baseline, None),
    }
    times = {label: min(single_time(call) for _ in range(3)) for label, (call, _) in routes.items()}
    base = times["lambdify(M, f) + numpy.linalg.solve"]
    print(f"\nissue 27: one-state rhs of the {links}-link pendulum on a cart (C; {mod.fast_path})")
    print("us per call, best of 3 x (timeit autorange, best of 3); target from the issue")
    for label, (_, target) in routes.items():
        t = times[label] * 1e6
        goal = f"target <= {target:g} us: {'met' if t <= target else 'NOT met'}" if target else ""
        print(f"  {label:38s} {t:8.2f} us  lambdify/this {base / times[label]:6.1f}  {goal}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--states", type=int, default=1_000_000, help="batch size (default 10^6)")
    ap.add_argument("--chunk", type=int, default=100_000, help="NumPy/lambdify chunk size")
    ap.add_argument(
        "--budget", type=float, default=20.0, help="seconds per NumPy/lambdify batch (20)"
    )
    ap.add_argument(
        "--limit", type=float, default=60.0, help="seconds allowed for one generate() (60)"
    )
    ap.add_argument("--error-states", type=int, default=16, help="states of the error table")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--issue13-only", action="store_true", help="only the issue 13 table")
    ap.add_argument("--one-state", action="store_true", help="only the issue 27 table")
    ap.add_argument(
        "--quick", action="store_true", help="every table at its smallest size (a smoke test)"
    )
    opts = ap.parse_args()
    if opts.quick:
        global QUICK
        QUICK = True
        opts.states, opts.chunk, opts.error_states, opts.budget = 2000, 1000, 2, 1.0
    one_state_table(2 if QUICK else 8)
    if opts.one_state:
        return
    issue13_table()
    if opts.issue13_only:
        return

    def log(msg: str) -> None:
        print(msg, file=sys.stderr, flush=True)

    compiler = os.environ.get("CC") or "gcc"
    cc_version = subprocess.run([compiler, "--version"], capture_output=True, text=True)
    started = time.perf_counter()
    print(f"$ {shlex.join(['python3', *sys.argv])}")
    print(
        f"python {sys.version.split()[0]}, sympy {sp.__version__}, numpy {np.__version__},"
        f" mpmath {mp.__version__}; {cc_version.stdout.splitlines()[0]};"
        f" {os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f}"
    )
    with tempfile.TemporaryDirectory(prefix="symmech_bench_") as tmp:
        work = Path(tmp)
        machine = Machine(compiler, work)
        print(
            f"peak scalar flop rate now: {machine.rate() / 1e9:.2f} GFlop/s (C kernel: 12"
            f" independent multiply-add chains, {' '.join(KERNEL_FLAGS[:3])}; re-measured next"
            f" to each C batch, table 4); numpy 1000^2 matmul: {blas_flop_rate() / 1e9:.1f}"
            " GFlop/s (reference only)"
        )
        print(
            "cases: n coordinates, m constraints; 'cart + k-link pend.' is"
            " symmech.examples.pendulum_on_cart(k), k links and k + 1 coordinates"
        )
        print(
            "libm cost per call now [ns] (same flags, throughput): "
            + ", ".join(
                f"{k} {v * 1e9:.1f}" for k, v in machine.libm(LIBM_UNARY + LIBM_BINARY).items()
            )
            + f"; division {machine.division() * 1e9:.2f} ns; copy kernel"
            f" {machine.bandwidth() / 1e9:.1f} GB/s (read + written)"
        )
        rows: list[Row] = []
        stopped: set[tuple[str, str]] = set()
        for case in cases():
            for strategy in ("closed_form", "linear_solve"):
                if (case.family, strategy) in stopped:
                    rows.append(
                        Row(
                            case,
                            strategy,
                            note="not attempted: a smaller size was refused or timed out",
                        )
                    )
                    continue
                log(f"{case.label}, {strategy} ...")
                row = run_row(case, strategy, opts, machine, work, log)
                if row.note and case.family:
                    stopped.add((case.family, strategy))
                rows.append(row)
        print_tables(rows, opts.states)
    print(f"\ntotal run time: {time.perf_counter() - started:.0f} s")


if __name__ == "__main__":
    main()
