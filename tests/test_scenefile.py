"""Scene files (issue 5): the built-in TOML scenes are the Python-built scenes, a scene
survives dump and load, and hostile or malformed files are refused with clear errors and
without running anything.

Expected values are independent of the code under test: the Python-built families of
:mod:`symmech.examples` (``pendulum_on_cart``, ``newtons_cradle``: a second, separately
written source for their files), formulas of the texts typed in by hand, and error
messages that name the field, line and token written into each test file.  The named
examples load the scene files (their single source), which the textbook checks
(:mod:`symmech.verify`, ``tests/test_impacts_examples.py``) and the simulator's closed
forms test.
"""

from __future__ import annotations

import builtins
import codecs
import doctest
import importlib
import math
import random
import string
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import sympy as sp
import sympy.parsing.sympy_parser
from sympy.core.function import AppliedUndef

import symmech as sm
import symmech.scenefile as scenefile
from symmech.declaration.symbols import t as TIME
from symmech.errors import SymmechError
from symmech.examples import EXAMPLES
from symmech.scene import Scene
from symmech.scenefile import (
    SceneFile,
    SceneFileError,
    builtin_scene_names,
    builtin_scene_path,
    dump_scene,
    load_scene,
    read_scene,
    reads_scene,
)

# Issue 5: "at least the bouncing ellipse, the spinning disk of text 001, Examples 3.7,
# 3.13, 4.4 of the Carnot paper, the rolling ball and the car of the slides".
REQUIRED_SCENES = {
    "bouncing_ellipse",
    "spinning_disk",
    "carnot_3_7",
    "carnot_3_13",
    "carnot_4_4",
    "rolling_ball",
    "car",
}
BUILTIN = sorted(builtin_scene_names())


# ---------------------------------------------------------------------------------------
# comparing two scenes


def _rational_point(symbols: set, rng: random.Random) -> dict:
    """Random rationals for the symbols (positive ones in [1/2, 2], others in [-2, 2])."""
    point = {}
    for s in sorted(symbols, key=str):
        lo = 1 if s.is_positive or s.is_nonnegative else -4
        point[s] = sp.Rational(rng.randint(lo * 100, 400), 200) or sp.Rational(1, 3)
    return point


def _is_zero(expr: sp.Expr, rng: random.Random) -> bool:
    """expr == 0 identically: by simplify, else at random rational points to 40 digits."""
    expr = sp.sympify(expr)
    if expr == 0 or sp.simplify(expr) == 0:
        return True
    applied = expr.atoms(AppliedUndef)
    if expr.has(sp.Derivative):
        return False
    for _ in range(3):
        point = _rational_point(expr.free_symbols, rng)
        point.update({f: sp.Rational(rng.randint(-300, 300), 100) for f in applied})
        value = sp.N(expr.xreplace(point), 40)
        if not value.is_number or abs(complex(value)) > 1e-30:
            return False
    return True


def _same_matrix(a: sp.MatrixBase | None, b: sp.MatrixBase | None, what: str) -> None:
    rng = random.Random(5)
    if a is None or b is None:
        assert a is None and b is None, f"{what}: one is None ({a} vs {b})"
        return
    assert a.shape == b.shape, f"{what}: shapes {a.shape} vs {b.shape}"
    for i in range(a.rows):
        for j in range(a.cols):
            assert _is_zero(a[i, j] - b[i, j], rng), f"{what}[{i},{j}]: {a[i, j]} vs {b[i, j]}"


def assert_same_system(a: Scene, b: Scene) -> None:
    """The two scenes declare the same mechanical system (see the module docstring)."""
    da, db = a.declaration, b.declaration
    assert da.name == db.name
    # Symbols compare equal only with equal names and assumptions.
    assert da.coordinates == db.coordinates
    assert da.velocities == db.velocities
    assert da.coordinate_velocities == db.coordinate_velocities
    assert da.parameters == db.parameters
    _same_matrix(da.frame, db.frame, "frame")
    _same_matrix(da.metric, db.metric, "metric")
    assert _is_zero(da.potential - db.potential, random.Random(1)), "potential"
    _same_matrix(da.constraint_matrix, db.constraint_matrix, "constraint rows")
    assert len(da.walls) == len(db.walls), "number of walls"
    for wa, wb in zip(da.walls, db.walls, strict=True):
        assert wa.name == wb.name
        assert wa.law == wb.law, f"wall {wa.name}: law"
        assert wa.restitution == wb.restitution, f"wall {wa.name}: restitution"
        assert _is_zero(wa.psi - wb.psi, random.Random(2)), f"wall {wa.name}: psi"
        _same_matrix(wa.impulsive_matrix, wb.impulsive_matrix, f"wall {wa.name}: impulsive")


# ---------------------------------------------------------------------------------------
# the built-in scenes


def test_every_required_scene_exists_in_both_sources():
    assert REQUIRED_SCENES <= set(BUILTIN)
    # a scene in one place and not in the other would let the two drift apart
    assert set(BUILTIN) == set(EXAMPLES)


@pytest.mark.parametrize("name", BUILTIN)
def test_builtin_scene_file_is_the_python_scene(name: str):
    sf = read_scene(name)
    assert isinstance(sf, SceneFile)
    python_scene = EXAMPLES[name][0]()
    assert_same_system(sf.scene, python_scene)
    # the one-line descriptions that `symmech examples` prints agree too
    assert sf.description == EXAMPLES[name][1]


@pytest.mark.parametrize("name", BUILTIN)
def test_builtin_scene_loads_by_name_and_by_path(name: str):
    path = builtin_scene_path(name)
    assert path.is_file() and path.suffix == ".toml" and path.stem == name
    by_name = load_scene(name)
    by_path = load_scene(path)
    by_str = read_scene(str(path))
    assert isinstance(by_name, Scene) and by_name.name == name
    assert_same_system(by_path, by_name)
    assert_same_system(by_str.scene, by_name)
    assert by_str.path == path


@pytest.mark.parametrize("name", BUILTIN)
def test_builtin_defaults_cover_every_parameter_with_its_sign(name: str):
    sf = read_scene(name)
    assert sf.missing_defaults() == []
    assert list(sf.defaults) == list(sf.scene.parameters)
    for p, value in sf.defaults.items():
        assert value.is_real and value.is_finite, (p, value)
        if p.is_positive:
            assert value > 0, (p, value)
        if p.is_nonnegative:
            assert value >= 0, (p, value)
    for wall in sf.scene.walls:
        alpha = wall.restitution
        value = sf.defaults.get(alpha, alpha)
        assert 0 <= value <= 1, (wall.name, value)


