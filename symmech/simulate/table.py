"""A run's states as tables and files: sampling the dense output, pandas frames, and files
that read back equal.

:func:`sample` evaluates a result's continuous output (:meth:`SimulationResult.sol`) at
chosen times and puts every event inside them at its exact time twice, the state before it
``(t_e, q_e, v_minus)`` and after it ``(t_e, q_e, v_plus)``: a plot or an animation sampled
so shows each jump of the velocity as a vertical step, never as a slope drawn across it.

:func:`to_frame` is the table of the accepted steps (or of :func:`sample`'s times): ``t``,
the coordinates, the velocities, ``energy`` (T + V) and a ``gap[wall]`` column per wall
(psi, from the run's compiled functions), and ``event``/``wall`` naming the events at a
row's time.  Its ``attrs`` hold the status, message, statistics and parameters.

:func:`save` writes that table with everything else a result holds, by the file's suffix:

* ``.csv``: a first line ``# symmech-result {JSON}`` (status, message, statistics,
  parameters, names, events), then the table (floats written as ``repr``, the shortest
  text that reads back to the same bits; ``pandas.read_csv(path, comment="#")`` reads it);
* ``.parquet``: the table, the same JSON in the schema's metadata under ``symmech-result``;
* ``.npz``: the arrays as they are, the JSON as the string array ``meta``.

:func:`load_result` reads any of them back into a :class:`SimulationResult` whose steps,
events, status, message, statistics and parameters equal the saved run's (it has no
continuous output: the interpolants of the steps are not stored).  Every file goes through
:func:`symmech.files.write_atomic`.  pandas (frames) and pyarrow (Parquet) are optional
dependencies (``pip install 'symmech[plot]'``); CSV and NPZ need neither.
"""

from __future__ import annotations

import csv
import io
import json
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from symmech.files import write_atomic
from symmech.simulate.protocol import EVENT_KINDS
from symmech.simulate.result import EventTable, SimulationResult
from symmech.simulate.system import SimulationError

__all__ = [
    "FORMATS",
    "FRAME_FORMATS",
    "META_KEY",
    "Samples",
    "batch_frame",
    "events_frame",
    "load_result",
    "observables",
    "sample",
    "save",
    "save_frame",
    "to_frame",
]

#: File suffixes :func:`save` writes and :func:`load_result` reads.
FORMATS = (".csv", ".parquet", ".npz")
#: File suffixes :func:`save_frame` writes (a table of many runs: a batch, a sweep).
FRAME_FORMATS = (".csv", ".parquet")
#: The key of the JSON that holds all but the table (CSV first line, Parquet metadata).
META_KEY = "symmech-result"
_VERSION = 1
_BEFORE, _PLAIN, _AFTER = -1, 0, 1


@dataclass(frozen=True)
class Samples:
    """States at chosen times: ``t`` (m,), ``q`` and ``v`` (m, n); ``event[i]`` is the index
    of the event whose instant row i is (-1 for a plain sample), ``side[i]`` is -1 for the
    state before it, +1 after it, 0 for a plain sample."""

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    event: np.ndarray
    side: np.ndarray


def _needs(module: str, what: str) -> Any:
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError as exc:
        raise SimulationError(
            f"{what} needs {module} ({exc}): python3 -m pip install 'symmech[plot]'"
        ) from None


def sample(res: SimulationResult, ts: Any, *, events: bool = True) -> Samples:
    """The states of ``res`` at the times ``ts`` (sorted, duplicates dropped) from its
    continuous output and, when ``events``, each event with ``min(ts) <= t_e <= max(ts)`` at
    its time as two rows, before and after (module docstring); a time of ``ts`` equal to an
    event's is given by the event's two rows.  Raises :class:`SimulationError` for times that
    are not finite or outside the run, or a result without continuous output."""
    times = np.unique(np.asarray(ts, dtype=float).ravel())
    if times.size == 0:
        raise SimulationError("sample: no times given")
    if not np.all(np.isfinite(times)):
        raise SimulationError("sample: times must be finite numbers")
    evs = list(res.events) if events else []
    inside = [k for k, e in enumerate(evs) if times[0] <= e.time <= times[-1]]
    at_event = np.isin(times, [evs[k].time for k in inside])
    plain = times[~at_event]
    try:
        states = res.sol(plain) if plain.size else np.empty((0, 2 * res.n))
    except ValueError as exc:
        raise SimulationError(f"sample: {exc}") from None
    n = res.n
    t_rows = [plain]
    q_rows, v_rows = [states[:, :n]], [states[:, n:]]
    ids = [np.full(plain.size, -1)]
    sides = [np.full(plain.size, _PLAIN)]
    for k in inside:
        e = evs[k]
        t_rows.append(np.array([e.time, e.time]))
        q_rows.append(np.vstack([e.q, e.q]))
        v_rows.append(np.vstack([e.v_minus, e.v_plus]))
        ids.append(np.array([k, k]))
        sides.append(np.array([_BEFORE, _AFTER]))
    t, event, side = np.concatenate(t_rows), np.concatenate(ids), np.concatenate(sides)
    order = np.lexsort((side, event, t))  # by time, then event, before ahead of after
    return Samples(
        t=t[order],
        q=np.vstack(q_rows)[order],
        v=np.vstack(v_rows)[order],
        event=event[order],
        side=side[order],
    )


