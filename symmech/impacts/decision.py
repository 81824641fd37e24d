"""The decision for a set of walls in contact: which walls take an impulse, and how much.

Frictionless generalized Newton law per contact (Moreau, "Unilateral contact and dry
friction in finite freedom dynamics", 1988; Glocker and Pfeiffer, "Multiple impacts with
friction in rigid multibody systems", Nonlinear Dynamics 1995; Brogliato, "Nonsmooth
Mechanics", ch. 6).  For the walls i = 1..k of a touching set, with pre-impact normal
rates ``u-_i = dpsi_i v- + psi_t,i``, restitutions alpha_i and the Delassus matrix ``W``
of their rows in the constrained metric (:attr:`symmech.impacts.several.SeveralImpactMap.
delassus`: ``u+ - u- = W Lambda``; permanent constraints projected out, the walls'
impulsive constraints held), the impulses solve

    0 <= Lambda_i  _|_  u+_i + alpha_i u-_i >= 0,      u+ = u- + W Lambda,

an LCP in Lambda: ``w = W Lambda + (1 + alpha) u-``.  Independent walls make W symmetric
positive definite, so there is exactly one solution (a P-matrix LCP), found exactly by
:func:`symmech.algebra.lcp.solve_lcp`.  The walls of its active set then take the
closed-form map of that set (``Scene.impact_map([...])``); the others take no impulse.

This is the simultaneous law: every closed contact of the set is resolved at once.  It is
not the only rigid multiple-impact law (three touching balls: (1, 0, 0) -> (-1/3, 2/3,
2/3) here, (0, 0, 1) by a cascade of one-wall impacts); see the README.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symmech.algebra.lcp import DEFAULT_RTOL, LCPError, solve_lcp
from symmech.errors import ImpactError

__all__ = ["ContactDecision", "simultaneous_impulses"]


@dataclass(frozen=True)
class ContactDecision:
    """The outcome of :func:`simultaneous_impulses`: the impulses ``Lambda`` (k), the
    post-impact normal rates ``u+ = u- + W Lambda`` (with ``u+_i = -alpha_i u-_i`` exactly
    where ``Lambda_i`` is free), the active walls (indices with a free impulse, the LCP's
    active set) and the LCP method used."""

    impulses: NDArray[np.float64]
    post_rates: NDArray[np.float64]
    active: tuple[int, ...]
    method: str


def simultaneous_impulses(
    W: ArrayLike,
    u_minus: ArrayLike,
    alpha: ArrayLike,
    *,
    method: Literal["auto", "enumerate", "murty"] = "auto",
    rtol: float = DEFAULT_RTOL,
) -> ContactDecision:
    """The impulses ``Lambda`` of the walls of a touching set (module docstring):
    ``0 <= Lambda _|_ u+ + alpha u- >= 0`` with ``u+ = u- + W Lambda``.

    ``W`` (k x k): the Delassus matrix at the contact state
    (:attr:`~symmech.impacts.several.SeveralImpactMap.delassus`); ``u_minus`` (k): the
    pre-impact normal rates ``dpsi_i v- + psi_t,i``
    (:attr:`~symmech.impacts.several.SeveralImpactMap.normal_rates`); ``alpha``: the
    restitutions (k, or one number).  ``method`` and ``rtol`` are those of
    :func:`symmech.algebra.lcp.solve_lcp` (active-set enumeration for k <= 4, Murty's
    principal pivoting beyond; its tolerance policy).

    Raises :class:`~symmech.ImpactError` for non-finite or non-real data, mismatched
    shapes, restitutions outside [0, 1], and an LCP without a solution (dependent walls).
    """
    try:
        u = np.asarray(u_minus, dtype=np.float64).ravel()
        a = np.broadcast_to(np.asarray(alpha, dtype=np.float64), u.shape).astype(np.float64)
    except (TypeError, ValueError) as exc:
        raise ImpactError(
            f"simultaneous impact: u_minus must be k real numbers and alpha one or k ({exc})"
        ) from None
    if not (np.all(np.isfinite(u)) and np.all(np.isfinite(a))):
        raise ImpactError("simultaneous impact: the normal rates and alphas must be finite")
    if np.any(a < 0) or np.any(a > 1):
        raise ImpactError(f"simultaneous impact: every alpha must lie in [0, 1], got {a}")
    try:
        sol = solve_lcp(W, (1.0 + a) * u, method=method, rtol=rtol)
    except LCPError as exc:
        raise ImpactError(f"simultaneous impact of {u.shape[0]} walls: {exc}") from None
    # w = u+ + alpha u-: u+ = w - alpha u-, exactly -alpha_i u-_i where w_i = 0
    return ContactDecision(
        impulses=sol.x, post_rates=sol.w - a * u, active=sol.active, method=sol.method
    )
