"""The argument lists of generated C functions, printed in Python from
:attr:`~symmech.codegen.lower.LoweredFunction.arguments` (the header, the source and the
batch loops share them; the templates only place them).

A function of the state arrays (``q``, ``v``, or ``y = (q, v)``) takes, in order, the
arrays it reads, then ``p`` (the parameters), ``t`` (the time), ``u`` (the inputs) if it
reads them, and ``out``.  Its batch form takes ``count`` first and a time per state.
"""

from __future__ import annotations

from symmech.codegen.lower import LoweredFunction

__all__ = ["batch_parameters", "call_arguments", "parameters", "scaled_arguments"]


def parameters(fn: LoweredFunction) -> str:
    """``const double *q, const double *v, const double *p, double t, const double *u,
    double *out`` (the arrays ``fn`` reads)."""
    out = ["double t" if a == "t" else f"const double *{a}" for a in fn.arguments]
    return ", ".join([*out, "double *out"])


def batch_parameters(fn: LoweredFunction) -> str:
    """``long count, ...``: the batch form, with a time per state."""
    out = [f"const double *{a}" for a in fn.arguments]
    return ", ".join(["long count", *out, "double *out"])


def call_arguments(
    fn: LoweredFunction, n: int, n_inputs: int, stride: int, velocity: str = ""
) -> str:
    """The arguments of the one-state call for state ``i`` of a batch (``velocity``: the
    velocity argument in place of ``v + i*n``, the scaled one of a block)."""
    out = []
    for a, size in zip(fn.arguments, fn.argument_sizes(n, 0, n_inputs), strict=True):
        if a == "v" and velocity:
            out.append(velocity)
        else:
            out.append("t[i]" if a == "t" else "p" if a == "p" else f"{a} + i*{size}")
    return ", ".join([*out, f"out + i*{stride}"])


def scaled_arguments(fn: LoweredFunction, velocity: str) -> str:
    """The arguments of the unscaled impact map for the scaled velocity ``velocity``."""
    return ", ".join([*(velocity if a == "v" else a for a in fn.arguments), "out"])
