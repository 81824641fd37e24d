"""Compile generated C into a shared library, cached by content, and load it with ctypes.

The cache key is a SHA-256 of the sources, the compiler's ``--version`` text and the
flags, so a library is rebuilt exactly when one of them changes.  The cache folder is
``$SYMMECH_CACHE_DIR``, else ``$XDG_CACHE_HOME/symmech``, else ``~/.cache/symmech``.
Libraries are built in a private temporary folder and moved into place atomically, so
concurrent builds of the same code do not collide.

A cached library is code this process runs, so the cache is trusted only as far as its
owner: a folder writable by other users must be sticky (``/tmp``), and a cached file is
reused only when it is a regular file owned by this user and writable by no one else
(:func:`trusted_file`) and its SHA-256 matches the digest written beside it at build time
(a truncated library, which loading could crash on, is rebuilt); otherwise it is rebuilt.
A relative cache path is taken from the current folder (made absolute before the compiler
runs in its build folder); a cache path that is not a usable folder is a
:class:`CompileError` naming it.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import stat
import subprocess
import tempfile
from collections.abc import Mapping, Sequence
from functools import cache
from pathlib import Path

from symmech.errors import SymmechError

__all__ = [
    "DEFAULT_FLAGS",
    "CompileError",
    "cache_dir",
    "compile_library",
    "extension_includes",
    "find_compiler",
    "trusted_file",
]

#: Flags for the loadable library: C99, optimised, position independent.  No
#: -ffast-math: the generated code relies on IEEE semantics (isfinite, no reassociation).
DEFAULT_FLAGS: tuple[str, ...] = ("-std=c99", "-O2", "-fPIC", "-shared")


class CompileError(SymmechError, RuntimeError):
    """The C compiler is missing or failed; the message holds its diagnostics."""


def find_compiler(compiler: str | None = None) -> str:
    """The C compiler to use: ``compiler``, else ``$CC``, else gcc, else cc."""
    for candidate in (compiler, os.environ.get("CC"), "gcc", "cc"):
        if candidate:
            path = shutil.which(candidate)
            if path:
                return path
    raise CompileError(
        "no C compiler found (tried $CC, gcc, cc); install gcc or use target='numpy'"
    )


@cache
def _compiler_identity(compiler: str) -> str:
    try:
        out = subprocess.run(
            [compiler, "--version"], capture_output=True, text=True, timeout=60, check=False
        )
    except OSError as exc:
        raise CompileError(f"cannot run the C compiler {compiler}: {exc}") from None
    return out.stdout + out.stderr


def cache_dir(path: str | Path | None = None) -> Path:
    """The library cache folder (see the module docstring), created if needed."""
    if path is None:
        env = os.environ.get("SYMMECH_CACHE_DIR")
        if env:
            path = env
        else:
            base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
            path = Path(base) / "symmech"
    # absolute: the compiler runs in a build folder, where a relative path means another place
    folder = Path(path).expanduser().absolute()
    try:
        folder.mkdir(mode=0o700, parents=True, exist_ok=True)
        if not folder.is_dir():
            raise NotADirectoryError(20, "not a folder")
    except OSError as exc:
        raise CompileError(
            f"cache folder {folder}: {exc.strerror or exc}; give a folder this user can write"
            " (SYMMECH_CACHE_DIR, or cache=...)"
        ) from None
    if hasattr(os, "getuid"):
        st = folder.stat()
        shared = st.st_mode & (stat.S_IWGRP | stat.S_IWOTH)
        if shared and not st.st_mode & stat.S_ISVTX:
            raise CompileError(
                f"cache folder {folder}: writable by other users and not sticky, so another"
                " user could replace a cached library (which is code this process runs); use"
                " a private folder (SYMMECH_CACHE_DIR, or cache=...)"
            )
    return folder


def trusted_file(path: Path) -> bool:
    """Whether a cached file may be reused: a regular file (not a link) and, on POSIX,
    owned by this user and writable by no one else.  Anything else may have been planted
    by another user of a shared folder; it is rebuilt (and replaced where the folder lets
    this user replace it)."""
    try:
        st = os.lstat(path)
    except OSError:
        return False
    if not stat.S_ISREG(st.st_mode):
        return False
    if hasattr(os, "getuid"):
        return st.st_uid == os.getuid() and not st.st_mode & (stat.S_IWGRP | stat.S_IWOTH)
    return True


def extension_includes() -> tuple[list[str], str | None]:
    """The include folders of the CPython and NumPy headers, and None; or ([], the reason)
    when a header is missing (e.g. a Python without its development files)."""
    import sysconfig

    import numpy

    folders = [sysconfig.get_paths().get("include", ""), numpy.get_include()]
    for folder, header in zip(folders, ("Python.h", "numpy/arrayobject.h"), strict=True):
        if not folder or not (Path(folder) / header).is_file():
            return [], f"{header} not found (in {folder or 'no include folder'})"
    return folders, None


def library_key(compiler: str, flags: Sequence[str], sources: Mapping[str, str]) -> str:
    """The cache key of a build: the compiler's identity, the flags and the sources."""
    digest = hashlib.sha256()
    for part in (_compiler_identity(compiler), "\0".join(flags)):
        digest.update(part.encode())
    for name in sorted(sources):
        digest.update(name.encode() + b"\0" + sources[name].encode() + b"\0")
    return digest.hexdigest()[:24]


