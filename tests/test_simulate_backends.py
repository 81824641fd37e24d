"""The simulator's shape: backends as objects, one frozen options object through every
entry, and the C loop's codes generated from the Python tables."""

from __future__ import annotations

import re

import numpy as np
import pytest

import symmech as sm
from symmech.examples import bouncing_ball
from symmech.simulate import (
    BACKENDS,
    Backend,
    RunOptions,
    SimulationError,
    protocol,
    simulate_batch,
)
from symmech.simulate.backend import backend_named
from symmech.simulate.csim import decode, simulator_source
from symmech.simulate.run import system_for

BALL = {"m": 1.0, "g": 9.81, "alpha": 0.5}
TEMPLATE = protocol.__file__.rsplit("symmech", 1)[0] + "templates/c/simulator.c.jinja"


def test_every_backend_is_an_object_with_name_target_methods_and_capabilities():
    assert tuple(BACKENDS) == ("c", "numpy", "scipy")
    for name, b in BACKENDS.items():
        assert isinstance(b, Backend) and b.name == name
        assert b.target in ("c", "numpy")
        assert b.methods and set(b.implicit) <= set(b.methods)
    assert "batch" in BACKENDS["c"].capabilities
    assert "implicit" in BACKENDS["numpy"].capabilities
    assert BACKENDS["scipy"].method("dop853") == "DOP853"
    assert BACKENDS["numpy"].is_implicit("rodas4") and not BACKENDS["c"].implicit


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: backend_named("fortran"), r"backend must be one of \('c', 'numpy', 'scipy'\)"),
        (lambda: backend_named(3), "backend must be one of"),
        (lambda: backend_named("numpy", "batch"), r"backend 'numpy' has no 'batch'.*\('c',\)"),
        (lambda: BACKENDS["numpy"].method("DOP853"), r"not available with backend='numpy'"),
        (lambda: BACKENDS["c"].method("radau"), r"not available with backend='c': it is implicit"),
        (lambda: BACKENDS["scipy"].method("tsit5"), r"choose one of \('DOP853'"),
    ],
)
def test_backend_refusals_name_the_choices(call, match):
    with pytest.raises(SimulationError, match=match):
        call()


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"rtol": 2.0}, "rtol must be below 1"),
        ({"rtol": 1e-17}, "below 100 eps"),
        ({"atol": 0.0}, "atol: expected a finite positive number"),
        ({"max_step": -1.0}, "max_step: expected a finite positive number"),
        ({"max_events": True}, "max_events must be a positive integer"),
        ({"max_steps": 0}, "max_steps must be a positive integer"),
        ({"event_samples": 10**7}, "event_samples must be a positive integer up to"),
        ({"contact": "glue"}, "contact must be one of"),
        ({"method": 3}, "method must be a name"),
        ({"t0": float("nan")}, "t0 must be finite"),
        ({"t0": "0"}, "t0: str '0' is not a real number"),
    ],
)
def test_run_options_are_checked_when_made(kwargs, match):
    with pytest.raises(SimulationError, match=match):
        RunOptions(**kwargs)


def test_run_options_are_frozen_and_keywords_beside_them_replace_fields():
    o = RunOptions(rtol=1e-9, max_events=np.int64(7))
    assert type(o.max_events) is int and o.max_events == 7
    with pytest.raises(AttributeError):
        o.rtol = 1e-3  # type: ignore[misc]
    merged = RunOptions.build(o, {"atol": 1e-12})
    assert (merged.rtol, merged.atol) == (1e-9, 1e-12)
    assert RunOptions.build(o, {}) is o
    with pytest.raises(SimulationError, match=r"unknown run options \['rtoll'\]"):
        RunOptions.build(None, {"rtoll": 1e-3})
    with pytest.raises(SimulationError, match=r"options: expected a symmech\.simulate\.RunOptions"):
        RunOptions.build({"rtol": 1e-3}, {})  # type: ignore[arg-type]
    with pytest.raises(SimulationError, match=r"t_end must be greater than t0 = 1\.0"):
        RunOptions(t0=1.0).end(0.5)


