"""The scene file reader: the fields, the walls, the Scene, and the public
:func:`load_scene`, :func:`loads_scene`, :func:`read_scene`, :func:`reads_scene`."""

from __future__ import annotations

import os
import re
import tomllib
from pathlib import Path

import sympy as sp

from symmech.declaration.expressions import (
    MAX_DIGITS,
)
from symmech.declaration.symbols import velocity_of
from symmech.declaration.wall import LAWS, Wall
from symmech.errors import Problem, SceneError
from symmech.scene import Scene
from symmech.scenefile.builtin import _resolve_path
from symmech.scenefile.format import (
    _IDENTIFIER,
    _MAX_IDENTIFIER,
    _TOP_KEYS,
    _WALL_KEYS,
    MAX_FILE_BYTES,
    MAX_WALLS,
    SceneFileError,
    _clip,
    _number_text,
    _short,
    _toml_error,
    _toml_type,
)
from symmech.scenefile.loaded import SceneFile
from symmech.scenefile.reader_drawing import read_drawing
from symmech.scenefile.reader_names import _NamesLoader


class _Loader(_NamesLoader):
    """Builds a Scene from parsed TOML data, collecting every problem: the fields (metric,
    kinetic energy, potential, forces, constraints, walls) and the Scene itself."""

    def constraint_list(
        self, raw: object, n: int, field: str, line: int | None
    ) -> list[sp.Expr | list[sp.Expr]] | None:
        if not isinstance(raw, list):
            self.fail(
                f"expected an array of expressions linear in the velocities (or rows of"
                f" coefficients), got {_toml_type(raw)}",
                field,
                line,
            )
            return None
        out: list[sp.Expr | list[sp.Expr]] = []
        ok = True
        coeff_table = {k: e for k, e in self.table.items() if e not in self.velocity_like}
        for a, c in enumerate(raw):
            label = f"{field}[{a}]"
            if isinstance(c, list):
                if len(c) != n:
                    self.fail(
                        f"a coefficient row needs {n} entries (one per velocity), got {len(c)}",
                        label,
                        line,
                    )
                    ok = False
                    continue
                row = [
                    self.expression(e, f"{label}[{j}]", self.loc.element(line, e), coeff_table)
                    for j, e in enumerate(c)
                ]
                ok &= all(e is not None for e in row)
                out.append(row)
            else:
                at = self.loc.element(line, c)
                self.field_lines[label] = at
                expr = self.expression(c, label, at, self.table)
                ok &= expr is not None
                out.append(expr)
        return out if ok else None

    def force_list(self, raw: object, n: int) -> list[sp.Expr] | None:
        """``forces``: n expressions (absent, or refused: None, the problem recorded)."""
        if raw is None:
            return None
        line = self.line(None, "forces")
        return self.expression_array(raw, n, "forces", line, self.table, "generalized force")

    def expression_array(
        self,
        raw: object,
        n: int,
        field: str,
        line: int | None,
        table: dict[str, sp.Expr],
        what: str,
    ) -> list[sp.Expr] | None:
        """An array of ``n`` expressions, one ``what`` per velocity (``field[k]`` located
        on its element); None when refused (every problem recorded)."""
        self.field_lines[field] = line
        if not isinstance(raw, list) or len(raw) != n:
            got = f"{len(raw)} entries" if isinstance(raw, list) else _toml_type(raw)
            self.fail(
                f"expected an array of {n} expressions (one {what} per velocity), got {got}",
                field,
                line,
            )
            return None
        out = []
        for k, e in enumerate(raw):
            at = self.loc.element(line, e)
            self.field_lines[f"{field}[{k}]"] = at
            out.append(self.expression(e, f"{field}[{k}]", at, table))
        return None if any(e is None for e in out) else out

    def walls(self, n: int) -> list[Wall]:
        raw = self.data.get("walls", [])
        if not isinstance(raw, list) or not all(isinstance(w, dict) for w in raw):
            self.fail(
                f"expected an array of tables ([[walls]] sections), got {_toml_type(raw)}",
                "walls",
                self.line(None, "walls") or self.loc.table("walls"),
            )
            return []
        if len(raw) > MAX_WALLS:
            self.fail(f"{len(raw)} walls (limit {MAX_WALLS})", "walls", None)
            return []
        walls = []
        for k, spec in enumerate(raw):
            label = f"walls[{k}]"
            wline = self.loc.table("walls", k)
            self.field_lines[label] = wline
            self.check_keys(spec, _WALL_KEYS, label, "walls", k)
            name = spec.get("name")
            if name is not None and (
                not isinstance(name, str) or not _IDENTIFIER.match(name) or len(name) > 64
            ):
                self.fail(
                    "a wall name must be an identifier (letters, digits, _; it names generated"
                    f" code), got {_short(name)}",
                    f"{label}.name",
                    self.line("walls", "name", k),
                    str(name)[:40],
                )
                name = None
            if "psi" not in spec:
                self.fail("required key 'psi' (the gap function) is missing", f"{label}.psi", wline)
                continue
            pline = self.line("walls", "psi", k)
            self.field_lines[f"{label}.psi"] = pline
            psi = self.expression(spec["psi"], f"{label}.psi", pline, self.table)
            restitution = self.restitution(spec.get("restitution", 1), label, k)
            law = spec.get("law", "newton")
            if law not in LAWS:
                self.fail(
                    f"law must be one of {', '.join(LAWS)}, got {_short(law, 60)}",
                    f"{label}.law",
                    self.line("walls", "law", k),
                    _clip(law),
                )
                continue
            iline = self.line("walls", "impulsive_constraints", k)
            self.field_lines[f"{label}.impulsive_constraints"] = iline
            impulsive = self.constraint_list(
                spec.get("impulsive_constraints", []), n, f"{label}.impulsive_constraints", iline
            )
            velocity = self.wall_velocity(spec.get("velocity"), n, label, k)
            if psi is None or restitution is None or impulsive is None or velocity is False:
                continue
            try:
                walls.append(
                    Wall(
                        psi,
                        restitution=restitution,
                        impulsive_constraints=impulsive,
                        name=name,
                        law=law,
                        velocity=velocity,
                    )
                )
            except SceneError as exc:
                for problem in exc.problems:
                    self.fail(problem, label, wline)
        return walls

    def wall_velocity(self, raw: object, n: int, label: str, k: int) -> list | bool | None:
        """``walls[k].velocity``: n expressions in t, q and the parameters; None when absent,
        False when refused (the problem is recorded)."""
        if raw is None:
            return None
        table = {k_: e for k_, e in self.table.items() if e not in self.velocity_like}
        line = self.line("walls", "velocity", k)
        out = self.expression_array(raw, n, f"{label}.velocity", line, table, "component")
        return False if out is None else out

    def restitution(self, raw: object, label: str, k: int) -> sp.Expr | None:
        field_name = f"{label}.restitution"
        line = self.line("walls", "restitution", k)
        params = {k_: e for k_, e in self.table.items() if isinstance(e, sp.Symbol)}
        value = self.expression(raw, field_name, line, params)
        if value is None:
            return None
        if not (value.is_number or (isinstance(value, sp.Symbol) and value in self.param_set)):
            self.fail(
                f"restitution must be a number in [0, 1] or a parameter name, got {_clip(value)}",
                field_name,
                line,
                _clip(raw),
            )
            return None
        if value.is_number and (not value.is_real or value < 0 or value > 1):
            self.fail(f"restitution {_clip(raw)} is outside [0, 1]", field_name, line, _clip(raw))
            return None
        if isinstance(value, sp.Symbol):
            # a restitution parameter: alpha in [0, 1], so its sign and default must allow it
            pline = self.entry_line("parameters", value.name)
            if not (value.is_nonnegative or value.is_positive):
                self.fail(
                    f"restitution parameter '{value.name}' must be declared with sign ="
                    ' "nonnegative" (or "positive"): a restitution coefficient lies in [0, 1]',
                    f"parameters.{value.name}.sign",
                    pline,
                    value.name,
                )
                return None
            default = self.defaults.get(value)
            if default is not None and default > 1:
                self.fail(
                    f"default value {_number_text(default)} of '{value.name}' is outside"
                    f" [0, 1], but '{value.name}' is the restitution of {label}",
                    f"parameters.{value.name}.value",
                    pline,
                    _number_text(default),
                )
                return None
        return value

    def build(self) -> SceneFile:
        data = self.data
        self.check_keys(data, _TOP_KEYS, "", None)
        name, description = self.header()
        q = self.coordinates()
        self.q = tuple(q)
        params, defaults = self.parameters()
        self.defaults = defaults
        self.param_set = frozenset(params)
        self.coord_like = frozenset({*q, *(velocity_of(s) for s in q)})
        fns = self.functions()
        self.velocity_like = frozenset(velocity_of(s) for s in q)
        S, v = self.frame(q)
        if v:
            self.velocity_like = self.velocity_like | frozenset(v)
            # in a frame, the kinetic energy and the constraints are written in the
            # quasi-velocities: the coordinate velocities have no place in the file
            names = ", ".join(s.name for s in v)
            for s in q:
                vel = velocity_of(s).name
                self.table.pop(vel, None)
                self.reserved[vel] = (
                    f"the velocity of coordinate '{s.name}' (with a [frame], velocities are"
                    f" written in the quasi-velocities {names})"
                )
        if self.names_refused:
            self.problems.raise_if_any(self.source)
        n = len(q)
        # metric or kinetic energy
        has_metric, has_T = "metric" in data, "kinetic_energy" in data
        metric = kinetic = None
        if has_metric == has_T:
            self.fail(
                "give exactly one of 'metric' and 'kinetic_energy'",
                "metric",
                self.line(None, "metric") or self.line(None, "kinetic_energy"),
            )
        elif has_metric and n:
            table = {k: e for k, e in self.table.items() if e not in self.velocity_like}
            metric = self.matrix(
                data["metric"], n, "metric", self.line(None, "metric"), table, True
            )
        elif has_T:
            kline = self.line(None, "kinetic_energy")
            self.field_lines["kinetic_energy"] = kline
            kinetic = self.expression(data["kinetic_energy"], "kinetic_energy", kline, self.table)
        pline = self.line(None, "potential")
        self.field_lines["potential"] = pline
        potential = self.expression(data.get("potential", 0), "potential", pline, self.table)
        forces = self.force_list(data.get("forces"), n)
        cline = self.line(None, "constraints")
        self.field_lines["constraints"] = cline
        constraints = self.constraint_list(data.get("constraints", []), n, "constraints", cline)
        walls = self.walls(n)
        drawing = read_drawing(self)
        unused = [p.name for p in params if p not in self.used]
        if unused and not self.problems.items:
            # (an expression refused above may be where a parameter is used)
            self.fail(
                f"declared but not used in any expression: {', '.join(unused)}",
                f"parameters.{unused[0]}",
                self.line("parameters", unused[0]) or self.line(None, "parameters"),
                unused[0],
            )
        self.problems.raise_if_any(self.source)
        try:
            scene = Scene(
                q,
                metric=metric,
                kinetic_energy=kinetic,
                potential=potential if potential is not None else 0,
                forces=forces,
                constraints=constraints or [],
                frame=S,
                quasi_velocities=v,
                walls=walls,
                parameters=params,
                name=name,
                drawing=drawing,
            )
        except SceneError as exc:
            for problem in exc.records:
                field_name, line, rest = self.locate_problem(problem)
                self.problems.add(rest, field=field_name, line=line)
            self.problems.raise_if_any(self.source)
            raise  # pragma: no cover - every SceneError has at least one problem
        return SceneFile(scene=scene, defaults=defaults, functions=fns, description=description)

    def locate_problem(self, problem: Problem) -> tuple[str | None, int | None, str]:
        """The field a Scene validation problem is about, its line in the file, and the
        message without its leading ``field:`` (the caller writes ``field (line N):``).

        The field is the problem's own (:class:`~symmech.errors.Problem`): the most
        specific of it and its parents (``walls[0].impulsive_constraints[1]``, then
        ``walls[0].impulsive_constraints``, then ``walls[0]``) that the file has a line
        for."""
        path, rest = problem.field, problem.reason
        parents = _parents(path) if path is not None else []
        if not parents or parents[-1] not in _LOCATED:
            return None, None, problem.message
        root = parents[-1]
        if root == "walls" and len(parents) > 1:  # one wall: its keys, else the wall itself
            for key in parents[:-1]:
                if key in self.field_lines:
                    return key, self.field_lines[key], rest
            return parents[-2], None, rest
        for key in parents:
            if key in self.field_lines:
                return key, self.field_lines[key], rest
        if root in ("frame", "walls"):
            return root, self.loc.table(root) or self.line(None, root), rest
        return root, self.field_lines.get(root) or self.line(None, root), rest


