"""A sweep planned: the runs of each chunk checked and prepared, and their results tabled.

:func:`prepare` turns the rows ``lo:hi`` of the grid into a
:class:`~symmech.sweep.worker.ChunkInput`, checking every run as
:func:`symmech.simulate.simulate` checks one (in the same order, with the same messages):
finite initial state, the parameters (:func:`~symmech.simulate.system.check_parameters`:
all given, finite, declared signs, restitutions in [0, 1]), ``psi >= 0`` at every wall
(a gap below ``-10 atol`` is refused) and, for a constrained scene, ``v0`` in D (a residual
within ``100 (atol + rtol |v0|)`` projected away with P by the same call ``simulate``
makes, a larger one refused).  A run that fails a check is a row with status
``"invalid"`` and the message; it is not run.

:func:`finish` decodes the info rows of the C loop (:func:`symmech.simulate.csim.decode`)
into a table of one row per run (see :data:`FIXED_COLUMNS` and the chosen outputs).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from symmech.codegen.module import NumericalError
from symmech.scene import Scene
from symmech.simulate.csim import FINISHED_CODE, INFO_HEAD, REACHED_END_CODE, decode
from symmech.simulate.hybrid import Options
from symmech.simulate.result import EVENT_KINDS, STATUSES
from symmech.simulate.system import Functions, HybridSystem, SimulationError, check_parameters
from symmech.sweep.grid import Columns
from symmech.sweep.worker import ChunkInput, LibrarySource, LoopOptions

__all__ = ["FIXED_COLUMNS", "INFO_OUTPUTS", "Plan", "Prepared", "finish", "prepare"]

#: The info row's status and reason of a run that reached t_end (the template's
#: ST_FINISHED and R_END, decoded by :func:`symmech.simulate.csim.decode`).
_FINISHED, _REACHED_END = FINISHED_CODE, REACHED_END_CODE

#: Outputs read from the C loop's statistics (entry of the info row).
INFO_OUTPUTS = {
    "rejected_steps": 12,
    "rhs_calls": 13,
    "constraint_drift": 14,
    "energy_drift": 15,
    "impact_condition": 22,
}

#: Columns of every sweep table besides the grid's and the state's (``<name>_final``).
FIXED_COLUMNS = (
    "status",
    "message",
    "t_final",
    "time_to_rest",
    "steps",
    *(f"n_{k}" for k in EVENT_KINDS),
)


@dataclass
class Plan:
    """Everything a chunk needs: the scene and its compiled system, the grid
    (``table`` (N, k) with the meaning of each column), the values no column sets, the
    loop's options and the library's source, and the outputs to compute."""

    scene: Scene
    system: HybridSystem
    parameters_of: Callable[[dict[str, float]], np.ndarray]
    columns: Columns
    table: np.ndarray
    base_params: dict[str, float]
    base_q: np.ndarray
    base_v: np.ndarray
    options: Options
    loop: LoopOptions
    source: LibrarySource
    outputs: tuple[str, ...]
    energy_conserved: bool
    expressions: dict[str, Callable[..., Any]] = field(default_factory=dict)

    @property
    def runs(self) -> int:
        return int(self.table.shape[0])

    @property
    def names(self) -> dict[str, list[str]]:
        decl = self.scene.declaration
        return {
            "q": [str(c) for c in decl.coordinates],
            "v": [str(v) for v in decl.velocities],
            "p": [str(p) for p in self.scene.parameters],
        }

    def column_names(self) -> list[str]:
        """The columns of the result table, in order (the index ``run`` aside)."""
        names = self.names
        final = [f"{s}_final" for s in names["q"] + names["v"]]
        return [
            *self.columns.names,
            *FIXED_COLUMNS[:3],
            *final,
            *FIXED_COLUMNS[3:],
            *self.outputs,
            *self.expressions,
        ]

    def states(self, lo: int, hi: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(Q0, V0, parameter values) of runs ``lo:hi``: the grid's columns over the base."""
        r = hi - lo
        Q = np.tile(self.base_q, (r, 1))
        V = np.tile(self.base_v, (r, 1))
        pnames = self.names["p"]
        base = [self.base_params.get(p, np.nan) for p in pnames]
        PV = np.tile(np.array(base, dtype=np.float64), (r, 1))
        for j in range(len(self.columns.names)):
            col = self.table[lo:hi, j]
            for target, index in ((Q, self.columns.q[j]), (V, self.columns.v[j])):
                if index >= 0:
                    target[:, index] = col
            if self.columns.params[j] >= 0:
                PV[:, self.columns.params[j]] = col
        return Q, V, PV


