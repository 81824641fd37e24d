"""Callers of generated functions: one per function and backend, behind
:class:`~symmech.codegen.module.SceneModule`.

A *raw* caller takes the converted arguments (state arrays, p, t, u: float64 arrays, see
:func:`symmech.codegen.runtime_checks.real_array`) and returns the output or raises
:class:`NumericalError`.  For C, a function of the state and the parameters also gets a
*fast* single-state caller through ctypes, which handles only plain arguments (float64 or
int64 vectors, lists of floats and ints, parameters within their declared ranges) and
returns None for anything else, so that the general path converts or explains.
"""

from __future__ import annotations

import ctypes
import math
import threading
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from symmech.codegen.lower import LoweredFunction
from symmech.codegen.plan import CodegenError
from symmech.codegen.runtime_checks import ParameterRule
from symmech.errors import SymmechError

__all__ = ["Fast", "NumericalError", "Raw", "c_raw", "numpy_fast", "numpy_raw"]

_STATUS = {
    1: "a matrix that must be positive definite is not",
    2: "an output, or an input of its linear solve, is not finite",
}

Raw = Callable[[tuple[np.ndarray, ...], Any, Any, Any], np.ndarray]
#: A fast single-state caller: the output, or None when the arguments are not the plain
#: case it handles (the general path then validates them and explains any problem).
Fast = Callable[[tuple[object, ...], object], "np.ndarray | None"]


class NumericalError(SymmechError, FloatingPointError):
    """A generated function failed at a state (non-SPD matrix or non-finite output)."""


def _failed(name: str, index: int | None, detail: str) -> NumericalError:
    where = f" at state {index}" if index is not None else ""
    return NumericalError(f"{name}{where}: {detail}")


def numpy_raw(fn: Callable, spec: LoweredFunction) -> Raw:
    shape_out = spec.out_shape

    def call(state, p, t, u):
        args = list(state)
        args += [p] if spec.takes_parameters else []
        args += [t] if spec.takes_time else []
        args += [u] if spec.takes_inputs else []
        try:
            with np.errstate(all="ignore"):
                out = np.asarray(fn(*args), dtype=np.float64)
        except np.linalg.LinAlgError:
            raise _failed(spec.name, None, _STATUS[1]) from None
        except FloatingPointError:  # _require_finite: an input of the linear solve
            raise _failed(spec.name, None, _STATUS[2]) from None
        bad = ~np.isfinite(out)
        if bad.any():
            lead = out.shape[: out.ndim - len(shape_out)]
            index = None
            if lead:
                flat = bad.reshape((-1, *shape_out)).reshape(int(np.prod(lead)), -1).any(axis=1)
                index = int(np.argmax(flat))
            raise _failed(spec.name, index, _STATUS[2])
        return out

    return call


_SEQUENCES = (list, tuple)
_DTYPES = "dl"  # float64, int64 (any byte order: a copy converts)
_PLAIN = (float, int)


def _plain_arguments(
    state: tuple[object, ...],
    params: object,
    takes_parameters: bool,
    checks: Sequence[tuple[int, tuple[int, ...]]],
) -> tuple[object, ...] | None:
    """The arguments of a one-state call (the state arrays, then p if taken) when they are
    the plain case the fast paths handle: float64 or int64 vectors, or lists and tuples of
    floats and ints, of the sizes in ``checks``; None for anything else (the general path
    then converts or explains)."""
    if takes_parameters:
        args = (*state, params)
    elif params is not None:
        return None  # the general path checks the parameters it is given
    else:
        args = state
    if len(args) != len(checks):
        return None
    for a, (k, shape) in zip(args, checks, strict=True):
        kind = type(a)
        if kind is np.ndarray:
            if a.shape != shape or a.dtype.char not in _DTYPES:  # type: ignore[attr-defined]
                return None
        elif kind not in _SEQUENCES or len(a) != k:  # type: ignore[arg-type]
            return None
        elif not all(type(x) in _PLAIN for x in a):  # type: ignore[attr-defined]
            return None  # bool, str, complex...: the general path refuses them
    return args


