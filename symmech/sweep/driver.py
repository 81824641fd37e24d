"""``sweep``: many runs of one scene over a grid of parameters and initial states.

>>> import symmech as sm
>>> from symmech.examples import bouncing_ball
>>> table = sm.sweep(bouncing_ball(), {"q0[0]": [1.0, 2.0]}, 10.0, v0=[0.0],
...                  params={"m": 1, "g": 9.81, "alpha": 0.5}, contact="stop")
>>> table["status"].tolist()
['zeno', 'zeno']
>>> [round(x, 6) for x in table["time_to_rest"]]   # sqrt(2h/g) (1 + 1/2)/(1 - 1/2)
[1.354571, 1.915653]

Row i of the result is ``simulate(scene, q0_i, v0_i, t_end, params=params_i,
backend="c", ...)`` summarised (its final state equal to ``res.q[-1]``, ``res.v[-1]`` of
that run bit for bit): the grid's columns, ``status`` (``"finished"``, ``"zeno"``,
``"max_events"``, ``"failed"``, ``"max_steps"``, or ``"invalid"`` for a run refused by the
input checks), ``message`` (missing where finished), ``t_final``, ``<coordinate>_final`` and
``<velocity>_final``, ``time_to_rest`` (the accumulation time, or the time the body came
to rest on a wall, of a run that stopped there, as ``res.accumulation_time``; NaN
otherwise: with ``contact="persistent"`` the loop continues in contact and reports no
time), ``steps``, ``n_impact``, ``n_grazing``, ``n_contact``, ``n_release`` (events by
kind) and the chosen ``outputs`` and ``expressions``, indexed by ``run`` (the grid row).
"""

from __future__ import annotations

import hashlib
import itertools
import os
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import sympy as sp

from symmech.declaration.expressions import parse_expression
from symmech.declaration.symbols import t as TIME
from symmech.errors import SymmechError
from symmech.scene import Scene
from symmech.simulate.arguments import count, states
from symmech.simulate.backend import backend_named
from symmech.simulate.csim import INFO_HEAD, library, options_vector
from symmech.simulate.functions import Functions
from symmech.simulate.hybrid import Options
from symmech.simulate.options import RunOptions
from symmech.simulate.parameters import real_number
from symmech.simulate.run import system_for
from symmech.simulate.system import HybridSystem, SimulationError
from symmech.sweep.chunks import FIXED_COLUMNS, INFO_OUTPUTS, Plan
from symmech.sweep.grid import read_grid, resolve_columns
from symmech.sweep.runner import Progress, run_dask, run_local
from symmech.sweep.store import Store
from symmech.sweep.worker import LibrarySource, LoopOptions

__all__ = ["OUTPUTS", "sweep"]

#: The outputs ``sweep`` can add: the energy T + V and the smallest wall gap psi at the
#: final state (below zero: the run ended inside a wall), and the C loop's statistics of
#: each run (``energy_drift`` NaN where the flow does not conserve energy).
OUTPUTS = ("energy", "gap", *INFO_OUTPUTS)

#: Largest default chunk (runs per C call sequence / Dask task).
MAX_CHUNK = 10_000


def _base_state(value: object, n: int, what: str) -> np.ndarray:
    return np.full(n, np.nan) if value is None else states(value, n, what)


def _loop(opts: RunOptions, t_end: object, width: int) -> tuple[Options, LoopOptions]:
    """The sweep-wide options of the C loop (checked as for :func:`symmech.simulate.simulate`)."""
    tend = opts.end(t_end)
    method = backend_named("c", "batch").method(opts.method)
    loop = opts.loop(tend)
    index, vec = options_vector(loop, method, opts.step_cap(tend), opts.t0)
    return loop, LoopOptions(t0=opts.t0, method=index, vector=vec, width=width)


#: A sweep builds the contact modes of every set of at most this many static walls into
#: its library before it runs (its chunks cannot build one on the way, as ``simulate``
#: does: they run the library they were sent).
SWEEP_CONTACT_WALLS = 4