@dataclass
class Prepared:
    """The client's record of a prepared chunk: its rows, the runs sent (``order``: their
    positions in the chunk, in the order of the ChunkInput), the parameter values of each
    vector, and the message of every refused run."""

    index: int
    lo: int
    hi: int
    chunk: ChunkInput
    order: np.ndarray
    group: np.ndarray
    values: list[dict[str, float]]
    messages: dict[int, str]


def _groups(rows: np.ndarray, group: np.ndarray) -> list[tuple[int, np.ndarray]]:
    """The rows of each parameter vector (the generated C functions take one per call)."""
    return [(int(g), rows[group[rows] == g]) for g in np.unique(group[rows])]


def _pvector(plan: Plan, values: dict[str, float]) -> np.ndarray | None:
    """The free-flight module's parameter vector at ``values`` (None if it takes none)."""
    names = plan.system.free.parameters
    return np.array([values[k] for k in names], dtype=np.float64) if names else None


def _psi_checks(
    plan: Plan, Q: np.ndarray, rows: np.ndarray, group: np.ndarray, values: list[dict]
) -> dict[int, str]:
    """Messages of the rows whose initial configuration is on the wrong side of a wall."""
    free = plan.system.free
    t0 = plan.loop.t0
    out: dict[int, str] = {}
    for g, idx in _groups(rows, group):
        p = _pvector(plan, values[g])
        for w, wall in enumerate(plan.scene.walls):
            live = idx[[int(i) not in out for i in idx]] if out else idx
            if live.size == 0:
                break
            try:
                psi = free.psi(Q[live], p, wall=w, t=np.full(live.size, t0))
                psi = np.asarray(psi, dtype=float).reshape(-1)
            except NumericalError:
                psi = np.full(live.size, np.nan)
                for k, i in enumerate(live):
                    try:
                        psi[k] = float(free.psi(Q[i], p, wall=w, t=t0))
                    except NumericalError as exc:
                        out[int(i)] = str(exc)
            for kk in np.flatnonzero(psi < -10 * plan.options.atol):
                out.setdefault(
                    int(live[kk]),
                    f"q0 is on the wrong side of wall {wall.name!r}: psi = {float(psi[kk])!r} < 0",
                )
    return out


def _without(rows: np.ndarray, messages: dict[int, str]) -> np.ndarray:
    """``rows`` less those with a message."""
    if not messages:
        return rows
    return rows[~np.isin(rows, np.fromiter(messages, dtype=np.int64))]


