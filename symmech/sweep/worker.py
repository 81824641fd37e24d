"""The compiled hybrid loop of a sweep, in whichever process runs a chunk.

A chunk travels as plain arrays (:class:`ChunkInput`: initial states grouped by parameter
vector) and the library as its generated C source (:class:`LibrarySource`), never as a
ctypes handle: the process that runs it compiles the source once (the build cache of
:func:`symmech.codegen.build.compile_library` is keyed by content, so a second process on
the same machine finds the library built) and keeps the loaded entry point for the rest of
its life, keyed by the source's hash.  The local route and every Dask worker run the same
function, :func:`run_chunk`, over the same library, so their results agree bit for bit.

The simulator's ``*_batch`` entry point runs ``count`` initial states with one parameter
vector ``P``; a chunk whose rows have several parameter vectors makes one call per vector
(the rows are sorted by vector when the chunk is prepared).  The call releases the GIL
(ctypes), so chunks in threads run in parallel.
"""

from __future__ import annotations

import ctypes
import hashlib
import threading
from dataclasses import dataclass
from typing import Any

import numpy as np

from symmech.codegen.build import compile_library, load_library

__all__ = ["ChunkInput", "LibrarySource", "LoopOptions", "run_chunk"]


@dataclass(frozen=True)
class LibrarySource:
    """The simulator library as source: ``files`` (name -> text), the C symbol ``prefix``
    of its entry points, the compiler ``flags``; ``key`` is a hash of all three."""

    files: tuple[tuple[str, str], ...]
    prefix: str
    flags: tuple[str, ...]

    @property
    def key(self) -> str:
        digest = hashlib.sha256(self.prefix.encode() + b"\0" + "\0".join(self.flags).encode())
        for name, text in self.files:
            digest.update(b"\0" + name.encode() + b"\0" + text.encode())
        return digest.hexdigest()


@dataclass(frozen=True)
class LoopOptions:
    """The C loop's settings shared by every run of a sweep: start time, method index and
    option vector (:func:`symmech.simulate.csim.options_vector`), info row width."""

    t0: float
    method: int
    vector: np.ndarray
    width: int


@dataclass(frozen=True)
class ChunkInput:
    """The runs of one chunk that passed the input checks: initial states ``Y`` (r, 2n),
    sorted by parameter vector, rows ``starts[g]:starts[g + 1]`` running with the library
    parameter vector ``P[g]``."""

    index: int
    Y: np.ndarray
    P: np.ndarray
    starts: np.ndarray


_LOADED: dict[str, tuple[Any, Any]] = {}
_LOCK = threading.Lock()


def batch_entry(source: LibrarySource) -> Any:
    """The ``*_batch`` function of ``source``'s library, compiled and loaded once per
    process (see the module docstring)."""
    key = source.key
    with _LOCK:
        hit = _LOADED.get(key)
        if hit is None:
            path = compile_library(dict(source.files), flags=source.flags)
            lib = load_library(path)
            fn = getattr(lib, source.prefix + "batch")
            vp = ctypes.c_void_p
            fn.argtypes = [ctypes.c_long, vp, ctypes.c_double, ctypes.c_int, vp, vp, vp]
            fn.restype = ctypes.c_int
            hit = (lib, fn)
            _LOADED[key] = hit
    return hit[1]


def loaded_libraries() -> int:
    """How many simulator libraries this process has loaded (for tests and benchmarks)."""
    return len(_LOADED)


def run_chunk(source: LibrarySource, chunk: ChunkInput, options: LoopOptions) -> np.ndarray:
    """The info rows (r, width) of the chunk's runs, in the order of ``chunk.Y``: one call
    of the batch entry point per parameter vector.  Raises MemoryError when the C loop
    cannot allocate its work arrays."""
    fn = batch_entry(source)
    Y = np.ascontiguousarray(chunk.Y, dtype=np.float64)
    info = np.zeros((Y.shape[0], options.width))
    vec = np.ascontiguousarray(options.vector, dtype=np.float64)
    P = np.ascontiguousarray(chunk.P, dtype=np.float64)
    row_bytes = Y.strides[0]
    info_bytes = info.strides[0]
    for g in range(P.shape[0]):
        lo, hi = int(chunk.starts[g]), int(chunk.starts[g + 1])
        if hi <= lo:
            continue
        status = fn(
            hi - lo,
            Y.ctypes.data + lo * row_bytes,
            options.t0,
            options.method,
            vec.ctypes.data,
            P[g].ctypes.data,
            info.ctypes.data + lo * info_bytes,
        )
        if status:
            raise MemoryError("the C simulator could not allocate its work arrays")
    return info
