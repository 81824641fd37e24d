"""Writing a Scene as a scene file: :func:`dump_scene` and :func:`save_scene`."""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from contextvars import ContextVar
from pathlib import Path
from typing import Any

import sympy as sp
from sympy.core.function import AppliedUndef
from sympy.printing.str import StrPrinter

from symmech.declaration.drawing import SHAPES, Drawing
from symmech.declaration.expression_rules import text_nodes
from symmech.declaration.expressions import (
    parse_expression,
    to_expression,
)
from symmech.declaration.symbols import t as TIME
from symmech.declaration.symbols import velocity_of
from symmech.errors import ExpressionError
from symmech.files import write_text_atomic
from symmech.scene import Scene
from symmech.scenefile.format import (
    _IDENTIFIER,
    _MAX_IDENTIFIER,
    FORMAT_VERSION,
    MAX_FILE_BYTES,
    MAX_FILE_CALLS,
    MAX_FILE_NODES,
    SIGNS,
    SceneFileError,
    _short,
)
from symmech.scenefile.reader_base import applications, tree_size

# ---------------------------------------------------------------------------------------
# writing


_REWRITES: dict[type, Any] = {
    sp.cot: lambda a: 1 / sp.tan(a),
    sp.sec: lambda a: 1 / sp.cos(a),
    sp.csc: lambda a: 1 / sp.sin(a),
    sp.coth: lambda a: 1 / sp.tanh(a),
    sp.sech: lambda a: 1 / sp.cosh(a),
    sp.csch: lambda a: 1 / sp.sinh(a),
    sp.acot: lambda a: sp.atan(1 / a),
}


class _FilePrinter(StrPrinter):
    """Prints expressions in the subset :func:`parse_expression` reads back.

    Applied functions of time print as their name (the scene file's convention).
    """

    def _print_Function(self, expr: sp.Function) -> str:
        if isinstance(expr, AppliedUndef):
            return expr.func.__name__
        return super()._print_Function(expr)


#: the nodes the reader will charge each expression string of the file being written
#: (:data:`symmech.scenefile.MAX_FILE_NODES`), collected by :func:`_print_expression`
_CHARGES: ContextVar[list[int] | None] = ContextVar("_CHARGES", default=None)


def _print_expression(expr: sp.Expr, where: str, table: Mapping[str, sp.Expr]) -> str:
    expr = sp.sympify(expr, strict=True)
    for fn, rewrite in _REWRITES.items():
        if expr.has(fn):
            expr = expr.replace(fn, rewrite)
    if expr.has(sp.Derivative, sp.Integral, sp.Subs):
        raise SceneFileError([f"{where}: cannot write {_short(expr, 60)}: it holds a derivative"])
    text = _FilePrinter().doprint(expr)
    try:
        back = parse_expression(
            text, table, field=where, max_length=MAX_FILE_BYTES, max_nodes=MAX_FILE_NODES
        )
    except ExpressionError as exc:
        raise SceneFileError(
            [f"{where}: cannot write {_short(expr, 60)} as a scene-file expression ({exc})"]
        ) from None
    if back != expr and sp.simplify(back - expr) != 0:
        raise SceneFileError(
            [f"{where}: {_short(expr, 60)} does not read back as itself (as {text!r})"]
        )
    charges = _CHARGES.get()
    if charges is not None:  # what the reader charges it: the nodes parsed or built
        charges.append(max(tree_size(back), text_nodes(text)))
    return text


def _toml_string(text: str) -> str:
    out = ['"']
    for ch in text:
        if ch == '"':
            out.append('\\"')
        elif ch == "\\":
            out.append("\\\\")
        elif ch == "\n":
            out.append("\\n")
        elif ch == "\t":
            out.append("\\t")
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    out.append('"')
    return "".join(out)


