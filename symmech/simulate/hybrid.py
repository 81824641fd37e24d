"""The hybrid loop: flow, events, impact maps, accumulation and resting contact.

One run alternates smooth phases and events.  Each accepted step of the flow
(:mod:`symmech.simulate.flow`) is searched for events before it is accepted
(:mod:`symmech.simulate.detection`; roots by :mod:`symmech.simulate.events`): a wall's
gap psi turning negative, or, while in contact, the normal contact force lambda_N turning
negative.  The step is cut at the earliest event
(located on the continuous output, reported on the admissible side) and the loop restarts
the flow from the state the event produces.

**At a wall** (psi = 0), with the normal rate ``r = d psi/dt = dpsi q_dot + psi_t`` and the
velocity tolerance ``tol_v = atol + rtol |v|_inf``:

* ``r < -tol_v``: an **impact**.  The scene's impact map gives v+ (Carnot paper eqs. 10,
  17, 20; text 001 Theorem 2.12).  Walls reached at the same instant (``psi <= tol_psi``,
  ``tol_psi = 10 atol``) that still approach after it are resolved one at a time, the one
  with the most negative normal rate first (ties: the lowest index), until none approaches:
  the sequential rule, deterministic, and for a row of equal elastic balls (Newton's
  cradle) the velocity passes down the row.
* ``|r| <= tol_v``: the wall is reached tangentially.  If the wall would have to push to
  keep the body out (lambda_N > 0 in its contact mode), or the body still creeps in
  (``r < -100 eps |v|_inf``, faster than the rounding of r) and nothing pulls it away
  (lambda_N >= 0), it stays on the wall: **contact** (so a slow approach never tunnels).
  Otherwise it is a **grazing** touch: reported, no impact map, and the free flow, which
  leads away from the wall (or creeps at the rounding level: the residue of an impact
  map between two balls left at rest), continues.
* **Accumulation (Zeno)**: after an impact whose rebound rate is below ``zeno_factor tol_v``
  (or so slow that its bounce would not rise above the position resolution, see
  :meth:`_Run.zeno_speed`) while the wall would have to push (lambda_N > 0), the impacts
  accumulate.  The
  accumulation time is estimated from the geometric decay of the last flight times,
  ``t* = t_k + dt_k rho / (1 - rho)`` with ``rho = dt_k / dt_(k-1)`` (exact for the bouncing
  ball).  With ``contact="stop"`` the run ends there with status ``"zeno"``; with
  ``contact="persistent"`` the velocity is projected onto the contact distribution (a
  perfectly plastic impact: Carnot paper eq. 10 with alpha = 0, and for a rough wall the
  rolling constraint kept) and the wall becomes an active holonomic constraint (see
  :func:`symmech.simulate.system.contact_scene`) until lambda_N would turn negative
  (**release**).  A moving wall has no contact mode: its accumulation stops the run.

**Conditioning.**  Before each impact of a constrained scene the condition number of the
Gram matrix ``[mu; dpsi S] g^-1 [mu; dpsi S]^T`` is computed (``stats["impact_condition"]``
is the largest); the impulse's relative error grows like it, and past :data:`COND_LIMIT`
the run stops with status ``"failed"`` and says why (a wall nearly dependent on the
constraints).

**Bounds.**  ``max_events`` events or ``max_steps`` accepted steps end the run with
status ``"max_events"`` or ``"max_steps"`` (a tiny ``max_step``, or a step size collapsing
on a stiff scene, would otherwise run without end: in C, without a way to interrupt it).
The last step to ``t_end`` is taken however short, so a run may end a few ulps after an
event; a step the controller shrinks below the resolution of t ends the run as
``"failed"``.

**Drift.**  After each accepted step of a constrained flow the velocity is projected with
the mode's P(q) (Carnot paper section 2.2) and, in contact, the position is moved back onto
psi = 0 along the gradient (one Newton step); the largest residual before projection is
``stats["constraint_drift"]``.  Where the flow conserves energy (potential independent of
t), ``stats["energy_drift"]`` is the largest ``|E(t) - E(0) - sum of the events' dE|``.
"""

from __future__ import annotations

