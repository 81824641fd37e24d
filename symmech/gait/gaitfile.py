"""Gait files: a gait's modes and transitions in TOML, beside the scene files of its bodies.

A gait file names scene files (in its own folder: a plain file name, no path), builds its
modes from them and declares its transitions; every expression is read by the scene files'
safe parser (:func:`symmech.declaration.expressions.to_expression`, never evaluated)::

    format = 1
    name = "rimless_wheel"
    description = "McGeer's rimless wheel"
    section = "strike"              # the transition whose stride map is studied
    guess = [0.3141592653589793, -1.5]    # a start for Newton, just after it

    [scenes]
    free = "rimless_wheel_free.toml"      # the wheel with its hub free: the impact scene

    [modes.stance]
    pinned = "free"                 # the pull-back of a scene by a holonomic embedding
    coordinates = ["theta"]
    embedding = { x = "-l*sin(theta)", y = "l*cos(theta)", theta = "theta" }
    # or: scene = "free" (a scene as it is); guards = [{ name = "strike", psi = "..." }]
    # adds guard walls to the mode

    [[transitions]]
    name = "strike"
    source = "stance"
    target = "stance"
    guard = "heel"                  # a wall of the source mode
    condition = "..."               # optional: where the guard counts (> 0)
    impact = "free"                 # the reset: the impact on this scene's wall ...
    wall = "heel"
    relabel = ["theta + 2*alpha"]   # ... then the target's coordinates
    # or: position = [...] and velocity = [...], the target state in the source's state

    [limit]                         # optional: the gait in a parameter's limit
    beta = 0                        # (symmech.gait.limits.limit_gait)

The impact scene of a transition is the scene its source mode is pinned from (or the
source mode's own scene): the embedding is the mode's.  The parameters' default values are
the scene files'; a parameter given two different values is refused.  Errors are
:class:`~symmech.scenefile.SceneFileError` s naming the file and the field.
"""

from __future__ import annotations

import math
import os
import re
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import sympy as sp

from symmech.declaration.expressions import to_expression
from symmech.declaration.wall import Wall
from symmech.errors import SymmechError
from symmech.gait.modes import Gait, Reset, Transition, impact_reset, pinned_scene
from symmech.scene import Scene
from symmech.scenefile import SceneFileError, read_scene

__all__ = ["GaitFile", "builtin_gait_files", "read_gait"]

_TOP_KEYS = {
    "format", "name", "description", "section", "guess", "scenes", "modes", "transitions",
    "limit",
}  # fmt: skip
_MODE_KEYS = {"scene", "pinned", "coordinates", "embedding", "walls", "guards"}
_TRANSITION_KEYS = {
    "name", "source", "target", "guard", "condition", "impact", "wall", "relabel",
    "position", "velocity",
}  # fmt: skip
_FILE_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]{0,100}\.toml")
MAX_GAIT_BYTES = 100_000
BUILTIN_DIR = Path(__file__).resolve().parent / "files"


@dataclass(frozen=True)
class GaitFile:
    """A gait read from a file, its parameters' default values, the section transition's
    index, a start for Newton and the description."""

    gait: Gait
    defaults: dict[str, float]
    section: int
    guess: tuple[float, ...]
    description: str
    path: Path


def builtin_gait_files() -> list[str]:
    """Names of the gait files shipped with symmech (``symmech gait NAME`` reads them)."""
    return sorted(p.name[: -len(".gait.toml")] for p in BUILTIN_DIR.glob("*.gait.toml"))


