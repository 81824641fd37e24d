"""A sweep's results on disk, chunk by chunk, so that a stopped sweep resumes.

``store="out.parquet"`` is a Parquet dataset: a folder holding one file per finished
chunk (``part-00000012.parquet``, rows ``12 chunk`` to ``13 chunk - 1``) and a manifest
``_sweep.json`` (the sweep's fingerprint: a hash of the library source, the grid, the
base values, the options, the outputs and the chunk size; the number of runs and the
chunk size).  Each part is written to a hidden temporary file and renamed into place, so
a sweep stopped at any moment leaves only whole parts; a rerun with the same fingerprint
runs only the chunks whose part is missing, and a store of another sweep is refused.
``pandas.read_parquet("out.parquet")`` reads the folder as one table (readers skip names
starting with ``_`` or ``.``).
"""

from __future__ import annotations

import json
import os
import threading
from pathlib import Path
from typing import Any

from symmech.simulate.system import SimulationError

__all__ = ["Store"]

_MANIFEST = "_sweep.json"


def _part(k: int) -> str:
    return f"part-{k:08d}.parquet"


class Store:
    """The Parquet folder of one sweep (see the module docstring)."""

    def __init__(self, path: str | os.PathLike[str], fingerprint: str, runs: int, chunk: int):
        self.path = Path(path)
        self.fingerprint = fingerprint
        self.runs = runs
        self.chunk = chunk
        self._count = 0
        self._lock = threading.Lock()

    @staticmethod
    def stored_chunk(path: str | os.PathLike[str]) -> int | None:
        """The chunk size recorded in the store at ``path`` (None if there is none)."""
        manifest = Path(path) / _MANIFEST
        if not manifest.is_file():
            return None
        try:
            return int(json.loads(manifest.read_text(encoding="utf-8"))["chunk"])
        except (ValueError, KeyError, TypeError, OSError):
            return None

    def open(self) -> set[int]:
        """Create the folder and its manifest, or check an existing one; return the
        indices of the chunks already stored."""
        manifest = self.path / _MANIFEST
        record = {"fingerprint": self.fingerprint, "runs": self.runs, "chunk": self.chunk}
        if self.path.exists() and not self.path.is_dir():
            raise SimulationError(
                f"store {str(self.path)!r} is a file: a sweep store is a folder of Parquet parts"
            )
        if self.path.is_dir() and any(self.path.iterdir()):
            try:
                held = json.loads(manifest.read_text(encoding="utf-8"))
            except (OSError, ValueError) as exc:
                raise SimulationError(
                    f"store {str(self.path)!r} is not empty and holds no readable sweep"
                    f" manifest {_MANIFEST} ({exc}); give an empty or new folder"
                ) from None
            if held != record:
                raise SimulationError(
                    f"store {str(self.path)!r} holds another sweep (runs {held.get('runs')},"
                    f" chunk {held.get('chunk')}, a different grid, scene or options):"
                    " give another path or delete it"
                )
        else:
            self.path.mkdir(parents=True, exist_ok=True)
            self._write_atomic(manifest, json.dumps(record, indent=1).encode())
        done = set()
        chunks = -(-self.runs // self.chunk)
        for k in range(chunks):
            if (self.path / _part(k)).is_file():
                done.add(k)
        return done

    def _write_atomic(self, target: Path, data: bytes) -> None:
        with self._lock:
            self._count += 1
            tmp = target.with_name(f".{target.name}.{os.getpid()}.{self._count}.tmp")
        tmp.write_bytes(data)
        os.replace(tmp, target)

    def write(self, k: int, table: Any) -> None:
        """Write chunk ``k``'s table (a pyarrow Table) as its part, atomically."""
        import pyarrow.parquet as pq

        with self._lock:
            self._count += 1
            tmp = self.path / f".{_part(k)}.{os.getpid()}.{self._count}.tmp"
        pq.write_table(table, tmp)
        os.replace(tmp, self.path / _part(k))

    def read(self, schema: Any) -> Any:
        """Every stored part as one pyarrow Table, in chunk order."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        chunks = -(-self.runs // self.chunk)
        tables = [pq.read_table(self.path / _part(k), schema=schema) for k in range(chunks)]
        return pa.concat_tables(tables)
