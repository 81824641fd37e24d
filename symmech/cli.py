"""The ``symmech`` command line (also ``python -m symmech``).

Commands:

``symmech derive [SCENE] [--emit c|numpy ...] [-o DIR]``
    Derive the scene and emit its code (:func:`symmech.codegen.generate`) into DIR; print the
    files written.  Default SCENE: the bouncing ellipse; default target: c; default DIR:
    ``<scene>_<target>`` in the current folder (with several ``--emit``, one sub-folder per
    target inside ``-o DIR``).
``symmech show [SCENE] [--latex] [--full]``
    Print the derived quantities: metric, forcing, Christoffel symbols (or the frame's
    connection coefficients), constrained equations, each wall's impact map and its Carnot
    residual (or energy change for the energy law), as text or LaTeX.  Above
    :data:`MAX_DETAILED_N` coordinates the Christoffel symbols (or connection coefficients)
    and the acceleration are left out, with a line saying so, unless ``--full``.
``symmech examples``
    List the built-in scenes.
``symmech verify [-k TEXT]``
    Run the textbook checks (slides 000, text 001, the Carnot paper 002) and print a table
    ``example | quantity | result``; ``-k`` keeps the checks whose example or quantity
    contains TEXT.
``symmech export [SCENE] [-o FILE]``
    Write a scene as a TOML scene file (to start a new scene from a built-in one).

``symmech simulate SCENE``, ``symmech bench CASE``, ``symmech stress``
    Simulate a scene, print its error against run time, run the stiff and extreme cases
    (:mod:`symmech.bench.commands`).
``symmech sweep SCENE --grid FILE --out FILE``
    Run the scene for every row of a grid (:mod:`symmech.sweep.command`).

SCENE is a scene file (TOML, :mod:`symmech.scenefile`) or the name of a built-in scene.
With no command, ``show`` runs on the bouncing ellipse.  Progress (stage and elapsed time)
goes to stderr; ``--quiet`` silences it.  Errors print one line and exit non-zero, with no
traceback unless ``--debug``.  Exit codes: 0 success, 1 a verification failed, 2 bad input
(unknown scene, refused scene file, usage), 3 an internal error,
130 interrupted.  Output that the terminal's encoding cannot represent is written with
backslash escapes (``PYTHONIOENCODING=ascii``), and ``show`` then pretty-prints in ASCII.

The report that ``show`` prints is also available as an object, :func:`derivation`, which
renders as Markdown with LaTeX in Jupyter.
"""

from __future__ import annotations

import argparse
import functools
import io
import os
import sys
import time
import traceback
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import NoReturn

import sympy as sp

from symmech.bench.commands import COMMANDS, add_commands, run_command
from symmech.codegen.escape import file_name, terminal
from symmech.codegen.output_files import write_text_atomic
from symmech.declaration.latex import latex_text
from symmech.declaration.symbols import coordinates as make_coordinates
from symmech.errors import SceneError, SymmechError
from symmech.examples import EXAMPLES, example
from symmech.geometry.lie import bracket_rank, hat, is_involutive, lie_bracket
from symmech.scene import Scene
from symmech.scenefile import (
    SceneFile,
    builtin_scene_names,
    builtin_scene_path,
    dump_scene,
    read_scene,
)
from symmech.sweep.command import add_command as add_sweep_command
from symmech.sweep.command import run_command as run_sweep_command

__all__ = [
    "DEFAULT_SCENE",
    "TARGETS",
    "Check",
    "Derivation",
    "checks",
    "derivation",
    "main",
    "resolve_scene",
]

DEFAULT_SCENE = "bouncing_ellipse"
#: Code generation targets of ``symmech derive --emit``.
TARGETS = ("c", "numpy")

EXIT_OK, EXIT_FAILED, EXIT_INPUT, EXIT_INTERNAL, EXIT_INTERRUPTED = 0, 1, 2, 3, 130


# ---------------------------------------------------------------------------------------
# progress


class _Progress:
    """Prints ``[symmech  12.34s] stage`` lines on stderr unless quiet."""

    def __init__(self, quiet: bool):
        self.quiet = quiet
        self.start = time.perf_counter()

    def __call__(self, stage: str) -> None:
        if not self.quiet:
            elapsed = time.perf_counter() - self.start
            line = f"[symmech {elapsed:7.2f}s] {terminal(stage)}"
            print(line, file=sys.stderr, flush=True)


