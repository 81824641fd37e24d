"""The ``symmech sweep`` command.

``symmech sweep SCENE --grid FILE --out FILE --t-end T [--q0 ...] [--v0 ...]
[--param NAME=VALUE ...] [--scheduler ADDRESS] ...``
    Run the scene (a built-in name or a scene file) for every row of the grid file (CSV or
    Parquet; its columns name parameters and initial values as :mod:`symmech.sweep.grid`
    describes) with :func:`symmech.sweep.sweep`.  ``--out`` ending in ``.parquet`` is the
    sweep's store: a folder of Parquet parts written as chunks finish, so rerunning the
    same command after an interruption runs only the missing chunks; ``.csv`` writes the
    table at the end.  Parameters default to the scene file's values; ``--q0``/``--v0``
    give the initial values no column sets.  ``--scheduler tcp://host:8786`` runs the
    chunks on that Dask cluster.  The command prints how many runs ended in each status.
"""

from __future__ import annotations

import argparse
import io
from collections.abc import Callable
from pathlib import Path
from typing import Any

from symmech.codegen.escape import terminal
from symmech.errors import SymmechError
from symmech.files import write_atomic
from symmech.simulate.arguments import numbers, parameter_values
from symmech.simulate.hybrid import MAX_STEPS
from symmech.simulate.result import STATUSES

__all__ = ["add_command", "run_command"]


def add_command(sub: Any, common: argparse.ArgumentParser) -> None:
    """Register ``sweep`` on the ``symmech`` sub-parsers."""
    sw = sub.add_parser("sweep", parents=[common], help="run a scene over a grid of runs")
    sw.add_argument("scene", help="scene file or built-in name")
    sw.add_argument("--grid", required=True, help="the runs: a CSV or Parquet file")
    sw.add_argument("--out", required=True, help="result: FILE.parquet (resumable) or FILE.csv")
    sw.add_argument("--t-end", type=float, required=True, help="final time of every run")
    sw.add_argument("--q0", help="initial coordinates no grid column sets, comma separated")
    sw.add_argument("--v0", help="initial velocities no grid column sets, comma separated")
    sw.add_argument(
        "--param", action="append", default=[], metavar="NAME=VALUE", help="a parameter value"
    )
    sw.add_argument("--method", default="dop853")
    sw.add_argument("--rtol", type=float, default=1e-8)
    sw.add_argument("--atol", type=float, default=1e-10)
    sw.add_argument("--contact", default="persistent", choices=("persistent", "stop"))
    sw.add_argument("--max-events", type=int, default=100_000)
    sw.add_argument("--max-steps", type=int, default=MAX_STEPS, help="steps per run")
    sw.add_argument("--outputs", default="energy", help="outputs, comma separated")
    sw.add_argument("--chunk", type=int, help="runs per chunk (default: N / (4 workers))")
    sw.add_argument("--threads", type=int, help="local threads (default: every core)")
    sw.add_argument("--scheduler", help="address of a Dask scheduler (tcp://host:8786)")
    sw.add_argument("--no-progress", action="store_true", help="no progress bar")


def _read_grid(path: str) -> Any:
    import pandas as pd

    suffix = Path(path).suffix.lower()
    if suffix not in (".csv", ".parquet"):
        raise SymmechError(f"--grid {path!r}: expected a .csv or .parquet file")
    try:
        return pd.read_csv(path) if suffix == ".csv" else pd.read_parquet(path)
    except (ValueError, ImportError) as exc:
        raise SymmechError(f"--grid {path!r}: cannot be read ({exc})") from None
    except OSError:
        raise
    except Exception as exc:  # pyarrow and pandas parser errors
        raise SymmechError(f"--grid {path!r}: cannot be read ({exc})") from None


def _write_csv(table: Any, path: str) -> None:
    """Write ``table`` to ``path`` atomically (:func:`~symmech.files.write_atomic`: a link
    at ``path`` is replaced, never written through)."""

    def produce(fh: Any) -> None:
        text = io.TextIOWrapper(fh, encoding="utf-8", newline="")
        table.to_csv(text)
        text.flush()
        text.detach()  # the binary handle stays open for write_atomic

    write_atomic(path, produce)


def _check_scheduler(address: str) -> None:
    """Refuse a ``--scheduler`` that is not a Dask address (``tcp://host:port``) before
    anything runs: Dask's own parser says why (a raw ValueError, exit 3, before)."""
    try:
        from distributed.comm.addressing import get_address_host_port
    except ImportError as exc:
        raise SymmechError(
            f"--scheduler needs dask.distributed ({exc}): pip install 'symmech[sweep]'"
        ) from None
    try:
        _, port = get_address_host_port(address)
        if not 0 < int(port) < 65536:
            raise ValueError(f"port {port} is not in 1..65535")
    except (ValueError, TypeError, KeyError) as exc:
        raise SymmechError(
            f"--scheduler {address!r}: not the address of a Dask scheduler ({exc});"
            " expected tcp://host:port"
        ) from None


def run_command(
    args: argparse.Namespace, load: Callable[[str], Any], say: Callable[[str], None]
) -> int:
    """Run ``symmech sweep`` (see the module docstring); ``load`` reads a scene file or
    built-in name into a :class:`~symmech.scenefile.SceneFile`, ``say`` reports progress.
    Returns 0 once the table is written (runs that failed are rows of it)."""
    from symmech.sweep.driver import sweep

    out = str(args.out)
    kind = Path(out).suffix.lower()
    if kind not in (".csv", ".parquet"):
        raise SymmechError(f"--out {out!r}: expected a .parquet folder or a .csv file")
    if args.scheduler:
        _check_scheduler(args.scheduler)
    sf = load(args.scene)
    params = {str(k): float(v) for k, v in sf.defaults.items()}
    params.update(parameter_values(args.param))
    grid = _read_grid(args.grid)  # a grid column overrides the file's default
    q0 = numbers(args.q0, "--q0") if args.q0 else None
    v0 = numbers(args.v0, "--v0") if args.v0 else None
    outputs = tuple(o.strip() for o in args.outputs.split(",") if o.strip())
    client = None
    if args.scheduler:
        try:
            from distributed import Client
        except ImportError as exc:
            raise SymmechError(
                f"--scheduler needs dask.distributed ({exc}): pip install 'symmech[sweep]'"
            ) from None
        say(f"connecting to the Dask scheduler at {args.scheduler}")
        try:
            client = Client(args.scheduler)
        except (TypeError, ValueError) as exc:  # e.g. tls:// without a TLS configuration
            raise SymmechError(
                f"--scheduler {args.scheduler!r}: cannot connect ({type(exc).__name__}: {exc})"
            ) from None
    say(f"sweeping {sf.scene.name}: {len(grid)} runs to t = {args.t_end}")
    try:
        table = sweep(
            sf.scene,
            grid,
            args.t_end,
            params=params,
            q0=q0,
            v0=v0,
            outputs=outputs,
            client=client,
            chunk=args.chunk,
            threads=args.threads,
            store=out if kind == ".parquet" else None,
            progress=False if args.no_progress else None,
            method=args.method,
            rtol=args.rtol,
            atol=args.atol,
            max_events=args.max_events,
            max_steps=args.max_steps,
            contact=args.contact,
        )
    finally:
        if client is not None:
            client.close()
    if kind == ".csv":
        _write_csv(table, out)
    counts = table["status"].value_counts().to_dict()
    for status in (*STATUSES, "invalid"):
        if counts.get(status):
            print(f"{status}: {counts[status]}")
    print(terminal(f"wrote {out}"))
    return 0
