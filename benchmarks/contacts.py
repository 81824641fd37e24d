"""Benchmark: the cost of several contacts at once in the C loop, against one wall.

Each figure is the time of one C run that starts at the event and ends a microsecond
later, taken over N runs in one call of the compiled loop (``simulate_batch``, one thread)
and reduced by the same runs from a state that leaves the floor (no event: the cost of a
run's start and its one short step).  What remains is the event itself:

* one-wall impact: the uniform rod, one end on the floor and approaching (tilted);
* two-wall impact: the rod flat, both ends approaching (the generalized Newton law:
  two Newton directions from the one-wall maps, the 2 x 2 complementarity by active sets);
* two-wall contact: the rod flat at rest on the floor (both ends held: the contact mode of
  the pair entered, its forces checked, settled).

The ratios to the one-wall impact are the issue's cost target (about 2x at most).

Run:  python benchmarks/contacts.py [--runs N] [--repeats R]     (not run in CI)
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

import symmech as sm

PARAMS = {"alpha": 0.5, "g": 9.81, "l": 1.0, "m": 1.0}
T_END = 1e-6


def _states(kind: str, n: int) -> tuple[np.ndarray, np.ndarray]:
    """N copies of the state of ``kind`` (rod: x, y, theta)."""
    tilt = 0.3
    q = {
        "leaving": [0.0, 0.5, 0.0],
        "one": [0.0, math.sin(tilt), tilt],  # end A on the floor
        "two": [0.0, 0.0, 0.0],
        "rest": [0.0, 0.0, 0.0],
    }[kind]
    v = {
        "leaving": [0.0, 1.0, 0.0],
        "one": [0.0, -1.0, 0.0],
        "two": [0.0, -1.0, 0.0],
        "rest": [0.0, 0.0, 0.0],
    }[kind]
    return np.tile(q, (n, 1)), np.tile(v, (n, 1))


def _times(scene: sm.Scene, kinds: tuple[str, ...], runs: int, repeats: int) -> dict[str, float]:
    """The best time per run of each kind, the kinds interleaved in every repeat (so that a
    slow spell of the machine does not fall on one kind only)."""
    states = {k: _states(k, runs) for k in kinds}
    best = dict.fromkeys(kinds, math.inf)
    for _ in range(repeats):
        for kind in kinds:
            Q, V = states[kind]
            t0 = time.perf_counter()
            res = sm.simulate_batch(scene, Q, V, T_END, params=PARAMS, threads=1)
            best[kind] = min(best[kind], (time.perf_counter() - t0) / runs)
            assert set(res.statuses) == {"finished"}, res.messages[0]
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=50_000)
    parser.add_argument("--repeats", type=int, default=9)
    parser.add_argument("--quick", action="store_true", help="a smoke test: 200 runs, once")
    args = parser.parse_args()
    if args.quick:
        args.runs, args.repeats = 200, 1
    scene = sm.load_scene("falling_rod")
    # warm: generate, compile and build the pair's contact mode in
    for kind in ("leaving", "one", "two", "rest"):
        Q, V = _states(kind, 2)
        sm.simulate_batch(scene, Q, V, T_END, params=PARAMS, threads=1)
    times = _times(scene, ("leaving", "one", "two", "rest"), args.runs, args.repeats)
    base = times["leaving"]
    one = times["one"] - base
    print(f"C loop, {args.runs} runs per call, best of {args.repeats}; run to t = {T_END:g}")
    print("| case | run [us] | event [us] | event / one-wall impact |")
    print("|---|---|---|---|")
    print(f"| no event (baseline) | {1e6 * base:.3f} | - | - |")
    for key, label in (
        ("one", "one-wall impact"),
        ("two", "two-wall impact (simultaneous)"),
        ("rest", "two-wall contact (enter, settle)"),
    ):
        event = times[key] - base
        print(f"| {label} | {1e6 * times[key]:.3f} | {1e6 * event:.3f} | {event / one:.2f} |")


if __name__ == "__main__":
    main()
