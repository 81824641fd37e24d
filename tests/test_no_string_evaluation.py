"""No string reaches sympy's parser (``sympify`` evaluates text with ``eval``).

The rule in the code: every ``sp.sympify`` call in the package passes ``strict=True``
(which refuses text); text is read only by :func:`symmech.parse_expression`.  The tests
below feed a payload that would create a file if it were evaluated to each public entry
that takes a value, and check that nothing ran and that the refusal names the argument.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest
import sympy as sp

import symmech as sm
from symmech.errors import SymmechError

PACKAGE = Path(sm.__file__).resolve().parent


def _sympify_calls_without_strict() -> list[str]:
    bad = []
    for path in sorted(PACKAGE.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if not isinstance(node, ast.Call):
                continue
            f = node.func
            name = f.attr if isinstance(f, ast.Attribute) else getattr(f, "id", "")
            if name not in ("sympify", "S", "parse_expr"):
                continue
            if name == "S" and not (isinstance(f, ast.Attribute) and f.attr == "S" and node.args):
                continue
            strict = any(
                k.arg == "strict" and isinstance(k.value, ast.Constant) and k.value.value is True
                for k in node.keywords
            )
            if name != "sympify" or not strict:
                bad.append(f"{path.relative_to(PACKAGE)}:{node.lineno}: {ast.unparse(node)}")
    return bad


def test_every_sympify_in_the_package_is_strict():
    assert _sympify_calls_without_strict() == []


@pytest.fixture
def payload(tmp_path):
    marker = tmp_path / "EVALUATED"
    text = f"__import__('pathlib').Path({str(marker)!r}).touch() or 1"
    yield text
    assert not marker.exists(), "a string was evaluated"


def _moving_wall():
    return sm.load_scene("carnot_4_4")


def test_definitions_text_is_parsed_safely_not_evaluated(payload):
    scene = _moving_wall()
    with pytest.raises(sm.codegen.CodegenError, match=r"definitions\['f'\].*not allowed"):
        sm.codegen.generate(scene, target="numpy", definitions={"f": payload})
    with pytest.raises(sm.codegen.CodegenError, match=r"definitions\['f'\].*not allowed"):
        sm.codegen.generate(scene, target="numpy", definitions={sp.Function("f"): payload})


def test_definitions_by_name_text_or_expression_give_the_same_code():
    scene = _moving_wall()
    t = sm.t
    by_text = sm.codegen.generate(scene, target="numpy", definitions={"f": "2 + r*sin(t)"})
    r = next(p for p in scene.parameters if str(p) == "r")
    f = sp.Function("f", real=True)
    by_expr = sm.codegen.generate(scene, target="numpy", definitions={f: 2 + r * sp.sin(t)})
    assert by_text.files == by_expr.files
    assert "inputs" not in "".join(by_text.files.values()).split("def psi")[1].split("\n")[0]


def test_definitions_refuse_unknown_functions_and_names():
    scene = _moving_wall()
    with pytest.raises(sm.codegen.CodegenError, match=r"has no function g\(t\).*\['f'\]"):
        sm.codegen.generate(scene, target="numpy", definitions={"g": 1})
    with pytest.raises(sm.codegen.CodegenError, match="unknown name 'x'"):
        sm.codegen.generate(scene, target="numpy", definitions={"f": "2 + x"})
    with pytest.raises(sm.codegen.CodegenError, match="not an arbitrary function of t"):
        sm.codegen.generate(scene, target="numpy", definitions={"": 1})


def test_shapes_refuse_text_for_radius_and_angle(payload):
    with pytest.raises(SymmechError, match="disk radius: expected a number or a sympy"):
        sm.shapes.disk_gap([0, 1], payload)
    with pytest.raises(SymmechError, match="ellipse angle: expected a number or a sympy"):
        sm.shapes.ellipse_support([1, 2], payload, [1, 0])
    with pytest.raises(SymmechError, match="expected a sequence of coordinates"):
        sm.shapes.disk_gap([payload, 0], 1)


def test_impact_map_apply_refuses_text(payload):
    x, y = sp.symbols("x y", real=True)
    scene = sm.Scene([x, y], metric=sp.eye(2), walls=[sm.Wall(x)])
    im = scene.impact_map(0)
    v = scene.velocities
    assert list(im.apply([-1, 2])) == [1, 2]  # elastic, the wall x >= 0
    with pytest.raises(sm.ImpactError, match="apply: the velocity component"):
        im.apply([payload, 0])
    with pytest.raises(sm.ImpactError, match="apply: the velocity component"):
        im.apply({v[0]: payload, v[1]: 0})


def test_wall_velocity_text_is_parsed_safely_and_array_forms_agree(payload):
    import numpy as np

    x, y = sp.symbols("x y", real=True)
    scene = sm.Scene([x, y], metric=sp.eye(2), walls=[sm.Wall(x)])
    with pytest.raises(sm.ImpactError, match=r"wall 'wall0': wall_velocity\[0\].*not allowed"):
        scene.impact_map(0, wall_velocity=[payload, 0])
    with pytest.raises(sm.ImpactError, match="wall_velocity must be a sequence"):
        scene.impact_map(0, wall_velocity="0, y")
    forms = [
        [0, "y"],
        [0, y],
        sp.Matrix([0, y]),
        [[0], [y]],
        [[0, y]],
        np.array([0, y], dtype=object),
        np.array([[0], [y]], dtype=object),
    ]
    maps = [scene.impact_map(0, wall_velocity=V) for V in forms]
    for m in maps[1:]:
        assert m.matrix == maps[0].matrix and m.offset == maps[0].offset
    assert list(maps[0].wall_velocity) == [0, y]
