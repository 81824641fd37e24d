"""Where a scene file's problems are reported: the line scan is linear in the file's size
whatever it holds, expressions in multi-line strings are located on their own lines, and
messages never echo a huge key whole.

Expected lines are those of the test files written here, counted by hand.
"""

from __future__ import annotations

import time

import pytest
import sympy as sp

from symmech.scenefile import MAX_FILE_BYTES, SceneFileError, reads_scene

BASE = 'coordinates = ["x"]\nmetric = ["m"]\n[parameters]\nm = 1\n'


def _refused(text: str) -> SceneFileError:
    with pytest.raises(SceneFileError) as info:
        reads_scene(text, source="f.toml")
    return info.value


# ---------------------------------------------------------------------------------------
# linear time


@pytest.mark.parametrize(
    ("table", "long_key"),
    [
        ('["' + " " * 400_000 + ']x"]', True),  # a quoted header full of spaces (was quadratic)
        ("[" + " " * 400_000 + "x]", False),
        ("[[" + " " * 400_000 + "walls]]\npsi = 1", False),
        ('["' + "]" * 400_000 + '"]', True),
        ("'" + " " * 400_000 + "'" + " = 1", True),
    ],
    ids=["quoted spaces", "bare spaces", "array of tables", "brackets", "quoted key"],
)
def test_a_huge_header_or_key_is_scanned_in_linear_time(table: str, long_key: bool):
    text = BASE + table + "\n"
    assert len(text) < MAX_FILE_BYTES
    start = time.perf_counter()
    exc = _refused(text)
    elapsed = time.perf_counter() - start
    assert elapsed < 2.0, elapsed  # 40 000 spaces took 9.8 s with a backtracking regex
    message = str(exc)
    assert len(message) < 600, len(message)  # a key is cut, not echoed whole
    assert ("..." in message) == long_key


def test_many_lines_and_keys_stay_linear():
    lines = [BASE.rstrip("\n")]
    lines += [f'[[walls]]\npsi = "x - {k}"\nrestitusion = 1 {" " * 2000}' for k in range(100)]
    text = "\n".join(lines) + "\n"
    start = time.perf_counter()
    exc = _refused(text)
    assert time.perf_counter() - start < 5.0
    assert len(exc.problems) == 100
    # each wall's unknown key on its own line: header on line 5 + 3 k, the key two below
    assert [line for _, line, _ in exc.details] == [7 + 3 * k for k in range(100)]


# ---------------------------------------------------------------------------------------
# messages


def test_long_keys_and_tokens_are_cut_to_60_characters():
    key = "k" * 5000
    exc = _refused(f"{key} = 1\n" + BASE)
    assert "k" * 61 not in str(exc)
    assert f"'{'k' * 60}...'" in str(exc)
    (detail,) = exc.details
    assert detail[2] == "k" * 60 + "..."
    name = "a b" * 3000  # not an identifier
    exc = _refused(f'coordinates = ["{name}"]\nmetric = ["1"]\n')
    assert name[:61] not in str(exc) and name[:60] + "..." in str(exc)
    sign = "s" * 3000
    exc = _refused(BASE.replace("m = 1", f'm = {{ value = 1, sign = "{sign}" }}'))
    assert "s" * 61 not in str(exc)
    law = "l" * 3000
    exc = _refused(BASE + f'[[walls]]\npsi = "x"\nlaw = "{law}"\n')
    assert "l" * 61 not in str(exc)


def test_a_long_unknown_name_in_an_expression_is_cut():
    name = "q" * 9000
    exc = _refused(BASE.replace('metric = ["m"]', f'metric = ["m"]\npotential = "{name}"'))
    assert "q" * 61 not in str(exc)
    assert "unknown name" in str(exc)


# ---------------------------------------------------------------------------------------
# multi-line strings


ML = """\
coordinates = ["x", "y"]
metric = ["m", "m"]
potential = \"\"\"
  m*g*y
  + k*x**2/2
\"\"\"
[parameters]
m = 1
g = 9.81
k = 2
"""


def test_a_multiline_expression_loads():
    sf = reads_scene(ML)
    m, g, k = sp.symbols("m g k", positive=True)
    x, y = sp.symbols("x y", real=True)
    assert sf.scene.potential == m * g * y + k * x**2 / 2


@pytest.mark.parametrize(
    ("old", "new", "where"),
    [
        ("+ k*x**2/2", "+ k*x.real", "potential (line 5, col 7): attribute access 'x.real'"),
        ("m*g*y", "m*g*y # gravity", "potential (line 4, col 9): character '#'"),
        ("  m*g*y", "  m*g*y)", "potential (line 4, col 8): syntax error"),
    ],
    ids=["attribute", "comment", "syntax"],
)
def test_a_multiline_expression_error_is_on_its_own_line(old: str, new: str, where: str):
    exc = _refused(ML.replace(old, new, 1))
    assert f"f.toml: {where}" in str(exc), str(exc)
    line = int(where.split("(line ")[1].split(",")[0])
    assert [d[:2] for d in exc.details] == [("potential", line)]


def test_a_multiline_string_on_the_key_line():
    text = ML.replace('potential = """\n  m*g*y', 'potential = """m*g*y.real')
    exc = _refused(text)
    assert "potential (line 3, col 5): attribute access 'y.real'" in str(exc)


def test_an_escaped_string_is_located():
    r"""A string written with escapes (``"\u006D.real"``) is found by its value."""
    text = 'coordinates = ["x"]\nmetric = [\n  "1",\n  ]\npotential = 0\n'
    text = text.replace('"1"', '"\\u006D.real"') + "[parameters]\nm = 1\n"
    exc = _refused(text)
    assert "metric[0,0] (line 3, col 1): attribute access 'm.real'" in str(exc)


def test_dotted_keys_are_located():
    text = (
        'coordinates = ["x"]\nmetric = ["m"]\nparameters.m.value = 1\n'
        'parameters.m.valeu = 2\nparameters.k = "x"\n'
    )
    exc = _refused(text)
    fields = {f: line for f, line, _ in exc.details}
    assert fields["parameters.m.valeu"] == 4
    assert fields["parameters.k.value"] == 5