import math
import time as _time
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from symmech.codegen.module import NumericalError
from symmech.simulate.detection import StepSearch
from symmech.simulate.flow import FlowFailure, Segment
from symmech.simulate.impact_sets import (
    COND_LIMIT,
    Stop,
    impact_alone,
    impact_together,
    simultaneous_group,
)
from symmech.simulate.impulses import solve_small
from symmech.simulate.result import Event, SimulationResult
from symmech.simulate.system import SimulationError

__all__ = ["COND_LIMIT", "MAX_STEPS", "Options", "run"]

#: Default bound on the accepted steps of one run (:attr:`Options.max_steps`).
MAX_STEPS = 10_000_000

#: After an event the flow restarts no longer than the step it cut, and never shorter
#: than this fraction of it (the step-size controller's own smallest factor, HNW I,
#: II.4): an event a few ulps after a step's start must not shrink the next step to that
#: sliver.
RESTART_FLOOR = 0.2


@dataclass(frozen=True)
class Options:
    """Options of one run (validated by :func:`symmech.simulate.simulate`)."""

    t_end: float
    rtol: float
    atol: float
    max_events: int = 100_000
    contact: str = "persistent"
    samples: int = 8
    zeno_factor: float = 100.0
    max_steps: int = MAX_STEPS
    impact_law: str = "simultaneous"


class Flow(Protocol):
    @property
    def stats(self) -> Any: ...

    def start(self, t: float, y: np.ndarray, t_bound: float) -> None: ...
    def advance(self) -> Segment: ...
    def limit_step(self, h: float) -> None: ...
    def accept_projection(self, y: np.ndarray) -> None: ...