def observables(
    res: SimulationResult, t: np.ndarray, q: np.ndarray, v: np.ndarray
) -> dict[str, np.ndarray]:
    """``energy`` (T + V) and ``gap[wall]`` (psi of each wall) at the rows ``(t, q, v)``:
    from the run's compiled functions, or, for a result read from a file, the stored columns
    when the rows are its steps; empty when neither is at hand."""
    fns = res.functions
    if fns is not None:
        rows = range(len(t))
        out = {"energy": np.array([fns.energy(t[i], q[i], v[i]) for i in rows], dtype=float)}
        gaps = np.array([fns.gaps(t[i], q[i]) for i in rows], dtype=float).reshape(len(t), -1)
        for w, name in enumerate(res.wall_names):
            out[f"gap[{name}]"] = gaps[:, w]
        return out
    if res.stored and len(t) == len(res.t) and np.array_equal(t, res.t):
        return dict(res.stored)
    return {}


def _event_labels(res: SimulationResult, t: np.ndarray) -> tuple[list[str], list[str]]:
    """Per row of times t, the kinds and wall names of the events at that time (joined by
    "+", empty where none)."""
    by_time: dict[float, list[Any]] = {}
    for e in res.events:
        by_time.setdefault(float(e.time), []).append(e)
    kinds, walls = [], []
    for ti in t:
        here = by_time.get(float(ti), [])
        kinds.append("+".join(e.kind for e in here))
        walls.append("+".join(e.wall_name for e in here))
    return kinds, walls


def _columns(res: SimulationResult, ts: Any = None) -> dict[str, np.ndarray | list[str]]:
    if ts is None:
        t, q, v = np.asarray(res.t, float), np.asarray(res.q, float), np.asarray(res.v, float)
        kinds, walls = _event_labels(res, t)
        side = None
    else:
        s = sample(res, ts)
        t, q, v = s.t, s.q, s.v
        evs = list(res.events)
        kinds = [evs[k].kind if k >= 0 else "" for k in s.event]
        walls = [evs[k].wall_name if k >= 0 else "" for k in s.event]
        side = [{_BEFORE: "before", _AFTER: "after"}.get(int(x), "") for x in s.side]
    cols: dict[str, np.ndarray | list[str]] = {"t": t}
    for i, name in enumerate(res.coordinates):
        cols[name] = q[:, i]
    for i, name in enumerate(res.velocities):
        cols[name] = v[:, i]
    cols.update(observables(res, t, q, v))
    cols["event"], cols["wall"] = kinds, walls
    if side is not None:
        cols["side"] = side
    return cols


def to_frame(res: SimulationResult, ts: Any = None) -> Any:
    """The run as a pandas DataFrame (module docstring); with ``ts``, the rows of
    :func:`sample` and a ``side`` column (``before``/``after`` at an event)."""
    pd = _needs("pandas", "to_frame")
    frame = pd.DataFrame(_columns(res, ts))
    frame.attrs.update(_meta(res))
    return frame


def events_frame(res: SimulationResult) -> Any:
    """The events as a pandas DataFrame: ``time``, ``wall`` (index), ``wall_name``,
    ``kind``, ``energy_change``, ``normal_speed``, then ``q[name]``, ``v_minus[name]`` and
    ``v_plus[name]`` per coordinate."""
    pd = _needs("pandas", "events_frame")
    return pd.DataFrame([_event_record(res, e) for e in res.events], columns=_event_keys(res))


def _event_keys(res: SimulationResult) -> list[str]:
    keys = ["time", "wall", "wall_name", "kind", "energy_change", "normal_speed"]
    keys += [f"q[{c}]" for c in res.coordinates]
    keys += [f"v_minus[{c}]" for c in res.velocities]
    return keys + [f"v_plus[{c}]" for c in res.velocities]


