"""Hostile scene files are refused by what reading them would cost, quickly, each with an
error naming the file and the field (or, for the file's size, the file alone: it is not
read): nesting depth (the parser's ``max_depth``), a huge number of terms in one entry or
spread over several (:data:`symmech.scenefile.MAX_FILE_NODES`, over the whole file), and
the file's size (:data:`symmech.scenefile.MAX_FILE_BYTES`).  A long entry alone is no
reason to refuse (an imported model's forcing is 53,000 characters):
``tests/test_scenefile.py::test_one_long_entry_loads_the_file_budget_bounds_the_cost``
and the bicycle's round trip in ``tests/test_bicycle.py``."""

from __future__ import annotations

import time

import pytest

import symmech as sm
from symmech.scenefile import MAX_FILE_BYTES, MAX_FILE_NODES, SceneFileError

#: generous: each case takes well under a second here; the bound only catches a reader
#: whose cost grows with the hostile input (the 20,000 distinct applications of sin that
#: the per-entry limit let through took 67 s)
SECONDS = 5.0


def _balanced(leaves: list[str], op: str = "+") -> str:
    """``leaves`` joined by ``op`` in a balanced tree of brackets (depth log2 of their
    number, so the depth limit is not what refuses it)."""
    while len(leaves) > 1:
        pairs = range(0, len(leaves) - 1, 2)
        leaves = [f"({leaves[i]}{op}{leaves[i + 1]})" for i in pairs] + leaves[len(pairs) * 2 :]
    return leaves[0]


def _scene(potential: str, metric: str = "m") -> str:
    """A one-coordinate scene file: metric on line 2, potential on line 3."""
    head = f'coordinates = ["y"]\nmetric = ["{metric}"]\n'
    return head + f'potential = "{potential}"\n[parameters]\nm = 1\n'


CASES = {
    # 100,000 brackets deep, 200 kB
    "deep nesting": (_scene("(" * 100_000 + "y" + ")" * 100_000), "potential", "max_depth=50"),
    # 250,000 terms in one flat sum (500,000 nodes), 500 kB
    "many terms": (_scene("+".join(["y"] * 250_000)), "potential", "MAX_FILE_NODES"),
    # 70,000 products in brackets: 280,000 nodes in one entry, 420 kB
    "many nodes": (_scene(_balanced(["m*y"] * 70_000)), "potential", "MAX_FILE_NODES"),
    # entries of 80,000 and 128,000 nodes: each under the budget, the file over it (the
    # first is read, about a second here, the second refused before it is parsed)
    "spread over fields": (
        _scene(_balanced(["m*y"] * 32_000), metric=_balanced(["m*m"] * 20_000)),
        "potential",
        "MAX_FILE_NODES",
    ),
}


@pytest.mark.parametrize("case", list(CASES))
def test_a_hostile_file_is_refused_quickly_naming_the_file_and_the_field(case, tmp_path):
    text, field, limit = CASES[case]
    path = tmp_path / "hostile.toml"
    path.write_text(text)
    assert len(text.encode()) < MAX_FILE_BYTES  # refused by its cost, not its size
    start = time.perf_counter()
    with pytest.raises(SceneFileError) as info:
        sm.load_scene(path)
    assert time.perf_counter() - start < SECONDS, case
    (problem,) = info.value.problems
    assert problem.startswith(f"{path}: {field} (line 3"), problem
    assert limit in problem, problem
    assert [d[0] for d in info.value.details] == [field]


def test_a_file_over_the_size_limit_is_refused_before_it_is_read(tmp_path):
    path = tmp_path / "huge.toml"
    path.write_text(_scene("+".join(["y"] * (MAX_FILE_BYTES // 2 + 1))))
    start = time.perf_counter()
    with pytest.raises(SceneFileError) as info:
        sm.load_scene(path)
    assert time.perf_counter() - start < SECONDS
    size = path.stat().st_size
    assert info.value.problems == [f"{path}: file is {size} bytes long (limit {MAX_FILE_BYTES})"]
    with pytest.raises(SceneFileError, match=f"longer than {MAX_FILE_BYTES} bytes"):
        sm.loads_scene(path.read_text())


def test_the_node_budget_leaves_room_for_an_imported_model():
    # the imported Whipple bicycle holds about 63,000 nodes (its round trip: test_bicycle)
    assert MAX_FILE_NODES >= 100_000