class _Run:
    """The state of one run (see the module docstring)."""

    def __init__(self, fns: Any, flow: Flow, t0: float, y0: np.ndarray, opts: Options):
        self.f, self.flow, self.o = fns, flow, opts
        self.mode = ()
        self.n = fns.n
        self.walls = fns.walls
        self.names = fns.wall_names
        self.t = t0
        self.y = fns.array(y0)
        self.ts: list[float] = [t0]
        self.ys: list[np.ndarray] = [self.y.copy()]
        self.segments: list[tuple[float, float, Any]] = []
        self.events: list[Event] = []
        self.history: dict[int, list[float]] = {w: [] for w in range(self.walls)}
        self.energy0 = math.nan  # set by start(): a failing call there ends the run
        self.energy_jumps = 0.0
        self.energy_drift = 0.0
        self.drift = 0.0
        self.tol_psi = 10 * opts.atol
        #: the run's time scale, min(1, |t_end|): the resolution of t near t = 0 is
        #: measured against it (step floor, event location, difference steps)
        self.time_scale = min(1, abs(opts.t_end))
        self.condition = 1.0
        #: walls grazed and not yet left (psi < 0 at every accepted step end since): a
        #: start inside such a wall is not an event again
        self.grazing: set[int] = set()
        #: walls released and not yet left beyond tol_psi: searched through psi + tol_psi
        self.banded: set[int] = set()

    @property
    def mode(self) -> tuple[int, ...]:
        """The walls in contact, sorted (``()``: free flight); the flow integrates this
        mode."""
        return self.f.mode

    @mode.setter
    def mode(self, walls: tuple[int, ...]) -> None:
        self.f.mode = tuple(sorted(walls))

    # -- helpers ----------------------------------------------------------------------------
    def q(self, y: np.ndarray) -> np.ndarray:
        return y[: self.n]

    def v(self, y: np.ndarray) -> np.ndarray:
        return y[self.n :]

    def speed(self, y: np.ndarray) -> float:
        """``|v|_inf``, the scale of the velocity tolerances below."""
        return max(map(abs, self.v(y).tolist()), default=0)

    def tol_v(self, y: np.ndarray) -> float:
        return self.o.atol + self.o.rtol * self.speed(y)

    def creep_floor(self, y: np.ndarray) -> float:
        """The rounding level of a normal rate, ``100 eps |v|_inf``: an approach slower
        than this (the residue of an impact map that should leave two equal balls at
        rest) is no approach."""
        return 100 * self.f.eps * self.speed(y)

    def record(self, t: float, y: np.ndarray) -> None:
        self.ts.append(t)
        self.ys.append(self.f.array(y))

    def event(
        self,
        kind: str,
        wall: int,
        y_minus: np.ndarray,
        y_plus: np.ndarray,
        rate: float,
        count_energy: bool = True,
    ) -> None:
        """Record an event; ``count_energy=False`` for the second and later walls of a
        simultaneous impact (the first carries the set's energy change)."""
        q = self.q(y_minus)
        e0 = self.f.energy(self.t, q, self.v(y_minus))
        e1 = self.f.energy(self.t, self.q(y_plus), self.v(y_plus)) if count_energy else e0
        self.energy_jumps += e1 - e0
        self.events.append(
            Event(
                time=self.t,
                wall=wall,
                wall_name=self.names[wall],
                kind=kind,
                q=q.copy(),
                v_minus=self.v(y_minus).copy(),
                v_plus=self.v(y_plus).copy(),
                energy_change=e1 - e0,
                normal_speed=rate,
            )
        )
        if len(self.events) >= self.o.max_events:
            raise Stop(
                "max_events", f"stopped after {len(self.events)} events at t = {float(self.t)!r}"
            )

    def needs_push(self, wall: int, y: np.ndarray) -> bool:
        """Whether the wall would have to push to keep the body out of it (lambda_N > 0),
        held together with the walls already in contact."""
        return self.normal_force(wall, y) > 0

    def with_wall(self, wall: int) -> tuple[int, ...]:
        """The current contact mode with ``wall`` added."""
        return tuple(sorted({*self.mode, wall}))

    def normal_force(self, wall: int, y: np.ndarray) -> float:
        """lambda_N of ``wall`` in the contact mode of the walls in contact and ``wall``,
        at the state with its normal velocity removed; for a moving wall (no contact
        mode) minus the second derivative of psi along the free flow, which has the same
        sign."""
        if self.f.moving[wall] or any(self.f.moving[w] for w in self.mode):
            return -self._free_psi_acceleration(wall, y)
        mode = self.with_wall(wall)
        q = self.q(y)
        v = self.f.project(mode, self.t, q, self.v(y))
        return self.f.normal_force(wall, self.t, q, v, mode)

    def zeno_speed(self, wall: int, y: np.ndarray) -> Any:
        """The rebound speed below which impacts accumulate: ``zeno_factor tol_v``, or the
        speed whose bounce ``r^2 / (2 |psi''|)`` does not rise above the position
        resolution ``max(atol, 16 eps |q|_inf)``: a bounce lower than the absolute
        tolerance is rest, and one lower than the arithmetic's resolution of q cannot be
        resolved at all (its events would stall, not decay)."""
        acc = abs(self._free_psi_acceleration(wall, y))
        q_max = max(map(abs, self.q(y).tolist()), default=0)
        resolution = max(self.o.atol, 16 * self.f.eps * q_max)
        return max(self.o.zeno_factor * self.tol_v(y), (2 * acc * resolution) ** 0.5)

    def _free_psi_acceleration(self, wall: int, y: np.ndarray) -> float:
        """``d^2 psi/dt^2`` of ``wall`` along the free flow at ``y``: a forward difference
        of the normal rate (the rate at ``y`` is the one the loop keeps)."""
        h = 1e-6 * max(self.time_scale, abs(self.t))
        ydot = self.f.rhs((), self.t, y)
        r0 = self.f.normal_rate(wall, self.t, y)
        y1 = y + h * ydot
        r1 = self.f.rate(wall, self.t + h, y1, self.f.rhs((), self.t + h, y1))
        return (r1 - r0) / h

    # -- events -----------------------------------------------------------------------------
    def detect(self, seg: Segment) -> tuple[float, np.ndarray, int, str] | None:
        """The earliest event inside ``seg``: (time, state, wall, "wall" | "release")
        (:class:`~symmech.simulate.detection.StepSearch`)."""
        return StepSearch(self, seg).earliest()

    def at_wall(self, wall: int) -> None:
        """Resolve the contact with ``wall`` reached at (self.t, self.y)."""
        y = self.y
        rate = self.f.normal_rate(wall, self.t, y)
        tol_v = self.tol_v(y)
        self.grazing.discard(wall)
        self.banded.discard(wall)
        if rate >= -tol_v:
            # reached tangentially: a resting contact if the wall must (or may) hold the
            # body while it still creeps in (lambda_N >= 0, faster than rounding), else a
            # grazing touch
            force = self.normal_force(wall, y)
            if force > 0 or (rate < -self.creep_floor(y) and force >= 0):
                self.enter_contact(wall, rate, reason="grazing contact with the wall pressing")
            else:
                self.event("grazing", wall, y, y, rate)
                if abs(rate) <= self.creep_floor(y):  # touching, moving together
                    self.banded.add(wall)
                else:
                    self.grazing.add(wall)
            return
        self.impacts(wall, rate)

    def impacts(self, first: int, rate: float) -> None:
        """Impact at ``first`` and every wall closed and approaching with it, resolved
        together by the generalized Newton law (:mod:`.impact_sets`, :mod:`.impulses`; with
        ``impact_law="sequential"``, or a set that holds a wall without a Newton
        direction, one wall at a time, the most negative rate first); then, in cascade,
        the walls that approach as a result."""
        hit: list[int] = []
        wall, r = first, rate
        for _ in range(100 * max(self.walls, 1)):
            group = simultaneous_group(self)
            struck = impact_together(self, group) if group else None
            if struck is None:
                struck = [wall]
                impact_alone(self, wall, r)
            for w in struck:
                self.history[w].append(self.t)
                hit.append(w)
            nxt = self.approaching()
            if nxt is None:
                break
            wall, r = nxt
        else:
            raise Stop(
                "failed",
                f"simultaneous impacts at t = {float(self.t)!r} did not resolve in"
                f" {100 * self.walls} rounds of the impact law",
            )
        self.band_touching()
        self.check_accumulation(list(dict.fromkeys(hit)))

    def band_touching(self) -> None:
        """Walls at contact (``|psi| <= tol_psi``) whose normal rate is below the rounding
        level (``creep_floor``): bodies that touch and move together, as the balls of a
        cradle left at rest by an impact.  Their gap hovers at 0 +- a few ulps of q, which
        is no event: they are searched through ``psi + tol_psi`` until they part."""
        y = self.y
        floor = self.creep_floor(y)
        for w in range(self.walls):
            if w in self.mode or abs(self.f.psi(w, self.t, self.q(y))) > self.tol_psi:
                continue
            if abs(self.f.normal_rate(w, self.t, y)) <= floor:
                self.banded.add(w)
                self.grazing.discard(w)

    def approaching_walls(self) -> list[tuple[int, float]]:
        """The walls at contact (psi <= tol_psi) whose normal rate is below -tol_v, with
        their rates, in the order of the walls."""
        y = self.y
        tol_v = self.tol_v(y)
        out = []
        for w in range(self.walls):
            if w in self.mode or self.f.psi(w, self.t, self.q(y)) > self.tol_psi:
                continue
            r = self.f.normal_rate(w, self.t, y)
            if r < -tol_v:
                out.append((w, r))
        return out

    def approaching(self) -> tuple[int, float] | None:
        """The wall at contact (psi <= tol_psi) with the most negative normal rate below
        -tol_v (ties: the lowest index), or None."""
        best: tuple[int, float] | None = None
        for w, r in self.approaching_walls():
            if best is None or r < best[1]:
                best = (w, r)
        return best

    def check_accumulation(self, walls: list[int]) -> None:
        """The walls just hit whose impacts accumulate (rebound below :meth:`zeno_speed`
        while the wall would have to push) are held, together: walls that accumulate at
        one instant (a rod bouncing flat) enter contact at once, so that none of them is
        made plastic before the others."""
        y = self.y
        held: list[tuple[int, float]] = []
        for wall in walls:
            rebound = self.f.normal_rate(wall, self.t, y)
            if rebound <= self.zeno_speed(wall, y) and self.needs_push(wall, y):
                held.append((wall, rebound))
        if not held:
            return
        wall, rebound = held[0]
        times = self.history[wall]
        estimate = self.t
        if len(times) >= 3:
            d1, d0 = times[-1] - times[-2], times[-2] - times[-3]
            if d0 > 0 and 0 < d1 < d0:
                rho = d1 / d0
                estimate = self.t + d1 * rho / (1 - rho)
        moving = [w for w, _ in held if self.f.moving[w]]
        if self.o.contact == "stop" or moving:
            if moving:
                wall, rebound = next((w, r) for w, r in held if self.f.moving[w])
            why = (
                "contact=stop"
                if self.o.contact == "stop"
                else "the wall moves (no contact mode for a moving wall)"
            )
            raise Stop(
                "zeno",
                f"impacts on wall {self.names[wall]!r} accumulate at t* = {float(estimate)!r}"
                f" (last impact at t = {float(self.t)!r}, rebound speed {float(rebound):.3g});"
                f" stopped: {why}",
                estimate,
            )
        self.enter_contacts(held, reason=f"accumulation of impacts (t* ~ {float(estimate)!r})")

    def enter_contact(self, wall: int, rate: float, reason: str) -> None:
        """Hold ``wall`` with the walls already in contact (:meth:`enter_contacts`)."""
        self.enter_contacts([(wall, rate)], reason)

    def enter_contacts(self, walls: list[tuple[int, float]], reason: str) -> None:
        """Hold the walls ``(wall, normal rate)`` with those already in contact (their
        mode: the scene with every held wall as a permanent constraint; the velocity
        projected onto it, a plastic impact), then :meth:`settle`.  One contact event per
        wall; the first carries the energy change."""
        for wall, _ in walls:
            if self.f.moving[wall] or self.o.contact == "stop":
                raise Stop(
                    "zeno",
                    f"the body comes to rest on wall {self.names[wall]!r} at"
                    f" t = {float(self.t)!r} ({reason}); stopped: "
                    + ("contact=stop" if self.o.contact == "stop" else "the wall moves"),
                    self.t,
                )
        mode = tuple(sorted({*self.mode, *(w for w, _ in walls)}))
        y = self.y.copy()
        y_plus = self.stabilise(mode, y, drift=False)
        for k, (wall, rate) in enumerate(walls):
            self.event("contact", wall, y, y_plus, rate, count_energy=k == 0)
        self.y = y_plus
        self.mode = mode
        self.settle()

    def settle(self) -> None:
        """Release, one at a time (the most negative first), the held walls whose contact
        force in the current mode is negative: the complementarity 0 <= lambda_N _|_
        d^2 psi/dt^2 >= 0 on the held set (Baraff 1994), decided by dropping the walls that
        would pull."""
        for _ in range(len(self.mode)):
            q, v = self.q(self.y), self.v(self.y)
            forces = [(self.f.normal_force(w, self.t, q, v, self.mode), w) for w in self.mode]
            worst, wall = min(forces)
            if worst >= 0:
                return
            self.release(wall)

    def release(self, wall: int) -> None:
        """Let ``wall`` go: the others stay held; the wall is banded until it is left."""
        self.event("release", wall, self.y, self.y, 0.0)
        self.mode = tuple(w for w in self.mode if w != wall)
        self.banded.add(wall)

    def stabilise(self, mode: tuple[int, ...], y: np.ndarray, drift: bool = True) -> np.ndarray:
        """Project onto the mode's constraints: every held psi = 0 (Gauss-Newton, two
        steps of ``q -= G^T (G G^T)^-1 psi``, G the walls' gradients) and P(q) v; with
        ``drift``, the residual before projection counts as integration drift."""
        q, v = self.q(y).copy(), self.v(y)
        for _ in range(2 if mode else 0):
            psi = [self.f.psi(w, self.t, q) for w in mode]
            G = [self.f.gradient(w, self.t, q) for w in mode]
            GG = [[sum(a * b for a, b in zip(gi, gj, strict=True)) for gj in G] for gi in G]
            z = solve_small(GG, psi)
            if z is None:
                break
            for zi, gi in zip(z, G, strict=True):
                q = q - zi * gi
        if drift:
            self.drift = max(self.drift, self.f.residual(mode, self.t, q, v))
        v = self.f.project(mode, self.t, q, v)
        return np.concatenate([q, v])

    # -- the loop ---------------------------------------------------------------------------
    def start(self) -> None:
        """The initial energy; resolve the walls touched at the initial state."""
        self.energy0 = self.f.energy(self.t, self.q(self.y), self.v(self.y))
        hit = self.approaching()
        if hit is not None:
            self.impacts(*hit)
        for w in range(self.walls):
            if w not in self.mode and abs(self.f.psi(w, self.t, self.q(self.y))) <= self.tol_psi:
                rate = self.f.normal_rate(w, self.t, self.y)
                if abs(rate) <= self.tol_v(self.y) and self.needs_push(w, self.y):
                    self.enter_contact(w, rate, reason="initial state at rest on the wall")
        self.band_touching()
        if len(self.ts) and not np.array_equal(self.ys[-1], self.y):
            self.record(self.t, self.y)

    def run(self) -> tuple[str, str, float | None]:
        t_end = self.o.t_end
        try:
            self.start()
            self.flow.start(self.t, self.y, t_end)
            while self.t < t_end:
                steps = self.flow.stats.steps
                if steps >= self.o.max_steps:  # the bound on a run's work
                    at = f"at t = {float(self.t)!r}"
                    raise Stop("max_steps", f"stopped after {steps} steps {at}")
                seg = self.flow.advance()
                ev = self.detect(seg)
                if ev is None:
                    y1 = seg.y1
                    if self.mode or self.f.constrained:
                        self.t = seg.t1
                        y1 = self.stabilise(self.mode, y1)
                        self.flow.accept_projection(y1)
                    self.segments.append((seg.t0, seg.t1, seg.dense))
                    self.t, self.y = seg.t1, y1
                    self.record(self.t, self.y)
                    for w in [w for w in self.grazing if self.f.psi(w, self.t, self.q(y1)) >= 0]:
                        self.grazing.discard(w)
                    for w in [
                        w for w in self.banded if self.f.psi(w, self.t, self.q(y1)) > self.tol_psi
                    ]:
                        self.banded.discard(w)
                    self.track_energy()
                    continue
                t_e, y_e, wall, what = ev
                self.segments.append((seg.t0, t_e, seg.dense))
                self.t, self.y = t_e, self.f.array(y_e)
                self.record(self.t, self.y)
                if what == "release":
                    self.release(wall)
                    self.settle()
                else:
                    self.at_wall(wall)
                self.record(self.t, self.y)
                self.flow.limit_step(max(t_e - seg.t0, RESTART_FLOOR * (seg.t1 - seg.t0)))
                self.flow.start(self.t, self.y, t_end)
        except Stop as stop:
            return stop.status, stop.message, stop.accumulation
        except FlowFailure as exc:
            return "failed", str(exc), None
        except NumericalError as exc:  # a generated call failed at an accepted state
            return "failed", f"{exc} at t = {float(self.t)!r}", None
        except SimulationError as exc:  # a contact the loop cannot hold (indeterminate)
            return "failed", f"{exc} at t = {float(self.t)!r}", None
        return "finished", f"reached t_end = {float(t_end)!r}", None

    def track_energy(self) -> None:
        if self.f.energy_conserved:
            e = self.f.energy(self.t, self.q(self.y), self.v(self.y))
            self.energy_drift = max(self.energy_drift, abs(e - self.energy0 - self.energy_jumps))