def numpy_fast(
    one: Callable, spec: LoweredFunction, n: int, n_parameters: int, rules: Sequence[ParameterRule]
) -> Fast:
    """The one-state caller of a NumPy function through its variant ``_one_<name>`` (plain
    floats, ``math``; the same operations in the same order as the vectorised function).
    None, for the general path to redo the call and explain, when the arguments are not
    plain, a parameter breaks its rule, or the evaluation fails or is not finite."""
    sizes = [2 * n if s == "y" else n for s in spec.state]
    checks = [(k, (k,)) for k in sizes]
    if spec.takes_parameters:
        checks.append((n_parameters, (n_parameters,)))
    out_shape = spec.out_shape
    isfinite = math.isfinite

    def fast(state: tuple[object, ...], params: object) -> np.ndarray | None:
        args = _plain_arguments(state, params, spec.takes_parameters, checks)
        if args is None:
            return None
        values = [a.tolist() if type(a) is np.ndarray else [float(x) for x in a] for a in args]  # type: ignore[attr-defined]
        if spec.takes_parameters:
            p = values[-1]
            if not all(isfinite(p[r.index]) and r.holds_value(p[r.index]) for r in rules):
                return None  # the general path names the parameter
        try:
            out = one(*values)
        except (ArithmeticError, ValueError, np.linalg.LinAlgError):
            return None  # math's domain and overflow errors, a failed factorisation
        if not all(isfinite(x) for x in out):
            return None
        return np.array(out).reshape(out_shape)

    return fast


