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
    "name", ["rimless_wheel", "compass_gait", "hopper", "simplest_walker_feet", "simplest_walker"]
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
RELABEL = 'relabel = ["theta + 2*alpha"]'  # the file's last line


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
        ((RELABEL, RELABEL + "\n[limit]\nnope = 0"), "'nope' is not one of its parameters"),
        ((RELABEL, RELABEL + '\n[limit]\nm = "0"'), "limit.m: expected a finite number"),
        ((RELABEL, RELABEL + "\n[limit]\nm = inf"), "limit.m: expected a finite number"),
        (("format = 1", "limit = 3\nformat = 1"), "limit: expected a table"),
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


def test_a_limit_declared_in_a_file_is_garcias_model():
    """The file's simplest walker (the feet's limit) has Garcia et al.'s field, eqs. 3-5:
    theta'' = sin(theta - gamma), phi'' = theta'' + theta'^2 sin phi - cos(theta - gamma)
    sin phi, with theta = theta1 and phi = theta1 - theta2."""
    import sympy as sp

    gait = read_gait("simplest_walker").gait
    scene = gait.modes["stance"]
    t1, t2 = scene.coordinates
    w1, _ = scene.velocities
    gamma = next(p for p in gait.parameters if p.name == "gamma")
    acc = scene.acceleration()
    theta_dd = sp.sin(t1 - gamma)
    phi = t1 - t2
    phi_dd = theta_dd + w1**2 * sp.sin(phi) - sp.cos(t1 - gamma) * sp.sin(phi)
    assert sp.simplify(acc[0] - theta_dd) == 0
    assert sp.simplify((acc[0] - acc[1]) - phi_dd) == 0
    assert [p.name for p in gait.parameters] == ["gamma"]


def test_not_a_gait_file(tmp_path):
    with pytest.raises(SceneFileError, match="not a gait file"):
        read_gait(tmp_path / "none.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[[[")
    with pytest.raises(SceneFileError, match="not a valid TOML"):
        read_gait(bad)
