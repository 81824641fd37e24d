"""Importing a sympy.physics.mechanics model: symmech against KanesMethod, in one run.

For the Whipple bicycle of sympy's own test suite (Meijaard et al. 2007; 4 coordinates,
6 generalized speeds, 3 velocity constraints) this prints:

* KanesMethod: the seconds it takes to form the equations (its construction and
  ``kanes_equations``; the kinematics, common to both routes, excluded): the baseline;
* a second baseline, what a PyDy user runs after KanesMethod: one ``sympy.cse`` over
  Kane's ``mass_matrix_full`` and ``forcing_full`` (dynamic symbols swapped for plain
  ones), then C printing, and KanesMethod plus that (the "route");
* symmech, twice, each after clearing sympy's cache (so nothing of Kane's work, or of the
  other run, is reused): every function (the default of ``codegen.generate``: the mass
  matrix, the forcing, the energy, the multipliers, the constraint residual, ``rhs``),
  then ``functions=["rhs"]`` (``rhs`` and the ``acceleration`` it calls: what
  KanesMethod's equations give).  Each: ``Scene.from_mechanics`` (reading the bodies and
  loads, the validation of the declaration), ``codegen.generate(target="c")`` (strategy
  auto), and the compilation and loading in an empty library cache (``load``: one gcc
  run, -O2, the CPython extension and the library in one shared object); the ratios to
  KanesMethod;
* the target of issue 25, from the model as built to loaded C of the equations of motion
  (import, generation of ``rhs``, compilation) against KanesMethod plus the PyDy route
  (target: a ratio below 1), and the full set of functions the same way (target: within
  1.5x).

Where the time goes (the rhs run, wall seconds of each step timed alone; ``--profile``
prints cProfile of the same run, which inflates sympy's many small calls): the import
about 0.85 s (``mechanics.convert``: the metric from the partial velocities 0.2, Kane's
inertia forces 0.1 and the velocity-quadratic forcing 0.1 that they are compared with
(memoised: the scene's forcing reuses it), the loads and the constraints 0.1 together,
then the declaration's checks 0.25, half of them the metric's definiteness with
parameters declared without a sign); the generation about 0.95 s (one CSE 0.33; the
stable forms of the metric's entries 0.15, ``algebra.stability``, the rolling
constraints' sums over square roots being kept as written; the note on the forcing's
zero connection coefficients 0.07; printing 0.2); gcc about 0.5 s, the CPython
extension compiled beside the library.  The partial velocities, accelerations, dot and
cross products of the import are formed by ``mechanics.rates`` (the expressions sympy's
vector algebra gives, without its ``diff`` and matrix products) and the metric's
expansions in one polynomial ring.  Every function: the generation about 1.6 s; the
acceleration and the multipliers are parts of one solve (``codegen.sharing``), and the
library is written as two source files that gcc compiles side by side with the
extension (``codegen.generate.SPLIT_SOURCE_CHARACTERS``; on this machine's 2 CPUs about
0.8 s of wall time for 1.3 s of gcc).  Nothing is cached between the routes: sympy's
cache is cleared and each library is built in an empty folder.  gcc at -O1 instead of
-O2 would save about a fifth of the compilation; the default stays -O2 (the benchmark
measures what a user gets).

Usage: python3 benchmarks/mechanics.py [--quick] [--profile]

``--quick`` (a smoke test) runs every step on the 1-link pendulum on a cart of
``benchmarks/derive.py`` (KanesMethod of sympy.physics.mechanics) instead of the bicycle.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

import sympy as sp
from codegen import pydy_print
from mechanics_models import sympy_bicycle
from sympy.core.cache import clear_cache

import symmech as sm


def pydy_generation(KM: object) -> float:
    """Seconds of PyDy's generation after KanesMethod: the dynamic symbols of Kane's full
    mass matrix and forcing swapped for plain symbols, then ``codegen.pydy_print`` (one
    ``sympy.cse`` over both, C printing; sympy's cache cleared first)."""
    from sympy.physics.mechanics import find_dynamicsymbols

    clear_cache()
    t0 = time.perf_counter()
    M, f = KM.mass_matrix_full, KM.forcing_full  # type: ignore[attr-defined]
    found = find_dynamicsymbols(M) | find_dynamicsymbols(f)
    plain = {s: sp.Symbol(f"s{k}") for k, s in enumerate(sorted(found, key=str))}
    pydy_print(M.xreplace(plain), f.xreplace(plain))
    return time.perf_counter() - t0


def small_model(timings: dict) -> object:
    """KanesMethod of the 1-link pendulum on a cart (``derive._mechanics_model``)."""
    from derive import _mechanics_model
    from sympy.physics.mechanics import KanesMethod

    q, u, frame, particles, forces, kindiffs = _mechanics_model(1)
    t0 = time.perf_counter()
    KM = KanesMethod(frame, q_ind=q, u_ind=u, kd_eqs=kindiffs)
    KM.kanes_equations(particles, forces)
    timings["kane"] = time.perf_counter() - t0
    return KM


def symmech_route(KM: object, name: str, functions: list[str] | None) -> dict[str, float]:
    """Seconds of symmech's route from the model to loaded C, sympy's cache cleared first:
    ``import`` (``Scene.from_mechanics``), ``generate`` (``codegen.generate``, C, the
    given functions or all) and ``compile`` (``load`` in an empty library cache)."""
    clear_cache()  # nothing of Kane's work (or of an earlier route) reused
    t0 = time.perf_counter()
    scene = sm.Scene.from_mechanics(KM, name=name)
    t1 = time.perf_counter()
    code = sm.codegen.generate(scene, target="c", functions=functions)
    t2 = time.perf_counter()
    with tempfile.TemporaryDirectory() as cache:
        code.load(cache=cache)
    t3 = time.perf_counter()
    return {"import": t1 - t0, "generate": t2 - t1, "compile": t3 - t2}


def profile_rhs(KM: object, lines: int = 25) -> None:
    """cProfile of the ``rhs`` route (import, generation, compilation): the symmech
    functions and the sympy entry points that take the longest, cumulative."""
    import cProfile
    import pstats

    profiler = cProfile.Profile()
    profiler.runcall(symmech_route, KM, "bicycle_rhs", ["rhs"])
    stats = pstats.Stats(profiler).sort_stats("cumulative")
    stats.print_stats(r"symmech/|cse_main|polytools.py:.*\(factor\)|subprocess.py:.*\(run\)", lines)


def _line(label: str, seconds: float, base: float | None = None, note: str = "") -> None:
    ratio = f"   {seconds / base:6.2f}x" if base else ""
    print(f"{label:48s} {seconds:8.2f}{ratio}{note}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="a smoke test (see the docstring)")
    ap.add_argument("--profile", action="store_true", help="also cProfile the rhs route")
    args = ap.parse_args()
    timings: dict = {}
    KM = small_model(timings) if args.quick else sympy_bicycle(timings)[0]
    kane = timings["kane"]
    pydy = pydy_generation(KM)
    route = kane + pydy
    warnings.simplefilter("ignore")
    full = symmech_route(KM, "bicycle", None)
    rhs = symmech_route(KM, "bicycle_rhs", ["rhs"])
    quick = "1-link pendulum on a cart (--quick)"
    print(
        f"{quick if args.quick else 'Whipple bicycle (sympy test_kane3)'}, seconds on this machine"
    )
    _line("KanesMethod forms the equations (baseline)", kane)
    _line("PyDy route: cse + C printing of Kane M, f", pydy)
    _line("KanesMethod + PyDy route", route)
    for what, t in (("", full), (", functions=[rhs]", rhs)):
        _line(f"symmech Scene.from_mechanics{what and ' (rhs run)'}", t["import"], kane)
        _line(f"symmech codegen.generate (C){what}", t["generate"], kane)
        _line(f"compile and load (empty cache){what and ', rhs'}", t["compile"])
        _line(
            f"symmech derivation + C generation{what and ', rhs'}",
            t["import"] + t["generate"],
            kane,
        )
    print("issue 25: from the model to loaded C, against KanesMethod + PyDy route")
    label = "symmech rhs: import + generation + compilation"
    _line(label, sum(rhs.values()), route, "  (target < 1)")
    _line("symmech all functions: the same", sum(full.values()), route, "  (target < 1.5)")
    if args.profile:
        profile_rhs(KM)


if __name__ == "__main__":
    main()
