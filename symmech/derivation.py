"""The derivation report: what ``symmech show`` prints, as an object.

:func:`derivation` derives the quantities of a scene (metric, forcing, Christoffel symbols
or connection coefficients, the constrained equations, each wall's impact map and its Carnot
residual or energy change) into a :class:`Derivation`, which prints as text, writes LaTeX,
and renders as Markdown with LaTeX in Jupyter.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import sympy as sp

from symmech.declaration.latex import latex_text
from symmech.scene import Scene
from symmech.verify import silent

__all__ = ["MAX_DETAILED_N", "Derivation", "derivation"]


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
        return "\n".join(
            self._walk(
                lambda title: f"== {title}",
                str,
                lambda plain, tex, e: f"{plain} = {_render(e, printer)}",
                lambda value: _render(value, printer),
                gap=True,
            )
        )

    def latex(self) -> str:
        """LaTeX: a ``\\paragraph`` per section and display math for each value."""
        return "\n".join(
            self._walk(
                lambda title: f"\\paragraph{{{latex_text(title)}}}",
                latex_text,
                lambda plain, tex, e: f"\\[ {tex} = {_render(e, sp.latex)} \\]",
                lambda value: f"\\[ {_render(value, sp.latex)} \\]",
                gap=True,
            )
        )

    def _repr_markdown_(self) -> str:
        body = self._walk(
            lambda title: f"**{title}**",
            str,
            lambda plain, tex, e: f"$$ {tex} = {_render(e, sp.latex)} $$",
            lambda value: f"$$ {_render(value, sp.latex)} $$",
            gap=False,
        )
        return "\n\n".join([f"### Scene `{self.scene.name}`", *body])

    def _walk(
        self,
        title: Callable[[str], str],
        text: Callable[[str], str],
        item: Callable[[str, str, Any], str],
        value: Callable[[Any], str],
        gap: bool,
    ) -> list[str]:
        """The lines of every section, each part rendered by the given function: a title,
        then its text, its labelled items (``(none)`` when empty) or its value; with
        ``gap`` an empty line after each section."""
        out = []
        for heading, content in self.sections:
            out.append(title(heading))
            if isinstance(content, str):
                out.append(text(content))
            elif isinstance(content, list):
                if not content:
                    out.append("(none)")
                out.extend(item(plain, tex, e) for plain, tex, e in content)
            else:
                out.append(value(content))
            if gap:
                out.append("")
        return out

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
    scene: Scene, progress: Callable[[str], None] = silent, *, full: bool = False
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
    _add_connection(rep, scene, detailed, progress)
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
        _add_wall(rep, scene, wall, progress)
    return rep


def _add_connection(
    rep: Derivation, scene: Scene, detailed: bool, progress: Callable[[str], None]
) -> None:
    """The non-zero Christoffel symbols (coordinates: of the second kind for a diagonal
    metric, else of the first) or connection coefficients (a frame), or a note that they
    are left out (not ``detailed``)."""
    q, v = scene.coordinates, scene.velocities
    if not detailed:
        what = "Christoffel symbols" if scene.frame is None else "connection coefficients"
        count = scene.n**2 * (scene.n + 1) // 2
        rep.add(what, _left_out(scene.n, f"up to {count} non-zero entries"))
    elif scene.frame is None:
        # the second kind needs g^-1: only for a diagonal metric (cheap and readable)
        kind = 2 if scene.mass_matrix().is_diagonal() else 1
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


def _add_wall(rep: Derivation, scene: Scene, wall: Any, progress: Callable[[str], None]) -> None:
    """A wall's gap, its post-impact velocity, and its Carnot residual (Newton law) or
    energy change (energy law)."""
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