def _default(sf: SceneFile, name: str) -> float:
    return sf.numeric_defaults()[name]


def test_builtin_defaults_are_uniform_bodies():
    """Inertias of uniform bodies (standard formulas, written in the files' comments)."""
    e = read_scene("bouncing_ellipse")  # uniform ellipse: I = m (a^2 + b^2) / 4
    m, a, b = (_default(e, s) for s in "mab")
    assert math.isclose(_default(e, "I"), m * (a**2 + b**2) / 4)
    d = read_scene("spinning_disk")  # uniform disk: I = m R^2 / 2
    assert math.isclose(_default(d, "I"), _default(d, "m") * _default(d, "R") ** 2 / 2)
    c = read_scene("carnot_3_7")  # uniform disc: k = R / sqrt(2)
    assert math.isclose(_default(c, "k"), _default(c, "R") / math.sqrt(2))
    for name in ("carnot_3_13", "carnot_4_4", "rolling_ball"):  # uniform ball: k^2 = 2 r^2/5
        s = read_scene(name)
        assert math.isclose(_default(s, "k") ** 2, 2 * _default(s, "r") ** 2 / 5), name


def test_carnot_4_4_wall_moves_with_an_arbitrary_function_of_time():
    sf = read_scene("carnot_4_4")
    f = sp.Function("f", real=True)(TIME)
    assert sf.functions == {"f": f}
    x = sp.Symbol("x", real=True)
    assert sf.scene.walls[0].psi == x - f
    assert sf.scene.time_dependent


ALPHA_LINE = (
    'alpha = { value = 0.8, sign = "nonnegative", description = "restitution coefficient" }\n'
)


@pytest.mark.parametrize(
    "mutation",
    [
        [('metric = ["m", "m", "m*k**2"]', 'metric = ["m", "m", "m*k**3"]')],
        [('psi = "y - R"', 'psi = "y - 2*R"')],
        [('impulsive_constraints = ["xdot - R*thetadot"]', 'impulsive_constraints = ["xdot"]')],
        [('restitution = "alpha"', "restitution = 1"), (ALPHA_LINE, "")],
        [('sign = "nonnegative"', 'sign = "positive"')],
        [('name = "rough_wall"', 'name = "wall"')],
        [('restitution = "alpha"', 'restitution = "alpha"\nlaw = "energy"')],
        [('R = { value = 0.5, description = "radius" }', 'R = { value = 0.5, sign = "real" }')],
        [('metric = ["m", "m", "m*k**2"]', 'metric = ["m", "m", "m*k**2"]\npotential = "m*y"')],
        [('name = "carnot_3_7"', 'name = "carnot_3_7b"')],
        [('impulsive_constraints = ["xdot - R*thetadot"]', "")],
    ],
    ids=[
        "metric",
        "psi",
        "impulsive",
        "restitution",
        "restitution sign",
        "wall name",
        "law",
        "sign",
        "potential",
        "name",
        "no impulsive",
    ],
)
def test_the_comparison_sees_a_changed_scene(mutation: list[tuple[str, str]]):
    """The check above can fail: carnot_3_7's file with one change is another system."""
    text = builtin_scene_path("carnot_3_7").read_text(encoding="utf-8")
    for old, new in mutation:
        assert old in text
        text = text.replace(old, new)
    changed = reads_scene(text).scene
    with pytest.raises(AssertionError):
        assert_same_system(changed, EXAMPLES["carnot_3_7"][0]())


def test_the_comparison_sees_a_changed_frame():
    text = builtin_scene_path("rolling_ball").read_text(encoding="utf-8")
    old = '["cos(psi)", "sin(psi)", 0],'
    assert old in text
    changed = reads_scene(text.replace(old, '["cos(psi)", "2*sin(psi)", 0],')).scene
    with pytest.raises(AssertionError):
        assert_same_system(changed, EXAMPLES["rolling_ball"][0]())


# ---------------------------------------------------------------------------------------
# writing and reading back


@pytest.mark.parametrize("name", BUILTIN)
def test_dump_then_load_gives_the_same_scene_file(name: str):
    sf = read_scene(name)
    text = dump_scene(sf.scene, defaults=sf.defaults, description=sf.description)
    back = reads_scene(text)
    assert_same_system(back.scene, sf.scene)
    assert back.defaults == sf.defaults
    assert back.description == sf.description
    assert back.functions == sf.functions
    # and once more: the text is a fixed point
    assert dump_scene(back.scene, defaults=back.defaults, description=back.description) == text


@pytest.mark.parametrize("name", BUILTIN)
def test_dump_then_load_a_python_scene(name: str):
    scene = EXAMPLES[name][0]()
    back = reads_scene(dump_scene(scene))
    assert_same_system(back.scene, scene)
    assert back.defaults == {}


# Written by hand: a kinetic energy with a cross term, a time-dependent potential through a
# defined function, coefficient-row constraints, a frame given by its inverse, a parameter
# of sign "real" without default, two walls (one with the energy law).
HAND_WRITTEN = """\
name = "hand_written"
description = "two masses on a rail, a spring of moving anchor"
coordinates = ["x", "y", "z"]
kinetic_energy = "m*(u**2 + w**2)/2 + m*u*w/4 + J*s**2/2"
potential = "k*(x - f)**2/2 + c*z"
constraints = [[0, 1, "-1"]]

[parameters]
m = 2
J = { value = "1/3" }
k = { value = 10.5 }
c = { sign = "real" }
A = { value = "sqrt(2)/10", description = "amplitude" }
omega = "2*pi"
alpha = { value = 0.25, sign = "nonnegative" }

[functions]
f = "A*sin(omega*t)"

[frame]
quasi_velocities = ["u", "w", "s"]
inverse = [
  [1, 0, 0],
  ["y", 1, 0],
  [0, 0, 1]
]

[[walls]]
name = "left"
psi = "x + 1"
restitution = "alpha"
impulsive_constraints = ["u + w"]

[[walls]]
name = "floor"
psi = "z - f"
law = "energy"
"""