def build_contact_sets(system: HybridSystem) -> None:
    """Build the contact mode of every set of two or more static walls into the C library
    of ``system`` when the scene has at most :data:`SWEEP_CONTACT_WALLS` of them (a set
    that cannot be held, statically indeterminate or dependent, is left out: a run that
    reaches it fails saying so).  With more walls only the single walls and the sets
    earlier runs of the scene reached are built in."""
    static = [w for w in range(len(system.scene.walls)) if system.has_contact_mode(w)]
    if len(static) > SWEEP_CONTACT_WALLS:
        return
    for size in range(2, len(static) + 1):
        for mode in itertools.combinations(static, size):
            try:
                system.add_c_mode(mode)
            except SymmechError:
                continue


def _expressions(scene: Scene, given: Mapping[str, Any] | None) -> dict[str, sp.Expr]:
    """Each expression (a string, parsed safely, or a sympy expression), checked to be in
    t, the coordinates, velocities and parameters only."""
    if not given:
        return {}
    if not isinstance(given, Mapping):
        raise SimulationError("expressions: expected a mapping {column name: expression}")
    decl = scene.declaration
    args = [TIME, *decl.coordinates, *decl.velocities, *scene.parameters]
    allowed = {str(s): s for s in args}
    out = {}
    for name, expr in given.items():
        if not isinstance(name, str) or not name:
            raise SimulationError(f"expressions: column names must be strings, got {name!r}")
        try:
            e = (
                parse_expression(expr, allowed, field=f"expressions[{name!r}]")
                if isinstance(expr, str)
                else sp.sympify(expr, strict=True)
            )
        except (SymmechError, sp.SympifyError, TypeError) as exc:
            raise SimulationError(f"expressions[{name!r}]: {exc}") from None
        unknown = sorted(str(s) for s in e.free_symbols if s not in set(args))
        if unknown:
            raise SimulationError(
                f"expressions[{name!r}] uses {unknown}: only t, the coordinates, velocities"
                f" and parameters {sorted(allowed)}"
            )
        out[name] = e
    return out


def _fingerprint(
    plan: Plan, table: np.ndarray, chunk: int, expressions: Mapping[str, Any] | None
) -> str:
    digest = hashlib.sha256()
    parts = [
        plan.source.key,
        repr(plan.columns.names),
        repr(sorted(plan.base_params.items())),
        repr(plan.loop.t0),
        repr(plan.loop.method),
        repr(plan.outputs),
        repr(sorted((k, str(v)) for k, v in (expressions or {}).items())),
        repr(chunk),
        repr(table.shape[0]),
    ]
    for part in parts:
        digest.update(part.encode() + b"\0")
    for array in (table, plan.base_q, plan.base_v, plan.loop.vector):
        digest.update(np.ascontiguousarray(array, dtype=np.float64).tobytes())
    return digest.hexdigest()