def _silent(stage: str) -> None:
    """A progress callback that prints nothing."""


# ---------------------------------------------------------------------------------------
# scenes


def resolve_scene(spec: str) -> SceneFile:
    """The scene named by ``spec``: a scene file path, or a built-in scene's name.

    A file that exists is read as a scene file; otherwise a built-in name is looked up,
    first among the shipped scene files (``symmech/scenes/NAME.toml``, which carry default
    parameter values), then among :data:`symmech.examples.EXAMPLES`.  (A folder named like
    a built-in scene, such as the output of ``symmech derive car -o car``, does not hide
    it.)
    """
    path = Path(spec)
    if path.is_file():
        return read_scene(path)
    builtin = spec in builtin_scene_names() or spec in EXAMPLES
    if path.exists() and not builtin:
        raise SceneError(f"{spec}: is not a file")
    if spec in builtin_scene_names():
        return read_scene(spec)
    if spec in EXAMPLES:
        return SceneFile(scene=example(spec), description=EXAMPLES[spec][1])
    if spec.endswith(".toml") or os.sep in spec or "/" in spec:
        raise SceneError(f"{spec}: no such scene file")
    names = sorted(set(EXAMPLES) | set(builtin_scene_names()))
    raise SceneError(
        f"{spec!r} is neither a scene file nor a built-in scene; built-in scenes:"
        f" {', '.join(names)} (see 'symmech examples')"
    )


def _builtin_names() -> list[tuple[str, str]]:
    """(name, description) of every built-in scene, in the order of EXAMPLES."""
    out = [(name, desc) for name, (_, desc) in EXAMPLES.items()]
    for name in builtin_scene_names():
        if name not in EXAMPLES:
            out.append((name, read_scene(name).description))
    return out


# ---------------------------------------------------------------------------------------
# the derivation report (show)


@dataclass
class Derivation:
    """The derived quantities of a scene, as titled sections.

    Each section is ``(title, value)`` with a sympy object, ``(title, [(text label,
    LaTeX label, expr), ...])`` for a list of named entries, or ``(title, note)`` with a
    plain-text note (what was left out).  :meth:`text` pretty-prints it, :meth:`latex`
    writes LaTeX, and in Jupyter it renders as Markdown with LaTeX (``_repr_markdown_``).
    """

    scene: Scene
    sections: list[tuple[str, object]] = field(default_factory=list)

    def add(self, title: str, value: object) -> None:
        self.sections.append((title, value))

    def text(self, *, unicode: bool = True) -> str:
        """Pretty-printed text, one ``== title`` block per section (ASCII art when not
        ``unicode``)."""
        printer = _pretty if unicode else _pretty_ascii
        out = []
        for title, value in self.sections:
            out.append(f"== {title}")
            if isinstance(value, str):
                out.append(value)
            elif isinstance(value, list):
                if not value:
                    out.append("(none)")
                out.extend(f"{label} = {_render(e, printer)}" for label, _, e in value)
            else:
                out.append(_render(value, printer))
            out.append("")
        return "\n".join(out)

    def latex(self) -> str:
        """LaTeX: a ``\\paragraph`` per section and display math for each value."""
        out = []
        for title, value in self.sections:
            out.append(f"\\paragraph{{{latex_text(title)}}}")
            if isinstance(value, str):
                out.append(latex_text(value))
            elif isinstance(value, list):
                if not value:
                    out.append("(none)")
                for _, label, e in value:
                    out.append(f"\\[ {label} = {_render(e, sp.latex)} \\]")
            else:
                out.append(f"\\[ {_render(value, sp.latex)} \\]")
            out.append("")
        return "\n".join(out)

    def _repr_markdown_(self) -> str:
        out = [f"### Scene `{self.scene.name}`"]
        for title, value in self.sections:
            out.append(f"**{title}**")
            if isinstance(value, str):
                out.append(value)
            elif isinstance(value, list):
                if not value:
                    out.append("(none)")
                out.extend(f"$$ {label} = {_render(e, sp.latex)} $$" for _, label, e in value)
            else:
                out.append(f"$$ {_render(value, sp.latex)} $$")
        return "\n\n".join(out)

    def _repr_latex_(self) -> str:
        return self.latex()


