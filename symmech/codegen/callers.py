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

__all__ = [
    "PLAIN_TIMES",
    "Fast",
    "NumericalError",
    "Raw",
    "c_raw",
    "check_out",
    "numpy_fast",
    "numpy_raw",
]

_STATUS = {
    1: "a matrix that must be positive definite is not",
    2: "an output, or an input of its linear solve, is not finite",
}

#: A general caller: ``raw(state, p, t, u, out=None)``; ``out``, when given, a checked
#: (:func:`check_out`) array the output is written into and returned.
Raw = Callable[..., np.ndarray]
#: A fast single-state caller: the output, or None when the arguments are not the plain
#: case it handles (the general path then validates them and explains any problem).
Fast = Callable[[tuple[object, ...], object], "np.ndarray | None"]


class NumericalError(SymmechError, FloatingPointError):
    """A generated function failed at a state (non-SPD matrix or non-finite output)."""


def _failed(name: str, index: int | None, detail: str) -> NumericalError:
    where = f" at state {index}" if index is not None else ""
    return NumericalError(f"{name}{where}: {detail}")


def _by_name(spec: LoweredFunction, state: Sequence[object], p, t, u) -> list:
    """The values of ``spec``'s arguments in the order of its
    :attr:`~symmech.codegen.lower.LoweredFunction.arguments`."""
    given = {"p": p, "t": t, "u": u, **dict(zip(spec.state, state, strict=True))}
    return [given[a] for a in spec.arguments]


def check_out(name: str, out: object, shape: tuple[int, ...]) -> np.ndarray:
    """``out`` when it is an array the output of ``name`` (of shape ``shape``) can be
    written into: a NumPy array (not a subclass) of float64 in native byte order, of
    exactly that shape, C-contiguous and writeable; else a CodegenError naming the
    function, what was expected and what was given."""
    want = f"{name}: out= must be a C-contiguous, writeable float64 array of shape {shape}"
    if type(out) is not np.ndarray:
        raise CodegenError(f"{want}; got {type(out).__name__}")
    if out.dtype != np.float64:
        raise CodegenError(f"{want}; got dtype {out.dtype.str} ({out.dtype})")
    if out.shape != shape:
        raise CodegenError(f"{want}; got shape {out.shape}")
    if not out.flags.c_contiguous:
        raise CodegenError(f"{want}; got a non-contiguous array (strides {out.strides})")
    if not out.flags.writeable:
        raise CodegenError(f"{want}; got a read-only array")
    return out


def numpy_raw(fn: Callable, spec: LoweredFunction) -> Raw:
    shape_out = spec.out_shape

    def call(state, p, t, u, out=None):
        dest = out
        args = _by_name(spec, state, p, t, u)
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
        if dest is not None:  # computed whole first: out may alias an input
            dest[...] = out
            return dest
        return out

    return call


_SEQUENCES = (list, tuple)
_DTYPES = "dl"  # float64, int64 (any byte order: a copy converts)
_PLAIN = (float, int, np.float64)
#: The times a one-state call of a function of the state and the parameters only takes on
#: its fast path (it does not read them; anything else goes the general way, which checks).
PLAIN_TIMES = _PLAIN


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


def _float_lists(args: Sequence[object]) -> list[list] | None:
    """The plain arguments as lists of floats; None for an int beyond float64 (the general
    path explains)."""
    try:
        return [a.tolist() if type(a) is np.ndarray else [float(x) for x in a] for a in args]  # type: ignore[attr-defined]
    except OverflowError:
        return None


#: How a one-state NumPy variant fails: math's domain and overflow errors, a failed
#: factorisation (the general path then explains).
_EVALUATION_FAILURES = (ArithmeticError, ValueError, np.linalg.LinAlgError)


