"""The grid of a sweep: which quantity each column sets, and the N runs it describes.

A grid is a table of N rows, one run each, given as a mapping of equal-length 1-D arrays
(the columns, zipped: row i takes entry i of every column), the :func:`product` of ranges
(every combination), or a pandas ``DataFrame``.  A column is named by what it sets:

* a parameter of the scene (``alpha``, ``m``);
* an initial coordinate: ``q0[i]`` or the coordinate's name followed by ``0`` (``theta0``
  for coordinate ``theta``);
* an initial velocity: ``v0[i]`` or the velocity's name followed by ``0`` (``thetadot0``
  for ``thetadot``; the quasi-velocities of a scene declared with a frame).

What no column sets comes from the sweep's ``params``, ``q0`` and ``v0``.  Unknown columns,
two columns setting the same quantity, and a name that could mean both a parameter and an
initial value are refused with a :class:`~symmech.simulate.SimulationError` naming them.
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from symmech.scene import Scene
from symmech.simulate.parameters import real_values
from symmech.simulate.system import SimulationError

__all__ = ["Columns", "product", "read_grid", "resolve_columns"]

_INDEXED = re.compile(r"^(q0|v0)\[(\d+)\]$")


def product(**ranges: Any) -> dict[str, np.ndarray]:
    """Every combination of the given ranges as a zipped grid (a dict of equal-length
    arrays): ``product(alpha=[0.5, 1], theta0=[0, 1, 2])`` has 6 rows, the first name
    varying slowest (row-major, as ``itertools.product``).

    >>> g = product(alpha=[0.5, 1.0], theta0=[0.0, 1.0, 2.0])
    >>> g["alpha"].tolist(), g["theta0"].tolist()
    ([0.5, 0.5, 0.5, 1.0, 1.0, 1.0], [0.0, 1.0, 2.0, 0.0, 1.0, 2.0])
    """
    if not ranges:
        raise SimulationError("product: give at least one range, e.g. product(alpha=[0.5, 1])")
    axes = {name: _column(values, name) for name, values in ranges.items()}
    rows = list(itertools.product(*axes.values()))
    table = np.array(rows, dtype=np.float64).reshape(len(rows), len(axes))
    return {name: table[:, j].copy() for j, name in enumerate(axes)}


def _column(values: object, name: str) -> np.ndarray:
    """``values`` as a non-empty 1-D float64 array (the column ``name``)."""
    a = real_values(values, f"grid column {name!r}")
    if a.ndim != 1 or a.size == 0:
        raise SimulationError(
            f"grid column {name!r}: expected a non-empty 1-D array, got shape {a.shape}"
        )
    return a.copy()


def read_grid(grid: object) -> tuple[tuple[str, ...], np.ndarray]:
    """The column names and the (N, k) float64 table of ``grid`` (a mapping of 1-D arrays
    or a pandas DataFrame)."""
    if type(grid).__module__.split(".")[0] == "pandas" and hasattr(grid, "columns"):
        frame: Any = grid
        mapping: Mapping[Any, Any] = {c: frame[c].to_numpy() for c in frame.columns}
        if len(set(map(str, frame.columns))) != len(frame.columns):
            raise SimulationError(f"grid: repeated column names in {list(frame.columns)}")
    elif isinstance(grid, Mapping):
        mapping = grid
    else:
        raise SimulationError(
            "grid: expected a dict of equal-length arrays, sweep.product(...) or a pandas"
            f" DataFrame, got {type(grid).__name__}"
        )
    if not mapping:
        raise SimulationError("grid: no columns")
    bad = [repr(k) for k in mapping if not isinstance(k, str)]
    if bad:
        raise SimulationError(f"grid: column names must be strings, got {', '.join(bad)}")
    columns = {name: _column(values, name) for name, values in mapping.items()}
    lengths = {name: len(a) for name, a in columns.items()}
    if len(set(lengths.values())) != 1:
        raise SimulationError(f"grid: the columns differ in length: {lengths}")
    names = tuple(columns)
    return names, np.column_stack([columns[k] for k in names])


@dataclass(frozen=True)
class Columns:
    """What each grid column sets: ``params[j]`` is the index of the scene parameter set
    by column j (or -1), ``q[j]`` and ``v[j]`` the index of the initial coordinate or
    velocity (or -1)."""

    names: tuple[str, ...]
    params: tuple[int, ...]
    q: tuple[int, ...]
    v: tuple[int, ...]


def resolve_columns(scene: Scene, names: tuple[str, ...]) -> Columns:
    """Map every column name to the quantity it sets (see the module docstring)."""
    decl = scene.declaration
    params = [str(p) for p in scene.parameters]
    coords = [str(c) for c in decl.coordinates]
    vels = [str(v) for v in decl.velocities]
    problems: list[str] = []
    targets: dict[tuple[str, int], str] = {}
    out: dict[str, list[int]] = {"p": [], "q": [], "v": []}
    for name in names:
        meanings: list[tuple[str, int]] = []
        if name in params:
            meanings.append(("p", params.index(name)))
        m = _INDEXED.match(name)
        if m:
            kind, i = m.group(1)[0], int(m.group(2))
            if i >= scene.n:
                problems.append(
                    f"{name!r}: the scene has {scene.n} coordinates (0 to {scene.n - 1})"
                )
                meanings.append(("bad", 0))
            else:
                meanings.append((kind, i))
        if name.endswith("0") and name[:-1] in coords:
            meanings.append(("q", coords.index(name[:-1])))
        if name.endswith("0") and name[:-1] in vels:
            meanings.append(("v", vels.index(name[:-1])))
        if not meanings:
            hint = ""
            if name in coords or name in vels:
                hint = f" (the initial value of {name} is the column {name + '0'!r})"
            problems.append(f"{name!r} is not a parameter nor an initial value{hint}")
            continue
        if len(meanings) > 1:
            problems.append(f"{name!r} is ambiguous: it names a parameter and an initial value")
            continue
        kind, i = meanings[0]
        if kind == "bad":
            continue
        key = (kind, i)
        if key in targets:
            problems.append(f"{targets[key]!r} and {name!r} set the same quantity")
        targets[key] = name
        for k in out:
            out[k].append(i if k == kind else -1)
    if problems:
        raise SimulationError(
            "grid columns: "
            + "; ".join(problems)
            + f" (parameters {params}; initial values q0[i], v0[i] or"
            f" {[c + '0' for c in coords]}, {[v + '0' for v in vels]})"
        )
    return Columns(names, tuple(out["p"]), tuple(out["q"]), tuple(out["v"]))
