"""Gait files: the built-in ones give the gaits built in Python; hostile files are refused
with the file and the field named."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from symmech.gait import CompiledGait
from symmech.gait.gaitfile import BUILTIN_DIR, builtin_gait_files, read_gait
from symmech.gait.models import GAITS
from symmech.gait.periodic import fixed_point
from symmech.scenefile import SceneFileError


@pytest.mark.parametrize(
    "name", ["rimless_wheel", "compass_gait", "hopper", "simplest_walker_feet"]
)
def test_builtin_gait_file_equals_the_python_gait(name):
    assert name in builtin_gait_files()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        gf = read_gait(name)
    case = GAITS[name]
    assert gf.section == case.section
    params = dict(case.parameters)
    assert gf.defaults == pytest.approx(params)
    from_file = fixed_point(CompiledGait(gf.gait, params), gf.section, gf.guess)
    from_python = fixed_point(CompiledGait(case.build(), params), case.section, case.guess)
    assert np.max(np.abs(from_file.x - from_python.x)) <= 1e-12
    m1, m2 = np.array(from_file.multipliers), np.array(from_python.multipliers)
    assert np.max(np.abs(m1 - m2)) <= 1e-10


def _gait(tmp_path: Path, text: str) -> Path:
    for f in ("rimless_wheel_free.toml",):
        (tmp_path / f).write_text((BUILTIN_DIR / f).read_text())
    path = tmp_path / "g.gait.toml"
    path.write_text(text)
    return path


WHEEL = (BUILTIN_DIR / "rimless_wheel.gait.toml").read_text()


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (('free = "rimless_wheel_free.toml"', 'free = "../rimless_wheel_free.toml"'), "no path"),
        (('free = "rimless_wheel_free.toml"', 'free = "/etc/passwd"'), "no path"),
        (('free = "rimless_wheel_free.toml"', 'free = "missing.toml"'), "no file 'missing.toml'"),
        (('relabel = ["theta + 2*alpha"]', "relabel = [\"__import__('os')\"]"), "relabel[0]"),
        (('relabel = ["theta + 2*alpha"]', 'relabel = ["theta", "theta"]'), "expected 1"),
        (('guard = "heel"', 'guard = "roof"'), "not a wall of mode"),
        (('target = "stance"', 'target = "flight"'), "must be in [modes]"),
        (('section = "strike"', 'section = "nowhere"'), "is not a transition"),
        (("guess = [0.3141592653589793, -1.5]", "guess = [1]"), "expected 2 numbers"),
        (("format = 1", "format = 2"), "format"),
        (('pinned = "free"', 'pinned = "free"\nevil = 1'), "unknown key 'evil'"),
        (('theta = "theta" }', 'theta = "theta", z = "1" }'), "unknown key 'z'"),
        (('y = "l*cos(theta)", ', ""), "missing coordinate 'y'"),
        (('impact = "free"', 'impact = "other"'), "must be the one mode"),
    ],
)
def test_hostile_gait_files_are_refused_naming_the_field(tmp_path, edit, message):
    old, new = edit
    assert old in WHEEL
    path = _gait(tmp_path, WHEEL.replace(old, new))
    with pytest.raises(SceneFileError) as info:
        read_gait(path)
    assert message in str(info.value)
    assert str(path) in str(info.value)


def test_not_a_gait_file(tmp_path):
    with pytest.raises(SceneFileError, match="not a gait file"):
        read_gait(tmp_path / "none.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[[[")
    with pytest.raises(SceneFileError, match="not a valid TOML"):
        read_gait(bad)