def numpy_fast(
    one: Callable, spec: LoweredFunction, n: int, n_parameters: int, rules: Sequence[ParameterRule]
) -> Fast:
    """The one-state caller of a NumPy function through its variant ``_one_<name>`` (plain
    floats, ``math``; the same operations in the same order as the vectorised function).
    None, for the general path to redo the call and explain, when the arguments are not
    plain, a parameter breaks its rule, or the evaluation fails or is not finite.  Its
    ``bind(p)`` is the same caller of the state alone at parameters already checked."""
    checks = [(k, (k,)) for k in spec.argument_sizes(n, n_parameters, 0)]
    state_checks = checks[: len(spec.state)]
    out_shape = spec.out_shape
    isfinite = math.isfinite

    flat = len(out_shape) == 1

    def outcome(values: list) -> list | None:
        try:
            out = one(*values)
        except _EVALUATION_FAILURES:
            return None
        # a finite sum means finite entries (an inf or a NaN makes any sum inf or NaN);
        # a sum that overflows sends a finite output to the general path, which is exact
        return out if isfinite(sum(out)) else None

    def evaluate(values: list) -> np.ndarray | None:
        out = outcome(values)
        if out is None:
            return None
        return np.array(out) if flat else np.array(out).reshape(out_shape)

    def fast(state: tuple[object, ...], params: object) -> np.ndarray | None:
        args = _plain_arguments(state, params, spec.takes_parameters, checks)
        if args is None:
            return None
        values = _float_lists(args)
        if values is None:
            return None
        if spec.takes_parameters:
            p = values[-1]
            if not all(isfinite(p[r.index]) and r.holds_value(p[r.index]) for r in rules):
                return None  # the general path names the parameter
        return evaluate(values)

    def bind(params: np.ndarray | None) -> Callable[[tuple[object, ...]], np.ndarray | None]:
        if params is not None and params.ndim != 1:
            return lambda state: None  # a batch of parameter vectors: the general path
        p = [params.tolist()] if spec.takes_parameters and params is not None else []

        def bound(state: tuple[object, ...]) -> np.ndarray | None:
            if len(state) == len(state_checks):  # the common case: float64 vectors
                values = []
                for a, (_, shape) in zip(state, state_checks, strict=True):
                    if type(a) is not np.ndarray or a.dtype.char != "d" or a.shape != shape:
                        break
                    values.append(a.tolist())
                else:
                    return evaluate(values + p)
            args = _plain_arguments(state, None, False, state_checks)
            if args is None:
                return None
            lists = _float_lists(args)
            return None if lists is None else evaluate(lists + p)

        return bound

    fast.bind = bind  # type: ignore[attr-defined]
    fast.plain = lambda params: _plain_caller(one, spec, params)  # type: ignore[attr-defined]
    return fast


def _plain_caller(
    one: Callable, spec: LoweredFunction, params: np.ndarray | None
) -> Callable[..., list | None] | None:
    """The one-state function over plain lists of floats (the state arrays as lists,
    each of its length) at parameters already checked: its output as a flat list, or
    None when the evaluation fails or is not finite (the general path explains).  For
    a loop of its own that converts a state once and calls several functions on it."""
    if not spec.one_state_fast or (params is not None and params.ndim != 1):
        return None
    p = [params.tolist()] if spec.takes_parameters and params is not None else []
    isfinite = math.isfinite

    def call(*values: list) -> list | None:  # (a hot path: no list built per call)
        try:
            out = one(*values, *p)
        except _EVALUATION_FAILURES:
            return None
        return out if isfinite(sum(out)) else None

    return call


