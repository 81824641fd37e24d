"""The ``[[drawing]]`` tables of a scene file: how the scene is drawn.

Each table is one shape of :mod:`symmech.declaration.drawing`, named by ``shape`` and
placed by expressions in the coordinates, the parameters and t (no velocities)::

    [[drawing]]
    shape = "ellipse"            # point: at; segment: start, end;
    center = ["x", "y"]          # disc: center, radius, angle (optional);
    axes = ["a", "b"]            # ellipse: center, axes = [a, b], angle;
    angle = "theta"              # wall: point, normal (a line; normal into the free side)

At most :data:`MAX_SHAPES` shapes; every problem is reported with its line like any other
field's.
"""

from __future__ import annotations

from typing import Any

import sympy as sp

from symmech.declaration.drawing import SHAPES, Drawing
from symmech.errors import SceneError

__all__ = ["DRAWING_KEYS", "MAX_SHAPES", "read_drawing"]

#: Largest number of shapes of a drawing.
MAX_SHAPES = 100
#: The keys of each shape's table (besides ``shape``): (name, number of components or 0
#: for a scalar, required).
DRAWING_KEYS: dict[str, tuple[tuple[str, int, bool], ...]] = {
    "point": (("at", 2, True),),
    "segment": (("start", 2, True), ("end", 2, True)),
    "disc": (("center", 2, True), ("radius", 0, True), ("angle", 0, False)),
    "ellipse": (("center", 2, True), ("axes", 2, True), ("angle", 0, False)),
    "wall": (("point", 2, True), ("normal", 2, True)),
}


def read_drawing(reader: Any) -> Drawing | None:
    """The drawing of the file ``reader`` reads (a :class:`~symmech.scenefile.reader.Reader`
    after its coordinates and parameters), or None without ``[[drawing]]``; problems are
    recorded on the reader."""
    raw = reader.data.get("drawing")
    if raw is None:
        return None
    where = reader.line(None, "drawing") or reader.loc.table("drawing")
    if not isinstance(raw, list) or not all(isinstance(s, dict) for s in raw):
        reader.fail("expected an array of tables ([[drawing]] sections)", "drawing", where)
        return None
    if len(raw) > MAX_SHAPES:
        reader.fail(f"{len(raw)} shapes (limit {MAX_SHAPES})", "drawing", where)
        return None
    table = {k: e for k, e in reader.table.items() if e not in reader.velocity_like}
    shapes = []
    for k, spec in enumerate(raw):
        shape = _shape(reader, spec, k, table)
        if shape is not None:
            shapes.append(shape)
    return Drawing(shapes) if len(shapes) == len(raw) else None


def _shape(reader: Any, spec: dict, k: int, table: dict[str, sp.Expr]) -> Any:
    label = f"drawing[{k}]"
    sline = reader.loc.table("drawing", k)
    kind = spec.get("shape")
    if kind not in DRAWING_KEYS:
        reader.fail(
            f"shape must be one of {', '.join(DRAWING_KEYS)}, got {str(kind)[:40]!r}",
            f"{label}.shape",
            reader.line("drawing", "shape", k) or sline,
        )
        return None
    keys = DRAWING_KEYS[kind]
    reader.check_keys(spec, ("shape", *(key for key, _, _ in keys)), label, "drawing", k)
    values: dict[str, Any] = {}
    for key, size, required in keys:
        line = reader.line("drawing", key, k)
        if key not in spec:
            if required:
                reader.fail(f"required key {key!r} is missing", f"{label}.{key}", sline)
                return None
            continue
        if size:
            got = reader.expression_array(spec[key], size, f"{label}.{key}", line, table, key)
        else:
            got = reader.expression(spec[key], f"{label}.{key}", line, table)
        if got is None:
            return None
        values[key] = got
    if kind == "ellipse":
        values["a"], values["b"] = values.pop("axes")
    try:
        return SHAPES[kind](**values)
    except SceneError as exc:
        reader.fail(str(exc), label, sline)
        return None
