"""A sweep planned: the runs of each chunk checked and prepared, and their results tabled.

:func:`prepare` turns a chunk (its grid rows, runs ``lo:lo + len(rows)``) into a
:class:`~symmech.sweep.worker.ChunkInput`, checking every run as
:func:`symmech.simulate.simulate` checks one (in the same order, with the same messages):
finite initial state, the parameters (:func:`~symmech.simulate.parameters.check_parameters`:
all given, finite, declared signs, restitutions in [0, 1]), ``psi >= 0`` at every wall
(a gap below ``-10 atol`` is refused) and, for a constrained scene, ``v0`` in D (a residual
within ``100 (atol + rtol |v0|)`` projected away with P by the same call ``simulate``
makes, a larger one refused).  A run that fails a check is a row with status
``"invalid"`` and the message; it is not run.

:func:`finish` decodes the info rows of the C loop (:func:`symmech.simulate.csim.decode`)
into a table of one row per run (see :data:`FIXED_COLUMNS` and the chosen outputs), and
:func:`chunk_table` does the three steps for one chunk and returns its Arrow table.

A :class:`Plan` pickles to plain data: the scene (its declaration), the generated source
of its free-flight functions (the checks and outputs call them) and of the simulator, and
the sweep's options.  The process that runs a chunk, the client's threads or a Dask worker,
loads that code once per plan (:attr:`Plan.system`), so the whole life of a chunk runs where
the chunk runs and a client only collects tables: its work per run does not grow with the
cluster.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import sympy as sp

from symmech.codegen.generate import GeneratedCode
from symmech.codegen.module import NumericalError
from symmech.declaration.symbols import t as TIME
from symmech.scene import Scene
from symmech.simulate.csim import (
    EVENT_COUNTS,
    FINISHED_CODE,
    REACHED_END_CODE,
    decode,
    info_entry,
    parameter_vector,
)
from symmech.simulate.functions import Functions
from symmech.simulate.hybrid import Options
from symmech.simulate.parameters import check_parameters
from symmech.simulate.protocol import INFO, INFO_HEAD, slot
from symmech.simulate.result import EVENT_KINDS, STATUSES
from symmech.simulate.system import FREE, HybridSystem, SimulationError
from symmech.sweep.grid import Columns
from symmech.sweep.worker import ChunkInput, LibrarySource, LoopOptions, run_chunk

__all__ = [
    "FIXED_COLUMNS",
    "INFO_OUTPUTS",
    "RUN_STATUSES",
    "Plan",
    "Prepared",
    "chunk_table",
    "failed_table",
    "finish",
    "prepare",
]

#: The info row's status and reason of a run that reached t_end (the template's
#: ST_FINISHED and R_END, decoded by :func:`symmech.simulate.csim.decode`).
_FINISHED, _REACHED_END = FINISHED_CODE, REACHED_END_CODE
_STATUS, _REASON = slot(INFO, "status"), slot(INFO, "reason")

#: Outputs read from the C loop's statistics (entry of the info row).
INFO_OUTPUTS = {
    name: slot(INFO, name)
    for name in (
        "rejected_steps",
        "rhs_calls",
        "constraint_drift",
        "energy_drift",
        "impact_condition",
    )
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


_LIVE_LOCK = threading.RLock()  # re-entrant: a build may need another live object


@dataclass
class Plan:
    """Everything a chunk needs, as plain data (see the module docstring): the scene, the
    generated code of its free flight (``free_code``) and the simulator's source, the
    simulator's parameter ``layout``, the meaning of the grid's columns, the values no
    column sets, the loop's options, the outputs and the expressions (sympy, in t, the
    coordinates, velocities and parameters) to compute.  The grid's rows travel with each
    chunk, not with the plan."""

    scene: Scene
    free_code: GeneratedCode
    layout: tuple[tuple[str, ...], ...]
    columns: Columns
    base_params: dict[str, float]
    base_q: np.ndarray
    base_v: np.ndarray
    options: Options
    loop: LoopOptions
    source: LibrarySource
    outputs: tuple[str, ...]
    energy_conserved: bool
    expressions: dict[str, sp.Expr] = field(default_factory=dict)
    strategy: str = "auto"
    definitions: dict[Any, Any] = field(default_factory=dict)
    #: this process's loaded objects (the system, the expressions' functions, the schema);
    #: never pickled
    _live: dict[str, Any] = field(default_factory=dict, repr=False, compare=False)

    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        state["_live"] = {}
        return state

    def attach(self, system: HybridSystem) -> Plan:
        """Use ``system`` (already loaded in this process) as :attr:`system`."""
        self._live["system"] = system
        return self

    def _loaded(self, key: str, build: Callable[[], Any]) -> Any:
        with _LIVE_LOCK:
            hit = self._live.get(key)
            if hit is None:
                hit = self._live[key] = build()
        return hit

    @property
    def system(self) -> HybridSystem:
        """The free-flight functions of the scene, loaded in this process once (contact
        modes, which no check calls, would be generated on first use)."""

        def build() -> HybridSystem:
            system = HybridSystem(self.scene, "c", self.strategy, dict(self.definitions))
            system.modules[FREE] = self.free_code.load()
            return system

        return self._loaded("system", build)

    def expression_functions(self) -> dict[str, Callable[..., Any]]:
        """Each expression as a NumPy function of (t, q..., v..., parameters...)."""

        def build() -> dict[str, Callable[..., Any]]:
            decl = self.scene.declaration
            args = [TIME, *decl.coordinates, *decl.velocities, *self.scene.parameters]
            return {k: sp.lambdify(args, e, modules="numpy") for k, e in self.expressions.items()}

        return self._loaded("expressions", build)

    def schema(self) -> Any:
        """The Arrow schema of the result table (``status`` a dictionary column)."""
        return self._loaded("schema", lambda: _schema(self))

    def parameters_of(self, values: dict[str, float]) -> np.ndarray:
        """The simulator library's parameter vector at ``values``."""
        return parameter_vector(self.layout, values)

    @property
    def names(self) -> dict[str, list[str]]:
        """The names of the coordinates, velocities and parameters (``q``, ``v``, ``p``)."""
        decl = self.scene.declaration

        def build() -> dict[str, list[str]]:
            return {
                "q": [str(c) for c in decl.coordinates],
                "v": [str(v) for v in decl.velocities],
                "p": [str(p) for p in self.scene.parameters],
            }

        return self._loaded("names", build)

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

    def states(self, grid: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(Q0, V0, parameter values) of the runs whose grid rows are ``grid``: the grid's
        columns over the base."""
        r = grid.shape[0]
        Q = np.tile(self.base_q, (r, 1))
        V = np.tile(self.base_v, (r, 1))
        pnames = self.names["p"]
        base = [self.base_params.get(p, np.nan) for p in pnames]
        PV = np.tile(np.array(base, dtype=np.float64), (r, 1))
        for j in range(len(self.columns.names)):
            col = grid[:, j]
            for target, index in ((Q, self.columns.q[j]), (V, self.columns.v[j])):
                if index >= 0:
                    target[:, index] = col
            if self.columns.params[j] >= 0:
                PV[:, self.columns.params[j]] = col
        return Q, V, PV


def _schema(plan: Plan) -> Any:
    import pyarrow as pa

    ints = {"steps", *(c for c in FIXED_COLUMNS if c.startswith("n_"))}
    fields = [pa.field("run", pa.int64())]
    for name in plan.column_names():
        if name == "status":  # categorical: names of RUN_STATUSES
            kind = pa.dictionary(pa.int8(), pa.string())
        else:
            kind = pa.string() if name == "message" else pa.float64()
        fields.append(pa.field(name, pa.int64() if name in ints else kind))
    return pa.schema(fields)


@dataclass
class Prepared:
    """A prepared chunk: its runs ``lo:hi`` and their ``grid`` rows, the runs sent
    (``order``: their positions in the chunk, in the order of the ChunkInput), the
    parameter values of each vector, and the message of every refused run."""

    index: int
    lo: int
    hi: int
    grid: np.ndarray
    chunk: ChunkInput
    order: np.ndarray
    group: np.ndarray
    values: list[dict[str, float]]
    messages: dict[int, str]


def _groups(rows: np.ndarray, group: np.ndarray) -> list[tuple[int, np.ndarray]]:
    """The rows of each parameter vector (the generated C functions take one per call)."""
    if rows.size == 0:
        return []
    of = group[rows]
    if (of == of[0]).all():  # the common case: one vector
        return [(int(of[0]), rows)]
    return [(int(g), rows[of == g]) for g in np.unique(of)]


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


def prepare(plan: Plan, index: int, lo: int, grid: np.ndarray) -> Prepared:
    """Check and prepare the runs ``lo:lo + len(grid)`` whose grid rows are ``grid``
    (chunk ``index``; see the module docstring)."""
    grid = np.asarray(grid, dtype=np.float64).reshape(-1, len(plan.columns.names))
    Q, V, PV = plan.states(grid)
    r = grid.shape[0]
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
            res = fns[g].residual(FREE, t0, Q[i], V[i])
            allowed = 100 * (opts.atol + opts.rtol * float(np.max(np.abs(V[i]), initial=0.0)))
            if res > allowed:
                messages[int(i)] = (
                    f"v0 is not in the constraint distribution D: |mu v0| = {res:.3g} >"
                    f" {allowed:.3g}; give a velocity that satisfies the constraints"
                )
            else:
                V[i] = fns[g].project(FREE, t0, Q[i], V[i])
        rows = _without(rows, messages)
    runs = _groups(rows, group)  # ascending vectors, rows in order within each
    order = np.concatenate([idx for _, idx in runs]) if runs else rows
    used = np.array([g for g, _ in runs], dtype=np.int64)
    starts = np.cumsum([0, *(idx.size for _, idx in runs)], dtype=np.int64)
    P = np.array([plan.parameters_of(values[g]) for g in used]) if used.size else np.zeros((0, 1))
    Y = np.ascontiguousarray(np.hstack([Q, V])[order])
    chunk = ChunkInput(index=index, Y=Y, P=P, starts=starts)
    return Prepared(index, lo, lo + r, grid, chunk, order, group, values, messages)


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
    for name, fn in plan.expression_functions().items():
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
    ``status`` as codes into :data:`RUN_STATUSES`, ``message`` None when no run has one."""
    r = prep.hi - prep.lo
    n = plan.scene.n
    status = np.full(r, _INVALID, dtype=np.int8)  # codes into RUN_STATUSES
    message = np.empty(r, dtype=object)  # None everywhere
    noted = bool(prep.messages)  # whether any run has a message
    t = np.full(r, np.nan)
    q = np.full((r, n), np.nan)
    v = np.full((r, n), np.nan)
    counts = np.zeros((r, len(EVENT_KINDS)), dtype=np.int64)
    steps = np.zeros(r, dtype=np.int64)
    rest = np.full(r, np.nan)
    stats = {k: np.full(r, np.nan) for k in INFO_OUTPUTS if k in plan.outputs}
    for i, text in prep.messages.items():
        message[i] = text
    sent = prep.order
    if info is None:
        for i in sent:
            status[i], message[i] = _FAILED, error
        noted = noted or sent.size > 0
        sent = np.zeros(0, dtype=np.int64)
    else:
        walls = tuple(w.name for w in plan.scene.walls)
        # a run that reached t_end decodes to ("finished", "reached t_end = ...", None):
        # only the others are decoded one by one
        status[sent] = _FINISHED_STATUS
        unusual = (info[:, _STATUS] != _FINISHED) | (info[:, _REASON] != _REACHED_END)
        for row in np.flatnonzero(unusual):
            st, msg, acc = decode(info[row], walls, plan.options.t_end)
            i = sent[row]
            status[i] = RUN_STATUSES.index(st)
            message[i] = None if st == "finished" else msg
            noted = noted or st != "finished"
            rest[i] = np.nan if acc is None else acc
        # every run sent, in order (one parameter vector, none refused): slices, not
        # fancy indexing, for the columns below
        at: Any = slice(None) if sent.size == r and np.array_equal(sent, np.arange(r)) else sent
        t[at] = info_entry(info, "last_t")
        q[at] = info[:, INFO_HEAD : INFO_HEAD + n]
        v[at] = info[:, INFO_HEAD + n : INFO_HEAD + 2 * n]
        counts[at] = info[:, EVENT_COUNTS]
        steps[at] = info_entry(info, "steps")
        for key, col in stats.items():
            col[at] = info[:, INFO_OUTPUTS[key]]
        if "energy_drift" in stats and not plan.energy_conserved:
            stats["energy_drift"][at] = np.nan
    cols: dict[str, Any] = {"run": np.arange(prep.lo, prep.hi, dtype=np.int64)}
    for j, name in enumerate(plan.columns.names):
        cols[name] = prep.grid[:, j]
    cols["status"] = status
    cols["message"] = message if noted else None  # None: no run has a message
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


def _arrow(plan: Plan, cols: dict) -> Any:
    """The chunk's columns as an Arrow table of :meth:`Plan.schema` (the status codes
    become a dictionary column: no string per run is converted)."""
    import pyarrow as pa

    names = pa.array(RUN_STATUSES, type=pa.string())
    cols["status"] = pa.DictionaryArray.from_arrays(cols["status"], names)
    if cols["message"] is None:
        cols["message"] = pa.nulls(len(cols["status"]), pa.string())
    return pa.table(cols, schema=plan.schema())


def chunk_table(plan: Plan, index: int, lo: int, grid: np.ndarray) -> Any:
    """The Arrow table of chunk ``index``, the runs ``lo:lo + len(grid)`` with grid rows
    ``grid``: checked and prepared, run by the C loop, tabled.  A chunk that cannot
    allocate the loop's work arrays becomes ``"failed"`` rows."""
    prep = prepare(plan, index, lo, grid)
    try:
        info, error = run_chunk(plan.source, prep.chunk, plan.loop), None
    except MemoryError as exc:
        info, error = None, f"chunk {index}: {exc}"
    return _arrow(plan, finish(plan, prep, info, error))


def failed_table(plan: Plan, index: int, lo: int, grid: np.ndarray, error: str) -> Any:
    """The table of a chunk that could not run: its runs that pass the checks are
    ``"failed"`` with ``error``, the others ``"invalid"`` as always."""
    return _arrow(plan, finish(plan, prepare(plan, index, lo, grid), None, error))
