"""The coefficients a C implementation of each integration method needs, as Python floats
(:func:`c_tableau`): the simulator's C loop (:mod:`symmech.simulate.csim`) and the gait
stride loop (:mod:`symmech.gait.native`) print them into their templates from the exact
tableaux of :mod:`symmech.simulate.tableaux`.
"""

from __future__ import annotations

from symmech.simulate.steppers import METHODS, StepperError
from symmech.simulate.tableaux import DOP853, DOP853_EXTRAS, RK4, RK45, RODAS4, TSIT5

__all__ = ["c_tableau"]


def _lower(M) -> list[float]:
    """The strictly lower triangle of a square matrix, row by row."""
    return [float(M[i][j]) for i in range(1, len(M)) for j in range(i)]


def c_tableau(name: str) -> dict[str, list[float]]:
    """Every coefficient a C implementation of method ``name`` needs, as Python floats.

    Matrices ``a`` (and ``C`` for rodas4) are flattened strictly-lower triangles, row by
    row (``a[1][0], a[2][0], a[2][1], ...``).  Explicit methods: ``c``, ``a``, ``b`` (the
    ``s`` stages) and ``e`` (error weights over ``K_0..K_s``, ``K_s = f(t0 + h, y1)``);
    tsit5 and rk45 add ``dense``, the ``(s + 1) x 4`` matrix ``P`` row by row
    (``y(t0 + theta h) = y0 + h sum_i K_i sum_k P_ik theta^(k+1)``); dop853 adds ``e3``,
    ``c_extra`` (3), ``a_extra`` (rows 13..15 over ``K_0..K_(i-1)``, 13 + 14 + 15 entries)
    and ``d`` (4 x 16, row by row) for :class:`_Dop853Dense`; rk4 has no ``e``.  rodas4:
    ``gamma`` (one entry), ``c``, ``d``, ``a``, ``C``, ``b``, ``bhat`` and ``h`` (2 x 6).
    """
    if name == "rodas4":
        t = RODAS4
        return {
            "gamma": [float(t.gamma)],
            "c": [float(v) for v in t.c],
            "d": [float(v) for v in t.d],
            "a": _lower(t.a),
            "C": _lower(t.C),
            "b": [float(v) for v in t.b],
            "bhat": [float(v) for v in t.bhat],
            "h": [float(v) for row in t.h for v in row],
        }
    tab = {"dop853": DOP853, "tsit5": TSIT5, "rk45": RK45, "rk4": RK4}.get(name)
    if tab is None:
        raise StepperError(
            f"unknown integration method {name!r}: choose one of {', '.join(METHODS)}"
        )
    out = {"c": [float(v) for v in tab.c], "a": _lower(tab.a), "b": [float(v) for v in tab.b]}
    if name != "rk4":
        out["e"] = [float(v) for v in tab.e]
    if tab.dense:
        out["dense"] = [float(v) for row in tab.dense for v in row]
    if name == "dop853":
        x = DOP853_EXTRAS
        out["e3"] = [float(v) for v in x.e3]
        out["c_extra"] = [float(v) for v in x.c_extra]
        out["a_extra"] = [float(x.a_extra[r][j]) for r in range(3) for j in range(13 + r)]
        out["d"] = [float(v) for row in x.d for v in row]
    return out
