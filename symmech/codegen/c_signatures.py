"""The argument lists of generated C functions, printed in Python (the header, the source
and the batch loops share them; the templates only place them).

A function of the state arrays (``q``, ``v``, or ``y = (q, v)``) takes, in order, the
arrays it reads, then ``p`` (the parameters), ``t`` (the time), ``u`` (the inputs) if it
reads them, and ``out``.  Its batch form takes ``count`` first and a time per state.
"""

from __future__ import annotations

from symmech.codegen.lower import LoweredFunction

__all__ = ["batch_parameters", "call_arguments", "parameters", "scaled_arguments"]


def _state(fn: LoweredFunction, declare: str) -> list[str]:
    if fn.state == ("y",):
        return [f"{declare}y"]
    return [f"{declare}{s}" for s in fn.state]


def parameters(fn: LoweredFunction) -> str:
    """``const double *q, const double *v, const double *p, double t, const double *u,
    double *out`` (the arrays ``fn`` reads)."""
    out = _state(fn, "const double *")
    out += ["const double *p"] * fn.takes_parameters
    out += ["double t"] * fn.takes_time
    out += ["const double *u"] * fn.takes_inputs
    return ", ".join([*out, "double *out"])


def batch_parameters(fn: LoweredFunction) -> str:
    """``long count, ...``: the batch form, with a time per state."""
    out = ["long count", *_state(fn, "const double *")]
    out += ["const double *p"] * fn.takes_parameters
    out += ["const double *t"] * fn.takes_time
    out += ["const double *u"] * fn.takes_inputs
    return ", ".join([*out, "double *out"])


def call_arguments(fn: LoweredFunction, n: int, n_inputs: int, stride: int) -> str:
    """The arguments of the one-state call for state ``i`` of a batch."""
    if fn.state == ("y",):
        out = [f"y + i*{2 * n}"]
    else:
        out = [f"{s} + i*{n}" for s in fn.state]
    out += ["p"] * fn.takes_parameters
    out += ["t[i]"] * fn.takes_time
    out += [f"u + i*{n_inputs}"] * fn.takes_inputs
    return ", ".join([*out, f"out + i*{stride}"])


def scaled_arguments(fn: LoweredFunction, velocity: str) -> str:
    """The arguments of the unscaled impact map for the scaled velocity ``velocity``."""
    out = ["q", velocity]
    out += ["p"] * fn.takes_parameters
    out += ["t"] * fn.takes_time
    out += ["u"] * fn.takes_inputs
    return ", ".join([*out, "out"])