def _event_record(res: SimulationResult, e: Any) -> dict[str, Any]:
    rec: dict[str, Any] = {
        "time": float(e.time),
        "wall": int(e.wall),
        "wall_name": e.wall_name,
        "kind": e.kind,
        "energy_change": float(e.energy_change),
        "normal_speed": float(e.normal_speed),
    }
    for what, names in (("q", res.coordinates), ("v_minus", res.velocities)):
        rec.update({f"{what}[{c}]": float(x) for c, x in zip(names, getattr(e, what), strict=True)})
    rec.update({f"v_plus[{c}]": float(x) for c, x in zip(res.velocities, e.v_plus, strict=True)})
    return rec


def _meta(res: SimulationResult) -> dict[str, Any]:
    """Everything but the table, as JSON-ready values (floats exact: JSON writes repr)."""
    acc = res.accumulation_time
    return {
        "format": META_KEY,
        "version": _VERSION,
        "scene": None if res.scene is None else str(res.scene.name),
        "status": res.status,
        "message": res.message,
        "stats": {k: _plain(v) for k, v in res.stats.items()},
        "params": dict(res.params),
        "accumulation_time": None if acc is None else float(acc),
        "coordinates": list(res.coordinates),
        "velocities": list(res.velocities),
        "walls": list(res.wall_names),
        "events": [_event_record(res, e) for e in res.events],
    }


def _plain(value: Any) -> Any:
    """A statistic as a JSON value (NumPy scalars as Python numbers)."""
    if isinstance(value, np.generic):
        return value.item()
    return value


def save(res: SimulationResult, path: str | os.PathLike[str]) -> Path:
    """Write ``res`` to ``path`` as CSV, Parquet or NPZ by its suffix (module docstring)."""
    suffix = Path(path).suffix.lower()
    if suffix not in FORMATS:
        raise SimulationError(
            f"save {os.fspath(path)!r}: unknown file type {suffix or '(none)'!r}; expected one"
            f" of {', '.join(FORMATS)}"
        )
    meta = json.dumps(_meta(res))
    cols = _columns(res)
    if suffix == ".npz":
        arrays: dict[str, Any] = {
            k: np.asarray(v) for k, v in cols.items() if k not in ("event", "wall")
        }
        arrays["meta"] = np.array(meta)
        return write_atomic(path, lambda fh: np.savez(fh, **arrays))
    if suffix == ".csv":
        return write_atomic(path, lambda fh: fh.write(_csv_text(meta, cols).encode()))
    pa = _needs("pyarrow", "writing .parquet")
    pq = _needs("pyarrow.parquet", "writing .parquet")
    table = pa.table({k: pa.array(v) for k, v in cols.items()})
    table = table.replace_schema_metadata({META_KEY: meta})
    return write_atomic(path, lambda fh: pq.write_table(table, fh))


def _csv_text(meta: str, cols: dict[str, Any]) -> str:
    """The CSV file: the JSON line, the header, the rows (floats as ``repr``: the shortest
    text that reads back to the same float)."""
    out = io.StringIO()
    out.write(f"# {META_KEY} {meta}\n")
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(cols)
    columns = [
        [repr(float(x)) for x in c] if isinstance(c, np.ndarray) else list(c) for c in cols.values()
    ]
    writer.writerows(zip(*columns, strict=True))
    return out.getvalue()


def batch_frame(
    batch: Any, coordinates: Sequence[str] | None = None, velocities: Sequence[str] | None = None
) -> Any:
    """A :class:`~symmech.simulate.batch.BatchResult` as a pandas DataFrame, one row per run
    (index ``run``): the final ``t``, coordinates and velocities (named ``q0, q1, ...`` and
    ``q0_dot, ...`` unless given), ``status``, ``message``, a count per event kind,
    ``accumulation_time`` and ``steps``."""
    pd = _needs("pandas", "to_frame")
    n = batch.q.shape[1]
    coordinates = list(coordinates or [f"q{i}" for i in range(n)])
    velocities = list(velocities or [f"{c}_dot" for c in coordinates])
    if len(coordinates) != n or len(velocities) != n:
        raise SimulationError(f"to_frame: expected {n} coordinate and velocity names")
    cols: dict[str, Any] = {"t": batch.t}
    cols.update({c: batch.q[:, i] for i, c in enumerate(coordinates)})
    cols.update({c: batch.v[:, i] for i, c in enumerate(velocities)})
    cols["status"] = list(batch.statuses)
    cols["message"] = list(batch.messages)
    cols.update({kind: batch.events[:, k] for k, kind in enumerate(batch.event_kinds)})
    cols["accumulation_time"] = batch.accumulation_time
    cols["steps"] = batch.steps
    frame = pd.DataFrame(cols)
    frame.index.name = "run"
    return frame