def prepare(plan: Plan, index: int, lo: int, hi: int) -> Prepared:
    """Check and prepare the runs ``lo:hi`` (chunk ``index``; see the module docstring)."""
    Q, V, PV = plan.states(lo, hi)
    r = hi - lo
    messages: dict[int, str] = {}
    for what, a in (("q0", Q), ("v0", V)):
        for i in np.flatnonzero(~np.isfinite(a).all(axis=1)):
            messages.setdefault(int(i), f"{what}: every entry must be finite, got {a[i].tolist()}")
    pnames = plan.names["p"]
    rows = _without(np.arange(r, dtype=np.int64), messages)
    group = np.full(r, -1, dtype=np.int64)
    values: list[dict[str, float]] = []
    if rows.size:
        varied = sorted({i for i in plan.columns.params if i >= 0})
        if varied:
            _, first, inverse = np.unique(
                PV[rows][:, varied], axis=0, return_index=True, return_inverse=True
            )
            unique = PV[rows][first]
            group[rows] = inverse.reshape(-1)
        else:  # no column sets a parameter: one vector
            unique = PV[rows][:1]
            group[rows] = 0
        for g, u in enumerate(unique):
            try:
                values.append(check_parameters(plan.scene, dict(zip(pnames, u, strict=True))))
            except SimulationError as exc:
                values.append({})
                for i in rows[group[rows] == g]:
                    messages[int(i)] = str(exc)
        rows = _without(rows, messages)
    messages.update(_psi_checks(plan, Q, rows, group, values))
    rows = _without(rows, messages)
    if plan.scene.is_constrained and rows.size:
        fns: dict[int, Functions] = {}
        t0, opts = plan.loop.t0, plan.options
        for i in rows:
            g = int(group[i])
            if g not in fns:
                fns[g] = Functions(plan.system, values[g])
            res = fns[g].residual(None, t0, Q[i], V[i])
            allowed = 100 * (opts.atol + opts.rtol * float(np.max(np.abs(V[i]), initial=0.0)))
            if res > allowed:
                messages[int(i)] = (
                    f"v0 is not in the constraint distribution D: |mu v0| = {res:.3g} >"
                    f" {allowed:.3g}; give a velocity that satisfies the constraints"
                )
            else:
                V[i] = fns[g].project(None, t0, Q[i], V[i])
        rows = _without(rows, messages)
    order = rows[np.argsort(group[rows], kind="stable")]
    used, local = np.unique(group[order], return_inverse=True)
    starts = np.searchsorted(local.reshape(-1), np.arange(len(used) + 1)).astype(np.int64)
    P = np.array([plan.parameters_of(values[g]) for g in used]) if used.size else np.zeros((0, 1))
    Y = np.ascontiguousarray(np.hstack([Q, V])[order])
    chunk = ChunkInput(index=index, Y=Y, P=P, starts=starts)
    return Prepared(index, lo, hi, chunk, order, group, values, messages)


def _outputs_at(
    plan: Plan, prep: Prepared, t: np.ndarray, q: np.ndarray, v: np.ndarray, sent: np.ndarray
) -> dict[str, np.ndarray]:
    """The chosen outputs at the final states of the runs at positions ``sent``."""
    r = prep.hi - prep.lo
    out: dict[str, np.ndarray] = {}
    for name in plan.outputs:
        col = np.full(r, np.nan)
        if name in ("energy", "gap"):
            for g, idx in _groups(sent, prep.group):
                p = _pvector(plan, prep.values[g])
                col[idx] = _evaluate(plan, name, p, t[idx], q[idx], v[idx])
        out[name] = col
    for name, fn in plan.expressions.items():
        col = np.full(r, np.nan)
        if sent.size:
            pnames = plan.names["p"]
            pv = [np.array([prep.values[prep.group[i]][k] for i in sent]) for k in pnames]
            args = [t[sent], *q[sent].T, *v[sent].T, *pv]
            with np.errstate(all="ignore"):
                col[sent] = np.broadcast_to(np.asarray(fn(*args), dtype=float), sent.shape)
        out[name] = col
    return out


def _evaluate(
    plan: Plan, name: str, p: np.ndarray | None, t: np.ndarray, q: np.ndarray, v: np.ndarray
) -> np.ndarray:
    """``energy`` (T + V) or ``gap`` (the smallest psi over the walls, +inf without walls)
    at the states (t, q, v) with one parameter vector; NaN where the generated function
    reports a non-finite value."""
    free = plan.system.free

    def one(tt: Any, qq: np.ndarray, vv: np.ndarray) -> np.ndarray:
        if name == "energy":
            return np.asarray(free.energy(qq, vv, p, t=tt), dtype=float)
        out = np.full(np.shape(tt), np.inf)
        for w in range(len(plan.scene.walls)):
            out = np.minimum(out, np.asarray(free.psi(qq, p, wall=w, t=tt), dtype=float))
        return out

    try:
        return one(t, q, v).reshape(-1)
    except NumericalError:
        col = np.full(len(t), np.nan)
        for i in range(len(t)):
            try:
                col[i] = float(one(float(t[i]), q[i], v[i]))
            except NumericalError:
                col[i] = np.nan
        return col


