"""Applied generalized forces: the non-potential part of the equations of motion.

A scene's equations are ``g v_dot = f + F + mu^T lambda`` where f holds the velocity-quadratic
(Christoffel, or connection) terms and the potential, and ``F`` is what the user applies:
damping, friction torques, motors, a controller's inputs (the "specified" quantities of
PyDy).  F is a covector (a one-form ``F_i dq^i``), given by its components in the scene's
velocity basis:

* without a frame, ``F_i`` is the generalized force dual to ``q_dot^i``: the virtual power of
  the applied loads is ``F_i q_dot^i`` (Lagrange's ``Q_i`` in ``d/dt dT/dq_dot - dT/dq =
  -dV/dq + Q``);
* with a frame ``q_dot = S v``, ``F_r`` is dual to the quasi-velocity ``v^r``: Kane's
  generalized active force ``F_r = sum_P R_P . dv_P/dv^r``, i.e. ``F = S^T Q`` (slides 000,
  Kane's method).

An entry may depend on the coordinates, the velocities of the basis, the time t, the
parameters and undefined functions of t (run-time inputs of generated code, e.g.
``tau(t)`` or ``sympy.physics.mechanics.dynamicsymbols("tau")``).  It is a real smooth
function; nothing else about it is assumed (it need not be linear in v, nor derive from a
potential).
"""

from __future__ import annotations

from collections.abc import Callable

import sympy as sp

from symmech.declaration.checks import Field, Problems

__all__ = ["forces_field"]


def forces_field(
    value: object,
    n: int,
    allowed: frozenset,
    expr: Callable[[object, str], sp.Expr | None],
    problems: Problems,
) -> Field | None:
    """The ``forces`` field as an n x 1 column, or None when absent or malformed.

    ``value`` is a sequence of n entries (numbers, sympy expressions or strings) or an
    n x 1 / 1 x n sympy Matrix; each problem found is recorded in ``problems``.
    """
    if value is None:
        return None
    if isinstance(value, sp.MatrixBase):
        if 1 not in value.shape:
            problems.add(f"forces: expected a column of {n} entries, got a {value.shape} matrix")
            return None
        entries = list(value)
    elif isinstance(value, (str, bytes, sp.Basic)) or not hasattr(value, "__iter__"):
        problems.add(
            f"forces: expected a sequence of {n} generalized forces (one per velocity), got"
            f" {value!r}"
        )
        return None
    else:
        entries = list(value)
    if len(entries) != n:
        problems.add(
            f"forces: {len(entries)} entries for {n} velocities; give one generalized force per"
            " velocity of the basis (0 where nothing is applied)"
        )
        return None
    out = []
    for k, e in enumerate(entries):
        with problems.about(f"forces[{k}]"):
            out.append(expr(e, f"forces[{k}]"))
    if any(e is None for e in out):
        return None
    return Field("forces", sp.Matrix(n, 1, out), allowed, True)
