"""The documentation site (``docs/``) builds with warnings as errors, every notebook page
holds the outputs of its executed cells, and the gallery has an animation per scene.

The build runs Sphinx as the README says, into a temporary folder; the notebooks are
executed by MyST-NB with its cache in ``docs/_build/.jupyter_cache`` (a fresh checkout, as
in CI, executes them all: about a minute on two cores; a notebook whose code did not change
is not run again locally).  ``tests/test_notebooks.py`` executes them afresh every time.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    try:
        import myst_nb  # noqa: F401
        import sphinx  # noqa: F401
    except ImportError as exc:
        pytest.fail(
            f"building the documentation needs sphinx and myst-nb ({exc}): python3 -m pip"
            " install '.[docs]'",
            pytrace=False,
        )
    out = tmp_path_factory.mktemp("site")
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
    }
    cmd = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html"]
    cmd += ["-d", str(out / "doctrees"), str(DOCS), str(out / "html")]
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=1200)
    assert proc.returncode == 0, (proc.stdout + proc.stderr)[-6000:]
    return out / "html"


def test_every_notebook_page_shows_its_outputs(site: Path):
    assert NOTEBOOKS
    for nb in NOTEBOOKS:
        page = (site / "examples" / f"{nb.stem}.html").read_text(encoding="utf-8")
        assert page.count('class="cell_output') >= 3, nb.name


def test_the_results_page_shows_a_plot_and_an_animation(site: Path):
    page = (site / "guide" / "results.html").read_text(encoding="utf-8")
    assert page.count("<img") >= 1  # res.plot()
    assert "anim_step_forward" in page or "Animation" in page  # res.animate(): the player


def test_the_api_reference_documents_the_public_names(site: Path):
    page = (site / "api.html").read_text(encoding="utf-8")
    for name in ("symmech.Scene", "symmech.simulate.simulate", "symmech.sweep.sweep"):
        assert f'id="{name}"' in page, name
    for name in ("to_frame", "plot", "animate", "save"):
        assert f'id="symmech.simulate.result.SimulationResult.{name}"' in page, name


def test_the_gallery_has_an_animation_of_every_built_in_scene(site: Path):
    sys.path.insert(0, str(DOCS))
    try:
        import make_gallery
    finally:
        sys.path.remove(str(DOCS))
    from symmech.scenefile import builtin_scene_names

    page = (site / "gallery.html").read_text(encoding="utf-8")
    for name in builtin_scene_names():
        if name in make_gallery.LEFT_OUT:
            assert f'id="{name.replace("_", "-")}"' in page
            continue
        gif = DOCS / "_static" / "gallery" / f"{name}.gif"
        assert gif.is_file(), f"{gif} is missing: run python3 docs/make_gallery.py {name}"
        assert f"{name}.gif" in page, name