#: Expressions with more operations than this are summarised, not printed, by ``show``.
MAX_SHOWN_OPS = 600


def _render(value: object, printer: Callable[[object], str]) -> str:
    """``printer(value)``, or a one-line summary when ``value`` is too large to read."""
    if isinstance(value, sp.Basic | sp.MatrixBase):
        ops = (
            sum(sp.count_ops(e) for e in value)
            if isinstance(value, sp.MatrixBase)
            else (sp.count_ops(value))
        )
        if ops > MAX_SHOWN_OPS:
            note = f"({ops} operations, not printed; 'symmech derive' emits it as code)"
            return note if printer in (_pretty, _pretty_ascii) else f"\\text{{{note}}}"
    return printer(value)


def _pretty(value: object) -> str:
    return sp.pretty(value, use_unicode=True, wrap_line=False)


def _pretty_ascii(value: object) -> str:
    return sp.pretty(value, use_unicode=False, wrap_line=False)


#: Above this many coordinates ``show`` leaves out the Christoffel symbols (or connection
#: coefficients) and the acceleration unless ``--full``: they have n^2 (n + 1) / 2 entries
#: and the closed-form acceleration needs the inverse of an n x n symbolic matrix.
MAX_DETAILED_N = 6


def _left_out(n: int, why: str) -> str:
    return (
        f"not derived for n = {n} > {MAX_DETAILED_N} coordinates ({why}); 'symmech show"
        " --full' derives and prints this section (slow for large n), 'symmech derive' emits"
        " the equations of motion as code"
    )


def derivation(
    scene: Scene, progress: Callable[[str], None] = _silent, *, full: bool = False
) -> Derivation:
    """Derive and collect what ``symmech show`` prints for ``scene``.

    Sections: coordinates and velocities, the frame, the mass matrix, the forcing, the
    non-zero Christoffel symbols (coordinates) or connection coefficients (frame), the
    constraint one-forms, projector and multipliers, the acceleration, and for each wall
    psi, the post-impact velocity, and the Carnot residual (Newton law) or the energy
    change (energy law).  For more than :data:`MAX_DETAILED_N` coordinates the Christoffel
    symbols and the acceleration are replaced by a note saying so, unless ``full``.
    ``progress`` is called with the name of each stage before it runs.
    """
    rep = Derivation(scene)
    q, v = scene.coordinates, scene.velocities
    progress(f"scene {scene.name}: {scene!r}")
    rep.add("coordinates", sp.Matrix(q).T)
    rep.add("velocities", sp.Matrix(v).T)
    if scene.parameters:
        rep.add("parameters", sp.Matrix(scene.parameters).T)
    if scene.frame is not None:
        rep.add("frame S (q_dot = S v)", scene.frame)
    rep.add("mass matrix M (T = 1/2 v^T M v)", scene.mass_matrix())
    if scene.potential != 0:
        rep.add("potential V", scene.potential)
    progress("forcing")
    rep.add("forcing f (M v_dot = f + mu^T lambda)", scene.forcing())
    detailed = full or scene.n <= MAX_DETAILED_N
    if not detailed:
        what = "Christoffel symbols" if scene.frame is None else "connection coefficients"
        count = scene.n**2 * (scene.n + 1) // 2
        rep.add(what, _left_out(scene.n, f"up to {count} non-zero entries"))
    elif scene.frame is None:
        # the second kind needs g^-1: only for a diagonal metric (cheap and readable)
        M = scene.mass_matrix()
        kind = 2 if M.is_diagonal() else 1
        progress(f"Christoffel symbols (kind {kind})")
        gam = scene.christoffel(kind=kind)
        entries = [
            (
                f"Gamma^{q[k]}_{q[i]},{q[j]}" if kind == 2 else f"Gamma_{q[k]},{q[i]},{q[j]}",
                f"\\Gamma^{{{sp.latex(q[k])}}}_{{{sp.latex(q[i])} {sp.latex(q[j])}}}"
                if kind == 2
                else f"\\Gamma_{{{sp.latex(q[k])} {sp.latex(q[i])} {sp.latex(q[j])}}}",
                gam[k, i, j],
            )
            for k in range(scene.n)
            for i in range(scene.n)
            for j in range(i, scene.n)
            if gam[k, i, j] != 0
        ]
        name = "Gamma^k_ij" if kind == 2 else "Gamma_kij (first kind)"
        rep.add(f"Christoffel symbols {name} (non-zero, i <= j)", entries)
    else:
        progress("connection coefficients of the frame")
        omega = scene.connection_coefficients()
        entries = [
            (
                f"omega^{v[k]}_{v[i]},{v[j]}",
                f"\\omega^{{{sp.latex(v[k])}}}_{{{sp.latex(v[i])} {sp.latex(v[j])}}}",
                omega[k, i, j],
            )
            for k in range(scene.n)
            for i in range(scene.n)
            for j in range(scene.n)
            if omega[k, i, j] != 0
        ]
        rep.add("connection coefficients omega^m_ij of the frame (non-zero)", entries)
    if scene.is_constrained:
        progress("projectors and multipliers")
        rep.add("constraint one-forms mu (rows; mu v = 0)", scene.constraint_matrix)
        rep.add("projector P onto the constraint distribution D", scene.projectors()[0])
        rep.add("multipliers lambda", scene.multipliers())
    title = "constrained acceleration" if scene.is_constrained else "acceleration"
    if detailed:
        progress("acceleration")
        rep.add(f"{title} v_dot", scene.acceleration())
    else:
        why = f"it needs the inverse of the {scene.n} x {scene.n} mass matrix"
        rep.add(f"{title} v_dot", _left_out(scene.n, why))
    for wall in scene.walls:
        progress(f"impact map of wall {wall.name!r}")
        imp = scene.impact_map(wall.index)
        rep.add(f"wall {wall.name!r}: gap psi (psi >= 0 admissible)", wall.psi)
        rep.add(
            f"wall {wall.name!r}: post-impact velocity v+ ({wall.law} law, restitution"
            f" {wall.restitution})",
            imp.post_velocity,
        )
        if wall.law == "newton":
            progress(f"Carnot residual of wall {wall.name!r}")
            res = imp.carnot()
            rep.add(f"wall {wall.name!r}: {res.theorem} residual (0 when it holds)", res.residual)
        else:
            progress(f"energy change of wall {wall.name!r}")
            rep.add(
                f"wall {wall.name!r}: energy change T(v+) - T(v-) (energy law)",
                sp.simplify(imp.energy_change()),
            )
    return rep


