"""Touching chains and near-coincident events (issue 24, item 4).

Newton's cradle: equal elastic balls on a line.  The exact outcome (Newton's law applied
contact by contact down the row, which is what a real cradle does) passes the incoming
velocities to the balls at the far end: one ball in, one ball out; two in, two out.  Every
run must finish at every tolerance, end with those velocities, and the C and NumPy loops
must take the same decisions (the same events, in the same order, at the same times to the
tolerance).  Balls touching and moving together raise no events; an event a few ulps
after a step's start does not shrink the next step to that sliver.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import symmech as sm
from symmech.examples import newtons_cradle

PARAMS = {"m": 1.0, "r": 0.1}
RTOLS = [10.0**-k for k in range(3, 13)]


def _row(balls: int, gap: float, swung: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Initial positions and velocities of a cradle whose first ``swung`` balls move in
    together (touching each other) at speed 1 toward a row at rest with gaps ``gap``, and
    the exact final velocities (the last ``swung`` balls leave at speed 1)."""
    d = 2 * PARAMS["r"]
    x = np.zeros(balls)
    for i in range(1, balls):
        x[i] = x[i - 1] + d + (gap if i >= swung else 0.0)
    if swung > 1:  # the moving group starts a little away from the row
        x[:swung] -= 0.05
    v0 = np.zeros(balls)
    v0[:swung] = 1.0
    vf = np.zeros(balls)
    vf[balls - swung :] = 1.0
    return x, v0, vf


CASES = {
    "touching": (0.0, 1),
    "two_in": (0.0, 2),
    "gap_0.1": (0.1, 1),
    "gap_0.001": (0.001, 1),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_cradle_of_five_finishes_at_every_tolerance_with_the_exact_velocities(case):
    scene = newtons_cradle(5)
    gap, swung = CASES[case]
    q0, v0, vf = _row(5, gap, swung)
    for rtol in RTOLS:
        events = {}
        for backend in ("c", "numpy"):
            res = sm.simulate(
                scene, q0, v0, 2.0, params=PARAMS, backend=backend, rtol=rtol, atol=rtol / 100
            )
            assert res.status == "finished", (backend, rtol, res.message)
            np.testing.assert_allclose(res.v[-1], vf, atol=1e-9, err_msg=f"{backend} {rtol}")
            assert res.stats["grazing"] == 0, (backend, rtol)
            events[backend] = res.events
        c, py = events["c"], events["numpy"]
        assert [(e.kind, e.wall) for e in c] == [(e.kind, e.wall) for e in py], rtol
        np.testing.assert_allclose([e.time for e in c], [e.time for e in py], atol=100 * rtol)


def test_c_and_numpy_take_the_same_decisions_over_a_grid_of_cradles():
    """3 to 5 balls, touching or with gaps, one or two balls swung in, four tolerances."""
    grid = itertools.product((3, 4, 5), (0.0, 0.001, 0.1), (1, 2), (1e-4, 1e-7, 1e-10, 1e-12))
    scenes = {b: newtons_cradle(b) for b in (3, 4, 5)}
    for balls, gap, swung, rtol in grid:
        q0, v0, vf = _row(balls, gap, swung)
        runs = [
            sm.simulate(scenes[balls], q0, v0, 1.5, params=PARAMS, backend=b, rtol=rtol,
                        atol=rtol / 100)
            for b in ("c", "numpy")
        ]  # fmt: skip
        label = (balls, gap, swung, rtol)
        for res in runs:
            assert res.status == "finished", (label, res.message)
            np.testing.assert_allclose(res.v[-1], vf, atol=1e-9, err_msg=str(label))
        kinds = [[(e.kind, e.wall) for e in r.events] for r in runs]
        assert kinds[0] == kinds[1], label


def test_balls_touching_and_moving_together_raise_no_events():
    """Two touching balls moving together, and a touching row at rest: no event at all,
    though their gaps hover at 0 +- a few ulps."""
    scene = newtons_cradle(3)
    for backend in ("c", "numpy", "scipy"):
        together = sm.simulate(
            scene, [0.0, 0.2, 1.0], [0.3, 0.3, 0.0], 1.0, params=PARAMS, backend=backend
        )
        assert together.status == "finished" and together.events == [], backend
        at_rest = sm.simulate(
            scene, [0.0, 0.2, 0.4], [0.0, 0.0, 0.0], 5.0, params=PARAMS, backend=backend
        )
        assert at_rest.status == "finished" and at_rest.events == [], backend


def test_a_banded_contact_still_becomes_an_impact_when_the_balls_close_in():
    """After the cascade the first balls rest touching (their gap banded); a third ball
    sent back into them is still an impact, not a tunnel."""
    scene = newtons_cradle(3)
    # balls 0 and 1 touch at rest; ball 2 comes in from the right at speed -1
    for backend in ("c", "numpy"):
        res = sm.simulate(
            scene, [0.0, 0.2, 0.6], [0.0, 0.0, -1.0], 1.0, params=PARAMS, backend=backend
        )
        assert res.status == "finished", res.message
        np.testing.assert_allclose(res.v[-1], [-1.0, 0.0, 0.0], atol=1e-9)
        assert [e.kind for e in res.events] == ["impact", "impact"]
        x = res.q[-1]
        assert np.all(np.diff(x) >= 2 * PARAMS["r"] - 1e-8), x


@pytest.mark.parametrize("m", [1.0, 2.0, 3.0, 0.7])
def test_an_impact_leaves_no_residue_where_the_exact_answer_is_zero(m):
    """Equal balls exchange their speeds exactly: the one-row impulse is r / G, one
    division (it was (r / sqrt(G)) / sqrt(G), which left 2e-16 on the ball that stops)."""
    scene = newtons_cradle(5)
    for backend in ("c", "numpy"):
        res = sm.simulate(
            scene, 0.2 * np.arange(5), [1.0, 0, 0, 0, 0], 0.5, params={"m": m, "r": 0.1},
            backend=backend,
        )  # fmt: skip
        for k, e in enumerate(res.impacts()):
            want = np.zeros(5)
            want[k + 1] = 1.0
            np.testing.assert_array_equal(e.v_plus, want)