def c_raw(
    lib: ctypes.CDLL,
    prefix: str,
    spec: LoweredFunction,
    n: int,
    n_inputs: int,
    n_parameters: int,
    rules: Sequence[ParameterRule] = (),
) -> tuple[Raw, Fast | None]:
    """The general caller of a generated C function, and (for a function of the state and
    the parameters only) a fast single-state caller.

    A single state is copied into per-thread float64 buffers whose addresses are taken once,
    and the function is called through a prototype of plain addresses: no ctypes array
    conversion and no address lookup per call (``ndarray.ctypes`` costs about a
    microsecond, as much as a small generated function).
    """
    symbol = getattr(lib, prefix + spec.name)
    batch = getattr(lib, prefix + spec.name + "_batch")
    ptr, dbl = ctypes.c_void_p, ctypes.c_double
    nstate = len(spec.state)
    single = ctypes.CFUNCTYPE(
        ctypes.c_int,
        *(
            [ptr] * nstate
            + ([ptr] if spec.takes_parameters else [])
            + ([dbl] if spec.takes_time else [])
            + ([ptr] if spec.takes_inputs else [])
            + [ptr]
        ),
    )(ctypes.cast(symbol, ctypes.c_void_p).value or 0)
    batch.argtypes = (
        [ctypes.c_long]
        + [ptr] * nstate
        + ([ptr] if spec.takes_parameters else [])
        + ([ptr] if spec.takes_time else [])
        + ([ptr] if spec.takes_inputs else [])
        + [ptr]
    )
    batch.restype = ctypes.c_long
    out_shape = spec.out_shape
    out_size = spec.out_size
    sizes = [2 * n if s == "y" else n for s in spec.state]
    local = threading.local()

    def parameters_hold(p: np.ndarray) -> bool:
        """Whether one parameter vector is finite and within its declared ranges."""
        values = p.tolist()
        return all(math.isfinite(values[r.index]) and r.holds_value(values[r.index]) for r in rules)

    def fast_buffers() -> tuple[list[np.ndarray], list[int]]:
        """Per-thread buffers of the fast path, in the order of the function's arguments."""
        arrays = [np.zeros(k) for k in sizes]
        if spec.takes_parameters:
            arrays.append(np.zeros(max(n_parameters, 1)))
        arrays.append(np.zeros(out_shape if out_shape else (1,)))
        return arrays, [a.ctypes.data for a in arrays]

    def buffers() -> tuple[list[np.ndarray], list[int]]:
        """Per-thread buffers for one state (state arrays, p, u, out) and their addresses
        (ctypes releases the GIL during the call, so threads must not share them)."""
        b = getattr(local, "buffers", None)
        if b is None:
            arrays = [np.zeros(k) for k in sizes]
            arrays += [np.zeros(max(n_parameters, 1)), np.zeros(max(n_inputs, 1))]
            arrays.append(np.zeros(out_shape if out_shape else (1,)))
            b = local.buffers = (arrays, [a.ctypes.data for a in arrays])
        return b

    def call_single(state, p, t, u) -> np.ndarray:
        arrays, addresses = buffers()
        args: list = []
        for i, a in enumerate(state):
            arrays[i][:] = a
            args.append(addresses[i])
        if spec.takes_parameters:
            arrays[-3][:] = p
            args.append(addresses[-3])
        if spec.takes_time:
            args.append(float(t))
        if spec.takes_inputs:
            arrays[-2][:] = u
            args.append(addresses[-2])
        args.append(addresses[-1])
        status = single(*args)
        if status:
            raise _failed(spec.name, None, _STATUS.get(status, f"status {status}"))
        return arrays[-1].reshape(out_shape).copy()

    fast: Fast | None = None
    if spec.one_state_fast:
        # what the fast path accepts: float64 (or int64) vectors of the right length, lists
        # or tuples of that length; anything else goes the general way
        checks = [(k, (k,)) for k in sizes]
        if spec.takes_parameters:
            checks.append((n_parameters, (n_parameters,)))

        def fast(state: tuple[object, ...], params: object) -> np.ndarray | None:
            args = _plain_arguments(state, params, spec.takes_parameters, checks)
            if args is None:
                return None
            try:
                arrays, addresses = local.fast
            except AttributeError:
                arrays, addresses = local.fast = fast_buffers()
            try:
                for buffer, a in zip(arrays, args, strict=False):
                    buffer[:] = a
            except OverflowError:
                return None  # an int beyond float64: the general path explains
            if spec.takes_parameters and not parameters_hold(arrays[len(sizes)]):
                return None  # the general path names the parameter
            status = single(*addresses)
            if status:
                raise _failed(spec.name, None, _STATUS.get(status, f"status {status}"))
            return arrays[-1].reshape(out_shape).copy()

    def call(state, p, t, u):
        if spec.takes_parameters and p.ndim != 1:
            raise CodegenError(
                f"{spec.name}: the C backend shares one parameter vector across a batch;"
                f" got params of shape {p.shape}"
            )
        if (
            all(a.ndim == 1 for a in state)
            and (t is None or t.ndim == 0)
            and (u is None or u.ndim == 1)
        ):
            return call_single(state, p, t, u)
        parts = [a.shape[:-1] for a in state]
        if t is not None:
            parts.append(t.shape)
        if u is not None:
            parts.append(u.shape[:-1])
        lead = np.broadcast_shapes(*parts)
        count = int(np.prod(lead))
        arrays = [
            np.ascontiguousarray(np.broadcast_to(a, (*lead, k)).reshape(count, k))
            for a, k in zip(state, sizes, strict=True)
        ]
        args = [count, *[a.ctypes.data for a in arrays]]
        keep = list(arrays)
        if spec.takes_parameters:
            args.append(p.ctypes.data)
        if spec.takes_time:
            tt = np.ascontiguousarray(np.broadcast_to(t, lead).reshape(count))
            keep.append(tt)
            args.append(tt.ctypes.data)
        if spec.takes_inputs:
            uu = np.ascontiguousarray(
                np.broadcast_to(u, (*lead, n_inputs)).reshape(count, n_inputs)
            )
            keep.append(uu)
            args.append(uu.ctypes.data)
        out = np.empty((count, out_size))
        args.append(out.ctypes.data)
        first = batch(*args)
        if first:
            # re-run the failing state alone to learn why
            i = first - 1
            try:
                call_single(
                    [a[i] for a in arrays],
                    p,
                    tt[i] if spec.takes_time else None,
                    uu[i] if spec.takes_inputs else None,
                )
            except NumericalError as exc:
                raise _failed(spec.name, i, str(exc).split(": ", 1)[1]) from None
            raise _failed(spec.name, i, "failed in the batch call only")
        return out.reshape((*lead, *out_shape))

    return call, fast