# ---------------------------------------------------------------------------------------
# textbook checks (verify)


@dataclass(frozen=True)
class Check:
    """One textbook check: ``run()`` returns (passed, detail)."""

    example: str
    quantity: str
    run: Callable[[], tuple[bool, str]]


def _zero(expr: object) -> bool:
    """True if a scalar or matrix expression simplifies to zero."""
    if isinstance(expr, sp.MatrixBase):
        return all(_zero(e) for e in expr)
    e = sp.sympify(expr)
    if e == 0:
        return True
    e = sp.cancel(sp.together(e))
    return e == 0 or sp.simplify(e) == 0


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
    ok = gam[0, 1, 1] == -r and _zero(gam[1, 0, 1] - 1 / r)
    return _result(ok, "Gamma^r_thth = -r, Gamma^th_rth = 1/r")


def _check_bracket_example() -> tuple[bool, str]:
    x, y, z = sp.symbols("x y z")
    Z = lie_bracket([y, 0, 0], [0, x, 0], (x, y, z))
    return _result(Z == sp.Matrix([-x, y, 0]), "[X, Y] = (-x, y, 0)")


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
    h = x + sp.sqrt(a**2 * sp.cos(th) ** 2 + b**2 * sp.sin(th) ** 2)
    Phi = sp.diff(h, th)
    C = (xd + Phi * thd) / (1 / m + Phi**2 / I)
    text = sp.Matrix([xd - 2 * C / m, yd, thd - 2 * C / I * Phi])
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
    beta = (I * thd - m * R * yd) / (I + m * R**2)
    x1_squared = xd**2 + yd**2 + I / m * thd**2 - beta**2 * R**2 - I / m * beta**2
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
    beta = (I * thd - m * R * yd) / (I + m * R**2)
    loss = m * I * (yd + R * thd) ** 2 / (2 * (I + m * R**2))
    ok = _zero(newton.post_velocity - sp.Matrix([-xd, -R * beta, beta]))
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
    paper = sp.Matrix(
        [
            (R**2 * xd + R * k**2 * thd) / (R**2 + k**2),
            -alpha * yd,
            (R * xd + k**2 * thd) / (R**2 + k**2),
        ]
    )
    return _result(_zero(scene.impact_map(0).post_velocity - paper), "v+ as printed")


