"""Time to derive the equations of motion of the n-link pendulum on a cart (PyDy benchmark).

For n = 2, 4, 8, 16, 32 this prints, measured in one run on this machine:

* symmech: the time to declare the scene from its kinetic and potential energy (including
  validation) and form the mass matrix g and the forcing f (g q_ddot = f);
* the time for all Christoffel symbols of the second kind as the API returns them by
  default (``scene.christoffel()``: kind 2, ``simplify="light"``; n <= 8), on a fresh
  scene, and the form it returned: "normal" (exact normal form, fraction-free adjugate
  with a shared determinant, see symmech/algebra/field.py) with its operation count, or
  "LU" when that normal form exceeds its term budget and the default falls back to the
  exact symbols as built by a symbolic LU solve (operation count not printed: it is not
  the size of a useful closed form);
* sympy.physics.mechanics KanesMethod and LagrangesMethod forming the equations of the
  same system (their mass matrix and forcing), and the ratios baseline / symmech;
* the operation counts (sympy.count_ops) of g + f and of the baselines' M + f.

Usage: python3 benchmarks/derive.py [--sizes 2 4 8] [--no-lagrange]
"""

from __future__ import annotations

import argparse
import time

import sympy as sp
from sympy.physics import mechanics as me

from symmech.algebra.field import field_solve
from symmech.examples import pendulum_on_cart


def symmech_route(n: int) -> tuple[float, float, int, tuple[float, str, int | None] | None]:
    """(total time, of which declaring the scene (validation included), operations,
    Christoffel row)."""
    t0 = time.perf_counter()
    scene = pendulum_on_cart(n)
    t_declare = time.perf_counter() - t0
    g = scene.mass_matrix()
    f = scene.forcing()
    t1 = time.perf_counter()
    gamma = christoffel_route(n) if n <= 8 else None
    return t1 - t0, t_declare, sp.count_ops(g) + sp.count_ops(f), gamma


def christoffel_route(n: int) -> tuple[float, str, int | None]:
    """Time of the default ``christoffel()`` on a fresh scene, the form it returned and,
    for the normal form, its operation count."""
    scene = pendulum_on_cart(n)
    scene.mass_matrix()
    t0 = time.perf_counter()
    gamma = scene.christoffel()
    elapsed = time.perf_counter() - t0
    # the default's route: the exact solve declines iff it declines on g alone (its budget
    # counts the minors of g only)
    g = sp.Matrix(scene.mass_matrix())
    normal = field_solve(g, sp.eye(g.rows)[:, :1]) is not None
    ops = sp.count_ops(list(gamma)) if normal else None
    return elapsed, "normal" if normal else "LU", ops


def _mechanics_model(n: int):
    """The same system built for sympy.physics.mechanics (PyDy's n_link_pendulum_on_cart)."""
    q = me.dynamicsymbols(f"q:{n + 1}")
    u = me.dynamicsymbols(f"u:{n + 1}")
    m = sp.symbols(f"m:{n + 1}")
    l = sp.symbols(f"l:{n}")
    g, t = sp.symbols("g t")
    I = me.ReferenceFrame("I")
    O = me.Point("O")
    O.set_vel(I, 0)
    P0 = me.Point("P0")
    P0.set_pos(O, q[0] * I.x)
    P0.set_vel(I, u[0] * I.x)
    particles = [me.Particle("Pa0", P0, m[0])]
    forces = [(P0, -m[0] * g * I.y)]
    kindiffs = [q[0].diff(t) - u[0]]
    prev = P0
    for i in range(n):
        Bi = I.orientnew(f"B{i}", "Axis", [q[i + 1], I.z])
        Bi.set_ang_vel(I, u[i + 1] * I.z)
        Pi = prev.locatenew(f"P{i + 1}", -l[i] * Bi.y)
        Pi.v2pt_theory(prev, I, Bi)
        particles.append(me.Particle(f"Pa{i + 1}", Pi, m[i + 1]))
        forces.append((Pi, -m[i + 1] * g * I.y))
        kindiffs.append(q[i + 1].diff(t) - u[i + 1])
        prev = Pi
    return q, u, I, particles, forces, kindiffs


