"""Writing generated files: atomically, and never through a link planted in the folder.

:func:`write_text_atomic` writes a file's text into a new temporary file in the target
folder (``mkstemp``: created exclusively, so an existing file or link of that name is never
opened) and renames it over the target (``os.replace``: the rename replaces a symbolic link
itself, never the file it points to).  A reader sees the old file or the new one, never a
half-written file, and a link planted where a generated file goes is replaced, its target
untouched.  Used by :meth:`~symmech.codegen.generate.GeneratedCode.write`, the module
cache of the NumPy backend, ``symmech derive -o`` / ``symmech export -o``,
:func:`symmech.save_scene`, ``symmech sweep --out FILE.csv``, the parts and manifest of a
sweep store (``--out FOLDER.parquet``) and ``symmech bench --plot`` (:func:`write_atomic`,
for writers that take a file handle).
"""

from __future__ import annotations

import contextlib
import errno
import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import BinaryIO

__all__ = ["FILE_MODE", "write_atomic", "write_text_atomic"]

#: Permissions of a written file (read for everyone, write for the owner).
FILE_MODE = 0o644


def write_text_atomic(path: str | os.PathLike[str], text: str) -> Path:
    """Write ``text`` (UTF-8, newlines as given) to ``path`` atomically (module docstring).

    Raises ``IsADirectoryError`` if ``path`` is a folder (not a link to one), and the
    ``OSError`` of the file system otherwise, naming ``path`` (the temporary file is
    removed)."""
    return write_atomic(path, lambda fh: fh.write(text.encode("utf-8")))


def write_atomic(path: str | os.PathLike[str], produce: Callable[[BinaryIO], object]) -> Path:
    """Write to ``path`` atomically what ``produce`` writes into a binary file handle (a
    plot's ``savefig``, a table's ``to_csv``): the one rule of every file symmech writes
    (module docstring).  Raises as :func:`write_text_atomic`."""
    path = Path(path)
    if path.is_dir() and not path.is_symlink():
        raise IsADirectoryError(errno.EISDIR, "is a folder, not a file", str(path))
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name[:60]}.", suffix=".tmp", dir=path.parent)
    except OSError as exc:  # name the file asked for, not the temporary one
        raise type(exc)(exc.errno, exc.strerror, str(path)) from None
    try:
        with os.fdopen(fd, "wb") as fh:
            produce(fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, FILE_MODE)
        os.replace(tmp, path)
    except OSError as exc:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise type(exc)(exc.errno, exc.strerror, str(path)) from None
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise
    return path