def _toml_value(expr: sp.Expr, where: str, table: Mapping[str, sp.Expr]) -> str:
    if isinstance(expr, sp.Integer) and abs(int(expr)) < 2**53:
        return str(int(expr))
    if isinstance(expr, sp.Float) and expr._prec == 53 and math.isfinite(float(expr)):
        return repr(float(expr))  # a TOML float, read back as the same 53-bit Float
    return _toml_string(_print_expression(expr, where, table))


def _sign_of(symbol: sp.Symbol) -> str | None:
    for sign, assumptions in SIGNS.items():
        if sp.Symbol(symbol.name, **assumptions) == symbol:
            return sign
    return None


def _matrix_toml(M: sp.MatrixBase, where: str, table: Mapping[str, sp.Expr]) -> str:
    n = M.rows
    if all(M[i, j] == 0 for i in range(n) for j in range(n) if i != j):
        entries = ", ".join(_toml_value(M[i, i], f"{where}[{i},{i}]", table) for i in range(n))
        return f"[{entries}]"
    rows = [
        "  [" + ", ".join(_toml_value(M[i, j], f"{where}[{i},{j}]", table) for j in range(n)) + "],"
        for i in range(n)
    ]
    return "[\n" + "\n".join(rows) + "\n]"


def _row_expression(row: sp.MatrixBase, v: Sequence[sp.Symbol]) -> sp.Expr:
    return sp.Add(*[c * s for c, s in zip(row, v, strict=True)])


def _check_function(
    f: sp.Expr, arguments: Sequence[sp.Symbol], applied: Mapping[str, sp.Expr]
) -> None:
    """Refuse an applied undefined function that a scene file cannot declare."""
    name = f.func.__name__
    allowed = ", ".join(a.name for a in arguments)
    if not _IDENTIFIER.match(name) or len(name) > _MAX_IDENTIFIER:
        raise SceneFileError([f"functions: the name of {_short(f, 60)} is not an identifier"])
    if f.func not in (sp.Function(name, real=True), sp.Function(name)):
        raise SceneFileError(
            [
                f"functions: {name} has sympy assumptions that a scene file cannot write (it"
                " declares a function real, the default, or not: real = false)"
            ]
        )
    bad = [a for a in f.args if a not in arguments]
    if not f.args or bad or len(set(f.args)) != len(f.args):
        why = (
            f"its argument {_short(bad[0], 60)} is not t or a coordinate"
            if bad
            else "it has no arguments"
            if not f.args
            else "an argument is repeated"
        )
        raise SceneFileError(
            [
                f"functions: cannot write {_short(f, 60)}: {why}.  A scene file declares an"
                f" arbitrary function by its name and its arguments, distinct names among"
                f" {allowed} (a function of an expression, of a velocity or of a parameter"
                " would need the expression written in the file, which the format does not"
                " have: substitute a new function of the coordinates, or a symbol, before"
                " writing)"
            ]
        )
    if name in applied and applied[name] != f:
        raise SceneFileError(
            [
                f"functions: {applied[name]} and {f} have the same name; a scene file names"
                " each function once"
            ]
        )


def dump_scene(
    scene: Scene,
    *,
    defaults: Mapping[sp.Symbol | str, object] | None = None,
    description: str = "",
    functions: Mapping[str, sp.Expr] | None = None,
) -> str:
    """The TOML text of ``scene`` in the scene-file format (see the module documentation).

    ``defaults`` (parameter Symbol or name -> number) become the parameters' default
    values; ``functions`` (name -> expression in t) are written as defined functions.  The
    applied undefined functions in the scene (``f(t)``, ``V(x, y)``) are written as
    arbitrary functions with their arguments.  The metric is written as a matrix (also for
    a scene declared by its kinetic energy), the frame as ``matrix`` (S), constraints as
    expressions in the velocities.  ``load``-ing the text gives a scene with the same
    coordinates, parameters, metric, potential, frame, constraints and walls.

    Raises :class:`SceneFileError` when something cannot be written (a name that is not an
    identifier, a parameter with assumptions no ``sign`` gives, an expression outside the
    parser's subset such as a derivative, an undefined function of something else than
    distinct coordinates and t, such as ``V(x + y)``: the format declares a function by
    its argument names only).
    """
    charges: list[int] = []
    token = _CHARGES.set(charges)
    try:
        text = _dump(scene, defaults, description, functions)
    finally:
        _CHARGES.reset(token)
    _check_readable(text, sum(charges))
    return text


