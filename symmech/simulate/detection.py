"""The search of one accepted step for its earliest event (the hybrid loop's, :mod:`.hybrid`).

The event functions of a step are the gap psi of every wall not held and, for every wall
held, its normal contact force lambda_N.  Each is sampled at ``samples - 1`` equally
spaced interior points of the step and at both ends; the earliest sign change
(``g >= 0 -> g < 0``, for a force ``g > 0 -> g <= 0``), or a dip of a gap below zero
between three non-negative samples (the vertex of their parabola), brackets an event,
which :func:`~symmech.simulate.events.find_root` narrows on the step's continuous output
(see :mod:`.events` for the rules).

A wall touched at the start of the step and left (``|psi(t0)| <= tol_psi``, normal rate
> 0) is searched through the divided gap ``psi(t) / (t - t0)``, whose value at t0 is the
normal rate; a wall released and not yet left (banded) through ``psi + tol_psi``; a start
inside a wall counts as ``psi(t0) = 0`` (a further dip is an event at once), and a wall
grazed and not left since as inside it.

Where the flow gives the gaps' rates at the stages of the step (``seg.gap_rates``: the
walls' columns of the stages of an :class:`~symmech.simulate.flow.AugmentedFlow`), a step
whose rates never turn from negative to positive holds no minimum of a gap: it is not
searched when every gap ends at or above zero, and where one ends below, its first negative
sample is found by bisection and the search looks there (:meth:`StepSearch._screened_end`).
The bracket is the one the sampled search finds, so the event is the same, bit for bit;
the step's continuous output is formed only where it is read.

The gaps are evaluated through the functions' direct one-state callers
(:meth:`Functions.gap_function <symmech.simulate.functions.Functions.gap_function>`).  A
gap reads only the coordinates: where every event function of the step is a gap and the
step gives the first entries of its continuous output as floats
(:attr:`Segment.head <symmech.simulate.flow.Segment.head>`), the samples and the probes of
the root search are those coordinates; otherwise (a contact force reads the velocities)
the samples are whole states, evaluated at once where the flow can
(:meth:`Segment.samples <symmech.simulate.flow.Segment.samples>`).  Either way the values
are the same, bit for bit: only the per-call array work differs (on a step of a small
system it is most of the search's cost).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from symmech.simulate.events import find_root
from symmech.simulate.flow import Segment

__all__ = ["StepSearch", "parabola_dip"]

#: An event found in a step: (time, state, wall, "wall" | "release").
Found = tuple[Any, np.ndarray, int, str]


class StepSearch:
    """The event functions of one step of a run (``run``: the loop's state, read for its
    functions ``f``, ``mode``, ``walls``, ``tol_psi``, ``banded``, ``grazing``,
    ``time_scale`` and options ``o``) and their search (:meth:`earliest`)."""

    def __init__(self, run: Any, seg: Segment):
        self.run, self.seg, self.f = run, seg, run.f
        mode = run.mode
        self.funcs: list[tuple[int, str]] = [
            (w, "wall") for w in range(run.walls) if w not in mode
        ] + [(w, "release") for w in mode]
        self.divided: list[bool] = []
        self.start: list[Any] = []
        self.band: list[bool] = []
        #: per event function: whether the stage rates may stand in for its samples
        #: (:meth:`_screened_end`)
        self.screenable: list[bool] = []
        #: per event function: whether it is a contact force (a force's sign change is
        #: ``g > 0 -> g <= 0``, a gap's ``g >= 0 -> g < 0``), and its evaluation at (t, y)
        self.force = [what == "release" for _, what in self.funcs]
        self.gaps = [self.f.gap_function(w) if what == "wall" else None for w, what in self.funcs]
        for (w, what), gap in zip(self.funcs, self.gaps, strict=True):
            self._prepare(w, what, gap)
        self._evals: list[Any] | None = None

    @property
    def evals(self) -> list[Any]:
        """Per event function, its evaluation at (t, y) (:meth:`_evaluation`; made on
        first use: a screened step has no use for them)."""
        if self._evals is None:
            self._evals = [self._evaluation(i) for i in range(len(self.funcs))]
        return self._evals

    def _prepare(self, w: int, what: str, gap: Any) -> None:
        """The search rule of event function ``(w, what)`` and its value at t0 (None: to be
        evaluated)."""
        run, seg = self.run, self.seg
        if gap is None:  # a held wall's contact force
            self.divided.append(False)
            self.start.append(None)
            self.band.append(False)
            self.screenable.append(False)
            return
        n = run.n
        psi0 = gap(seg.t0, seg.y0[:n])
        rate0 = self.f.normal_rate(w, seg.t0, seg.y0) if abs(psi0) <= run.tol_psi else None
        banded = w in run.banded
        g0 = psi0 + run.tol_psi if banded else psi0
        divided = not banded and rate0 is not None and rate0 > 0 and w not in run.grazing
        self.divided.append(divided)
        self.band.append(banded)
        self.screenable.append(not banded and w not in run.grazing and (divided or g0 >= 0))
        if w in run.grazing:  # grazed, not left since: counts as inside until it leaves
            self.start.append(0 * psi0 - 1)
        elif divided:
            self.start.append(rate0)
        elif g0 < 0:
            self.start.append(0 * g0)
        else:
            self.start.append(g0)

    def value(self, i: int, t: Any, y: np.ndarray) -> Any:
        """Event function ``i`` at (t, y)."""
        return self.evals[i](t, y)

    def _evaluation(self, i: int) -> Any:
        """``(t, y) ->`` event function ``i`` (its rule fixed by :meth:`_prepare`): a held
        wall's normal force, or the gap, plus ``tol_psi`` when banded, divided by
        ``t - t0`` when divided."""
        w, what = self.funcs[i]
        run, n = self.run, self.run.n
        if what == "release":
            force, mode = self.f.normal_force, run.mode
            return lambda t, y: force(w, t, y[:n], y[n:], mode)
        rule = self._gap_rule(i)
        return lambda t, y: rule(t, y[:n])

    def _gap_rule(self, i: int) -> Any:
        """``(t, q) ->`` event function ``i``, a gap: psi, plus ``tol_psi`` when banded,
        divided by ``t - t0`` when divided (``q`` an array or a list of floats)."""
        gap = self.gaps[i]
        assert gap is not None
        if self.band[i]:
            tol = self.run.tol_psi
            return lambda t, q: gap(t, q) + tol
        if self.divided[i]:
            t0 = self.seg.t0
            return lambda t, q: gap(t, q) / (t - t0)
        return gap

    def state(self, t: Any) -> np.ndarray:
        seg = self.seg
        return seg.y0 if t == seg.t0 else seg.y1 if t == seg.t1 else seg.dense(t)

    def earliest(self) -> Found | None:
        """The earliest event inside the step, or None."""
        if not self.funcs:
            return None
        seg = self.seg
        end = self._screened_end()
        if end is not None and all(g >= 0 or g != g for g in end):
            return None  # no minimum inside and no sign change at t1 (NaN: none either)
        t0, K = seg.t0, self.run.o.samples
        times = [t0] + [t0 + (seg.t1 - t0) * k / K for k in range(1, K)] + [seg.t1]
        # on a step a few ulps long the samples round onto each other: keep distinct times
        times = [tk for k, tk in enumerate(times) if k == 0 or tk > times[k - 1]]
        start = [self.value(i, t0, seg.y0) if s is None else s for i, s in enumerate(self.start)]
        row, evals = self._sampled(times)
        known: dict[int, list[Any]] = {0: start}

        def at(k: int) -> list[Any]:
            """The event functions at sample ``k`` (each sample evaluated once)."""
            out = known.get(k)
            if out is None:
                tk, yk = times[k], row(k)
                out = known[k] = [g(tk, yk) for g in evals]
            return out

        first = 1
        if end is not None and len(times) >= 3:
            known[len(times) - 1] = end  # the last sample is t1, its values the same
            first = self._first_negative(end, at, len(times) - 1)
        vals = [start]
        for k in range(1, len(times)):
            # samples before first - 2 are never read by _brackets from ``first`` on
            vals.append(at(k) if k >= first - 2 else [])
            if k >= first:
                brackets = self._brackets(times, vals, k)
                if brackets:
                    return self._locate(brackets)
        return None

    def _screened_end(self) -> list[Any] | None:
        """The event functions at t1 where the rates of the walls' gaps at the stages of
        the step (``seg.gap_rates``, where the flow has them) show that no gap has a
        minimum inside the step; None where the step is to be searched sample by sample
        (a rate that turns from negative to positive, a contact force, a banded, grazed or
        entered wall, no stages).

        Where no gap's rate turns from negative to positive at the stages (taken in the
        order of their times), each gap is largest inside or monotone, so its least value
        is at an end: a gap left by the step (psi(t0) >= 0 and psi(t1) >= 0, or leaving a
        wall at t0) has no event in it, and one below zero at t1 crosses zero once
        (:meth:`_first_negative`)."""
        rates = self.seg.gap_rates
        if rates is None or not all(self.screenable):
            return None
        per_wall = rates[1]
        if not all(_no_minimum(per_wall[w]) for w, _ in self.funcs):
            return None
        seg, n = self.seg, self.run.n
        q1 = seg.y1[:n]  # every function is a gap: the values of :attr:`evals` at t1
        return [self._gap_rule(i)(seg.t1, q1) for i in range(len(self.funcs))]

    @staticmethod
    def _first_negative(end: list[Any], at: Callable[[int], list[Any]], last: int) -> int:
        """The first sample at which the search must look for a bracket, on a step
        screened by :meth:`_screened_end` with an event function below zero at t1 (sample
        ``last``, values ``end``): the first negative sample of each such function, found
        by bisection over the samples (a few evaluations where the sampled search takes up
        to ``samples``); the search looks from there, with the samples it reads evaluated
        as it would."""
        first = last
        for i, g in enumerate(end):
            if g >= 0 or g != g:  # no sign change at t1
                continue
            lo, hi = 0, last  # f(lo) >= 0 > f(hi)
            while hi - lo > 1:
                mid = (lo + hi) // 2
                if at(mid)[i] < 0:
                    hi = mid
                else:
                    lo = mid
            first = min(first, hi)
        return first

    def _sampled(self, times: list) -> tuple[Any, list[Any]]:
        """``(row, functions)``: the argument of the event functions at sample ``k``
        (``row(k)``) and the functions over it.  Where every function is a gap and the
        step gives its coordinates as floats (``seg.head``), the coordinates (``y1``'s at
        t1, as :meth:`Segment.samples <symmech.simulate.flow.Segment.samples>`: the same
        values) and the gaps' rules; else the states and :attr:`evals`."""
        seg = self.seg
        head = seg.head
        if head is None or any(self.force):
            states: list[list[np.ndarray]] = []

            def state(k: int) -> np.ndarray:
                if times[k] == seg.t1:  # as Segment.samples, without the others
                    return seg.y1
                if not states:
                    states.append(seg.samples(times))
                return states[0][k]

            return state, self.evals
        n, t1 = self.run.n, seg.t1
        rules = [self._gap_rule(i) for i in range(len(self.funcs))]

        def row(k: int) -> list[float]:
            tk = times[k]
            return seg.y1[:n].tolist() if tk == t1 else head(tk, n)

        return row, rules

    def _brackets(self, times: list, vals: list, k: int) -> list[tuple[int, Any, Any, Any, Any]]:
        """The brackets ``(i, lo, hi, g(lo), g(hi))`` of the event functions between
        samples ``k - 1`` and ``k`` (a sign change, or a gap's dip below zero)."""
        out = []
        force = self.force
        for i in range(len(self.funcs)):
            a, b = vals[k - 1][i], vals[k][i]
            if (a > 0 >= b) if force[i] else (a >= 0 > b):
                out.append((i, times[k - 1], times[k], a, b))
            elif k >= 2 and a <= b and not force[i] and a <= vals[k - 2][i]:
                # a local minimum at sample k - 1 (parabola_dip's own first test)
                tv = parabola_dip(times[k - 2 : k + 1], [vals[j][i] for j in (k - 2, k - 1, k)])
                if tv is not None:
                    gv = self.value(i, tv, self.state(tv))
                    if gv < 0:
                        before = tv < times[k - 1]
                        lo = times[k - 2] if before else times[k - 1]
                        glo = vals[k - 2][i] if before else vals[k - 1][i]
                        out.append((i, lo, tv, glo, gv))
        return out

    def _locate(self, brackets: list[tuple[int, Any, Any, Any, Any]]) -> Found:
        """The earliest root over the brackets (each narrowed on the continuous output)."""
        run = self.run
        best: Found | None = None
        for i, lo, hi, glo, ghi in brackets:
            g = self._root_function(i)

            if ghi == 0:  # a contact force reaching exactly zero at the sample
                a = hi
            else:
                bracket = find_root(g, lo, hi, glo, ghi, self.f.eps, time_scale=run.time_scale)
                a = self.polish(i, *bracket)
            if best is None or a < best[0]:
                best = (a, self.state(a), *self.funcs[i])
        assert best is not None
        return best

    def _root_function(self, i: int) -> Any:
        """``t ->`` event function ``i`` on the step's continuous output; a gap through the
        coordinates alone where the step gives them as floats (``seg.head``: the same
        values, without building the whole state at every probe of the root search)."""
        seg = self.seg
        head = seg.head
        if head is None or self.force[i]:
            return lambda t: self.value(i, t, seg.dense(t))
        rule, n = self._gap_rule(i), self.run.n
        return lambda t: rule(t, head(t, n))

    def polish(self, i: int, a: Any, b: Any, ga: Any, gb: Any) -> Any:
        """The event time found on the step's continuous output; where the step can
        recompute its state to full order at any time (``seg.refine``, the mpmath
        reference), the root of the gap is polished on that by the secant method, keeping
        the admissible side."""
        refine = getattr(self.seg, "refine", None)
        if refine is None:
            return a
        eps, scale = self.f.eps, self.run.time_scale
        fa = self.value(i, a, refine(a))
        fb = self.value(i, b, refine(b))
        for _ in range(8):
            if fa == fb:
                break
            c = b - fb * (b - a) / (fb - fa)
            fc = self.value(i, c, refine(c))
            a, fa, b, fb = b, fb, c, fc
            if abs(b - a) <= 4 * eps * max(abs(b), scale):
                break
        lo = min(a, b)
        step = 4 * eps * max(abs(lo), scale)
        return lo if self.value(i, lo, refine(lo)) >= 0 else lo - step


def _no_minimum(rates: list[float]) -> bool:
    """Whether the rates of a gap, in time order, never turn from negative to positive
    (then the gap has no minimum between them)."""
    falling = False
    for r in rates:
        if r < 0:
            falling = True
        elif r > 0 and falling:
            return False
    return True


def parabola_dip(ts: list, gs: list) -> Any:
    """The vertex of the parabola through three non-negative samples of a gap, when it
    lies inside their span and below zero (a dip between samples), else None."""
    (t0, t1, t2), (g0, g1, g2) = ts, gs
    if min(g0, g1, g2) < 0 or g1 > min(g0, g2):
        return None
    d01 = (g1 - g0) / (t1 - t0)
    d12 = (g2 - g1) / (t2 - t1)
    curv = (d12 - d01) / (t2 - t0)
    if curv <= 0:
        return None
    tv = 0.5 * (t0 + t1) - d01 / (2 * curv)
    if not t0 < tv < t2:
        return None
    gv = g1 + d01 * (tv - t1) + curv * (tv - t0) * (tv - t1)
    return tv if gv < 0 else None