def sweep(
    scene: Scene,
    grid: Any,
    t_end: float,
    *,
    params: Mapping[str, float] | None = None,
    q0: Any = None,
    v0: Any = None,
    outputs: Sequence[str] = ("energy",),
    expressions: Mapping[str, Any] | None = None,
    client: Any = None,
    chunk: int | None = None,
    threads: int | None = None,
    store: str | os.PathLike[str] | None = None,
    progress: bool | None = None,
    options: RunOptions | None = None,
    strategy: str = "auto",
    definitions: Mapping | None = None,
    **run_options: Any,
) -> Any:
    """Run ``scene`` for every row of ``grid`` and return a pandas DataFrame, one row per
    run (see the module docstring and :mod:`symmech.sweep.grid` for the columns).

    ``params``, ``q0``, ``v0``: the values no grid column sets.  ``outputs``: names from
    :data:`OUTPUTS`; ``expressions``: ``{column: expression}`` evaluated at each final
    state (strings are parsed by symmech's whitelist parser, never evaluated).  Without
    ``client`` the chunks run in ``threads`` threads (default: every core); with a
    ``dask.distributed.Client`` they run as Dask tasks on its cluster (``threads`` unused).
    ``chunk``: runs per chunk (default ``ceil(N / (4 workers))``, at most 10^4).
    ``store``: a folder that receives each finished chunk as a Parquet part; a rerun of the
    same sweep skips the chunks stored (:mod:`symmech.sweep.store`).  ``progress``: a
    progress bar on stderr (default: on a terminal, after a second).  The run options are
    :func:`symmech.simulate.simulate`'s (:class:`~symmech.simulate.options.RunOptions`, as
    keywords or ``options``), shared by every run.  The results do not depend on
    ``chunk``, ``threads`` or the route: each run is independent and runs the same C code.
    """
    if not isinstance(scene, Scene):
        raise SimulationError(f"scene: expected a symmech.Scene, got {type(scene).__name__}")
    try:
        import pandas  # noqa: F401
        import pyarrow  # noqa: F401
    except ImportError as exc:
        raise SimulationError(
            f"sweep needs pandas and pyarrow ({exc}): python3 -m pip install 'symmech[sweep]'"
        ) from None
    run = RunOptions.build(options, run_options)
    names, table = read_grid(grid)
    columns = resolve_columns(scene, names)
    base_params = _base_params(scene, params)
    base_q, base_v = _base_state(q0, scene.n, "q0"), _base_state(v0, scene.n, "v0")
    _check_complete(scene, columns, base_params, base_q, base_v)
    exprs = _checked_outputs(scene, names, outputs, expressions)
    threads = _checked_route(store, threads, client)
    opts, loop = _loop(run, t_end, INFO_HEAD + 2 * scene.n)
    system = system_for(scene, "c", strategy, definitions)
    build_contact_sets(system)
    fns = Functions(system, {str(p): 1.0 for p in scene.parameters})
    lib = library(system)
    plan = Plan(
        scene=scene,
        free_code=system.free.code,
        layout=lib.spec.parameter_layout,
        columns=columns,
        base_params=base_params,
        base_q=base_q,
        base_v=base_v,
        options=opts,
        loop=loop,
        source=LibrarySource(tuple(sorted(lib.sources.items())), lib.spec.prefix, lib.flags),
        outputs=tuple(outputs),
        energy_conserved=fns.energy_conserved,
        expressions=exprs,
        strategy=strategy,
        definitions=dict(definitions or {}),
    ).attach(system)
    plan.expression_functions()  # built here once, so a bad expression fails before any run
    return _execute(plan, table, client, chunk, threads, store, progress, expressions)


def _base_params(scene: Scene, params: Mapping[str, float] | None) -> dict[str, float]:
    """The parameter values no grid column sets, checked real and named by the scene."""
    pnames = [str(p) for p in scene.parameters]
    given = {} if params is None else params
    if not isinstance(given, Mapping):
        raise SimulationError(f"params: expected a mapping name -> value, got {params!r}")
    unknown = sorted(str(k) for k in given if str(k) not in pnames)
    if unknown:
        raise SimulationError(f"params: unknown {unknown}; the scene's parameters are {pnames}")
    return {str(k): real_number(v, f"params[{str(k)!r}]") for k, v in given.items()}


def _check_complete(
    scene: Scene,
    columns: Any,
    base_params: Mapping[str, float],
    base_q: np.ndarray,
    base_v: np.ndarray,
) -> None:
    """Every parameter and every initial coordinate and velocity is set, by the grid or by
    the values given; else a :class:`SimulationError` naming the missing ones."""
    pnames = [str(p) for p in scene.parameters]
    set_p = {pnames[i] for i in columns.params if i >= 0}
    missing = [p for p in pnames if p not in base_params and p not in set_p]
    decl, n = scene.declaration, scene.n
    for what, base, index, syms in (
        ("q0", base_q, columns.q, decl.coordinates),
        ("v0", base_v, columns.v, decl.velocities),
    ):
        if np.isnan(base).any():
            free = [str(syms[i]) for i in range(n) if i not in index]
            if free:
                missing.append(f"{what} (no column sets {free} and {what} is not given)")
    if missing:
        raise SimulationError(f"sweep: missing values for {missing}")


