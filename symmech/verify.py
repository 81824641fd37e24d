"""The textbook checks of ``symmech verify``: symmech's derivations against the reference
values of :mod:`symmech.references` (slides 000, text 001, the Carnot paper 002).

Each :class:`Check` derives one quantity of a built-in scene and compares it with the text's
formula; :func:`verify` runs them and prints a table.  Comparisons are exact (``cancel``,
then ``simplify``) so a check cannot pass by rounding.
"""

from __future__ import annotations

import functools
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import sympy as sp

from symmech import references
from symmech.algebra.zero import is_zero
from symmech.declaration.symbols import coordinates as make_coordinates
from symmech.errors import SceneError, SymmechError
from symmech.geometry.distributions import bracket_rank, is_involutive
from symmech.geometry.lie import hat, lie_bracket
from symmech.scene import Scene
from symmech.scenefile import builtin_scene_path, read_scene

__all__ = ["Check", "checks", "silent", "verify"]


def silent(stage: str) -> None:
    """A progress callback that prints nothing (the default of :func:`verify` and
    :func:`symmech.derivation.derivation`)."""


@dataclass(frozen=True)
class Check:
    """One textbook check: ``run()`` returns (passed, detail)."""

    example: str
    quantity: str
    run: Callable[[], tuple[bool, str]]


def _zero(expr: object) -> bool:
    """True if a scalar or every entry of a matrix is identically zero
    (:func:`symmech.algebra.zero.is_zero`)."""
    if isinstance(expr, sp.MatrixBase):
        return all(_zero(e) for e in expr)
    return is_zero(sp.sympify(expr, strict=True)) is True


def _result(ok: bool, what: str) -> tuple[bool, str]:
    return ok, what


@functools.cache
def _scene(name: str) -> Scene:
    """A built-in scene, shared by the checks of one ``verify`` run (it caches derivations).

    The shipped scene file, whatever the current folder holds (a file named ``car`` there
    is not what the textbook checks are about).
    """
    return read_scene(builtin_scene_path(name)).scene


def _check_polar() -> tuple[bool, str]:
    r, th = make_coordinates("r theta")
    gam = Scene((r, th), metric=sp.diag(1, r**2)).christoffel()
    g_r_thth, g_th_rth = references.polar_christoffel(r)
    ok = _zero(gam[0, 1, 1] - g_r_thth) and _zero(gam[1, 0, 1] - g_th_rth)
    return _result(ok, "Gamma^r_thth = -r, Gamma^th_rth = 1/r")


def _check_bracket_example() -> tuple[bool, str]:
    x, y, z = sp.symbols("x y z")
    Z = lie_bracket([y, 0, 0], [0, x, 0], (x, y, z))
    return _result(Z == references.bracket_example(x, y), "[X, Y] = (-x, y, 0)")


def _check_rolling_ball_bracket() -> tuple[bool, str]:
    R = sp.Matrix(3, 3, sp.symbols("R0:9"))
    X, Y = hat((1, 0, 0)) * R, hat((0, 1, 0)) * R
    ok = lie_bracket(X, Y, R) == -hat((0, 0, 1)) * R
    return _result(ok, "[[e1x]R, [e2x]R] = -[e3x]R")


def _check_rolling_ball_frame() -> tuple[bool, str]:
    scene = _scene("rolling_ball")
    c = scene.commutation_coefficients()
    ok = _zero(c[2, 0, 1] + 1) and _zero(c[2, 1, 0] - 1)
    return _result(ok, "[u_x, u_y] = -u_z: omega_z = 0 is non-holonomic")


def _check_car() -> tuple[bool, str]:
    x, y, th, kap = sp.symbols("x y theta kappa", real=True)
    fields = [[sp.cos(th), sp.sin(th), kap, 0], [0, 0, 0, 1]]
    q = (x, y, th, kap)
    inv = is_involutive(fields, q)
    rank = bracket_rank(fields, q, depth=3)
    ok = not inv and rank.rank == 4 and rank.bracket_generating
    return _result(ok, f"not involutive; bracket rank {rank.rank} of 4 at depth 3")


def _check_ellipse_map() -> tuple[bool, str]:
    scene = _scene("bouncing_ellipse")
    x, _, th = scene.coordinates
    xd, yd, thd = scene.velocities
    m, I, a, b = (sp.Symbol(s, positive=True) for s in ("m", "I", "a", "b"))
    imp = scene.impact_map("wall")
    text = references.ellipse_post_velocity(x, th, xd, yd, thd, m, I, a, b)
    return _result(_zero(imp.post_velocity - text), "v+ = v- - 2 C (1/m, 0, Phi/I)")


def _check_ellipse_energy() -> tuple[bool, str]:
    imp = _scene("bouncing_ellipse").impact_map("wall")
    return _result(_zero(imp.energy_change()), "T(v+) - T(v-) = 0 (elastic)")


def _disk_symbols() -> tuple[sp.Symbol, ...]:
    return tuple(sp.Symbol(s, positive=True) for s in ("m", "I", "R"))


