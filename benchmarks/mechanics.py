"""Importing a sympy.physics.mechanics model: symmech against KanesMethod, in one run.

For the Whipple bicycle of sympy's own test suite (Meijaard et al. 2007; 4 coordinates,
6 generalized speeds, 3 velocity constraints) this prints:

* KanesMethod: the seconds it takes to form the equations (its construction and
  ``kanes_equations``; the kinematics, common to both routes, excluded): the baseline;
* symmech, after clearing sympy's cache (so nothing of Kane's work is reused):
  ``Scene.from_mechanics`` (reading the bodies and loads, the validation of the
  declaration), then ``codegen.generate(target="c")`` (strategy auto) and the compilation;
* the ratios symmech / KanesMethod (the issue's target: derivation plus C generation
  faster than KanesMethod alone, a ratio below 1);
* a second baseline, what a PyDy user runs after KanesMethod: one ``sympy.cse`` over
  Kane's ``mass_matrix_full`` and ``forcing_full`` (dynamic symbols swapped for plain
  ones), then C printing, and KanesMethod plus that;
* the same for the equations of motion alone: a fresh import, then
  ``generate(..., functions=["rhs"])`` (``rhs`` and the ``acceleration`` it calls: what
  KanesMethod's equations give; the default also emits the mass matrix, the forcing, the
  energy, the multipliers and the constraint residual);
* the target of issue 25, from the model as built to loaded C of the equations of motion
  (import, generation of ``rhs``, compilation in an empty library cache) against
  KanesMethod plus the PyDy route (target: a ratio below 1), and the full set of
  functions the same way (target: within 1.5x).

Usage: python3 benchmarks/mechanics.py [--quick]

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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="a smoke test (see the docstring)")
    quick = ap.parse_args().quick
    timings: dict = {}
    KM = small_model(timings) if quick else sympy_bicycle(timings)[0]
    kane = timings["kane"]
    pydy = pydy_generation(KM)
    warnings.simplefilter("ignore")
    clear_cache()  # nothing of Kane's work reused through sympy's cache
    t0 = time.perf_counter()
    scene = sm.Scene.from_mechanics(KM, name="bicycle")
    t1 = time.perf_counter()
    code = sm.codegen.generate(scene, target="c")
    t2 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        code.write(tmp)
        t3 = time.perf_counter()
        code.load()
        t4 = time.perf_counter()
    imp, gen, comp = t1 - t0, t2 - t1, t4 - t3
    model = "1-link pendulum on a cart (--quick)" if quick else "Whipple bicycle (sympy test_kane3)"
    print(f"{model}, seconds on this machine")
    print(f"{'KanesMethod forms the equations (baseline)':48s} {kane:8.2f}")
    print(f"{'PyDy route: cse + C printing of Kane M, f':48s} {pydy:8.2f}")
    print(f"{'KanesMethod + PyDy route':48s} {kane + pydy:8.2f}")
    print(f"{'symmech Scene.from_mechanics':48s} {imp:8.2f}   {imp / kane:6.2f}x")
    print(f"{'symmech codegen.generate (C)':48s} {gen:8.2f}   {gen / kane:6.2f}x")
    print(f"{'compile and load':48s} {comp:8.2f}")
    total = imp + gen
    print(f"{'symmech derivation + C generation':48s} {total:8.2f}   {total / kane:6.2f}x")
    clear_cache()
    t0 = time.perf_counter()
    scene = sm.Scene.from_mechanics(KM, name="bicycle_rhs")
    t1 = time.perf_counter()
    code_rhs = sm.codegen.generate(scene, target="c", functions=["rhs"])
    t2 = time.perf_counter()
    with tempfile.TemporaryDirectory() as cache:
        code_rhs.load(cache=cache)
    t3 = time.perf_counter()
    rhs, rhs_gen = t2 - t0, t2 - t1
    label = "symmech codegen.generate (C), functions=[rhs]"
    print(f"{label:48s} {rhs_gen:8.2f}   {rhs_gen / kane:6.2f}x")
    print(f"{'symmech derivation + C generation of rhs':48s} {rhs:8.2f}   {rhs / kane:6.2f}x")
    route = kane + pydy
    loaded_rhs = t3 - t0
    print("issue 25: from the model to loaded C, against KanesMethod + PyDy route")
    label = "symmech rhs: import + generation + compilation"
    print(f"{label:48s} {loaded_rhs:8.2f}   {loaded_rhs / route:6.2f}x  (target < 1)")
    with tempfile.TemporaryDirectory() as cache:
        t4 = time.perf_counter()
        code.load(cache=cache)
        cold = time.perf_counter() - t4
    full = imp + gen + cold
    label = "symmech all functions: the same"
    print(f"{label:48s} {full:8.2f}   {full / route:6.2f}x  (target < 1.5)")


if __name__ == "__main__":
    main()
