"""Packaging: the wheel ships the templates, the package list is complete, imports are lean,
and the layers import only to their left."""

from __future__ import annotations

import ast
import os
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PKG = ROOT / "symmech"

# declaration -> geometry -> constraints -> impacts -> scene -> examples/scene files ->
# codegen -> simulate -> sweep -> verify/bench -> cli
LAYERS = [
    "errors",
    "files",
    "algebra",
    "declaration",
    "geometry",
    "constraints",
    "impacts",
    "mechanics",
    "scene",
    "scenefile",
    "examples",
    "codegen",
    "simulate",
    "gait",
    "sweep",
    "references",
    "verify",
    "derivation",
    "bench",
    "cli",
]
# not layers: the package's entry points
ENTRY_POINTS = {"__init__", "__main__"}


def test_every_module_has_a_layer():
    names = {p.stem for p in PKG.glob("*.py")} | {p.parent.name for p in PKG.glob("*/__init__.py")}
    unplaced = sorted(names - set(LAYERS) - ENTRY_POINTS - {"scenes"})
    assert not unplaced, f"modules not in LAYERS (place them in the layer order): {unplaced}"


def _layer_of(module: str) -> int | None:
    parts = module.split(".")
    if parts[0] != "symmech" or len(parts) == 1:
        return None
    name = parts[1]
    return LAYERS.index(name) if name in LAYERS else None


def test_package_list_names_every_subpackage():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    listed = set(config["tool"]["setuptools"]["packages"])
    found = {
        ".".join(p.parent.relative_to(ROOT).parts)
        for p in PKG.rglob("__init__.py")
        if "__pycache__" not in p.parts
    }
    assert found <= listed, f"sub-packages missing from pyproject.toml: {sorted(found - listed)}"
    assert "symmech.templates" in listed
    # and the other way round: a listed package that does not exist breaks every install
    mapped = config["tool"]["setuptools"].get("package-dir", {})
    missing = [
        name
        for name in sorted(listed)
        if not (ROOT / mapped.get(name, name.replace(".", "/")) / "__init__.py").is_file()
    ]
    assert not missing, f"pyproject.toml lists packages that do not exist: {missing}"


def test_layers_import_only_to_their_left():
    bad = []
    for path in PKG.rglob("*.py"):
        rel = path.relative_to(ROOT).with_suffix("")
        module = ".".join(rel.parts).removesuffix(".__init__")
        own = _layer_of(module)
        if own is None:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            targets = []
            if isinstance(node, ast.ImportFrom) and node.module:
                targets = [node.module]
            elif isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            for target in targets:
                other = _layer_of(target)
                if other is not None and other > own:
                    bad.append(f"{module} (layer {LAYERS[own]}) imports {target}")
    assert not bad, "\n".join(bad)


def test_import_pulls_only_core_dependencies():
    code = "import sys, symmech\nprint('\\n'.join(sorted({m.split('.')[0] for m in sys.modules})))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    loaded = set(out.stdout.split())
    for heavy in ("scipy", "matplotlib", "symengine", "pytest", "hypothesis", "IPython"):
        assert heavy not in loaded, f"import symmech loads {heavy}"
    assert {"sympy", "numpy", "mpmath"} <= loaded


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """The wheel built from this checkout (pip wheel, no dependencies)."""
    out = tmp_path_factory.mktemp("wheel")
    proc = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "-w", str(out), str(ROOT)],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    (built,) = out.glob("symmech-*.whl")
    return built


def test_wheel_ships_templates(wheel):
    """The top-level templates/ folder is inside the wheel."""
    names = zipfile.ZipFile(wheel).namelist()
    assert "symmech/templates/README.md" in names
    assert "symmech/templates/__init__.py" in names
    templates = sorted(
        p.relative_to(ROOT).as_posix() for p in (ROOT / "templates").rglob("*.jinja")
    )
    for t in templates:
        assert "symmech/" + t in names, f"{t} missing from the wheel"


def test_generation_works_from_an_installed_wheel(wheel, tmp_path):
    """Install the wheel (not editable) into a bare folder, then generate, compile, load
    and call C and NumPy code from there, outside the checkout."""
    target = tmp_path / "site"
    proc = subprocess.run(
        [sys.executable, "-m", "pip", "install", "--no-deps", "--target", str(target), str(wheel)],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    script = """
import sys, symmech
from pathlib import Path
here = Path(symmech.__file__).resolve()
assert here.is_relative_to(Path(sys.argv[1]).resolve()), here
from symmech.examples import carnot_3_7
for target in ("c", "numpy"):
    mod = symmech.codegen.generate(carnot_3_7(), target).load()
    out = mod.impact([0, 1.0, 0], [1.0, -2.0, 0.0], [1.0, 0.5, 1.0, 2.0])
    assert [round(float(x), 12) for x in out] == [0.5, 1.0, 0.5], out
print("ok")
"""
    env = dict(os.environ, PYTHONPATH=str(target), SYMMECH_CACHE_DIR=str(tmp_path / "cache"))
    run = subprocess.run(
        [sys.executable, "-c", script, str(target)],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    assert run.stdout.strip() == "ok"


def test_ci_runs_the_readme_test_command_verbatim():
    """.ci/run ends with the README's second quick-start command, word for word."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    block = readme.split("```bash\n", 1)[1].split("```", 1)[0].strip().splitlines()
    assert len(block) == 2, block  # exactly two commands
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8").strip().splitlines()
    assert ci[-1] == block[1]


def test_no_two_modules_share_a_file_name():
    """Each module name says what it holds, once: no two modules of the package (packages'
    __init__ aside) share a file name."""
    names: dict[str, list[str]] = {}
    for path in PKG.rglob("*.py"):
        if path.name != "__init__.py":
            names.setdefault(path.name, []).append(str(path.relative_to(PKG)))
    shared = {name: paths for name, paths in names.items() if len(paths) > 1}
    assert not shared, f"modules sharing a file name: {shared}"