def test_hand_written_scene_has_the_values_written():
    sf = reads_scene(HAND_WRITTEN)
    scene = sf.scene
    x, y, z = (sp.Symbol(s, real=True) for s in "xyz")
    u, w, s_ = (sp.Symbol(s, real=True) for s in ("u", "w", "s"))
    m, J, k, A, omega = sp.symbols("m J k A omega", positive=True)
    c = sp.Symbol("c", real=True)
    alpha = sp.Symbol("alpha", nonnegative=True)
    assert scene.name == "hand_written"
    assert scene.parameters == (m, J, k, c, A, omega, alpha)
    assert sf.defaults == {
        m: 2,
        J: sp.Rational(1, 3),
        k: sp.Float(10.5),
        A: sp.sqrt(2) / 10,
        omega: 2 * sp.pi,
        alpha: sp.Float(0.25),
    }
    assert sf.missing_defaults() == [c]
    f = A * sp.sin(omega * TIME)
    assert sf.functions == {"f": f}
    # S is the inverse of the matrix written (v = S^-1 q_dot): by hand, [[1,0,0],[-y,1,0],...]
    _same_matrix(scene.frame, sp.Matrix([[1, 0, 0], [-y, 1, 0], [0, 0, 1]]), "frame")
    assert scene.velocities == (u, w, s_)
    _same_matrix(scene.mass_matrix(), sp.Matrix([[m, m / 4, 0], [m / 4, m, 0], [0, 0, J]]), "g")
    assert _is_zero(scene.potential - (k * (x - f) ** 2 / 2 + c * z), random.Random(3))
    _same_matrix(scene.constraint_matrix, sp.Matrix([[0, 1, -1]]), "constraints")
    left, floor = scene.walls
    assert (left.name, left.restitution, left.law) == ("left", alpha, "newton")
    _same_matrix(left.impulsive_matrix, sp.Matrix([[1, 1, 0]]), "left: impulsive")
    assert (floor.name, floor.restitution, floor.law) == ("floor", 1, "energy")
    assert floor.psi == z - f and floor.moving


def test_hand_written_scene_round_trip():
    sf = reads_scene(HAND_WRITTEN)
    fns = {"f": sf.functions["f"]}
    text = dump_scene(sf.scene, defaults=sf.defaults, description=sf.description, functions=fns)
    back = reads_scene(text)
    assert_same_system(back.scene, sf.scene)
    assert back.defaults == sf.defaults
    assert back.description == sf.description


def test_dump_refuses_a_default_string_it_would_have_to_evaluate(monkeypatch):
    _forbid_evaluation(monkeypatch, [])
    scene = load_scene("carnot_3_7")
    text = dump_scene(scene, defaults={"R": "sqrt(2)/4"})  # parsed by the safe parser
    assert 'R = { value = "sqrt(2)/4" }' in text
    with pytest.raises(SceneFileError, match=r"attribute access '\(\)\.__class__'"):
        dump_scene(scene, defaults={"R": "().__class__"})
    with pytest.raises(SceneFileError, match=r"\['nope'\] are not parameters"):
        dump_scene(scene, defaults={"nope": 1})


def test_scene_name_defaults_to_the_file_stem(tmp_path: Path):
    text = HAND_WRITTEN.replace('name = "hand_written"\n', "")
    (tmp_path / "my_scene.toml").write_text(text, encoding="utf-8")
    (tmp_path / "2-link arm.toml").write_text(text, encoding="utf-8")
    assert load_scene(tmp_path / "my_scene.toml").name == "my_scene"
    odd = load_scene(tmp_path / "2-link arm.toml").name
    assert odd == "scene_2_link_arm"
    assert reads_scene(text, name="given").scene.name == "given"


def test_parameters_are_in_the_order_of_the_file():
    text = 'coordinates = ["x"]\nmetric = ["b*a"]\n[parameters]\nb = 1\na = 2\n'
    assert [p.name for p in reads_scene(text).scene.parameters] == ["b", "a"]


def test_scenefile_docstring_examples():
    result = doctest.testmod(scenefile, optionflags=doctest.ELLIPSIS)
    assert result.attempted >= 4
    assert result.failed == 0


# ---------------------------------------------------------------------------------------
# hostile and malformed files

# the codec read_scene uses is imported once here, not lazily inside a test that forbids
# exec (the tests must pass in any order and selection)
codecs.lookup("utf-8-sig")

H_IMPORT = "__import__('os').system('touch {marker}')"
H_BASES = "().__class__.__bases__"

# Each test file is this template with some fields replaced; every placeholder is on a line
# of its own, so the line of each field is known: coordinates 1, metric 2, potential 3,
# constraints 4, a free line 5, [parameters] 6, m 7, g 8, alpha 9, a free line 10, [[walls]]
# 11, psi 12, restitution 13, a free line 14, then $tail from line 15 on.
TEMPLATE = string.Template(
    """\
coordinates = $coordinates
metric = $metric
potential = $potential
constraints = $constraints
$top
[parameters]
m = $m
g = 9.81
alpha = { value = $alpha, sign = "nonnegative" }
$parameters
[[walls]]
psi = $psi
restitution = $restitution
$wall
$tail
"""
)
FIELDS = {
    "coordinates": '["x", "y"]',
    "metric": '["m", "m"]',
    "potential": '"m*g*y"',
    "constraints": "[]",
    "top": "",
    "m": "1",
    "alpha": "0.5",
    "parameters": "",
    "psi": '"y"',
    "restitution": '"alpha"',
    "wall": "",
    "tail": "",
}


def scene_text(**fields: str) -> str:
    """The template with the given fields replaced (TOML text of each value)."""
    unknown = set(fields) - set(FIELDS)
    assert not unknown, unknown
    return TEMPLATE.substitute({**FIELDS, **fields})


def _frame(entry: str) -> str:
    """A [frame] section (from line 15) whose last matrix row, line 19, ends with entry."""
    return f'[frame]\nquasi_velocities = ["u", "w"]\nmatrix = [\n  [1, 0],\n  [0, {entry}]\n]\n'