def _check_3_7_carnot() -> tuple[bool, str]:
    res = _scene("carnot_3_7").impact_map(0).carnot(restrict=True)
    return _result(res.theorem == "Theorem 3.6" and _zero(res.residual), res.theorem)


def _check_3_12() -> tuple[bool, str]:
    scene = _scene("carnot_3_7")
    xd, _, thd = scene.velocities
    m, k, R, _ = _disc_symbols()
    res = scene.impact_map(0).carnot()
    T_C = m * k**2 / (2 * (k**2 + R**2)) * (xd - R * thd) ** 2
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
    y1 = ((k**2 + r**2) * y0 + r * k**2 * w0) / (2 * k**2 + r**2)
    paper = sp.Matrix([-alpha * x0, y1, 0, -y1 / r, -alpha * x0 / r, y1 / r])
    return _result(_zero(post - paper), "v+ for v- = (x0, y0, 0, -y0/r, x0/r, wz0)")


def _check_3_13_carnot() -> tuple[bool, str]:
    scene = _scene("carnot_3_13")
    k, r, _ = _sphere_symbols()
    sub, (_, y0, w0) = _sphere_pre(scene.velocities, r)
    res = scene.impact_map(0).carnot()
    T_C = k**2 * (k**2 + r**2) / (2 * r**2 * (2 * k**2 + r**2)) * (y0 - r * w0) ** 2
    ok = res.theorem == "Theorem 3.11" and _zero(res.residual)
    ok = ok and _zero(res.terms["T_C"].xreplace(sub) - T_C)
    return _result(ok, f"T_C as printed; {res.theorem}")


def _paper_M(k: sp.Symbol, r: sp.Symbol, a: sp.Symbol) -> sp.Matrix:
    D1, D2 = k**2 + r**2, 2 * k**2 + r**2
    return sp.Matrix(
        [
            [1 - (r**2 + a * r**2) / D1, 0, 0, 0, -(k**2) * r * (1 + a) / D1, 0],
            [0, 1 - k**2 * r**2 / (D1 * D2), 0, k**4 * r / (D1 * D2), 0, k**2 * r / D2],
            [0, 0, 1, 0, 0, 0],
            [0, k**2 * r / (D1 * D2), 0, 1 - k**4 / (D1 * D2), 0, -(k**2) / D2],
            [-r * (a + 1) / D1, 0, 0, 0, 1 - k**2 * (a + 1) / D1, 0],
            [0, r / D2, 0, -(k**2) / D2, 0, 1 - D1 / D2],
        ]
    )


def _check_4_4_matrix() -> tuple[bool, str]:
    scene = _scene("carnot_4_4")
    k, r, alpha = _sphere_symbols()
    imp = scene.impact_map(0)
    (f,) = [
        a for a in scene.walls[0].psi.atoms(sp.Function) if a.args == (sp.Symbol("t", real=True),)
    ]
    fd = sp.Derivative(f, f.args[0])
    W = sp.Matrix([fd, 0, 0, 0, fd / r, 0])
    ok = _zero(imp.matrix - _paper_M(k, r, alpha)) and _zero(imp.W - W)
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


def _verify(pattern: str | None, progress: Callable[[str], None]) -> int:
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
    return EXIT_FAILED if failed else EXIT_OK


# ---------------------------------------------------------------------------------------
# derive


