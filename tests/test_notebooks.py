"""The notebooks in ``notebooks/`` (issue 5) are executed here, so none can rot.

Each notebook runs top to bottom in a fresh ``python3`` Jupyter kernel (nbclient), with
``notebooks/`` as the working directory, this working tree first on the kernel's
``PYTHONPATH`` (so the notebooks test the code next to them, not an installed copy of
symmech) and a timeout per cell; its cells check their
results against the texts with ``assert``, so a failing check fails the test, which reports
the failing cell's source and error.  Nothing is skipped: a missing kernel or a missing
nbclient/nbformat is a failure with instructions.  The notebooks must also be stored without
outputs, so that their diffs stay small.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
NOTEBOOK_DIR = ROOT / "notebooks"
NOTEBOOKS = sorted(NOTEBOOK_DIR.glob("*.ipynb"))
KERNEL = "python3"
CELL_TIMEOUT = 120  # seconds per cell; each notebook as a whole should take well under 30 s
_ANSI = re.compile(r"\x1b\[[0-9;]*m")


def _nb_modules():
    """nbformat and nbclient, or a failure naming the fix (never a skip)."""
    try:
        import nbclient
        import nbformat
    except ImportError as exc:
        problem = str(exc)
    else:
        return nbformat, nbclient
    pytest.fail(
        f"executing the notebooks needs nbclient and nbformat ({problem}); install the test"
        " extra: python3 -m pip install '.[test]'",
        pytrace=False,
    )


def _require_kernel() -> None:
    """Fail (never skip) with instructions when the ``python3`` kernel is not installed."""
    try:
        from jupyter_client.kernelspec import KernelSpecManager, NoSuchKernel
    except ImportError as exc:
        problem = f"executing the notebooks needs jupyter_client ({exc})"
    else:
        try:
            KernelSpecManager().get_kernel_spec(KERNEL)
        except NoSuchKernel:
            problem = f"no Jupyter kernel named {KERNEL!r} is installed; the notebooks cannot run"
        else:
            return
    pytest.fail(
        f"{problem}; install ipykernel in this environment (python3 -m pip install '.[test]')"
        " or register a kernel with: python3 -m ipykernel install --user --name python3",
        pytrace=False,
    )


def _read(path: Path):
    nbformat, _ = _nb_modules()
    return nbformat.read(path, as_version=4)


def test_notebooks_are_present_and_listed_in_the_readme():
    assert NOTEBOOKS, f"no notebooks found in {NOTEBOOK_DIR}"
    readme = (NOTEBOOK_DIR / "README.md").read_text(encoding="utf-8")
    missing = [p.name for p in NOTEBOOKS if p.name not in readme]
    assert not missing, f"notebooks/README.md does not list {missing}"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_is_stored_without_outputs(path: Path):
    nb = _read(path)
    dirty = [
        i
        for i, cell in enumerate(nb.cells)
        if cell.cell_type == "code" and (cell.get("outputs") or cell.get("execution_count"))
    ]
    assert not dirty, (
        f"{path.name}: cells {dirty} are stored with outputs or execution counts; clear them"
        f" before saving (jupyter nbconvert --clear-output --inplace notebooks/{path.name})"
    )


def _kernel_env() -> dict[str, str]:
    """The kernel's environment: this working tree first on PYTHONPATH."""
    path = os.environ.get("PYTHONPATH")
    return {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), *([path] if path else [])])}


def _execute(nb, name: str) -> None:
    """Run ``nb`` in place in a fresh kernel; fail with the failing cell's report."""
    _, nbclient = _nb_modules()
    from nbclient.exceptions import CellExecutionError, CellTimeoutError

    _require_kernel()
    client = nbclient.NotebookClient(
        nb,
        timeout=CELL_TIMEOUT,
        kernel_name=KERNEL,
        resources={"metadata": {"path": str(NOTEBOOK_DIR)}},
    )
    report = None
    try:
        client.execute(env=_kernel_env())
    except (CellExecutionError, CellTimeoutError) as exc:
        report = _failure_report(name, nb, exc)
    if report is not None:  # outside the except block: no chained nbclient traceback
        pytest.fail(report, pytrace=False)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_executes(path: Path):
    _execute(_read(path), path.name)


def test_the_kernel_imports_this_working_tree():
    """The notebooks run against the symmech next to them, not an installed copy."""
    nbformat, _ = _nb_modules()
    nb = nbformat.v4.new_notebook()
    nb.cells.append(nbformat.v4.new_code_cell("import symmech\nprint(symmech.__file__)"))
    _execute(nb, "probe")
    (output,) = nb.cells[0].outputs
    assert Path(output["text"].strip()) == ROOT / "symmech" / "__init__.py"


def _failure_report(name: str, nb, exc: Exception) -> str:
    """The failing cell (index and source) and its error, without terminal colours."""
    for index, cell in enumerate(nb.cells):
        errors = [o for o in cell.get("outputs", []) if o.get("output_type") == "error"]
        if errors:
            err = errors[0]
            trace = _ANSI.sub("", "\n".join(err.get("traceback", [])))
            return (
                f"{name}: cell {index} failed\n"
                f"----- cell source -----\n{cell.source}\n"
                f"----- error -----\n{err.get('ename')}: {err.get('evalue')}\n{trace}"
            )
    return f"{name}: execution failed\n{_ANSI.sub('', str(exc))}"