#: The declaration fields a scene file gives a line for.
_LOCATED = ("constraints", "forces", "metric", "kinetic_energy", "potential", "frame", "walls")


def _parents(path: str) -> list[str]:
    """``walls[0].psi`` -> ``["walls[0].psi", "walls[0]", "walls"]``: the path and its
    parents, most specific first (a path is ``name``, ``name[i]`` and ``.name`` parts)."""
    out = [path]
    while True:
        cut = max(path.rfind("."), path.rfind("["))
        if cut <= 0:
            return out
        path = path[:cut]
        out.append(path)


def _load(text: str, *, source: str, default_name: str, path: Path | None) -> SceneFile:
    if "\x00" in text:
        line = text[: text.index("\x00")].count("\n") + 1
        raise SceneFileError(
            [f"{source} (line {line}): null character in the file"],
            path=source,
            details=[(None, line, "\\x00")],
        )
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise _toml_error(text, source, str(exc)) from None
    except RecursionError:
        raise SceneFileError(
            [f"{source}: not valid TOML: arrays or tables nested too deeply"], path=source
        ) from None
    except ValueError as exc:  # an integer too long for int() (sys.get_int_max_str_digits)
        m = re.search(rf"[0-9][0-9_]{{{MAX_DIGITS},}}", text)
        if m is None:
            raise SceneFileError([f"{source}: not valid TOML: {exc}"], path=source) from None
        line = text[: m.start()].count("\n") + 1
        token = m.group(0)[:20] + "..."
        raise SceneFileError(
            [
                f"{source} (line {line}): integer {token} has {len(m.group(0))} digits"
                f" (limit {MAX_DIGITS})"
            ],
            path=source,
            details=[(None, line, token)],
        ) from None
    loader = _Loader(data, text, source, default_name)
    result = loader.build()
    return SceneFile(
        scene=result.scene,
        defaults=result.defaults,
        functions=result.functions,
        description=result.description,
        path=path,
    )