def run(fns: Any, flow: Flow, t0: float, y0: np.ndarray, opts: Options) -> SimulationResult:
    """One hybrid run from (t0, y0) to ``opts.t_end`` (see the module docstring)."""
    clock = _time.perf_counter()
    r = _Run(fns, flow, t0, y0, opts)
    status, message, accumulation = r.run()
    wall_time = _time.perf_counter() - clock
    st = flow.stats
    kinds = [e.kind for e in r.events]
    stats = {
        "steps": st.steps,
        "rejected_steps": st.rejected,
        "rhs_calls": st.nfev,
        "jacobian_calls": st.njev,
        "wall_time": wall_time,
        "constraint_drift": r.drift,
        "impact_condition": r.condition,
        "energy_drift": r.energy_drift if fns.energy_conserved else None,
        "impacts": kinds.count("impact"),
        "grazing": kinds.count("grazing"),
        "contacts": kinds.count("contact"),
        "releases": kinds.count("release"),
    }
    ys = np.array(r.ys)
    return SimulationResult(
        t=np.array(r.ts),
        q=ys[:, : r.n],
        v=ys[:, r.n :],
        events=r.events,
        status=status,
        message=message,
        stats=stats,
        segments=r.segments,
        n=r.n,
        accumulation_time=accumulation,
    )
