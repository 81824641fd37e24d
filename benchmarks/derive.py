"""Time to derive the equations of motion of the n-link pendulum on a cart (PyDy benchmark).

For n = 2, 4, 8, 16, 32 this prints, measured in one run on this machine:

* symmech: the time to declare the scene from its kinetic and potential energy (including
  validation) and form the mass matrix g and the forcing f (g q_ddot = f), for T and V
  written as ``symmech.examples.pendulum_on_cart`` writes them (each sum built once) and
  as users write them (:func:`user_pendulum_on_cart`: the velocity accumulated link by
  link with ``+=``, T and V grown term by term);
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

sympy's cache is cleared before every timed route (``sympy.core.cache.clear_cache``), so
that no route reuses another's expressions.

Usage: python3 benchmarks/derive.py [--sizes 2 4 8] [--no-lagrange] [--quick]
"""

from __future__ import annotations

import argparse
import time

import sympy as sp
from sympy.core.cache import clear_cache
from sympy.physics import mechanics as me

import symmech as sm
from symmech.algebra.field import field_solve
from symmech.examples import pendulum_on_cart


def user_pendulum_on_cart(n: int) -> sm.Scene:
    """The system of ``pendulum_on_cart(n)`` written as a user writes it: the velocity of
    each mass accumulated link by link, T and V grown term by term."""
    q = sm.coordinates(["x"] + [f"q{i}" for i in range(n)])
    qd = sm.velocities(q)
    m = sp.symbols(f"m0:{n + 1}", positive=True)
    l = sp.symbols(f"l0:{n}", positive=True)
    g = sp.Symbol("g", positive=True)
    vx, vy, height = qd[0], sp.S.Zero, sp.S.Zero
    T, V = m[0] * qd[0] ** 2 / 2, sp.S.Zero
    for i in range(n):
        vx += l[i] * sp.cos(q[i + 1]) * qd[i + 1]
        vy += l[i] * sp.sin(q[i + 1]) * qd[i + 1]
        height -= l[i] * sp.cos(q[i + 1])
        T += m[i + 1] * (vx**2 + vy**2) / 2
        V += m[i + 1] * g * height
    return sm.Scene(q, kinetic_energy=T, potential=V, name=f"user_pendulum_on_cart_{n}")


def symmech_route(
    n: int, make=pendulum_on_cart
) -> tuple[float, float, int, tuple[float, str, int | None] | None]:
    """(total time, of which declaring the scene (validation included), operations,
    Christoffel row (``pendulum_on_cart`` only)), sympy's cache cleared first."""
    clear_cache()
    t0 = time.perf_counter()
    scene = make(n)
    t_declare = time.perf_counter() - t0
    g = scene.mass_matrix()
    f = scene.forcing()
    t1 = time.perf_counter()
    gamma = christoffel_route(n) if n <= 8 and make is pendulum_on_cart else None
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
    clear_cache()
    t0 = time.perf_counter()
    q, u, I, particles, forces, kindiffs = _mechanics_model(n)
    kane = me.KanesMethod(I, q_ind=q, u_ind=u, kd_eqs=kindiffs)
    kane.kanes_equations(particles, forces)
    M, f = kane.mass_matrix, kane.forcing
    t1 = time.perf_counter()
    return t1 - t0, sp.count_ops(M) + sp.count_ops(f)


def lagrange_route(n: int) -> tuple[float, int]:
    clear_cache()
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
    parser.add_argument(
        "--repeat", type=int, default=3, help="runs of each route but Lagrange (fastest kept)"
    )
    parser.add_argument("--quick", action="store_true", help="a smoke test: n = 2, every route")
    args = parser.parse_args()
    if args.quick:
        args.sizes, args.repeat = [2], 1
    repeat = max(1, args.repeat)
    head = (
        f"{'n':>3} | {'symmech g,f [s]':>15} {'declare':>7} {'ops':>7} | "
        f"{'Gamma^k_ij default [s]':>22} {'form':>6} {'ops':>8} | "
        f"{'Kane [s]':>9} {'ops':>7} {'Kane/sm':>8} | {'Lagr. [s]':>9} {'ops':>7} {'Lagr/sm':>8}"
        f" | {'user g,f [s]':>12} {'Kane/user':>9}"
    )
    # warm-up: imports and sympy's caches of trivial objects, for both routes
    symmech_route(2)
    kane_route(2)
    print(head)
    print("-" * len(head))
    summary: list[tuple[int, float, float, float, float]] = []
    for n in args.sizes:
        # the routes alternate, each run `repeat` times and its fastest kept (shared machine)
        runs = [
            (symmech_route(n), kane_route(n), symmech_route(n, user_pendulum_on_cart))
            for _ in range(repeat)
        ]
        t_sm, t_decl, ops_sm, gamma = min((r[0] for r in runs), key=lambda r: r[0])
        t_k, ops_k = min((r[1] for r in runs), key=lambda r: r[0])
        t_user = min(r[2][0] for r in runs)
        summary.append((n, t_sm, t_k / t_sm, t_user, t_k / t_user))
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
            f"{t_k:9.3f} {ops_k:7d} {t_k / t_sm:8.1f} | {lag} | {t_user:12.3f}"
            f" {t_k / t_user:9.1f}",
            flush=True,
        )
    print(
        "\nGamma^k_ij default: scene.christoffel() (kind 2, simplify='light') on a fresh scene;"
        "\nform 'normal': exact normal form (fraction-free adjugate, shared determinant,"
        " sin^2 -> 1 - cos^2);\nform 'LU': that normal form exceeds its term budget, and the"
        " default returns the exact\nsymbols as built by a symbolic LU solve (no closed form"
        " of useful size exists: det g alone\nhas 3^n terms for the n-link pendulum)."
        "\ndeclare: the part of 'symmech g,f' spent declaring the scene from T and V"
        " (validation included).\nuser g,f: the same for T and V written as users write"
        " them (user_pendulum_on_cart).\nEvery route starts with sympy's cache cleared;"
        f" each but Lagrange is run {repeat} times, alternating, and its fastest run kept."
    )
    print(
        "\nissue 13 and 27 targets: Kane/sm >= 20 at n = 8 and 16 for both forms of T;"
        " symmech g,f at n = 32 < 1 s"
    )
    for n, t_sm, ratio, t_user, ratio_user in summary:
        if n in (8, 16, 32):
            print(
                f"  n = {n:2d}: symmech {t_sm:.3f} s, Kane/sm {ratio:.1f};"
                f" as users write T: {t_user:.3f} s, Kane/user {ratio_user:.1f}"
            )


if __name__ == "__main__":
    main()