def _prototypes(lib: ctypes.CDLL, prefix: str, spec: LoweredFunction) -> tuple[Any, Any]:
    """The one-state function as a prototype of plain addresses (a double for ``t``), and
    the batch function (``count`` first, a time per state), both over
    :attr:`~symmech.codegen.lower.LoweredFunction.arguments` and ``out``."""
    ptr = ctypes.c_void_p
    symbol = getattr(lib, prefix + spec.name)
    kinds = [ctypes.c_double if a == "t" else ptr for a in spec.arguments]
    single = ctypes.CFUNCTYPE(ctypes.c_int, *kinds, ptr)(ctypes.cast(symbol, ptr).value or 0)
    batch = getattr(lib, prefix + spec.name + "_batch")
    batch.argtypes = [ctypes.c_long, *([ptr] * len(spec.arguments)), ptr]
    batch.restype = ctypes.c_long
    return single, batch


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

    A single state is copied into per-thread float64 buffers, one per argument of
    :attr:`~symmech.codegen.lower.LoweredFunction.arguments` and one for ``out``, whose
    addresses are taken once, and the function is called through a prototype of plain
    addresses: no ctypes array conversion and no address lookup per call
    (``ndarray.ctypes`` costs about a microsecond, as much as a small generated function).
    """
    single, batch = _prototypes(lib, prefix, spec)
    names = spec.arguments
    sizes = spec.argument_sizes(n, n_parameters, n_inputs)
    out_shape = spec.out_shape
    local = threading.local()

    def buffers() -> tuple[list[np.ndarray], list[int]]:
        """This thread's buffers (ctypes releases the GIL during the call, so threads must
        not share them): one per array argument (a placeholder for ``t``), then ``out``;
        and their addresses."""
        b = getattr(local, "buffers", None)
        if b is None:
            arrays = [np.zeros(max(k, 1)) for k in sizes]
            arrays.append(np.zeros(out_shape if out_shape else (1,)))
            b = local.buffers = (arrays, [a.ctypes.data for a in arrays])
        return b

    def call_single(values: Sequence[Any]) -> np.ndarray:
        """One state: ``values`` in the order of the arguments."""
        arrays, addresses = buffers()
        args: list = []
        for name, value, buffer, address in zip(names, values, arrays, addresses, strict=False):
            if name == "t":
                args.append(float(value))
            else:
                buffer[:] = value
                args.append(address)
        status = single(*args, addresses[-1])
        if status:
            raise _failed(spec.name, None, _STATUS.get(status, f"status {status}"))
        return arrays[-1].reshape(out_shape).copy()

    fast = _fast_caller(spec, single, buffers, sizes, rules) if spec.one_state_fast else None

    def call(state, p, t, u, out=None):
        if spec.takes_parameters and p.ndim != 1:
            raise CodegenError(
                f"{spec.name}: the C backend shares one parameter vector across a batch;"
                f" got params of shape {p.shape}"
            )
        values = _by_name(spec, state, p, t, u)
        leads = [
            v.shape if a == "t" else v.shape[:-1]
            for a, v in zip(names, values, strict=True)
            if a != "p"
        ]
        lead = np.broadcast_shapes(*leads)
        if lead == ():
            if out is None:
                return call_single(values)
            out[...] = call_single(values)
            return out
        return _batch(batch, call_single, spec, sizes, values, lead, out)

    return call, fast


def _fast_caller(
    spec: LoweredFunction,
    single: Any,
    buffers: Callable[[], tuple[list[np.ndarray], list[int]]],
    sizes: Sequence[int],
    rules: Sequence[ParameterRule],
) -> Fast:
    """The fast single-state caller of :func:`c_raw` (a function of the state and the
    parameters only): plain float64 (or int64) vectors of the right length, lists or
    tuples of that length, written into the thread's buffers; anything else (and a
    parameter outside its rule) returns None, so the general path explains."""
    checks = [(k, (k,)) for k in sizes]
    where_p = spec.arguments.index("p") if spec.takes_parameters else -1
    out_shape = spec.out_shape

    def fast(state: tuple[object, ...], params: object) -> np.ndarray | None:
        args = _plain_arguments(state, params, spec.takes_parameters, checks)
        if args is None:
            return None
        arrays, addresses = buffers()
        try:
            for buffer, a in zip(arrays, args, strict=False):
                buffer[:] = a
        except OverflowError:
            return None  # an int beyond float64: the general path explains
        if where_p >= 0 and not _parameters_hold(rules, arrays[where_p]):
            return None  # the general path names the parameter
        status = single(*addresses)
        if status:
            raise _failed(spec.name, None, _STATUS.get(status, f"status {status}"))
        return arrays[-1].reshape(out_shape).copy()

    return fast


def _batch(
    batch: Any,
    call_single: Callable[[Sequence[Any]], np.ndarray],
    spec: LoweredFunction,
    sizes: Sequence[int],
    values: Sequence[Any],
    lead: tuple[int, ...],
    dest: np.ndarray | None = None,
) -> np.ndarray:
    """The batch function over the states of shape ``lead`` (the arguments broadcast and
    made contiguous, p shared); a failing state is run alone to learn why.  The output is
    written into ``dest`` (checked by :func:`check_out`) when given, through a fresh array
    when ``dest`` may share memory with an argument (the generated loop would read states
    it has overwritten)."""
    names = spec.arguments
    count = int(np.prod(lead))
    per_state = [
        v
        if a == "p"
        else np.ascontiguousarray(np.broadcast_to(v, lead).reshape(count))
        if a == "t"
        else np.ascontiguousarray(np.broadcast_to(v, (*lead, k)).reshape(count, k))
        for a, v, k in zip(names, values, sizes, strict=True)
    ]
    shared = dest is not None and any(
        isinstance(a, np.ndarray) and np.may_share_memory(dest, a) for a in per_state
    )
    if dest is None or shared:
        out = np.empty((count, spec.out_size))
    else:
        out = dest.reshape(count, spec.out_size)  # a view: dest is C-contiguous
    first = batch(count, *[a.ctypes.data for a in per_state], out.ctypes.data)
    if first:
        i = first - 1
        try:
            call_single([v if a == "p" else v[i] for a, v in zip(names, per_state, strict=True)])
        except NumericalError as exc:
            raise _failed(spec.name, i, str(exc).split(": ", 1)[1]) from None
        raise _failed(spec.name, i, "failed in the batch call only")
    if dest is None:
        return out.reshape((*lead, *spec.out_shape))
    if shared:
        dest[...] = out.reshape(dest.shape)
    return dest


def _parameters_hold(rules: Sequence[ParameterRule], p: np.ndarray) -> bool:
    """Whether one parameter vector is finite and within its declared ranges."""
    values = p.tolist()
    return all(math.isfinite(values[r.index]) and r.holds_value(values[r.index]) for r in rules)