def save_frame(frame: Any, path: str | os.PathLike[str]) -> Path:
    """Write a table of runs (:func:`batch_frame`, a sweep's DataFrame) as CSV or Parquet
    by the suffix, through :func:`symmech.files.write_atomic`; ``pandas.read_csv(path,
    index_col=0)`` or ``pandas.read_parquet(path)`` reads it back."""
    suffix = Path(path).suffix.lower()
    if suffix not in FRAME_FORMATS:
        raise SimulationError(
            f"save {os.fspath(path)!r}: unknown file type {suffix or '(none)'!r}; expected one"
            f" of {', '.join(FRAME_FORMATS)}"
        )
    if suffix == ".csv":
        return write_atomic(path, lambda fh: fh.write(frame.to_csv().encode()))
    _needs("pyarrow", "writing .parquet")
    return write_atomic(path, lambda fh: frame.to_parquet(fh))


def load_result(path: str | os.PathLike[str]) -> SimulationResult:
    """The run saved at ``path`` by :func:`save` (module docstring).  A file that is not one
    raises :class:`SimulationError` naming it and the reason."""
    where = os.fspath(path)
    suffix = Path(path).suffix.lower()
    if suffix not in FORMATS:
        raise SimulationError(f"{where}: not a saved run (expected {', '.join(FORMATS)})")
    try:
        meta, cols = _read(path, suffix)
        return _result(meta, cols)
    except (KeyError, TypeError, ValueError, IndexError) as exc:
        raise SimulationError(f"{where}: not a run saved by symmech ({exc})") from None


def _read(path: str | os.PathLike[str], suffix: str) -> tuple[dict, dict[str, np.ndarray]]:
    if suffix == ".npz":
        with np.load(path, allow_pickle=False) as data:
            cols = {k: data[k] for k in data.files if k != "meta"}
            return json.loads(str(data["meta"])), cols
    if suffix == ".csv":
        with open(path, encoding="utf-8", newline="") as fh:
            first = fh.readline()
            prefix = f"# {META_KEY} "
            if not first.startswith(prefix):
                raise ValueError(f"its first line does not start with {prefix.strip()!r}")
            rows = list(csv.reader(fh))
        header, body = rows[0], rows[1:]
        text = {"event", "wall", "side"}
        cols = {
            name: np.array([row[j] for row in body], dtype=object if name in text else float)
            for j, name in enumerate(header)
        }
        return json.loads(first[len(prefix) :]), cols
    pq = _needs("pyarrow.parquet", "reading .parquet")
    table = pq.read_table(path)
    raw = (table.schema.metadata or {}).get(META_KEY.encode())
    if raw is None:
        raise ValueError(f"no {META_KEY!r} metadata")
    cols = {k: table.column(k).to_numpy(zero_copy_only=False) for k in table.column_names}
    return json.loads(raw), cols


def _result(meta: dict, cols: dict[str, np.ndarray]) -> SimulationResult:
    if meta.get("format") != META_KEY or meta.get("version") != _VERSION:
        raise ValueError(f"format {meta.get('format')!r} version {meta.get('version')!r}")
    coords, vels, walls = meta["coordinates"], meta["velocities"], meta["walls"]
    n = len(coords)
    t = np.asarray(cols["t"], dtype=float)
    q = np.column_stack([cols[c] for c in coords]).astype(float) if n else np.empty((t.size, 0))
    v = np.column_stack([cols[c] for c in vels]).astype(float) if n else np.empty((t.size, 0))
    rows, ids = [], []
    for rec in meta["events"]:
        row = [rec["time"], rec["energy_change"], rec["normal_speed"]]
        row += [rec[f"q[{c}]"] for c in coords]
        row += [rec[f"v_minus[{c}]"] for c in vels] + [rec[f"v_plus[{c}]"] for c in vels]
        rows.append(row)
        ids.append([int(rec["wall"]), EVENT_KINDS.index(rec["kind"])])
    table = EventTable(
        np.array(rows, dtype=float).reshape(len(rows), 3 + 3 * n),
        np.array(ids, dtype=int).reshape(len(ids), 2),
        walls,
        n,
    )
    stored_keys = ["energy"] + [f"gap[{w}]" for w in walls]
    return SimulationResult(
        t=t,
        q=q,
        v=v,
        events=table,
        status=str(meta["status"]),
        message=str(meta["message"]),
        stats=dict(meta["stats"]),
        n=n,
        accumulation_time=meta["accumulation_time"],
        params={str(k): float(x) for k, x in meta["params"].items()},
        coordinates=tuple(coords),
        velocities=tuple(vels),
        wall_names=tuple(walls),
        stored={k: np.asarray(cols[k], dtype=float) for k in stored_keys if k in cols},
    )