def _dump(
    scene: Scene,
    defaults: Mapping[sp.Symbol | str, object] | None,
    description: str,
    functions: Mapping[str, sp.Expr] | None,
) -> str:
    """The text of :func:`dump_scene`, its cost not yet checked."""
    decl = scene.declaration
    lines = _header_lines(decl, description)
    params = _parameters(decl)
    applied = _applied_functions(decl)
    table = _symbol_table(decl, params, applied)
    lines += _field_lines(decl, table)
    lines += _parameter_lines(params, defaults)
    lines += _function_lines(applied, dict(functions or {}), table)
    lines += _frame_lines(decl, table)
    for k, w in enumerate(decl.walls):
        lines += _wall_lines(w, f"walls[{k}]", decl.velocities, table)
    if decl.drawing is not None:
        lines.extend(_drawing_toml(decl.drawing, table))
    return "\n".join(lines) + "\n"


def _header_lines(decl: Any, description: str) -> list[str]:
    """The format, the name, the description and the coordinates (checked identifiers)."""
    q, v = decl.coordinates, decl.velocities
    lines = [f"# symmech scene file (format {FORMAT_VERSION}); load with symmech.load_scene"]
    lines.append(f"format = {FORMAT_VERSION}")
    if not _IDENTIFIER.match(decl.name):
        raise SceneFileError([f"name: the scene name {decl.name!r} is not an identifier"])
    lines.append(f"name = {_toml_string(decl.name)}")
    if description:
        lines.append(f"description = {_toml_string(description)}")
    for s in (*q, *(v if decl.frame is not None else ())):
        if not _IDENTIFIER.match(s.name) or sp.Symbol(s.name, real=True) != s:
            raise SceneFileError(
                [f"coordinates: {s.name!r} must be a real symbol named by an identifier"]
            )
    lines.append("coordinates = [" + ", ".join(_toml_string(s.name) for s in q) + "]")
    return lines


def _parameters(decl: Any) -> list[sp.Symbol]:
    """The scene's parameters, and a symbolic restitution (the Scene may not list it)."""
    params = list(decl.parameters)
    for w in decl.walls:
        if isinstance(w.restitution, sp.Symbol) and w.restitution not in params:
            params.append(w.restitution)
    return params


def _applied_functions(decl: Any) -> dict[str, sp.Expr]:
    """The arbitrary functions the scene's expressions apply, by name (each checked)."""
    applied: dict[str, sp.Expr] = {}
    arguments = (TIME, *decl.coordinates)
    for e in decl.expressions():
        for f in sorted(sp.sympify(e, strict=True).atoms(AppliedUndef), key=sp.default_sort_key):
            _check_function(f, arguments, applied)
            applied[f.func.__name__] = f
    return applied


def _symbol_table(
    decl: Any, params: list[sp.Symbol], applied: Mapping[str, sp.Expr]
) -> dict[str, sp.Expr]:
    """The symbol table of the read-back check: t, the coordinates and their velocities,
    the quasi-velocities, the parameters and the applied functions."""
    q = decl.coordinates
    table: dict[str, sp.Expr] = {"t": TIME}
    table.update({s.name: s for s in q})
    table.update({velocity_of(s).name: velocity_of(s) for s in q})
    table.update({s.name: s for s in decl.velocities})
    table.update({p.name: p for p in params})
    table.update(applied)
    return table