# ---------------------------------------------------------------------------------------
# loading


def load_scene(path: str | os.PathLike[str]) -> Scene:
    """Load the scene file ``path`` and return its :class:`~symmech.Scene`.

    ``path`` is a TOML file (see the module documentation for the format), or the name of
    a built-in scene file (``"carnot_3_7"``; see :func:`builtin_scene_names`) when no file
    of that name exists.  The default values of the parameters, which a Scene does not
    hold, are in :func:`read_scene`'s :attr:`SceneFile.defaults`.

    Raises :class:`SceneFileError` listing every problem, each with the field and line.
    """
    return read_scene(path).scene


def read_scene(path: str | os.PathLike[str]) -> SceneFile:
    """Load the scene file ``path`` (or built-in scene name); return a :class:`SceneFile`."""
    p = _resolve_path(path)
    source = str(path)
    try:
        if not p.is_file():  # a folder, a device (/dev/zero never ends), a pipe
            raise SceneFileError([f"{source}: not a regular file"], path=source)
        size = p.stat().st_size
        if size > MAX_FILE_BYTES:
            raise SceneFileError(
                [f"{source}: file is {size} bytes long (limit {MAX_FILE_BYTES})"], path=source
            )
        with p.open("rb") as handle:  # bounded, should the file grow meanwhile
            data = handle.read(MAX_FILE_BYTES + 1)
        if len(data) > MAX_FILE_BYTES:
            raise SceneFileError(
                [f"{source}: file is longer than {MAX_FILE_BYTES} bytes"], path=source
            )
    except OSError as exc:
        raise SceneFileError(
            [f"{source}: cannot read: {exc.strerror or exc}"], path=source
        ) from None
    try:
        # (utf-8-sig: a byte-order mark that some editors write is not part of the text)
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise SceneFileError(
            [f"{source} (line {line}): not UTF-8 text ({exc.reason} at byte {exc.start})"],
            path=source,
            details=[(None, line, None)],
        ) from None
    stem = re.sub(r"\W", "_", p.stem) or "scene"
    if not _IDENTIFIER.match(stem):
        stem = "scene_" + stem
    return _load(text, source=source, default_name=stem[:_MAX_IDENTIFIER], path=p)


def reads_scene(text: str, *, name: str = "scene", source: str = "<string>") -> SceneFile:
    """Load a scene from TOML ``text``; ``name`` is used when the text has no ``name``."""
    if not isinstance(text, str):
        raise SceneFileError([f"{source}: expected TOML text, got a {type(text).__name__}"])
    if len(text.encode("utf-8", errors="replace")) > MAX_FILE_BYTES:
        raise SceneFileError([f"{source}: text is longer than {MAX_FILE_BYTES} bytes"])
    return _load(text, source=source, default_name=name, path=None)


def loads_scene(text: str, *, name: str = "scene", source: str = "<string>") -> Scene:
    """The Scene of a scene file given as text: :func:`load_scene` for text, as
    :func:`reads_scene` is :func:`read_scene` for text (the :class:`SceneFile` with the
    parameters' defaults, the functions and the description)."""
    return reads_scene(text, name=name, source=source).scene
