"""Sphinx configuration of the symmech documentation site.

Build (from the repository root, after ``python3 -m pip install -e ".[docs]"``)::

    python3 -m sphinx -W --keep-going -b html docs docs/_build/html

The notebooks of ``notebooks/`` are copied into ``docs/examples/`` (a copy only when a
notebook changed, so the build's own bookkeeping sees what changed) and executed by MyST-NB
with cached execution: a notebook is run again only when its code changed
(``docs/_build/.jupyter_cache``).  The API reference is generated from the docstrings
(autodoc); the user guide takes its text from README.md's sections (one source).
"""

from __future__ import annotations

import filecmp
import shutil
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))  # document (and run the notebooks with) this checkout

import symmech  # noqa: E402


def _copy_notebooks() -> None:
    target = DOCS / "examples"
    target.mkdir(exist_ok=True)
    for nb in sorted((ROOT / "notebooks").glob("*.ipynb")):
        dest = target / nb.name
        if not dest.exists() or not filecmp.cmp(nb, dest, shallow=False):
            shutil.copy2(nb, dest)


_copy_notebooks()

project = "symmech"
author = "the symmech developers"
release = version = symmech.__version__
copyright = "the symmech developers, MIT licence"

extensions = [
    "myst_nb",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
]
exclude_patterns = ["_build", "make_gallery.py", "**.ipynb_checkpoints"]
html_theme = "alabaster"
html_static_path = ["_static"]
html_title = f"symmech {release}"
html_theme_options = {
    "description": "Symbolic geometric mechanics: equations of motion, impact laws, code,"
    " hybrid simulation",
    "fixed_sidebar": True,
}

# MyST and MyST-NB: run the notebooks, each again only when its code changed
myst_enable_extensions = ["dollarmath", "amsmath"]
myst_heading_anchors = 3
nb_execution_mode = "cache"
nb_execution_cache_path = str(DOCS / "_build" / ".jupyter_cache")
nb_execution_timeout = 600
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_merge_streams = True

# autodoc: the docstrings as written (they use reST and NumPy-style sections)
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": False}
napoleon_numpy_docstring = True
napoleon_google_docstring = False
napoleon_use_ivar = True  # "Attributes" as fields of the class, not objects of their own