def _derive(
    spec: str,
    targets: Sequence[str],
    out: str | None,
    progress: Callable[[str], None],
    strategy: str = "auto",
) -> list[Path]:
    progress(f"loading scene {spec}")
    scene = resolve_scene(spec).scene
    try:
        from symmech import codegen
    except ImportError as exc:
        raise SceneError(f"code generation is not available in this installation ({exc})") from None
    progress(f"mass matrix and forcing of {scene.name} ({scene.n} coordinates)")
    scene.mass_matrix()
    scene.forcing()
    written: list[Path] = []
    for target in dict.fromkeys(targets):
        if out is None:
            folder = Path(f"{file_name(scene.name)}_{target}")
        elif len(set(targets)) > 1:
            folder = Path(out) / target
        else:
            folder = Path(out)
        progress(f"generating {target} code ({strategy} strategy) into {folder}")
        code = codegen.generate(scene, target, strategy=strategy)
        if code.plan.fallback:
            progress(code.plan.fallback)
        written.extend(code.write(folder))
    return written


# ---------------------------------------------------------------------------------------
# the parser


class _Parser(argparse.ArgumentParser):
    """An ArgumentParser whose usage errors are one line and exit with code 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_INPUT, f"symmech: error: {terminal(message)} (see 'symmech --help')\n")


def _parser() -> argparse.ArgumentParser:
    common = _Parser(add_help=False)
    common.add_argument(
        "--quiet", action="store_true", default=argparse.SUPPRESS, help="no progress on stderr"
    )
    common.add_argument(
        "--debug",
        action="store_true",
        default=argparse.SUPPRESS,
        help="show the traceback of an error",
    )
    parser = _Parser(
        prog="symmech",
        description="Symbolic geometric mechanics: derive a scene's equations and impact"
        " maps, and emit code.",
        epilog="SCENE is a scene file (TOML) or a built-in scene name ('symmech examples').",
    )
    parser.add_argument("--quiet", action="store_true", help="no progress on stderr")
    parser.add_argument("--debug", action="store_true", help="show the traceback of an error")
    parser.add_argument("--version", action="store_true", help="print the version and exit")
    sub = parser.add_subparsers(dest="command", parser_class=_Parser, metavar="COMMAND")

    derive = sub.add_parser(
        "derive", parents=[common], help="derive a scene and emit C or NumPy code"
    )
    derive.add_argument("scene", nargs="?", default=DEFAULT_SCENE, help="scene file or name")
    derive.add_argument(
        "--emit",
        action="append",
        choices=TARGETS,
        help="code to emit: c (default) or numpy; repeat for both",
    )
    derive.add_argument("-o", "--output", help="output folder (default: <scene>_<target>)")
    derive.add_argument(
        "--strategy",
        choices=("auto", "closed_form", "linear_solve"),
        default="auto",
        help="closed_form evaluates the symbolic solutions; linear_solve solves g v_dot = f"
        " (and the constraint and impact systems) in the generated code; auto: closed form"
        " up to 3 coordinates",
    )

    show = sub.add_parser("show", parents=[common], help="print a scene's derived quantities")
    show.add_argument("scene", nargs="?", default=DEFAULT_SCENE, help="scene file or name")
    show.add_argument("--latex", action="store_true", help="print LaTeX instead of text")
    show.add_argument(
        "--full",
        action="store_true",
        help=f"also above {MAX_DETAILED_N} coordinates, derive and print the Christoffel"
        " symbols and the acceleration",
    )

    sub.add_parser("examples", parents=[common], help="list the built-in scenes")

    verify = sub.add_parser("verify", parents=[common], help="run the textbook checks")
    verify.add_argument("-k", dest="pattern", help="only checks whose name contains TEXT")

    add_commands(sub, common)
    add_sweep_command(sub, common)

    export = sub.add_parser("export", parents=[common], help="write a scene as a TOML file")
    export.add_argument("scene", nargs="?", default=DEFAULT_SCENE, help="scene file or name")
    export.add_argument("-o", "--output", help="file to write (default: standard output)")
    return parser


def _one_line(exc: BaseException) -> str:
    """The error as one line safe for a terminal (file and scene names may hold escape
    sequences: :func:`symmech.codegen.escape.terminal`)."""
    problems = getattr(exc, "problems", None)
    if isinstance(problems, list) and len(problems) > 1:
        text = f"{len(problems)} problems: " + "; ".join(problems)
    else:
        text = str(exc)
    return terminal(" ".join(text.split()))


def _run(args: argparse.Namespace, progress: _Progress) -> int:
    command = args.command or "show"
    if command == "examples":
        names = _builtin_names()
        width = max(len(n) for n, _ in names)
        for name, description in names:
            print(f"{name:{width}}  {description}")
        return EXIT_OK
    if command == "verify":
        return _verify(args.pattern, progress)
    if command in COMMANDS:
        return run_command(args, resolve_scene, progress)
    if command == "sweep":
        return run_sweep_command(args, resolve_scene, progress)
    spec = getattr(args, "scene", DEFAULT_SCENE)
    if command == "derive":
        targets = args.emit or ["c"]
        paths = _derive(spec, targets, args.output, progress, args.strategy)
        for p in paths:
            print(terminal(p))
        progress(f"done: {len(paths)} files")
        return EXIT_OK
    if command == "export":
        sf = resolve_scene(spec)
        text = dump_scene(
            sf.scene,
            defaults=sf.defaults,
            description=sf.description,
            functions={k: e for k, e in sf.functions.items() if not _is_applied(e)},
        )
        if args.output:
            write_text_atomic(args.output, text)
            progress(f"wrote {args.output}")
        else:
            sys.stdout.write(text)
        return EXIT_OK
    # show
    progress(f"loading scene {spec}")
    rep = derivation(resolve_scene(spec).scene, progress, full=getattr(args, "full", False))
    if getattr(args, "latex", False):
        print(rep.latex())
    else:
        print(rep.text(unicode=_can_encode(sys.stdout, "\u23a1\u23a3\u03b8\u22c5")))
    progress("done")
    return EXIT_OK


def _can_encode(stream: object, sample: str) -> bool:
    """Whether ``stream`` (a text stream) can write ``sample`` without escapes."""
    encoding = getattr(stream, "encoding", None) or "utf-8"
    try:
        sample.encode(encoding)
    except (UnicodeEncodeError, LookupError):
        return False
    return True


def _escape_unencodable(streams: Sequence[object]) -> list[tuple[object, str]]:
    """Make each text stream write what its encoding cannot represent as backslash escapes
    (``PYTHONIOENCODING=ascii``, a latin-1 terminal) instead of raising; return what to
    restore."""
    changed = []
    for stream in streams:
        errors = getattr(stream, "errors", None)
        reconfigure = getattr(stream, "reconfigure", None)
        if errors == "strict" and reconfigure is not None:
            try:
                reconfigure(errors="backslashreplace")
            except (ValueError, io.UnsupportedOperation):  # pragma: no cover - exotic stream
                continue
            changed.append((stream, errors))
    return changed


def _is_applied(expr: sp.Expr) -> bool:
    from sympy.core.function import AppliedUndef

    return isinstance(expr, AppliedUndef)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``symmech`` console script (and ``python -m symmech``)."""
    changed = _escape_unencodable([sys.stdout, sys.stderr])
    try:
        return _main(sys.argv[1:] if argv is None else list(argv))
    finally:
        for stream, errors in changed:
            try:
                stream.reconfigure(errors=errors)  # type: ignore[attr-defined]
            except (ValueError, io.UnsupportedOperation):  # pragma: no cover - closed
                pass


def _main(argv: list[str]) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if args.version:
        from symmech import __version__

        print(f"symmech {__version__}")
        return EXIT_OK
    progress = _Progress(args.quiet)
    try:
        return _run(args, progress)
    except SymmechError as exc:
        if args.debug:
            raise
        print(f"symmech: error: {_one_line(exc)}", file=sys.stderr)
        return EXIT_INPUT
    except BrokenPipeError:
        # the reader went away (symmech show | head): stop quietly
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return EXIT_OK
    except OSError as exc:
        if args.debug:
            raise
        where = f" {terminal(exc.filename)}:" if exc.filename else ""
        print(f"symmech: error:{where} {terminal(exc.strerror or exc)}", file=sys.stderr)
        return EXIT_INPUT
    except KeyboardInterrupt:
        print("symmech: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception as exc:
        if args.debug:
            raise
        last = traceback.extract_tb(exc.__traceback__)[-1]
        print(
            f"symmech: internal error: {type(exc).__name__}: {_one_line(exc)}"
            f" (in {Path(last.filename).name}:{last.lineno}; run with --debug for the"
            " traceback)",
            file=sys.stderr,
        )
        return EXIT_INTERNAL


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