def _checked_outputs(
    scene: Scene,
    names: Sequence[str],
    outputs: Sequence[str],
    expressions: Mapping[str, Any] | None,
) -> dict[str, Any]:
    """The expressions' columns (:func:`_expressions`), the outputs checked known, and no
    column name repeated among the grid's, the fixed ones, the outputs and expressions."""
    if isinstance(outputs, str) or not isinstance(outputs, Sequence):
        unknown_out = [outputs]
    else:
        unknown_out = [o for o in outputs if o not in OUTPUTS]
    if unknown_out:
        raise SimulationError(
            f"outputs: expected a sequence of names from {OUTPUTS}, got {outputs!r}"
        )
    exprs = _expressions(scene, expressions)
    decl = scene.declaration
    taken = set(names) | set(FIXED_COLUMNS) | {"run"}
    taken |= {f"{s}_final" for s in [*decl.coordinates, *decl.velocities]}
    clash = sorted(({*outputs} | set(exprs)) & taken) + sorted(set(outputs) & set(exprs))
    if clash or len(set(outputs)) != len(outputs):
        raise SimulationError(f"outputs and expressions: repeated column names {clash}")
    return exprs


def _checked_route(store: Any, threads: int | None, client: Any) -> int:
    """The number of threads (default: every core), ``store`` and ``client`` checked."""
    if store is not None and not isinstance(store, str | os.PathLike):
        raise SimulationError(f"store: expected a folder path, got {store!r}")
    threads = count((os.cpu_count() or 1) if threads is None else threads, "threads")
    if client is not None and not (hasattr(client, "submit") and hasattr(client, "scatter")):
        raise SimulationError(
            f"client: expected a dask.distributed.Client, got {type(client).__name__}"
        )
    return threads


def _execute(
    plan: Plan, table: np.ndarray, client: Any, chunk: int | None, threads: int, store: Any,
    progress: Any, expressions: Any,
) -> Any:  # fmt: skip
    import pyarrow as pa

    N = table.shape[0]
    workers = threads
    if client is not None:
        workers = max(1, sum(client.nthreads().values()))
    if chunk is None and store is not None:
        chunk = Store.stored_chunk(store)
    if chunk is None:
        chunk = max(1, min(MAX_CHUNK, -(-N // (4 * workers))))
    chunk = count(chunk, "chunk")
    fingerprint = _fingerprint(plan, table, chunk, expressions)
    schema = plan.schema()
    chunks = [(k, lo, min(lo + chunk, N)) for k, lo in enumerate(range(0, N, chunk))]
    tables: dict[int, Any] = {}
    saver = None
    if store is not None:
        saver = Store(store, fingerprint, N, chunk)
        done = saver.open(schema)
        chunks = [c for c in chunks if c[0] not in done]
    bar = Progress(sum(hi - lo for _, lo, hi in chunks), progress)

    def sink(k: int, t: Any) -> None:
        if saver is not None:
            saver.write(k, t)
        else:
            tables[k] = t
        bar.update(t.num_rows)

    try:
        if client is None:
            run_local(plan, table, chunks, threads, sink)
        else:
            run_dask(plan, table, chunks, client, 2 * workers, sink, fingerprint[:16])
    finally:
        bar.close()
    full = saver.read(schema) if saver is not None else pa.concat_tables(
        [tables[k] for k in sorted(tables)]
    )  # fmt: skip
    # split_blocks: a column per block, not copied into 2-D blocks (the copy was most of
    # the serial time at the end of a large sweep, with every worker idle)
    return full.to_pandas(split_blocks=True).set_index("run")