def _field_lines(decl: Any, table: Mapping[str, sp.Expr]) -> list[str]:
    """The metric, the potential, the forces and the constraints."""
    lines = ["metric = " + _matrix_toml(decl.metric, "metric", table)]
    if decl.potential != 0:
        lines.append("potential = " + _toml_value(decl.potential, "potential", table))
    if any(e != 0 for e in decl.forces):
        forces = [_toml_value(e, f"forces[{k}]", table) for k, e in enumerate(decl.forces)]
        lines.append("forces = [" + ", ".join(forces) + "]")
    if decl.m:
        cons = [
            _toml_value(
                _row_expression(decl.constraint_matrix.row(a), decl.velocities),
                f"constraints[{a}]",
                table,
            )
            for a in range(decl.m)
        ]
        lines.append("constraints = [" + ", ".join(cons) + "]")
    return lines


def _parameter_lines(
    params: list[sp.Symbol], defaults: Mapping[sp.Symbol | str, object] | None
) -> list[str]:
    """The ``[parameters]`` table: each parameter's default value and sign."""
    by_name = {(k if isinstance(k, str) else k.name): val for k, val in (defaults or {}).items()}
    unknown = sorted(set(by_name) - {p.name for p in params})
    if unknown:
        raise SceneFileError([f"defaults: {unknown} are not parameters of the scene"])
    lines = ["", "[parameters]"]
    for p in params:
        sign = _sign_of(p)
        if sign is None:
            raise SceneFileError(
                [f"parameters.{p.name}: its assumptions {p.assumptions0} match no sign"]
            )
        parts = []
        if p.name in by_name:
            value = by_name[p.name]
            try:
                # a string is parsed by the safe parser, never sympified
                number = to_expression(value, {}, field=f"defaults[{p.name!r}]")
            except ExpressionError as exc:
                raise SceneFileError([str(exc)]) from None
            if not number.is_number:
                raise SceneFileError([f"defaults: {p.name} = {value!r} is not a number"])
            parts.append(f"value = {_toml_value(number, f'parameters.{p.name}', {})}")
        if sign != "positive":
            parts.append(f"sign = {_toml_string(sign)}")
        lines.append(f"{p.name} = {{ {', '.join(parts)} }}" if parts else f"{p.name} = {{}}")
    return lines


def _function_lines(
    applied: Mapping[str, sp.Expr], fn_defs: Mapping[str, sp.Expr], table: Mapping[str, sp.Expr]
) -> list[str]:
    """The ``[functions]`` table: the applied functions' arguments and reality, and the
    functions defined by expressions; nothing when there are none."""
    if not applied and not fn_defs:
        return []
    lines = ["", "[functions]"]
    for nm, f in applied.items():
        parts = []
        if f.args != (TIME,):
            parts.append("arguments = [" + ", ".join(f'"{a.name}"' for a in f.args) + "]")
        if f.func != sp.Function(nm, real=True):
            parts.append("real = false")
        lines.append(f"{nm} = {{ {', '.join(parts)} }}" if parts else f"{nm} = {{}}")
    for nm, expr in fn_defs.items():
        lines.append(f"{nm} = {_toml_value(expr, f'functions.{nm}', table)}")
    return lines


def _frame_lines(decl: Any, table: Mapping[str, sp.Expr]) -> list[str]:
    """The ``[frame]`` table of quasi-velocities; nothing without a frame."""
    if decl.frame is None:
        return []
    lines = ["", "[frame]"]
    lines.append(
        "quasi_velocities = [" + ", ".join(_toml_string(s.name) for s in decl.velocities) + "]"
    )
    rows = [
        "  ["
        + ", ".join(
            _toml_value(decl.frame[i, j], f"frame.matrix[{i},{j}]", table) for j in range(decl.n)
        )
        + "],"
        for i in range(decl.n)
    ]
    lines.append("matrix = [\n" + "\n".join(rows) + "\n]")
    return lines