def _check_disk_energy_law() -> tuple[bool, str]:
    """Text 001 §3.2: the tangential part is projected onto the rolling direction (0, -R, 1),
    beta = (I thetadot - m R ydot) / I_1 with I_1 = I + m R^2, and the rebound xdot_1 is the
    negative root of xdot_1^2 = xdot_0^2 + ydot_0^2 + (I/m) thetadot_0^2 - beta^2 R^2 -
    (I/m) beta^2 (energy conservation; the text calls beta "alpha")."""
    scene = _scene("spinning_disk")
    xd, yd, thd = scene.velocities
    m, I, R = _disk_symbols()
    imp = scene.impact_map("wall")
    post = imp.post_velocity
    beta = references.disk_beta(yd, thd, m, I, R)
    x1_squared = references.disk_energy_law_rebound_squared(xd, yd, thd, m, I, R)
    ok = _zero(post[1] + R * beta) and _zero(post[2] - beta)
    ok = ok and _zero(post[0] ** 2 - x1_squared)
    # the negative root: the disk, arriving with xdot_0 > 0, leaves the wall x = 0
    for sample in (
        {xd: 2, yd: -1, thd: 3, m: 1, I: 2, R: sp.Rational(1, 2)},
        {xd: 1, yd: 0, thd: 0, m: 3, I: 5, R: 7},
    ):
        ok = ok and bool(post[0].subs(sample) < 0)
    ok = ok and _zero(imp.energy_change())
    return _result(
        ok, "xdot+ = -sqrt(text's xdot_1^2), y+ = -R beta, theta+ = beta, energy conserved"
    )


def _check_disk_newton() -> tuple[bool, str]:
    """The same collision under Newton's law with alpha = 1 (Carnot paper, Prop. 3.4):
    v+ = (-xdot, -R beta, beta), and it loses the kinetic energy of the part of
    (0, ydot, thetadot) that the projection removes.  By hand, with I_1 = I + m R^2:
    (m ydot^2 + I thetadot^2)/2 - I_1 beta^2/2 = m I (ydot + R thetadot)^2 / (2 I_1),
    which is T_C of Theorem 3.11 (the alpha-term vanishes at alpha = 1)."""
    scene = _scene("spinning_disk")
    xd, yd, thd = scene.velocities
    m, I, R = _disk_symbols()
    newton = scene.impact_map("wall", law="newton")
    loss = references.disk_newton_loss(yd, thd, m, I, R)
    ok = _zero(newton.post_velocity - references.disk_newton_post_velocity(xd, yd, thd, m, I, R))
    ok = ok and _zero(newton.energy_change() + loss)
    res = newton.carnot()
    ok = ok and res.theorem == "Theorem 3.11" and _zero(res.residual)
    ok = ok and _zero(res.terms["T_C"] - loss)
    return _result(
        ok, f"T+ - T- = -m I (ydot + R thetadot)^2 / (2 (I + m R^2)) = -T_C ({res.theorem})"
    )


def _disc_symbols() -> tuple[sp.Symbol, ...]:
    return (
        *(sp.Symbol(s, positive=True) for s in ("m", "k", "R")),
        sp.Symbol("alpha", nonnegative=True),
    )


def _check_3_7_velocities() -> tuple[bool, str]:
    scene = _scene("carnot_3_7")
    xd, yd, thd = scene.velocities
    _, k, R, alpha = _disc_symbols()
    paper = references.carnot_3_7_post_velocity(xd, yd, thd, k, R, alpha)
    return _result(_zero(scene.impact_map(0).post_velocity - paper), "v+ as printed")


def _check_3_7_carnot() -> tuple[bool, str]:
    res = _scene("carnot_3_7").impact_map(0).carnot(restrict=True)
    return _result(res.theorem == "Theorem 3.6" and _zero(res.residual), res.theorem)


def _check_3_12() -> tuple[bool, str]:
    scene = _scene("carnot_3_7")
    xd, _, thd = scene.velocities
    m, k, R, _ = _disc_symbols()
    res = scene.impact_map(0).carnot()
    T_C = references.carnot_3_12_t_c(xd, thd, m, k, R)
    ok = res.theorem == "Theorem 3.11" and _zero(res.residual) and _zero(res.terms["T_C"] - T_C)
    return _result(ok, f"T_C = m k^2 (xdot - R thetadot)^2 / (2 (k^2 + R^2)); {res.theorem}")


def _sphere_pre(v: Sequence[sp.Symbol], r: sp.Symbol) -> tuple[dict, tuple[sp.Symbol, ...]]:
    x0, y0, w0 = sp.symbols("x0 y0 wz0", real=True)
    vx, vy, vz, wx, wy, wz = v
    return {vx: x0, vy: y0, vz: 0, wx: -y0 / r, wy: x0 / r, wz: w0}, (x0, y0, w0)


def _sphere_symbols() -> tuple[sp.Symbol, ...]:
    return (
        sp.Symbol("k", positive=True),
        sp.Symbol("r", positive=True),
        sp.Symbol("alpha", nonnegative=True),
    )