def _q(text: str) -> str:
    """``text`` as a TOML basic string."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _with_kinetic_energy(entry: str) -> str:
    """The template with ``kinetic_energy = entry`` on line 2 instead of the metric."""
    text = scene_text()
    return text.replace('metric = ["m", "m"]', f"kinetic_energy = {entry}", 1)


def _payload_cases() -> Iterator:
    """Each payload in each field that holds an expression: (text, field, line, fragments)."""
    for tag, payload, fragments in (
        ("import", H_IMPORT, ["call of", "__import__('os').system", "is not allowed"]),
        ("bases", H_BASES, ["attribute access", "().__class__.__bases__", "is not allowed"]),
    ):
        p = _q(payload)
        for where, text, field, line in (
            ("potential", scene_text(potential=p), "potential", 3),
            ("metric entry", scene_text(metric=f'["m", {p}]'), "metric[1,1]", 2),
            ("metric row", scene_text(metric=f'[["m", 0], [0, {p}]]'), "metric[1,1]", 2),
            ("kinetic energy", _with_kinetic_energy(p), "kinetic_energy", 2),
            ("constraint", scene_text(constraints=f"[{p}]"), "constraints[0]", 4),
            ("psi", scene_text(psi=p), "walls[0].psi", 12),
            ("default value", scene_text(m=p), "parameters.m.value", 7),
            ("default in a table", scene_text(alpha=p), "parameters.alpha.value", 9),
            ("frame entry", scene_text(tail=_frame(p)), "frame.matrix[1,1]", 19),
            ("restitution", scene_text(restitution=p), "walls[0].restitution", 13),
            (
                "impulsive constraint",
                scene_text(wall=f"impulsive_constraints = [{p}]"),
                "walls[0].impulsive_constraints[0]",
                14,
            ),
            ("function", scene_text(tail=f"[functions]\nf = {p}"), "functions.f", 16),
        ):
            yield pytest.param(text, field, line, fragments, id=f"{tag} in {where}")


# (id, text, field, line, fragments of the message); field and line None where the file
# has none (a TOML syntax error has a line but no field).
def _balanced(leaves: list[str], op: str = "+") -> str:
    """``leaves`` joined by ``op`` as a balanced tree of brackets (depth log2 of their
    number: no chain for Python's parser to recurse on)."""
    while len(leaves) > 1:
        pairs = range(0, len(leaves) - 1, 2)
        leaves = [f"({leaves[i]}{op}{leaves[i + 1]})" for i in pairs] + leaves[len(pairs) * 2 :]
    return leaves[0]


# 5001 terms in brackets, 30 kB: longer than an entry could be before (10,000 characters);
# a flat chain of that many is refused by Python's own parser (its recursion)
_LONG = _balanced(["y"] * 5001)
# 70,000 products: 210,000 nodes, over the file's MAX_FILE_NODES (420 kB, under its bytes)
_MANY_NODES = _balanced(["m*y"] * 70_000)
# 1,001 distinct applications of sin, over MAX_FILE_CALLS
_MANY_CALLS = "+".join(f"sin({k}*y)" for k in range(1001))
MALFORMED = [
    (
        "lambda",
        scene_text(potential='"(lambda: y)()"'),
        "potential",
        3,
        ["lambda: y", "not allowed"],
    ),
    ("lambda alone", scene_text(psi='"lambda: 0"'), "walls[0].psi", 12, ["lambda", "not allowed"]),
    (
        "nested powers",
        scene_text(potential='"(((y + 1)**64)**64)**64"'),
        "potential",
        3,
        ["degree 4096", "limit 256"],
    ),
    (
        "nested exponentials",
        scene_text(potential='"m*y*exp(exp(exp(100)))"'),
        "potential",
        3,
        ["exp(exp(100))", "outside the range of float64"],
    ),
    (
        "float overflow",
        scene_text(metric='["m*1e308*1e308", "m"]'),
        "metric[0,0]",
        2,
        ["'m*1e308*1e308' has the coefficient 1.00E+616", "outside the range of float64"],
    ),
    (
        "terminal escape in a key",
        scene_text(parameters='"\\u001b]0;pwned\\u0007" = 1'),
        "parameters.\\x1b]0;pwned\\x07",
        10,
        ["is not an identifier", "'\\x1b]0;pwned\\x07'"],
    ),
    ("attribute", scene_text(psi='"y.func"'), "walls[0].psi", 12, ["attribute access 'y.func'"]),
    ("subscript", scene_text(potential='"y[0]"'), "potential", 3, ["subscript 'y[0]'"]),
    (
        "list comprehension",
        scene_text(potential='"[y for y in (1, 2)]"'),
        "potential",
        3,
        ["list comprehension", "not allowed"],
    ),
    (
        "generator in a call",
        scene_text(potential='"sin(y for y in (1, 2))"'),
        "potential",
        3,
        ["generator expression", "not allowed"],
    ),
    ("f-string", scene_text(potential="'f\"{y}\"'"), "potential", 3, ["f-string", 'f"{y}"']),
    (
        "huge exponent",
        scene_text(potential='"2**10**10"'),
        "potential",
        3,
        ["exponent 10000000000", "too large", "max_exponent=64"],
    ),
    (
        "nested parentheses",
        scene_text(potential=_q("(" * 200 + "y" + ")" * 200)),
        "potential",
        3,
        ["nested more than 50 levels", "'('", "max_depth=50"],
    ),
    (
        "too many nodes in the file",
        scene_text(potential=_q(_MANY_NODES)),
        "potential",
        3,
        ["expression too large", "MAX_FILE_NODES=200000"],
    ),
    (
        "too many distinct function applications in the file",
        scene_text(potential=_q(_MANY_CALLS)),
        "potential",
        3,
        ["more than 1000 distinct arguments", "MAX_FILE_CALLS=1000"],
    ),
    (
        "unknown name",
        scene_text(potential='"m*gg*y"'),
        "potential",
        3,
        ["unknown name 'gg'", "did you mean 'g'?"],
    ),
    (
        "dunder name",
        scene_text(potential='"__builtins__"'),
        "potential",
        3,
        ["unknown name '__builtins__'"],
    ),
    (
        "velocity in the metric",
        scene_text(metric='["m", "m + xdot"]'),
        "metric[1,1]",
        2,
        ["'xdot' is the velocity of coordinate 'x'", "may not appear in metric[1,1]"],
    ),
    (
        "velocity in a frame",
        scene_text(tail=_frame('"1 + ydot**2"')),
        "frame.matrix[1,1]",
        19,
        ["'ydot' is the velocity of coordinate 'y'"],
    ),
    (
        "Abs",
        scene_text(potential='"m*g*Abs(y)"'),
        "potential",
        3,
        ["function 'Abs' is not allowed"],
    ),
    (
        "sign",
        scene_text(psi='"sign(y)*y"'),
        "walls[0].psi",
        12,
        ["function 'sign' is not allowed", "did you mean 'sin'"],
    ),
    ("eval", scene_text(potential='"eval(y)"'), "potential", 3, ["function 'eval' is not allowed"]),
    (
        "getattr",
        scene_text(potential="\"getattr(y, 'func')\""),
        "potential",
        3,
        ["function 'getattr' is not allowed"],
    ),
    ("comparison", scene_text(psi='"y > 0"'), "walls[0].psi", 12, ["comparison 'y > 0'"]),
    ("walrus", scene_text(potential='"(z := y)"'), "potential", 3, ["assignment expression"]),
    ("keyword argument", scene_text(potential='"sin(x=y)"'), "potential", 3, ["keyword argument"]),
    ("string literal", scene_text(potential="\"'y'\""), "potential", 3, ["string literal"]),
    ("complex literal", scene_text(potential='"1j*y"'), "potential", 3, ["complex number '1j'"]),
    ("not real", scene_text(potential='"y*sqrt(-1)"'), "potential", 3, ["is not real"]),
    ("division by zero", scene_text(psi='"y/0"'), "walls[0].psi", 12, ["division by zero"]),
    (
        "long integer",
        scene_text(m="1" + "0" * 50),
        "parameters.m.value",
        7,
        ["more than 40 digits"],
    ),
    ("huge integer", scene_text(m="7" * 5000), None, 7, ["5000 digits", "(limit 40)"]),
    (
        "unknown top-level key",
        scene_text(top='potentail = "m*g*y"'),
        "potentail",
        5,
        ["unknown key 'potentail'", "did you mean 'potential'?"],
    ),
    (
        "unknown wall key",
        scene_text(wall="restitusion = 1"),
        "walls[0].restitusion",
        14,
        ["unknown key 'restitusion'", "did you mean 'restitution'?"],
    ),
    (
        "unknown parameter key",
        scene_text(m="{ valeu = 1 }"),
        "parameters.m.valeu",
        7,
        ["unknown key 'valeu'", "did you mean 'value'?"],
    ),
    (
        "unknown frame key after a matrix over several lines",
        scene_text(tail=_frame("1") + "quasi_velocity = 1\n"),
        "frame.quasi_velocity",
        21,
        ["unknown key 'quasi_velocity'", "did you mean 'quasi_velocities'?"],
    ),
    (
        "coordinates as a string",
        scene_text(coordinates='"x y"'),
        "coordinates",
        1,
        ["expected an array of name strings", "got string 'x y'"],
    ),
    (
        "metric as a string",
        scene_text(metric='"m"'),
        "metric",
        2,
        ["expected an array of 2 rows, got string"],
    ),
    ("boolean potential", scene_text(potential="true"), "potential", 3, ["got boolean"]),
    ("date as psi", scene_text(psi="1979-05-27"), "walls[0].psi", 12, ["TOML date"]),
    ("table as psi", scene_text(psi="{ a = 1 }"), "walls[0].psi", 12, ["got table"]),
    (
        "ragged metric",
        scene_text(metric='[["m", 0], ["m"]]'),
        "metric",
        2,
        ["expected 2 rows of 2 entries", "[2, 1]"],
    ),
    (
        "too many coordinates",
        scene_text(coordinates="[" + ", ".join(f'"c{i}"' for i in range(201)) + "]"),
        "coordinates",
        1,
        ["201 coordinates (limit 200)"],
    ),
    (
        "repeated coordinate",
        scene_text(coordinates='["x", "x"]'),
        "coordinates[1]",
        1,
        ["'x' is already used for the coordinate declared in coordinates[0]"],
    ),
    (
        "dunder coordinate",
        scene_text(coordinates='["__class__", "y"]'),
        "coordinates[0]",
        1,
        ["'__class__' may not start with '__'"],
    ),
    (
        "coordinate named like a function",
        scene_text(coordinates='["sin", "y"]'),
        "coordinates[0]",
        1,
        ["'sin' is the name of a built-in function"],
    ),
    ("bad TOML", scene_text(m="= 1"), None, 7, ["not valid TOML", "near '= 1'"]),
    ("unclosed string", scene_text(potential='"m*g*y'), None, 3, ["not valid TOML"]),
    ("unsupported format", scene_text(top="format = 2"), "format", 5, ["unsupported format 2"]),
    (
        "scene name not an identifier",
        scene_text(top='name = "my scene"'),
        "name",
        5,
        ["must be an identifier", "'my scene'"],
    ),
    (
        "dependent constraints",
        scene_text(
            coordinates='["x", "y", "z"]',
            metric='["m", "m", "m"]',
            constraints='["xdot - ydot", "2*xdot - 2*ydot"]',
        ),
        "constraints",
        4,
        ["linearly dependent", "rank 1 < 2"],
    ),
    (
        "impulsive constraint dependent on a permanent one",
        scene_text(
            coordinates='["x", "y", "z"]',
            metric='["m", "m", "m"]',
            constraints='["xdot - zdot"]',
            wall='impulsive_constraints = ["2*zdot - 2*xdot"]',
        ),
        "walls[0].impulsive_constraints",
        14,
        ["linearly dependent", "with the permanent constraints"],
    ),
    (
        "as many constraints as coordinates",
        scene_text(constraints='["xdot", "ydot"]'),
        "constraints",
        4,
        ["2 constraints for 2 coordinates leave no admissible motion"],
    ),
    (
        "restitution 1.5",
        scene_text(restitution="1.5"),
        "walls[0].restitution",
        13,
        ["restitution 1.5 is outside [0, 1]"],
    ),
    (
        "restitution parameter alpha = 1.5",
        scene_text(alpha="1.5"),
        "parameters.alpha.value",
        9,
        ["default value 1.5 of 'alpha' is outside [0, 1]", "restitution of walls[0]"],
    ),
    (
        "restitution parameter of any sign",
        scene_text(parameters='beta = { value = 0.5, sign = "real" }', restitution='"beta"'),
        "parameters.beta.sign",
        10,
        ["restitution parameter 'beta' must be declared with sign"],
    ),
    (
        "restitution not a parameter",
        scene_text(restitution='"alpha/2"'),
        "walls[0].restitution",
        13,
        ["a number in [0, 1] or a parameter name, got alpha/2"],
    ),
    ("unknown law", scene_text(wall='law = "elastic"'), "walls[0].law", 14, ["'elastic'"]),
    (
        "non-linear constraint",
        scene_text(constraints='["xdot*ydot"]'),
        "constraints[0]",
        4,
        ["xdot*ydot is not linear in the velocities"],
    ),
    (
        "affine constraint",
        scene_text(constraints='["xdot - 1"]'),
        "constraints[0]",
        4,
        ["velocity-free part -1"],
    ),
    (
        "holonomic constraint",
        scene_text(constraints='["x - y"]'),
        "constraints[0]",
        4,
        ["does not involve any velocity"],
    ),
    (
        "kinetic energy not quadratic",
        _with_kinetic_energy('"m*xdot**3 + m*ydot**2"'),
        "kinetic_energy",
        2,
        ["not a quadratic form in the velocities"],
    ),
    (
        "metric and kinetic energy",
        scene_text(top='kinetic_energy = "m*xdot**2"'),
        "metric",
        2,
        ["give exactly one of 'metric' and 'kinetic_energy'"],
    ),
    (
        "metric depends on time",
        scene_text(metric='["m", "m*(1 + t**2)"]'),
        "metric",
        2,
        ["depends on time t"],
    ),
    (
        "metric not positive definite",
        scene_text(metric='["m", "-m"]'),
        "metric",
        2,
        ["not positive definite"],
    ),
    (
        "psi without coordinates",
        scene_text(psi='"g - 1"'),
        "walls[0].psi",
        12,
        ["does not depend on the coordinates"],
    ),
    ("psi with a velocity", scene_text(psi='"y + xdot"'), "walls[0].psi", 12, ["velocities"]),
    (
        "unused parameter",
        scene_text(parameters="zeta = 2"),
        "parameters.zeta",
        10,
        ["declared but not used in any expression: zeta"],
    ),
    (
        "default of the wrong sign",
        scene_text(m="-1"),
        "parameters.m.value",
        7,
        ["default value -1 of 'm' is not positive"],
    ),
    (
        "unknown sign",
        scene_text(m='{ value = 1, sign = "postive" }'),
        "parameters.m.sign",
        7,
        ["got 'postive'", "did you mean 'positive'"],
    ),
    (
        "function of time called",
        scene_text(psi='"y - f(t)"', tail='[functions]\nf = "sin(t)"'),
        "walls[0].psi",
        12,
        ["'f' is a function of time", "by name alone"],
    ),
    (
        "function of a coordinate",
        scene_text(tail='[functions]\nf = "x*t"'),
        "functions.f",
        16,
        ["'x' is the coordinate", "may not appear in functions.f"],
    ),
    (
        # the refused definition is the one problem: no follow-on complaint where f is used
        "refused function used in psi and the potential",
        scene_text(psi='"y - f"', potential='"m*g*y + f"', tail='[functions]\nf = "x*t"'),
        "functions.f",
        16,
        ["'x' is the coordinate", "may not appear in functions.f"],
    ),
    (
        "function of a boolean used in psi",
        scene_text(psi='"y - f"', tail="[functions]\nf = true"),
        "functions.f",
        16,
        ["expected an expression string in t", "got boolean"],
    ),
    (
        "arbitrary function of an unknown argument",
        scene_text(tail='[functions]\nV = { arguments = ["x", "q"] }'),
        "functions.V.arguments",
        16,
        ["'q' is not t or a coordinate", "among t, x, y"],
    ),
    (
        "arbitrary function with a repeated argument",
        scene_text(tail='[functions]\nV = { arguments = ["x", "x"] }'),
        "functions.V.arguments",
        16,
        ["argument 'x' is repeated"],
    ),
    (
        "function with an expression and arguments",
        scene_text(tail='[functions]\nV = { expression = "t", arguments = ["x"] }'),
        "functions.V.arguments",
        16,
        ["give 'expression'", "or 'arguments'", "not both"],
    ),
    (
        "a comment inside an expression",
        scene_text(potential='"m*g*y # +1000*x"'),
        "potential",
        3,
        ["(line 3, col 7)", "character '#'", "would silently drop"],
    ),
    (
        "a homoglyph of a coordinate",
        scene_text(psi='"\U0001d432"'),
        "walls[0].psi",
        12,
        ["(line 12, col 1)", "name '\U0001d432'", "U+1D432", "reads as 'y'"],
    ),
    (
        "a no-break space",
        scene_text(potential='"m*g*y\u00a0+ 1"'),
        "potential",
        3,
        ["(line 3, col 6)", "U+00A0 (NO-BREAK SPACE)"],
    ),
    (
        "frame without quasi-velocities",
        scene_text(tail="[frame]\nmatrix = [[1, 0], [0, 1]]"),
        "frame.quasi_velocities",
        15,
        ["required key 'quasi_velocities'"],
    ),
    (
        "singular frame inverse",
        scene_text(
            tail='[frame]\nquasi_velocities = ["u", "w"]\n'
            'inverse = [["cos(x)**2 + sin(x)**2", 1], [1, 1]]'
        ),
        "frame.inverse",
        17,
        ["singular"],
    ),
    (
        "coordinate velocity in a frame scene",
        scene_text(constraints='["xdot - ydot"]', tail=_frame("1")),
        "constraints[0]",
        4,
        ["'xdot' is the velocity of coordinate 'x'", "quasi-velocities u, w"],
    ),
]


@pytest.fixture
def marker(tmp_path: Path) -> Path:
    """The file the payloads would create if they ran."""
    return tmp_path / "PWNED_x"


class _Forbidden(AssertionError):
    pass


def _forbid_evaluation(monkeypatch: pytest.MonkeyPatch, calls: list) -> None:
    """Make eval, exec, sympify and parse_expr raise when given text (and record every call).

    sympify is allowed on sympy objects (the Scene validation converts its own results), but
    never on a string; eval and exec are never allowed.  (``compile`` is not guarded: the
    expression parser calls ``ast.parse``, which compiles the text to a syntax tree only.)
    """

    def never(name: str):
        def guard(*args, **kwargs):
            calls.append((name, args))
            raise _Forbidden(f"{name} called with {args!r}")

        return guard

    def on_objects_only(name: str, original):
        def guard(*args, **kwargs):
            calls.append((name, args))
            if any(isinstance(a, str) for a in (*args, *kwargs.values())):
                raise _Forbidden(f"{name} called on a string: {args!r}")
            return original(*args, **kwargs)

        return guard

    monkeypatch.setattr(builtins, "eval", never("eval"))
    monkeypatch.setattr(builtins, "exec", never("exec"))
    # (the attribute sympy.core.sympify is the function, which hides the module's name)
    module = importlib.import_module("sympy.core.sympify")
    sympify = module.sympify
    monkeypatch.setattr(sp, "sympify", on_objects_only("sympify", sympify))
    monkeypatch.setattr(module, "sympify", on_objects_only("sympify", sympify))
    monkeypatch.setattr(sympy.parsing.sympy_parser, "parse_expr", never("parse_expr"))
    monkeypatch.setattr(sp, "parse_expr", never("parse_expr"), raising=False)


def test_the_payload_would_run_if_evaluated(marker: Path):
    """Control: the payload is live; evaluated by Python it creates the marker file."""
    payload = H_IMPORT.replace("{marker}", str(marker))
    subprocess.run([sys.executable, "-c", payload], check=True, timeout=60)
    assert marker.exists()


def test_the_guard_catches_evaluation(monkeypatch: pytest.MonkeyPatch):
    """The guard used below works: each way of evaluating a string raises."""
    calls: list = []
    _forbid_evaluation(monkeypatch, calls)
    for run in (
        lambda: eval("1"),
        lambda: exec("x = 1"),
        lambda: sp.sympify("1 + 1"),
        lambda: sympy.parsing.sympy_parser.parse_expr("1 + 1"),
    ):
        with pytest.raises(_Forbidden):
            run()
    assert [c[0] for c in calls] == ["eval", "exec", "sympify", "parse_expr"]


def _load_refused(path: Path) -> SceneFileError:
    with pytest.raises(SceneFileError) as info:
        read_scene(path)
    return info.value


def _check_message(
    exc: SceneFileError,
    path: Path,
    field: str | None,
    line: int | None,
    fragments: list[str],
) -> None:
    message = str(exc)
    assert str(path) in message
    if field is not None:
        assert field in message
    if line is not None:
        assert f"line {line}" in message
    for fragment in fragments:
        assert fragment in message, f"{fragment!r} not in {message!r}"
    # the structured form names the same field and line
    assert (field, line) in [(f, ln) for f, ln, _ in exc.details], exc.details


@pytest.mark.parametrize(("text", "field", "line", "fragments"), list(_payload_cases()))
def test_payload_is_refused_and_nothing_runs(
    text: str,
    field: str,
    line: int,
    fragments: list[str],
    tmp_path: Path,
    marker: Path,
    monkeypatch: pytest.MonkeyPatch,
):
    text = text.replace("{marker}", str(marker))
    assert str(marker) in text or H_BASES in text
    path = tmp_path / "evil.toml"
    path.write_text(text, encoding="utf-8")
    calls: list = []
    with monkeypatch.context() as patch:
        _forbid_evaluation(patch, calls)
        exc = _load_refused(path)
    _check_message(exc, path, field, line, fragments)
    assert len(exc.problems) == 1, exc.problems
    # the token named is the payload's outermost offending part
    tokens = [tok for _, _, tok in exc.details]
    assert any(tok and (tok.startswith("__import__") or tok.startswith("()")) for tok in tokens)
    assert not marker.exists()
    # nothing evaluated a string (a guard that raised inside a caught exception would still
    # have recorded its call)
    assert [name for name, _ in calls if name != "sympify"] == []
    assert [args for _, args in calls if any(isinstance(a, str) for a in args)] == []


@pytest.mark.parametrize(
    ("text", "field", "line", "fragments"),
    [pytest.param(*case[1:], id=case[0]) for case in MALFORMED],
)
def test_malformed_scene_is_refused_with_field_line_and_token(
    text: str,
    field: str | None,
    line: int | None,
    fragments: list[str],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
):
    path = tmp_path / "bad.toml"
    path.write_text(text, encoding="utf-8")
    calls: list = []
    with monkeypatch.context() as patch:
        _forbid_evaluation(patch, calls)
        exc = _load_refused(path)
    assert [name for name, _ in calls if name != "sympify"] == []
    assert [args for _, args in calls if any(isinstance(a, str) for a in args)] == []
    _check_message(exc, path, field, line, fragments)
    # one problem, not a cascade of follow-on complaints
    assert len(exc.problems) == 1, exc.problems


def test_malformed_table_is_large_enough():
    assert len(MALFORMED) + len(list(_payload_cases())) >= 20
    assert len({case[0] for case in MALFORMED}) == len(MALFORMED)


def test_template_itself_loads():
    """The malformed cases differ from a valid file only by what each changes."""
    sf = reads_scene(scene_text())
    assert sf.scene.coordinates == (sp.Symbol("x", real=True), sp.Symbol("y", real=True))
    assert reads_scene(scene_text(tail=_frame("1"))).scene.frame == sp.eye(2)
    assert reads_scene(_with_kinetic_energy('"m*(xdot**2 + ydot**2)/2"')).scene.n == 2


def test_every_problem_is_listed(tmp_path: Path):
    """Independent problems are reported together, each with its own field and line."""
    text = scene_text(top="potentail = 1", potential='"y.real"', wall='law = "elastic"')
    path = tmp_path / "three.toml"
    path.write_text(text, encoding="utf-8")
    exc = _load_refused(path)
    assert [(f, ln) for f, ln, _ in exc.details] == [
        ("potentail", 5),
        ("potential", 3),
        ("walls[0].law", 14),
    ]
    assert str(exc).startswith("3 problems in the scene:")


def test_file_level_refusals(tmp_path: Path):
    binary = tmp_path / "binary.toml"
    binary.write_bytes(b'coordinates = ["x"]\nmetric = ["\xff"]\n')
    exc = _load_refused(binary)
    assert "(line 2): not UTF-8 text" in str(exc)
    big = tmp_path / "big.toml"
    big.write_text("#" * (scenefile.MAX_FILE_BYTES + 1), encoding="utf-8")
    assert f"(limit {scenefile.MAX_FILE_BYTES})" in str(_load_refused(big))
    with pytest.raises(SceneFileError, match="no such scene file"):
        read_scene(tmp_path / "missing.toml")
    with pytest.raises(SceneFileError, match="not a regular file"):
        read_scene(tmp_path)  # (a device such as /dev/zero is refused the same way)
    with pytest.raises(SceneFileError, match=r"did you mean 'carnot_3_7'"):
        read_scene("carnot_3_8")
    with pytest.raises(SceneFileError, match="null character"):
        reads_scene('coordinates = ["x"]\x00')
    with pytest.raises(SceneFileError, match="expected TOML text, got a bytes"):
        reads_scene(b'coordinates = ["x"]')  # type: ignore[arg-type]


def test_byte_order_mark_and_crlf_line_ends(tmp_path: Path):
    path = tmp_path / "windows.toml"
    text = 'coordinates = ["x"]\r\nmetric = ["m"]\r\n[parameters]\r\nm = 1\r\nk = 2\r\n'
    path.write_bytes(b"\xef\xbb\xbf" + text.encode())
    exc = _load_refused(path)
    assert ("parameters.k", 5, "k") in exc.details
    path.write_bytes(b"\xef\xbb\xbf" + text.replace("k = 2\r\n", "").encode())
    assert load_scene(path).name == "windows"


def test_lines_inside_multiline_values_are_not_table_headers(tmp_path: Path):
    """A matrix row or a line of a multi-line string that looks like ``[table]`` does not
    move the lines reported for the keys after it."""
    text = (
        'description = """\n'  # 1
        "[[walls]]\n"  # 2: text, not a wall
        '"""\n'  # 3
        'coordinates = ["x", "y"]\n'  # 4
        "metric = [\n"  # 5
        '  ["m", 0],\n'  # 6
        '  [0, "m"]\n'  # 7: a row, not a table [0, "m"]
        "]\n"  # 8
        "metrik = 1\n"  # 9
        "[parameters]\n"  # 10
        "m = 1\n"  # 11
        "[[walls]]\n"  # 12
        'psi = "x"\n'  # 13
        "restitution = 2\n"  # 14
    )
    path = tmp_path / "rows.toml"
    path.write_text(text, encoding="utf-8")
    exc = _load_refused(path)
    assert [(f, ln) for f, ln, _ in exc.details] == [
        ("metrik", 9),
        ("walls[0].restitution", 14),
    ]


def test_a_folder_named_like_a_builtin_scene_does_not_hide_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    (tmp_path / "car").mkdir()
    monkeypatch.chdir(tmp_path)
    assert load_scene("car").name == "car"


def test_scene_file_errors_are_symmech_errors():
    with pytest.raises(SymmechError):
        reads_scene("coordinates = 1")
    with pytest.raises(ValueError):
        reads_scene("coordinates = 1")


def test_messages_never_carry_control_characters(tmp_path: Path):
    """A key or name with terminal escapes is echoed escaped: it cannot drive the
    terminal or forge a line of the report."""
    path = tmp_path / "bad.toml"
    path.write_text(
        scene_text(parameters='"\\u001b[2J\\nline 1: fake" = 1\n"\\u0007" = 2'),
        encoding="utf-8",
    )
    exc = _load_refused(path)
    text = str(exc)
    assert "\\x1b[2J\\nline 1: fake" in text and "\\x07" in text
    assert all(c.isprintable() or c == "\n" for c in text), repr(text)
    lines = text.splitlines()
    assert len(lines) == 1 + len(exc.details) == 3  # a header, then one line per problem
    assert all(line.startswith("  - ") for line in lines[1:])


def test_load_and_read_are_symmetric_for_paths_and_text(tmp_path):
    """load_scene / loads_scene give the Scene, read_scene / reads_scene the SceneFile,
    for a path and for text alike; save_scene / dump_scene write it back."""
    text = sm.dump_scene(sm.load_scene("carnot_3_7"), defaults={"m": 2})
    path = sm.save_scene(sm.loads_scene(text), tmp_path / "c37.toml", defaults={"m": 2})
    from_text, from_path = sm.loads_scene(text), sm.load_scene(path)
    assert isinstance(from_text, sm.Scene) and isinstance(from_path, sm.Scene)
    assert from_text.mass_matrix() == from_path.mass_matrix()
    sf_text, sf_path = sm.reads_scene(text), sm.read_scene(path)
    assert isinstance(sf_text, sm.SceneFile) and isinstance(sf_path, sm.SceneFile)
    assert {str(k): v for k, v in sf_text.defaults.items()} == {"m": 2}
    assert sf_text.defaults == sf_path.defaults


def test_one_long_entry_loads_the_file_budget_bounds_the_cost():
    """An entry's length alone is no reason to refuse (an imported model's forcing is
    long); what the file's expressions cost together is bounded instead, so hostile
    files are refused quickly: within MAX_FILE_NODES, within MAX_FILE_CALLS distinct
    function applications (20,000 distinct ones took 67 s to build)."""
    from symmech.scenefile import MAX_FILE_CALLS, MAX_FILE_NODES

    scene = sm.loads_scene(scene_text(potential=_q("g*" + _LONG)))
    assert scene.potential == 5001 * sp.Symbol("g", positive=True) * sp.Symbol("y", real=True)
    hostile = {
        "nodes": _MANY_NODES,
        "calls": _balanced([f"sin(x*{k})*y" for k in range(20_000)]),
        "chain": "+".join(["y"] * 250_000),
    }
    for what, expression in hostile.items():
        text = scene_text(potential=_q(expression))
        start = time.perf_counter()
        with pytest.raises(SceneFileError) as info:
            sm.loads_scene(text)
        assert time.perf_counter() - start < 5.0, what
        assert len(info.value.problems) == 1, info.value.problems
    assert MAX_FILE_NODES >= 100_000 and MAX_FILE_CALLS >= 100  # room for imported models