class _Reader:
    def __init__(self, path: Path, data: dict[str, Any]):
        self.path = path
        self.source = str(path)
        self.data = data
        self.problems: list[str] = []

    def fail(self, field: str, why: str) -> None:
        self.problems.append(f"{self.source}: {field}: {why}")

    def check(self) -> None:
        if self.problems:
            raise SceneFileError(self.problems, path=self.source)

    def keys(self, table: object, allowed: set[str], field: str) -> dict[str, Any]:
        if not isinstance(table, dict):
            self.fail(field, f"expected a table, got {type(table).__name__}")
            return {}
        for key in sorted(set(table) - allowed):
            self.fail(field, f"unknown key {key!r} (expected one of {sorted(allowed)})")
        return table

    def expr(self, text: object, names: Mapping[str, sp.Basic], field: str) -> sp.Expr | None:
        try:
            return to_expression(text, names, field=field)
        except (SymmechError, ValueError) as exc:
            self.problems.append(f"{self.source}: {exc}")
            return None

    # -- the parts ---------------------------------------------------------------------------
    def scenes(self) -> tuple[dict[str, Scene], dict[str, float]]:
        out: dict[str, Scene] = {}
        defaults: dict[str, float] = {}
        table = self.keys(self.data.get("scenes", {}), set(self.data.get("scenes", {})), "scenes")
        for key, file_name in table.items():
            if not isinstance(file_name, str) or not _FILE_NAME.fullmatch(file_name):
                self.fail(
                    f"scenes.{key}",
                    f"{file_name!r} is not a scene file name in the gait file's folder"
                    " (letters, digits, _ . -, ending in .toml; no path)",
                )
                continue
            target = self.path.parent / file_name
            if not target.is_file():
                self.fail(f"scenes.{key}", f"no file {file_name!r} beside the gait file")
                continue
            sf = read_scene(target)
            out[key] = sf.scene
            for p, value in sf.defaults.items():
                name = str(p)
                if name in defaults and defaults[name] != float(value):
                    self.fail(
                        f"scenes.{key}",
                        f"parameter {name} = {value} here, {defaults[name]} in another scene",
                    )
                defaults[name] = float(value)
        return out, defaults

    def mode(self, key: str, raw: object, scenes: dict[str, Scene]):
        """(scene, parent scene name, embedding) of mode ``key``."""
        field = f"modes.{key}"
        table = self.keys(raw, _MODE_KEYS, field)
        if ("scene" in table) == ("pinned" in table):
            self.fail(field, "give exactly one of 'scene' (as it is) and 'pinned' (pulled back)")
            return None
        parent = table.get("scene", table.get("pinned"))
        if parent not in scenes:
            self.fail(field, f"{parent!r} is not a scene of [scenes] {sorted(scenes)}")
            return None
        base = scenes[parent]
        if "scene" in table:
            scene, embedding = base, {s: s for s in base.coordinates}
        else:
            coords = table.get("coordinates")
            if not (
                isinstance(coords, list) and coords and all(isinstance(c, str) for c in coords)
            ):
                self.fail(f"{field}.coordinates", "expected an array of coordinate names")
                return None
            try:
                q = sp.symbols(coords, real=True)
            except (ValueError, TypeError) as exc:
                self.fail(f"{field}.coordinates", str(exc))
                return None
            names = {**{s.name: s for s in q}, **{p.name: p for p in base.parameters}}
            emb_raw = self.keys(table.get("embedding"), {s.name for s in base.coordinates},
                                f"{field}.embedding")  # fmt: skip
            embedding = {}
            for s in base.coordinates:
                if s.name not in emb_raw:
                    self.fail(f"{field}.embedding", f"missing coordinate {s.name!r}")
                    continue
                e = self.expr(emb_raw[s.name], names, f"{field}.embedding.{s.name}")
                if e is not None:
                    embedding[s] = e
            self.check()
            walls = table.get("walls")
            scene = pinned_scene(base, embedding, list(q), name=f"{self.data['name']}_{key}",
                                 walls=walls)  # fmt: skip
        guards = table.get("guards", [])
        if guards:
            names = {**{s.name: s for s in scene.coordinates},
                     **{p.name: p for p in scene.parameters}}  # fmt: skip
            extra = []
            for i, g in enumerate(guards if isinstance(guards, list) else [None]):
                if not (isinstance(g, dict) and set(g) == {"name", "psi"}):
                    self.fail(f"{field}.guards[{i}]", "expected { name = ..., psi = ... }")
                    continue
                psi = self.expr(g["psi"], names, f"{field}.guards[{i}].psi")
                if psi is not None:
                    extra.append(Wall(psi, name=str(g["name"])))
            self.check()
            plain = [Wall(w.psi, restitution=w.restitution, name=w.name) for w in scene.walls]
            scene = scene.replace(walls=[*plain, *extra])
        return scene, parent, embedding

    def transition(self, i: int, raw: object, modes, scenes) -> Transition | None:
        field = f"transitions[{i}]"
        t = self.keys(raw, _TRANSITION_KEYS, field)
        for need in ("source", "target", "guard"):
            if not isinstance(t.get(need), str):
                self.fail(f"{field}.{need}", "required, a name")
        self.check()
        if t["source"] not in modes or t["target"] not in modes:
            self.fail(field, f"modes {t['source']!r} and {t['target']!r} must be in [modes]")
            self.check()
        source, parent, embedding = modes[t["source"]]
        target = modes[t["target"]][0]
        names = {
            **{s.name: s for s in (*source.coordinates, *source.velocities)},
            **{p.name: p for m in modes.values() for p in m[0].parameters},
        }
        condition = None
        if "condition" in t:
            condition = self.expr(t["condition"], names, f"{field}.condition")
        if "impact" in t:
            if t["impact"] != parent:
                self.fail(
                    f"{field}.impact",
                    f"the impact scene must be the one mode {t['source']!r} is built from"
                    f" ({parent!r})",
                )
                return None
            impact = scenes[parent]
            q_names = {**{s.name: s for s in impact.coordinates},
                       **{p.name: p for p in impact.parameters}}  # fmt: skip
            relabel = t.get("relabel")
            if not isinstance(relabel, list) or len(relabel) != target.n:
                self.fail(f"{field}.relabel", f"expected {target.n} expressions")
                return None
            exprs = [self.expr(e, q_names, f"{field}.relabel[{j}]") for j, e in enumerate(relabel)]
            self.check()
            try:
                wall = str(t.get("wall", t["guard"]))
                reset = impact_reset(source, impact, wall, embedding, exprs)
            except SymmechError as exc:
                self.fail(field, str(exc))
                return None
        else:
            pos, vel = t.get("position"), t.get("velocity")
            if not (isinstance(pos, list) and isinstance(vel, list)):
                self.fail(field, "give impact, wall and relabel, or position and velocity")
                return None
            p = [self.expr(e, names, f"{field}.position[{j}]") for j, e in enumerate(pos)]
            v = [self.expr(e, names, f"{field}.velocity[{j}]") for j, e in enumerate(vel)]
            self.check()
            reset = Reset(sp.ImmutableMatrix(p), sp.ImmutableMatrix(v))
        return Transition(t["source"], t["target"], t["guard"], reset, condition,
                          name=str(t.get("name", "")))  # fmt: skip

    def limits(self, gait: Gait, table: object) -> Gait:
        """``gait`` in the limits of ``[limit]`` (``beta = 0``: feet of vanishing mass),
        taken in the table's order (:func:`symmech.gait.limits.limit_gait`)."""
        from symmech.gait.limits import limit_gait

        for key, value in self.keys(table, set(table) if isinstance(table, dict) else set(),
                                    "limit").items():  # fmt: skip
            number = isinstance(value, (int, float)) and not isinstance(value, bool)
            if not (number and math.isfinite(value)):
                self.fail(f"limit.{key}", f"expected a finite number, got {value!r}")
                self.check()
            try:
                gait = limit_gait(gait, key, sp.nsimplify(value), name=gait.name)
            except SymmechError as exc:
                self.fail(f"limit.{key}", str(exc))
                self.check()
        self.check()
        return gait

    def read(self) -> GaitFile:
        data = self.keys(self.data, _TOP_KEYS, "file")
        if data.get("format") != 1:
            self.fail("format", f"expected 1, got {data.get('format')!r}")
        if not isinstance(data.get("name"), str) or not data["name"].isidentifier():
            self.fail("name", "required, an identifier")
        self.check()
        scenes, defaults = self.scenes()
        self.check()
        modes_raw = data.get("modes")
        if not isinstance(modes_raw, dict) or not modes_raw:
            self.fail("modes", "required, a table of modes")
            self.check()
        modes = {}
        for key, raw in modes_raw.items():  # type: ignore[union-attr]
            got = self.mode(key, raw, scenes)
            if got is not None:
                modes[key] = got
        self.check()
        raw_tr = data.get("transitions")
        if not isinstance(raw_tr, list) or not raw_tr:
            self.fail("transitions", "required, an array of tables")
            self.check()
        transitions = [self.transition(i, t, modes, scenes) for i, t in enumerate(raw_tr)]  # type: ignore[arg-type]
        self.check()
        try:
            gait = Gait(data["name"], {k: m[0] for k, m in modes.items()},
                        tuple(t for t in transitions if t is not None))  # fmt: skip
        except SymmechError as exc:
            raise SceneFileError([f"{self.source}: {exc}"], path=self.source) from None
        gait = self.limits(gait, data.get("limit", {}))
        defaults = {k: v for k, v in defaults.items() if k in {p.name for p in gait.parameters}}
        section = 0
        if "section" in data:
            names = [tr.name for tr in gait.transitions]
            if data["section"] not in names:
                self.fail("section", f"{data['section']!r} is not a transition {names}")
            else:
                section = names.index(data["section"])
        guess = data.get("guess", [])
        size = 2 * gait.modes[gait.transitions[section].target].n
        numbers = isinstance(guess, list) and all(
            isinstance(x, (int, float)) and not isinstance(x, bool) for x in guess
        )
        if not (numbers and len(guess) == size):
            self.fail("guess", f"expected {size} numbers (the state just after the section)")
        self.check()
        return GaitFile(gait, defaults, section, tuple(float(x) for x in guess),
                        str(data.get("description", "")), self.path)  # fmt: skip


def read_gait(path: str | os.PathLike[str]) -> GaitFile:
    """Read the gait file ``path`` (or the built-in gait file of that name)."""
    p = Path(path)
    if not p.suffix and str(path) in builtin_gait_files():
        p = BUILTIN_DIR / f"{path}.gait.toml"
    source = str(path)
    if not p.is_file():
        raise SceneFileError([f"{source}: not a gait file (no such regular file)"], path=source)
    if p.stat().st_size > MAX_GAIT_BYTES:
        raise SceneFileError([f"{source}: longer than {MAX_GAIT_BYTES} bytes"], path=source)
    try:
        data = tomllib.loads(p.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError, RecursionError) as exc:
        raise SceneFileError([f"{source}: not a valid TOML file: {exc}"], path=source) from None
    return _Reader(p, data).read()
