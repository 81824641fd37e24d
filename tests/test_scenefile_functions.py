"""Arbitrary functions of the coordinates in scene files (``[functions]`` with
``arguments``): a generic potential V(x, y), as the Python API takes it, loads, derives and
survives dump and load; what the format cannot declare is refused by ``dump_scene`` with
the reason.

Expected values by hand: for T = m (xdot^2 + ydot^2) / 2 and V = V(x, y) + m g y the
forcing is f = -dV = (-dV/dx, -dV/dy - m g).
"""

from __future__ import annotations

import pytest
import sympy as sp

import symmech as sm
from symmech.declaration.symbols import t as TIME
from symmech.scenefile import SceneFileError, dump_scene, reads_scene

X, Y = sm.coordinates("x y")
M, G = sp.symbols("m g", positive=True)
V_REAL = sp.Function("V", real=True)
FILE = """\
coordinates = ["x", "y"]
metric = ["m", "m"]
potential = "V + m*g*y"
[parameters]
m = 1
g = 9.81
[functions]
V = { arguments = ["x", "y"], description = "a generic potential" }
"""


def test_a_generic_potential_loads_and_derives():
    sf = reads_scene(FILE)
    V = V_REAL(X, Y)
    assert sf.functions == {"V": V}
    assert sf.scene.potential == V + M * G * Y
    expected = sp.Matrix([-sp.Derivative(V, X), -sp.Derivative(V, Y) - M * G])
    assert sp.simplify(sf.scene.forcing() - expected) == sp.zeros(2, 1)


def test_arguments_may_include_time_and_real_false():
    text = FILE.replace('arguments = ["x", "y"]', 'arguments = ["t", "x"], real = false')
    sf = reads_scene(text)
    assert sf.functions == {"V": sp.Function("V")(TIME, X)}
    assert sf.scene.time_dependent


@pytest.mark.parametrize(
    "potential",
    [
        sp.Function("V")(X),  # as a user of the Python API writes it (no assumptions)
        V_REAL(X, Y) + sp.Function("W", real=True)(Y),
        sp.Function("V")(TIME, Y) * M,
    ],
    ids=["V(x)", "V(x, y) + W(y)", "m V(t, y)"],
)
def test_a_python_scene_with_a_generic_potential_survives_dump_and_load(potential):
    scene = sm.Scene((X, Y), metric=sp.diag(M, M), potential=potential, name="generic")
    text = dump_scene(scene)
    assert "[functions]" in text
    back = reads_scene(text).scene
    assert back.potential == potential
    assert back.forcing() == scene.forcing()
    assert dump_scene(back) == text


@pytest.mark.parametrize(
    ("potential", "fragments"),
    [
        (sp.Function("V")(X + Y), ["V(x + y)", "its argument x + y is not t or a coordinate"]),
        (sp.Function("V")(M), ["V(m)", "its argument m is not t or a coordinate"]),
        (sp.Function("V")(X, X), ["an argument is repeated"]),
        (sp.Function("V")(X) + sp.Function("V")(Y), ["have the same name"]),
        (sp.Function("V", positive=True)(X), ["sympy assumptions", "real = false"]),
    ],
    ids=["of an expression", "of a parameter", "repeated", "one name twice", "positive"],
)
def test_dump_says_why_it_cannot_write_a_function(potential, fragments):
    scene = sm.Scene((X, Y), metric=sp.diag(M, M), potential=potential)
    with pytest.raises(SceneFileError) as info:
        dump_scene(scene)
    message = str(info.value)
    for fragment in fragments:
        assert fragment in message, (fragment, message)


def test_functions_of_time_are_written_as_before():
    f = sp.Function("f", real=True)(TIME)
    scene = sm.Scene(
        (X, Y), metric=sp.diag(M, M), walls=[sm.Wall(X - f, name="moving")], name="moving_wall"
    )
    text = dump_scene(scene)
    assert "\n[functions]\nf = {}\n" in text
    assert reads_scene(text).scene.walls[0].psi == X - f