def _wall_lines(
    w: Any, label: str, v: Sequence[sp.Symbol], table: Mapping[str, sp.Expr]
) -> list[str]:
    """One ``[[walls]]`` table: name, gap, restitution, impulsive constraints, law and
    velocity, each written only when it is not the default."""
    lines = ["", "[[walls]]"]
    if w.wall.name:
        if not _IDENTIFIER.match(w.wall.name):
            raise SceneFileError([f"{label}.name: {w.wall.name!r} is not an identifier"])
        lines.append(f"name = {_toml_string(w.wall.name)}")
    lines.append(f"psi = {_toml_value(w.psi, f'{label}.psi', table)}")
    if w.restitution != 1:
        lines.append(f"restitution = {_toml_value(w.restitution, f'{label}.restitution', table)}")
    if w.impulsive_matrix.rows:
        nus = [
            _toml_value(
                _row_expression(w.impulsive_matrix.row(A), v),
                f"{label}.impulsive_constraints[{A}]",
                table,
            )
            for A in range(w.impulsive_matrix.rows)
        ]
        lines.append("impulsive_constraints = [" + ", ".join(nus) + "]")
    if w.law != "newton":
        lines.append(f"law = {_toml_string(w.law)}")
    if w.velocity is not None:
        comps = [_toml_value(c, f"{label}.velocity[{j}]", table) for j, c in enumerate(w.velocity)]
        lines.append("velocity = [" + ", ".join(comps) + "]")
    return lines


def _drawing_toml(drawing: Drawing, table: Mapping[str, sp.Expr]) -> list[str]:
    """The ``[[drawing]]`` tables of ``drawing`` (:mod:`symmech.scenefile.reader_drawing`)."""
    lines = []
    kinds = {cls: kind for kind, cls in SHAPES.items()}
    for k, shape in enumerate(drawing):
        kind = kinds[type(shape)]
        fields: dict[str, Any] = {
            "point": lambda s: {"at": s.at},
            "segment": lambda s: {"start": s.start, "end": s.end},
            "disc": lambda s: {"center": s.center, "radius": s.radius, "angle": s.angle},
            "ellipse": lambda s: {"center": s.center, "axes": (s.a, s.b), "angle": s.angle},
            "wall": lambda s: {"point": s.point, "normal": s.normal},
        }[kind](shape)
        lines += ["", "[[drawing]]", f"shape = {_toml_string(kind)}"]
        for key, value in fields.items():
            where = f"drawing[{k}].{key}"
            if value is None:
                continue
            if isinstance(value, tuple):
                items = ", ".join(
                    _toml_value(e, f"{where}[{j}]", table) for j, e in enumerate(value)
                )
                lines.append(f"{key} = [{items}]")
            else:
                lines.append(f"{key} = {_toml_value(value, where, table)}")
    return lines


def _check_readable(text: str, nodes: int) -> None:
    """Refuse to write what the reader would refuse by its cost limits (the file's bytes,
    the ``nodes`` its expression strings are charged, and its distinct function
    applications: :mod:`symmech.scenefile.format`)."""
    size = len(text.encode("utf-8"))
    calls = len(applications(text))
    over = [
        f"{what} {value} (limit {name}={limit})"
        for what, value, name, limit in (
            ("bytes", size, "MAX_FILE_BYTES", MAX_FILE_BYTES),
            ("operands and operations", nodes, "MAX_FILE_NODES", MAX_FILE_NODES),
            ("distinct function applications", calls, "MAX_FILE_CALLS", MAX_FILE_CALLS),
        )
        if value > limit
    ]
    if over:
        raise SceneFileError([f"the scene is too large for a scene file: {'; '.join(over)}"])


def save_scene(
    scene: Scene,
    path: str | os.PathLike[str],
    *,
    defaults: Mapping[sp.Symbol | str, object] | None = None,
    description: str = "",
    functions: Mapping[str, sp.Expr] | None = None,
) -> Path:
    """Write :func:`dump_scene` of ``scene`` to ``path``; return the path."""
    text = dump_scene(scene, defaults=defaults, description=description, functions=functions)
    return write_text_atomic(path, text)
