"""Operation counts of the linear-algebra steps of generated code.

:func:`step_flops` counts the floating-point operations of a step
(:data:`symmech.codegen.plan.STEPS`) as the loop algorithm performs it on a dense problem:
the figure printed beside what the unrolled code (:mod:`symmech.codegen.unroll`) performs
in every function's header, and the bound the tests hold the unrolled code to.
"""

from __future__ import annotations

from symmech.codegen.blocks import CodegenError
from symmech.codegen.unroll import CONSTRAINED_STEPS

__all__ = ["step_flops", "step_sizes"]


def _cholesky_flops(n: int) -> int:
    """sm_cholesky: column j costs 2j + 2 (its diagonal, the sqrt and the reciprocal)
    and 2j + 1 for each of the n - 1 - j rows below it."""
    return sum(2 * j + 2 + (n - 1 - j) * (2 * j + 1) for j in range(n))


def _factor_flops(n: int, diag: int) -> int:
    """A diagonal metric is only checked (its solve divides by the diagonal)."""
    return 0 if diag else _cholesky_flops(n)


def _factor_solve_flops(n: int, diag: int, r: int) -> int:
    """Forward and back substitution cost n^2 each per column; a diagonal metric n r
    divisions."""
    return n * r if diag else 2 * n * n * r


def step_flops(step: str | None, args: tuple[int, ...]) -> int:
    """Floating-point operations (+ - * / sqrt, one each) of a linear-algebra step as the
    loop algorithm performs it on a dense problem with the sizes ``args`` of
    :class:`~symmech.codegen.plan.FunctionPlan`: an upper bound of what the unrolled code
    of :mod:`symmech.codegen.unroll` performs (it skips the operations on constants and,
    in C = mu X_mu and G = A Y, the upper triangle that the factorisation never reads).

    ``spd_solve`` (n, diag): factor and one solve.  ``constrained_*`` (n, m, diag): factor,
    a solve with m + 1 columns, ``C = mu X_mu`` (2 n m^2) and ``mu X_f`` (2 n m), the
    Cholesky factorisation of C and one solve (2 m^2), and for the acceleration
    (``constrained_acceleration``, ``constrained_dynamics``) ``X_f + X_mu lambda``
    (2 n m).  ``impact_kkt`` (n, k, m, diag): factor, a solve with k columns, ``A v``
    (2 n k), ``G = A Y`` (2 n k^2), the right-hand side (3 per row from row m on), the
    Cholesky factorisation of G and one solve (2 k^2; for k = 1 one division), and
    ``v + Y lambda`` (2 n k).
    """
    if step is None:
        return 0
    if step == "spd_solve":
        n, diag = args
        return _factor_flops(n, diag) + _factor_solve_flops(n, diag, 1)
    if step in CONSTRAINED_STEPS:
        n, m, diag = args
        out = _factor_flops(n, diag) + _factor_solve_flops(n, diag, m + 1)
        out += 2 * n * m * m + 2 * n * m + _cholesky_flops(m) + 2 * m * m
        return out + (2 * n * m if step != "constrained_multipliers" else 0)
    if step == "impact_kkt":
        n, k, m, diag = args
        out = _factor_flops(n, diag) + _factor_solve_flops(n, diag, k)
        out += 2 * n * k + 2 * n * k * k + 3 * (k - m)
        out += 1 if k == 1 else _cholesky_flops(k) + 2 * k * k  # one row: r / G
        return out + 2 * n * k
    raise CodegenError(f"unknown linear-algebra step {step!r}")


def step_sizes(step: str, args: tuple[int, ...]) -> str:
    """The sizes of a step for a function's header: ``n = 6, m = 3, diagonal metric``."""
    diag = ", diagonal metric" if args[-1] else ""
    if step == "spd_solve":
        return f"n = {args[0]}{diag}"
    if step == "impact_kkt":
        return f"n = {args[0]}, k = {args[1]}{diag}"
    return f"n = {args[0]}, m = {args[1]}{diag}"
