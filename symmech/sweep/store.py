"""A sweep's results on disk, chunk by chunk, so that a stopped sweep resumes.

``store="out.parquet"`` is a Parquet dataset: a folder holding one file per finished
chunk (``part-00000012.parquet``, rows ``12 chunk`` to ``13 chunk - 1``) and a manifest
``_sweep.json`` (the sweep's fingerprint: a hash of the library source, the grid, the
base values, the options, the outputs and the chunk size; the number of runs and the
chunk size).  Each part is written to a hidden temporary file and renamed into place, so
a sweep stopped at any moment leaves only whole parts; a rerun with the same fingerprint
runs only the chunks whose part is missing, and a store of another sweep is refused.
On a rerun every stored part is read back before it is trusted: a part that cannot be read
as the rows of its chunk (truncated, corrupt, another table) is treated as missing, with
a :class:`~symmech.errors.SymmechWarning` naming it, and recomputed; a symbolic link or a
folder where a part or the manifest goes is refused (a store holds only its own files,
and a link would be read from, or written through, to a file elsewhere).  Every file is
written by :func:`symmech.files.write_atomic`.
``pandas.read_parquet("out.parquet")`` reads the folder as one table (readers skip names
starting with ``_`` or ``.``).
"""

from __future__ import annotations

import json
import os
import warnings
from pathlib import Path
from typing import Any

from symmech.errors import SymmechWarning
from symmech.files import write_atomic
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

    def open(self, schema: Any = None) -> set[int]:
        """Create the folder and its manifest, or check an existing one; return the
        indices of the chunks already stored (each read back with ``schema``, a pyarrow
        schema, and the number of rows of its chunk; see the module docstring)."""
        manifest = self.path / _MANIFEST
        self._own_file(manifest)
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
            part = self.path / _part(k)
            self._own_file(part)
            if part.is_file() and self._readable(k, schema):
                done.add(k)
        return done

    def _own_file(self, path: Path) -> None:
        """Refuse a link or a folder where the store's own file ``path`` goes."""
        if path.is_symlink() or (path.exists() and not path.is_file()):
            what = "a symbolic link" if path.is_symlink() else "not a regular file"
            raise SimulationError(
                f"store {str(self.path)!r}: {path.name} is {what}; a sweep store holds only"
                " the files it wrote: remove it, or give another path"
            )

    def _rows(self, k: int) -> int:
        return min(self.chunk, self.runs - k * self.chunk)

    def _readable(self, k: int, schema: Any) -> bool:
        """Whether part ``k`` reads back as the rows of chunk ``k``; else warn that it
        is recomputed."""
        import pyarrow.parquet as pq

        part = self.path / _part(k)
        try:
            table = pq.read_table(part, schema=schema)
            if table.num_rows != self._rows(k):
                raise ValueError(f"{table.num_rows} rows, chunk {k} has {self._rows(k)}")
        except Exception as exc:  # pyarrow's ArrowInvalid, OSError, schema errors
            warnings.warn(
                f"store {str(self.path)!r}: {part.name} cannot be read as the rows of chunk"
                f" {k} ({type(exc).__name__}: {exc}); its runs are computed again",
                SymmechWarning,
                stacklevel=3,
            )
            return False
        return True

    def _write_atomic(self, target: Path, data: bytes) -> None:
        write_atomic(target, lambda fh: fh.write(data))

    def write(self, k: int, table: Any) -> None:
        """Write chunk ``k``'s table (a pyarrow Table) as its part, atomically."""
        import pyarrow.parquet as pq

        write_atomic(self.path / _part(k), lambda fh: pq.write_table(table, fh))

    def read(self, schema: Any) -> Any:
        """Every stored part as one pyarrow Table, in chunk order."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        chunks = -(-self.runs // self.chunk)
        tables = []
        for k in range(chunks):
            part = self.path / _part(k)
            self._own_file(part)
            try:
                tables.append(pq.read_table(part, schema=schema))
            except Exception as exc:  # changed under the sweep: no raw pyarrow error
                raise SimulationError(
                    f"store {str(self.path)!r}: {part.name} cannot be read"
                    f" ({type(exc).__name__}: {exc}); run the sweep again to recompute it"
                ) from None
        return pa.concat_tables(tables)