def kane_route(n: int) -> tuple[float, int]:
    t0 = time.perf_counter()
    q, u, I, particles, forces, kindiffs = _mechanics_model(n)
    kane = me.KanesMethod(I, q_ind=q, u_ind=u, kd_eqs=kindiffs)
    kane.kanes_equations(particles, forces)
    M, f = kane.mass_matrix, kane.forcing
    t1 = time.perf_counter()
    return t1 - t0, sp.count_ops(M) + sp.count_ops(f)


def lagrange_route(n: int) -> tuple[float, int]:
    t0 = time.perf_counter()
    q, u, I, particles, forces, _ = _mechanics_model(n)
    qd = [qi.diff() for qi in q]
    # velocities in terms of q_dot for the Lagrangian
    L = me.Lagrangian(I, *particles)
    L = L.subs(dict(zip(u, qd, strict=True)))
    lm = me.LagrangesMethod(L, q, forcelist=forces, frame=I)
    lm.form_lagranges_equations()
    M, f = lm.mass_matrix, lm.forcing
    t1 = time.perf_counter()
    return t1 - t0, sp.count_ops(M) + sp.count_ops(f)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[2, 4, 8, 16, 32])
    parser.add_argument("--no-lagrange", action="store_true", help="skip LagrangesMethod")
    parser.add_argument("--quick", action="store_true", help="a smoke test: n = 2, every route")
    args = parser.parse_args()
    if args.quick:
        args.sizes = [2]
    head = (
        f"{'n':>3} | {'symmech g,f [s]':>15} {'declare':>7} {'ops':>7} | "
        f"{'Gamma^k_ij default [s]':>22} {'form':>6} {'ops':>8} | "
        f"{'Kane [s]':>9} {'ops':>7} {'Kane/sm':>8} | {'Lagr. [s]':>9} {'ops':>7} {'Lagr/sm':>8}"
    )
    # warm-up: imports and sympy's caches of trivial objects, for both routes
    symmech_route(2)
    kane_route(2)
    print(head)
    print("-" * len(head))
    summary: list[tuple[int, float, float]] = []
    for n in args.sizes:
        t_sm, t_decl, ops_sm, gamma = symmech_route(n)
        t_k, ops_k = kane_route(n)
        summary.append((n, t_sm, t_k / t_sm))
        if gamma is None:
            gam = f"{'-':>22} {'-':>6} {'-':>8}"
        else:
            t_gam, form, ops_gam = gamma
            ops_text = f"{ops_gam:8d}" if ops_gam is not None else f"{'-':>8}"
            gam = f"{t_gam:22.3f} {form:>6} {ops_text}"
        if args.no_lagrange:
            lag = f"{'-':>9} {'-':>7} {'-':>8}"
        else:
            t_l, ops_l = lagrange_route(n)
            lag = f"{t_l:9.3f} {ops_l:7d} {t_l / t_sm:8.1f}"
        print(
            f"{n:3d} | {t_sm:15.3f} {t_decl:7.3f} {ops_sm:7d} | {gam} | "
            f"{t_k:9.3f} {ops_k:7d} {t_k / t_sm:8.1f} | {lag}",
            flush=True,
        )
    print(
        "\nGamma^k_ij default: scene.christoffel() (kind 2, simplify='light') on a fresh scene;"
        "\nform 'normal': exact normal form (fraction-free adjugate, shared determinant,"
        " sin^2 -> 1 - cos^2);\nform 'LU': that normal form exceeds its term budget, and the"
        " default returns the exact\nsymbols as built by a symbolic LU solve (no closed form"
        " of useful size exists: det g alone\nhas 3^n terms for the n-link pendulum)."
        "\ndeclare: the part of 'symmech g,f' spent declaring the scene from T and V"
        " (validation included)."
    )
    print("\nissue 13 targets: Kane/sm >= 20 at n = 8 and 16; symmech g,f at n = 32 < 1 s")
    for n, t_sm, ratio in summary:
        if n in (8, 16, 32):
            print(f"  n = {n:2d}: symmech {t_sm:.3f} s, Kane/sm {ratio:.1f}")


if __name__ == "__main__":
    main()