def test_one_options_object_gives_the_same_runs_through_all_three_entries():
    """simulate, simulate_batch and sweep take the same RunOptions; each gives the run that
    the same keywords give, bit for bit."""
    scene = bouncing_ball()
    opts = RunOptions(rtol=1e-9, atol=1e-11, contact="stop", max_events=50)
    by_object = sm.simulate(scene, [1.0], [0.0], 3.0, params=BALL, options=opts)
    by_keywords = sm.simulate(
        scene, [1.0], [0.0], 3.0, params=BALL, rtol=1e-9, atol=1e-11, contact="stop",
        max_events=50,
    )  # fmt: skip
    assert by_object.status == by_keywords.status == "zeno"
    assert by_object.accumulation_time == by_keywords.accumulation_time
    np.testing.assert_array_equal(by_object.y, by_keywords.y)
    batch = simulate_batch(scene, [[1.0]], [[0.0]], 3.0, params=BALL, options=opts)
    assert batch.accumulation_time[0] == by_object.accumulation_time
    table = sm.sweep(scene, {"q0[0]": [1.0]}, 3.0, v0=[0.0], params=BALL, options=opts)
    assert table["time_to_rest"].iloc[0] == by_object.accumulation_time
    # a keyword beside the object replaces its field
    stricter = sm.simulate(scene, [1.0], [0.0], 3.0, params=BALL, options=opts, rtol=1e-11)
    assert stricter.accumulation_time != by_object.accumulation_time


def test_unknown_run_option_is_refused_by_every_entry():
    scene = bouncing_ball()
    with pytest.raises(SimulationError, match=r"unknown run options \['tolerance'\]"):
        sm.simulate(scene, [1.0], [0.0], 1.0, params=BALL, tolerance=1e-3)
    with pytest.raises(SimulationError, match=r"unknown run options \['tolerance'\]"):
        simulate_batch(scene, [[1.0]], [[0.0]], 1.0, params=BALL, tolerance=1e-3)
    with pytest.raises(SimulationError, match=r"unknown run options \['tolerance'\]"):
        sm.sweep(scene, {"q0[0]": [1.0]}, 1.0, v0=[0.0], params=BALL, tolerance=1e-3)


def _enums(text: str) -> dict[str, list[str]]:
    out = {}
    for body in re.findall(r"enum \{ ([A-Z0-9_, ]+) \};", text):
        names = [x.strip() for x in body.split(",")]
        prefix = names[-1][: -len("COUNT")]
        out[prefix] = [n[len(prefix) :].lower() for n in names[:-1]]
    return out


def test_the_c_loops_codes_are_printed_from_the_python_tables():
    text = simulator_source(system_for(bouncing_ball(), "c"))["symmech_bouncing_ball_simulator.c"]
    enums = _enums(text)
    assert enums["ST_"] == list(protocol.RUN_STATES)
    assert enums["R_"] == list(protocol.REASONS)
    assert enums["K_"] == list(protocol.EVENT_KINDS)
    assert enums["F_"] == [c for c, _ in protocol.FUNCTIONS]
    assert enums["OPT_"] == list(protocol.OPTIONS)
    assert enums["I_"] == list(protocol.INFO)
    # no number of the protocol is restated in the template: options and info by name
    template = open(TEMPLATE, encoding="utf-8").read()
    assert not re.search(r"options\[\d", template)
    assert not re.search(r"\bout\[\d", template)


def test_decode_reads_a_c_runs_info_row_by_the_tables():
    """A run stopped at max_events decodes to the status and counts the loop wrote."""
    res = sm.simulate(bouncing_ball(), [1.0], [0.0], 10.0, params=BALL, max_events=3)
    assert res.status == "max_events" and res.stats["impacts"] == 3
    row = np.zeros(protocol.INFO_HEAD)
    row[protocol.slot(protocol.INFO, "status")] = protocol.slot(protocol.RUN_STATES, "zeno")
    row[protocol.slot(protocol.INFO, "reason")] = protocol.slot(protocol.REASONS, "accumulation")
    row[protocol.slot(protocol.INFO, "why")] = 0
    row[protocol.slot(protocol.INFO, "d0")] = 1.25
    status, message, t_star = decode(row, ("floor",), 10.0)
    assert (status, t_star) == ("zeno", 1.25)
    assert "impacts on wall 'floor' accumulate at t* = 1.25" in message