#: The statuses of a sweep's runs: the simulator's, and "invalid" for a run refused by the
#: input checks; the ``status`` column of a chunk holds their indices (int8 codes), and
#: the table their names (a categorical column).
RUN_STATUSES = (*STATUSES, "invalid")
_INVALID = RUN_STATUSES.index("invalid")
_FAILED = RUN_STATUSES.index("failed")
_FINISHED_STATUS = RUN_STATUSES.index("finished")


def finish(plan: Plan, prep: Prepared, info: np.ndarray | None, error: str | None) -> dict:
    """The chunk's table (a dict of columns, ``run`` first) from the info rows of the runs
    sent (None with ``error``: the chunk failed as a whole, its runs are ``"failed"``);
    ``status`` as codes into :data:`RUN_STATUSES`."""
    r = prep.hi - prep.lo
    n = plan.scene.n
    status = np.full(r, _INVALID, dtype=np.int8)  # codes into RUN_STATUSES
    message = np.array([None] * r, dtype=object)
    t = np.full(r, np.nan)
    q = np.full((r, n), np.nan)
    v = np.full((r, n), np.nan)
    counts = np.zeros((r, len(EVENT_KINDS)), dtype=np.int64)
    steps = np.zeros(r, dtype=np.int64)
    rest = np.full(r, np.nan)
    stats = {k: np.full(r, np.nan) for k in INFO_OUTPUTS}
    for i, text in prep.messages.items():
        message[i] = text
    sent = prep.order
    if info is None:
        for i in sent:
            status[i], message[i] = _FAILED, error
        sent = np.zeros(0, dtype=np.int64)
    else:
        walls = tuple(w.name for w in plan.scene.walls)
        # a run that reached t_end decodes to ("finished", "reached t_end = ...", None):
        # only the others are decoded one by one
        status[sent] = _FINISHED_STATUS
        for row in np.flatnonzero((info[:, 0] != _FINISHED) | (info[:, 1] != _REACHED_END)):
            st, msg, acc = decode(info[row], walls, plan.options.t_end)
            i = sent[row]
            status[i] = RUN_STATUSES.index(st)
            message[i] = None if st == "finished" else msg
            rest[i] = np.nan if acc is None else acc
        t[sent] = info[:, 21]
        q[sent] = info[:, INFO_HEAD : INFO_HEAD + n]
        v[sent] = info[:, INFO_HEAD + n : INFO_HEAD + 2 * n]
        counts[sent] = info[:, 17:21].astype(np.int64)
        steps[sent] = info[:, 11].astype(np.int64)
        for key, j in INFO_OUTPUTS.items():
            stats[key][sent] = info[:, j]
        if not plan.energy_conserved:
            stats["energy_drift"][sent] = np.nan
    cols: dict[str, Any] = {"run": np.arange(prep.lo, prep.hi, dtype=np.int64)}
    for j, name in enumerate(plan.columns.names):
        cols[name] = plan.table[prep.lo : prep.hi, j]
    cols["status"] = status
    cols["message"] = message
    cols["t_final"] = t
    names = plan.names
    for k, s in enumerate(names["q"]):
        cols[f"{s}_final"] = q[:, k]
    for k, s in enumerate(names["v"]):
        cols[f"{s}_final"] = v[:, k]
    cols["time_to_rest"] = rest
    cols["steps"] = steps
    for k, kind in enumerate(EVENT_KINDS):
        cols[f"n_{kind}"] = counts[:, k]
    outs = _outputs_at(plan, prep, t, q, v, sent)
    for name in plan.outputs:
        cols[name] = stats[name] if name in INFO_OUTPUTS else outs[name]
    for name in plan.expressions:
        cols[name] = outs[name]
    return cols