def compile_library(
    sources: Mapping[str, str],
    *,
    compiler: str | None = None,
    flags: Sequence[str] = DEFAULT_FLAGS,
    cache: str | Path | None = None,
    filename: str | None = None,
) -> Path:
    """Compile the ``.c`` files of ``sources`` (name -> text, headers included) into a
    shared library and return its path, reusing a cached build with the same key.
    ``filename`` names the library (``{key}`` is replaced by the cache key; default
    ``symmech_{key}.so``)."""
    cc = find_compiler(compiler)
    key = library_key(cc, flags, sources)
    folder = cache_dir(cache)
    library = folder / (filename or "symmech_{key}.so").format(key=key)
    if trusted_file(library) and _intact(library):
        return library
    with tempfile.TemporaryDirectory(prefix="build_", dir=folder) as tmp:
        work = Path(tmp)
        for name, text in sources.items():
            (work / name).write_text(text, encoding="utf-8")
        c_files = [name for name in sorted(sources) if name.endswith(".c")]
        if not c_files:
            raise CompileError("no .c file to compile")
        target = work / library.name
        _build(cc, list(flags), c_files, target, work)
        digest = work / (library.name + ".sha256")
        digest.write_text(_sha256(target), encoding="utf-8")
        try:
            os.replace(target, library)
            os.replace(digest, _digest_path(library))
        except OSError as exc:
            raise CompileError(
                f"cannot put the library in place at {library}: {exc.strerror} (a file of"
                " that name that this user may not replace: use a private cache folder)"
            ) from None
    return library


def _build(cc: str, flags: list[str], c_files: list[str], target: Path, work: Path) -> None:
    """Compile ``c_files`` (in ``work``) and link them into ``target``.  With several
    files and several CPUs each is compiled to an object file by its own compiler
    process, at once, then linked (the library and its CPython extension compile side by
    side); otherwise one compiler run does both."""
    if len(c_files) < 2 or _cpus() < 2:
        _run([cc, *flags, "-o", str(target), *c_files, "-lm"], work)
        return
    objects = [f"{name[:-2]}.o" for name in c_files]
    compiles: list[tuple[list[str], subprocess.Popen]] = []
    try:
        for name, obj in zip(c_files, objects, strict=True):
            compiles.append(_start([cc, *flags, "-c", "-o", obj, name], work))
        for cmd, process in compiles:
            _finish(cmd, process)
    finally:
        for _, process in compiles:  # (after a failure: the others are not waited for)
            if process.poll() is None:
                process.kill()
                process.communicate()
    _run([cc, *flags, "-o", str(target), *objects, "-lm"], work)


def _cpus() -> int:
    """The CPUs this process may run on."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1  # pragma: no cover - platforms without affinity


def _start(cmd: list[str], work: Path) -> tuple[list[str], subprocess.Popen]:
    try:
        return cmd, subprocess.Popen(
            cmd, cwd=work, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
        )
    except OSError as exc:
        raise CompileError(f"running {' '.join(cmd)} failed: {exc}") from None


def _finish(cmd: list[str], process: subprocess.Popen) -> None:
    """Wait for a compiler run (at most 600 s); a failure is a :class:`CompileError` with
    the compiler's message."""
    try:
        out, err = process.communicate(timeout=600)
    except subprocess.TimeoutExpired:
        process.kill()
        process.communicate()
        raise CompileError(f"running {' '.join(cmd)} failed: timed out after 600 s") from None
    if process.returncode != 0:
        raise CompileError(
            f"{' '.join(cmd)} failed with exit code {process.returncode}:\n" + (err or out).strip()
        )


def _run(cmd: list[str], work: Path) -> None:
    _finish(*_start(cmd, work))


def _digest_path(library: Path) -> Path:
    return library.with_name(library.name + ".sha256")


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _intact(library: Path) -> bool:
    """Whether a cached library is the file that was built: its SHA-256 matches the digest
    written beside it at build time (a truncated or altered library, which loading could
    crash on, is rebuilt)."""
    digest = _digest_path(library)
    if not trusted_file(digest):
        return False
    try:
        return digest.read_text(encoding="utf-8").strip() == _sha256(library)
    except OSError:
        return False


def load_library(path: str | Path) -> ctypes.CDLL:
    """Load a shared library built by :func:`compile_library`."""
    try:
        return ctypes.CDLL(str(path))
    except OSError as exc:
        raise CompileError(f"cannot load {path}: {exc}") from None