def _check_3_13_velocities() -> tuple[bool, str]:
    scene = _scene("carnot_3_13")
    k, r, alpha = _sphere_symbols()
    sub, (x0, y0, w0) = _sphere_pre(scene.velocities, r)
    post = scene.impact_map(0).apply(sub)
    paper = references.carnot_3_13_post_velocity(x0, y0, w0, k, r, alpha)
    return _result(_zero(post - paper), "v+ for v- = (x0, y0, 0, -y0/r, x0/r, wz0)")


def _check_3_13_carnot() -> tuple[bool, str]:
    scene = _scene("carnot_3_13")
    k, r, _ = _sphere_symbols()
    sub, (_, y0, w0) = _sphere_pre(scene.velocities, r)
    res = scene.impact_map(0).carnot()
    T_C = references.carnot_3_13_t_c(y0, w0, k, r)
    ok = res.theorem == "Theorem 3.11" and _zero(res.residual)
    ok = ok and _zero(res.terms["T_C"].xreplace(sub) - T_C)
    return _result(ok, f"T_C as printed; {res.theorem}")


def _check_4_4_matrix() -> tuple[bool, str]:
    scene = _scene("carnot_4_4")
    k, r, alpha = _sphere_symbols()
    imp = scene.impact_map(0)
    (f,) = [
        a for a in scene.walls[0].psi.atoms(sp.Function) if a.args == (sp.Symbol("t", real=True),)
    ]
    fd = sp.Derivative(f, f.args[0])
    W = references.carnot_4_4_wall_velocity(fd, r)
    ok = _zero(imp.matrix - references.carnot_4_4_matrix(k, r, alpha)) and _zero(imp.W - W)
    return _result(ok, "6 x 6 matrix M (acting on columns) and W = (f', 0, 0, 0, f'/r, 0)")


def _check_4_4_carnot() -> tuple[bool, str]:
    res = _scene("carnot_4_4").impact_map(0).carnot()
    ok = res.theorem.startswith("Theorem 4.3") and _zero(res.residual)
    return _result(ok, res.theorem)


def checks() -> list[Check]:
    """The textbook checks ``symmech verify`` runs; expected values are typed in from the
    texts (slides 000, text 001, Carnot paper 002), none is produced by symmech."""
    return [
        Check("slides 000: polar coordinates", "Christoffel symbols", _check_polar),
        Check("slides 000: Lie bracket example", "[X, Y] in coordinates", _check_bracket_example),
        Check("slides 000: rolling ball", "Lie bracket on SO(3)", _check_rolling_ball_bracket),
        Check("slides 000: rolling ball", "frame commutation", _check_rolling_ball_frame),
        Check("slides 000: car", "Frobenius and bracket rank", _check_car),
        Check("text 001 §3.1: bouncing ellipse", "impact map (C, Phi)", _check_ellipse_map),
        Check("text 001 §3.1: bouncing ellipse", "energy balance", _check_ellipse_energy),
        Check("text 001 §3.2: spinning disk", "energy law", _check_disk_energy_law),
        Check("text 001 §3.2: spinning disk", "Newton law on the same impact", _check_disk_newton),
        Check("Carnot ex. 3.7", "post-impact velocity", _check_3_7_velocities),
        Check("Carnot ex. 3.7", "Carnot theorem (image of PP + T~)", _check_3_7_carnot),
        Check("Carnot ex. 3.12", "T_C and energy balance", _check_3_12),
        Check("Carnot ex. 3.13", "post-impact velocity", _check_3_13_velocities),
        Check("Carnot ex. 3.13", "T_C and energy balance", _check_3_13_carnot),
        Check("Carnot ex. 4.4", "impact matrix and W", _check_4_4_matrix),
        Check("Carnot ex. 4.4", "Carnot theorem (moving wall)", _check_4_4_carnot),
    ]


def verify(pattern: str | None = None, progress: Callable[[str], None] = silent) -> int:
    """Run the checks whose example or quantity contains ``pattern`` (all by default),
    print the table ``example | quantity | result`` and return the number that failed.
    Raises :class:`~symmech.SceneError` when no check matches."""
    selected = [
        c
        for c in checks()
        if pattern is None or pattern.lower() in f"{c.example} {c.quantity}".lower()
    ]
    if not selected:
        raise SceneError(f"verify: no check matches {pattern!r}")
    _scene.cache_clear()
    rows = []
    failed = 0
    for c in selected:
        progress(f"check {c.example}: {c.quantity}")
        start = time.perf_counter()
        try:
            ok, detail = c.run()
        except SymmechError as exc:
            ok, detail = False, f"error: {' '.join(str(exc).split())}"
        elapsed = time.perf_counter() - start
        failed += not ok
        rows.append((c.example, c.quantity, ("ok" if ok else "FAIL") + f"  {detail}", elapsed))
    w1 = max(len("example"), *(len(r[0]) for r in rows))
    w2 = max(len("quantity"), *(len(r[1]) for r in rows))
    print(f"{'example':{w1}}  {'quantity':{w2}}  result")
    print(f"{'-' * w1}  {'-' * w2}  {'-' * 6}")
    for ex, qty, res, el in rows:
        print(f"{ex:{w1}}  {qty:{w2}}  {res}  ({el:.1f}s)")
    print(f"\n{len(rows) - failed} passed, {failed} failed")
    return failed
