"""The ``symmech`` command line (issue 5), driven as a user drives it: a subprocess
``python -m symmech ...``, checking its output, its stderr and its exit code.

``derive`` is tested with the code generation (tests/test_codegen*).  Expected values come
from the texts (formulas typed in by hand, printed with sympy's own printers), from
``pyproject.toml`` (the version) and from the rules of issue 5 (progress on stderr, one
error line, exit codes); none is produced by symmech.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
import sympy as sp

from symmech.examples import EXAMPLES
from symmech.scenefile import read_scene, reads_scene

ROOT = Path(__file__).resolve().parents[1]
# Issue 5: "at least the bouncing ellipse, the spinning disk of text 001, Examples 3.7,
# 3.13, 4.4 of the Carnot paper, the rolling ball and the car of the slides".
REQUIRED_SCENES = (
    "bouncing_ellipse",
    "spinning_disk",
    "carnot_3_7",
    "carnot_3_13",
    "carnot_4_4",
    "rolling_ball",
    "car",
)
PROGRESS = re.compile(r"^\[symmech +(\d+\.\d\d)s\] (.+)$")
EXIT_INPUT = 2  # bad input: unknown scene, refused scene file, usage (cli module docstring)


def _env(extra: dict[str, str] | None = None) -> dict[str, str]:
    """The environment of a subprocess: this working tree first on PYTHONPATH, so that
    ``python -m symmech`` in another folder runs the code under test, not an installed
    copy."""
    path = os.environ.get("PYTHONPATH")
    tree = os.pathsep.join([str(ROOT), *([path] if path else [])])
    return {**os.environ, "PYTHONPATH": tree, **(extra or {})}


def python(
    *args: str,
    cwd: Path,
    env: dict[str, str] | None = None,
    encoding: str = "utf-8",
    timeout: float = 120,
) -> subprocess.CompletedProcess:
    """Run ``python ARGS`` (this interpreter, this working tree) in ``cwd``; return the
    finished process, its output decoded with ``encoding``."""
    return subprocess.run(
        [sys.executable, *args],
        cwd=cwd,
        env=_env(env),
        capture_output=True,
        text=True,
        encoding=encoding,
        timeout=timeout,
    )


def symmech(
    *args: str,
    cwd: Path,
    timeout: float = 120,
    env: dict[str, str] | None = None,
    encoding: str = "utf-8",
) -> subprocess.CompletedProcess:
    """Run ``python -m symmech ARGS`` in ``cwd``; return the finished process (text)."""
    env = {"PYTHONIOENCODING": "utf-8", **(env or {})}
    return python("-m", "symmech", *args, cwd=cwd, env=env, encoding=encoding, timeout=timeout)


def _error_lines(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines() if not PROGRESS.match(line)]


def assert_one_line_error(proc: subprocess.CompletedProcess, *fragments: str) -> str:
    """A refused command: non-zero exit, no traceback, one error line holding fragments."""
    assert proc.returncode == EXIT_INPUT, (proc.returncode, proc.stderr)
    assert "Traceback" not in proc.stderr
    lines = _error_lines(proc.stderr)
    assert len(lines) == 1, proc.stderr
    (line,) = lines
    assert line.startswith("symmech: error: ")
    for fragment in fragments:
        assert fragment in line, (fragment, line)
    return line


# the formulas of the texts, written here
X, Y, TH = (sp.Symbol(s, real=True) for s in ("x", "y", "theta"))
XD, YD, THD = (sp.Symbol(s, real=True) for s in ("xdot", "ydot", "thetadot"))
M, I_, A, B, K, R = sp.symbols("m I a b k R", positive=True)
ALPHA = sp.Symbol("alpha", nonnegative=True)
# text 001 §3.1: the wall x = 0, approached from x < 0: psi = -x - h(theta)
ELLIPSE_PSI = -X - sp.sqrt(A**2 * sp.cos(TH) ** 2 + B**2 * sp.sin(TH) ** 2)


def _pretty(expr: sp.Basic) -> str:
    return sp.pretty(expr, use_unicode=True, wrap_line=False)


# ---------------------------------------------------------------------------------------
# the code under test


def test_subprocesses_run_this_working_tree(tmp_path: Path):
    """Every subprocess here imports the symmech next to this file, in any folder."""
    proc = python("-c", "import symmech; print(symmech.__file__)", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert Path(proc.stdout.strip()) == ROOT / "symmech" / "__init__.py"
    probe = "import sys, symmech.cli; print(symmech.cli.__file__); sys.exit(0)"
    assert Path(python("-c", probe, cwd=tmp_path).stdout.strip()) == ROOT / "symmech" / "cli.py"


# ---------------------------------------------------------------------------------------
# examples, --version


def test_examples_lists_the_builtin_scenes(tmp_path: Path):
    proc = symmech("examples", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    rows = [line.split(None, 1) for line in proc.stdout.splitlines()]
    names = [row[0] for row in rows]
    assert set(REQUIRED_SCENES) <= set(names)
    assert len(names) == len(set(names))
    # every row has a description, and every scene listed loads
    assert all(len(row) == 2 and row[1].strip() for row in rows)
    for name in names:
        assert read_scene(name).scene.name == name
    assert "text 001" in dict(rows)["bouncing_ellipse"]
    assert "3.7" in dict(rows)["carnot_3_7"]


def test_version_is_the_package_version(tmp_path: Path):
    version = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    proc = symmech("--version", cwd=tmp_path)
    assert proc.returncode == 0
    assert proc.stdout == f"symmech {version}\n"
    assert proc.stderr == ""


# ---------------------------------------------------------------------------------------
# show


def test_show_bouncing_ellipse_text_and_progress(tmp_path: Path):
    proc = symmech("show", "bouncing_ellipse", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout
    for title in (
        "== coordinates",
        "== mass matrix",
        "== Christoffel symbols",
        "== wall 'wall': gap psi",
        "== wall 'wall': post-impact velocity v+ (newton law, restitution 1)",
        "== wall 'wall': Theorem",
    ):
        assert title in out, title
    # the mass matrix diag(m, m, I) and the gap of text 001 §3.1, pretty-printed
    assert _pretty(sp.diag(M, M, I_)) in out
    assert _pretty(ELLIPSE_PSI) in out
    # progress on stderr: stage and elapsed time, in order, the impact map among the stages
    lines = proc.stderr.splitlines()
    assert lines and all(PROGRESS.match(line) for line in lines), proc.stderr
    times = [float(PROGRESS.match(line).group(1)) for line in lines]
    stages = [PROGRESS.match(line).group(2) for line in lines]
    assert times == sorted(times)
    assert "impact map of wall 'wall'" in stages
    assert stages[-1] == "done"


def test_show_bouncing_ellipse_latex(tmp_path: Path):
    proc = symmech("--quiet", "show", "bouncing_ellipse", "--latex", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout
    assert f"\\[ {sp.latex(ELLIPSE_PSI)} \\]" in out
    assert f"\\[ {sp.latex(sp.diag(M, M, I_))} \\]" in out
    assert "\\paragraph{wall 'wall': post-impact velocity v+" in out
    # LaTeX, not the terminal's pretty printing
    assert "⎡" not in out and "==" not in out
    # titles are LaTeX text: no special character left unescaped ("v^T", "Gamma^k_ij")
    titles = re.findall(r"^\\paragraph\{(.*)\}$", out, re.M)
    assert len(titles) >= 8
    for title in titles:
        escapes = r"\\(text(asciicircum|asciitilde|backslash|less|greater)\{\}|[&%$#_{}])"
        plain = re.sub(escapes, "", title)
        assert not set(plain) & set("\\^_&%$#~{}<>"), title
    assert "M (T = 1/2 v\\textasciicircum{}T M v)" in out
    assert "\\paragraph{wall 'wall': gap psi (psi \\textgreater{}= 0 admissible)}" in out


def test_show_carnot_3_7_text(tmp_path: Path):
    proc = symmech("show", "carnot_3_7", "--quiet", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    out = proc.stdout
    assert _pretty(sp.diag(M, M, M * K**2)) in out
    assert _pretty(Y - R) in out  # the rough wall y = R
    assert "restitution alpha" in out
    # Theorem 3.11 (Carnot's theorem with instantaneous constraints) holds: residual 0
    assert re.search(r"== wall 'rough_wall': Theorem 3\.11 residual \(0 when it holds\)\n0\n", out)


def test_show_carnot_3_7_latex(tmp_path: Path):
    proc = symmech("show", "carnot_3_7", "--latex", "--quiet", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout
    # the paper's post-impact velocity: ydot+ = -alpha ydot-
    assert sp.latex(-ALPHA * YD) in out
    assert f"\\[ {sp.latex(Y - R)} \\]" in out
    assert (
        "\\paragraph{wall 'rough\\_wall': Theorem 3.11 residual (0 when it holds)}\n\\[ 0 \\]"
        in out
    )


def test_no_command_shows_the_bouncing_ellipse(tmp_path: Path):
    default = symmech("--quiet", cwd=tmp_path)
    assert default.returncode == 0, default.stderr
    assert default.stderr == ""
    assert "== wall 'wall': gap psi" in default.stdout
    assert _pretty(ELLIPSE_PSI) in default.stdout


def test_quiet_silences_progress_wherever_it_is_written(tmp_path: Path):
    for args in (("--quiet", "show", "spinning_disk"), ("show", "spinning_disk", "--quiet")):
        proc = symmech(*args, cwd=tmp_path)
        assert proc.returncode == 0, proc.stderr
        assert proc.stderr == ""
        assert "energy law" in proc.stdout


# ---------------------------------------------------------------------------------------
# verify


def test_verify_passes_every_textbook_check(tmp_path: Path):
    proc = symmech("verify", "--quiet", cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert proc.stderr == ""
    lines = proc.stdout.splitlines()
    assert re.match(r"example +quantity +result$", lines[0])
    rows = [line for line in lines[2:] if line.strip() and not re.match(r"\d+ passed", line)]
    assert "FAIL" not in proc.stdout
    assert all(re.search(r"  ok  .*\(\d+\.\ds\)$", row) for row in rows), rows
    summary = re.search(r"^(\d+) passed, (\d+) failed$", proc.stdout, re.M)
    assert summary and int(summary.group(1)) == len(rows) and summary.group(2) == "0"
    # a check of each text: slides 000, text 001, the Carnot paper's worked examples
    for example in (
        "slides 000: rolling ball",
        "slides 000: car",
        "text 001 §3.1: bouncing ellipse",
        "text 001 §3.2: spinning disk",
        "Carnot ex. 3.7",
        "Carnot ex. 3.12",
        "Carnot ex. 3.13",
        "Carnot ex. 4.4",
    ):
        assert any(row.startswith(example) for row in rows), example


def test_verify_selects_checks_and_refuses_an_empty_selection(tmp_path: Path):
    proc = symmech("verify", "-k", "ex. 4.4", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert re.search(r"^2 passed, 0 failed$", proc.stdout, re.M)
    assert all(PROGRESS.match(line) for line in proc.stderr.splitlines())
    assert "check Carnot ex. 4.4" in proc.stderr
    assert_one_line_error(symmech("verify", "-k", "no such check", cwd=tmp_path), "no such check")


# ---------------------------------------------------------------------------------------
# export


def test_export_writes_a_scene_file_that_loads_back(tmp_path: Path):
    out = tmp_path / "disc.toml"
    proc = symmech("export", "carnot_3_7", "-o", str(out), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == ""
    assert f"wrote {out}" in proc.stderr
    back = read_scene(out)
    builtin = read_scene("carnot_3_7")
    assert back.scene.name == "carnot_3_7"
    assert back.defaults == builtin.defaults
    assert back.scene.parameters == builtin.scene.parameters
    assert back.scene.mass_matrix() == sp.diag(M, M, M * K**2)
    (wall,) = back.scene.walls
    assert (wall.name, wall.restitution, wall.psi) == ("rough_wall", ALPHA, Y - R)
    assert wall.impulsive_matrix == sp.Matrix([[1, 0, -R]])  # xdot - R thetadot
    # and the exported file is a scene file like any other for the other commands
    shown = symmech("--quiet", "show", str(out), "--latex", cwd=tmp_path)
    assert shown.returncode == 0, shown.stderr
    assert sp.latex(-ALPHA * YD) in shown.stdout


def test_export_to_stdout_moving_wall(tmp_path: Path):
    proc = symmech("export", "carnot_4_4", "--quiet", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    sf = reads_scene(proc.stdout)
    f = sp.Function("f", real=True)(sp.Symbol("t", real=True))
    assert sf.scene.walls[0].psi == X - f
    assert sf.functions == {"f": f}


def test_export_into_a_missing_folder_is_one_line(tmp_path: Path):
    target = tmp_path / "no" / "such" / "folder" / "x.toml"
    proc = symmech("export", "car", "-o", str(target), cwd=tmp_path)
    assert_one_line_error(proc, str(target), "No such file or directory")


# ---------------------------------------------------------------------------------------
# errors


def test_unknown_scene_is_one_readable_line(tmp_path: Path):
    proc = symmech("show", "carnot_3_8", cwd=tmp_path)
    line = assert_one_line_error(proc, "'carnot_3_8'", "carnot_3_7", "symmech examples")
    assert "neither a scene file nor a built-in scene" in line
    quiet = symmech("--quiet", "show", "no_such_scene", cwd=tmp_path)
    assert_one_line_error(quiet, "no_such_scene")
    assert len(quiet.stderr.splitlines()) == 1
    missing = symmech("show", "missing.toml", cwd=tmp_path)
    assert_one_line_error(missing, "missing.toml: no such scene file")


def test_hostile_scene_file_is_refused_and_runs_nothing(tmp_path: Path):
    marker = tmp_path / "PWNED_x"
    evil = tmp_path / "evil.toml"
    evil.write_text(
        'coordinates = ["x"]\n'
        'metric = ["m"]\n'
        f"potential = \"__import__('os').system('touch {marker}')\"\n"
        "[parameters]\n"
        "m = 1\n",
        encoding="utf-8",
    )
    for command in (("show",), ("export",), ("derive", "--emit", "c", "-o", "out")):
        proc = symmech(*command, str(evil), cwd=tmp_path)
        assert_one_line_error(
            proc, str(evil), "potential (line 3, col 1)", "__import__('os').system", "not allowed"
        )
        assert proc.stdout == ""
    assert not marker.exists()
    # derive stopped before writing anything
    assert sorted(p.name for p in tmp_path.iterdir()) == ["evil.toml"]


def test_control_the_hostile_payload_would_create_the_marker(tmp_path: Path):
    """The payload above is live: run by Python, it creates the marker file."""
    marker = tmp_path / "PWNED_x"
    proc = python("-c", f"__import__('os').system('touch {marker}')", cwd=tmp_path)
    assert proc.returncode == 0 and marker.exists()


def test_malformed_scene_file_is_one_readable_line(tmp_path: Path):
    bad = tmp_path / "bad.toml"
    bad.write_text('coordinates = ["x", "y"]\nmetric = ["m", "m"\n[parameters]\nm = 1\n')
    proc = symmech("show", str(bad), cwd=tmp_path)
    assert_one_line_error(proc, str(bad), "(line 3)", "not valid TOML")
    # several problems in one file: still one line, naming each
    two = tmp_path / "two.toml"
    two.write_text(
        'coordinates = ["x", "y"]\nmetric = ["m", "m"]\npotential = "m*y.real"\n'
        'constraint = ["xdot"]\n[parameters]\nm = 1\n'
    )
    proc = symmech("--quiet", "show", str(two), cwd=tmp_path)
    line = assert_one_line_error(proc, "2 problems", "did you mean 'constraints'")
    assert "potential (line 3, col 3): attribute access 'y.real'" in line
    assert "constraint (line 4)" in line
    assert len(proc.stderr.splitlines()) == 1


def test_debug_shows_the_traceback(tmp_path: Path):
    bad = tmp_path / "bad.toml"
    bad.write_text('coordinates = ["x"]\nmetric = ["m.real"]\n[parameters]\nm = 1\n')
    for args in (("--debug", "show", str(bad)), ("show", str(bad), "--debug")):
        proc = symmech(*args, cwd=tmp_path)
        assert proc.returncode != 0
        assert "Traceback (most recent call last)" in proc.stderr
        assert "SceneFileError" in proc.stderr
        assert "metric[0,0] (line 2, col 1): attribute access 'm.real'" in proc.stderr
    ok = symmech("--debug", "--quiet", "examples", cwd=tmp_path)
    assert ok.returncode == 0 and ok.stderr == ""


_FAILING_DERIVATION = """\
import sys
import symmech.cli as cli

def fail(*args, **kwargs):
    raise {exc}

cli.derivation = fail
sys.exit(cli.main({argv!r}))
"""


@pytest.mark.parametrize(
    ("exc", "code", "fragments"),
    [
        ("RuntimeError('boom')", 3, ["symmech: internal error: RuntimeError: boom", "--debug"]),
        ("KeyboardInterrupt()", 130, ["symmech: interrupted"]),
    ],
    ids=["internal error", "interrupted"],
)
def test_unexpected_failure_is_one_line(tmp_path: Path, exc: str, code: int, fragments: list[str]):
    """A failure inside a derivation (simulated: symmech has none on purpose) is one line."""
    script = _FAILING_DERIVATION.format(exc=exc, argv=["--quiet", "show", "car"])
    proc = python("-c", script, cwd=tmp_path)
    assert proc.returncode == code
    assert "Traceback" not in proc.stderr
    assert len(proc.stderr.splitlines()) == 1, proc.stderr
    for fragment in fragments:
        assert fragment in proc.stderr
    debug = script.replace("'--quiet'", "'--debug', '--quiet'")
    if code == 3:
        proc = python("-c", debug, cwd=tmp_path)
        assert proc.returncode != 0 and "Traceback (most recent call last)" in proc.stderr


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (("frobnicate",), "invalid choice: 'frobnicate'"),
        (("show", "--nope"), "unrecognized arguments: --nope"),
        (("examples", "extra"), "unrecognized arguments: extra"),
        (("verify", "-k"), "expected one argument"),
    ],
    ids=["unknown command", "unknown option", "extra argument", "missing value"],
)
def test_usage_error_exits_2(tmp_path: Path, args: tuple[str, ...], fragment: str):
    proc = symmech(*args, cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stdout == ""
    assert_one_line_error(proc, fragment, "symmech --help")


def test_help_lists_every_command(tmp_path: Path):
    proc = symmech("--help", cwd=tmp_path)
    assert proc.returncode == 0 and proc.stderr == ""
    assert proc.stdout.startswith("usage: symmech")
    for command in ("derive", "show", "examples", "verify", "export"):
        assert re.search(rf"^    {command} ", proc.stdout, re.M), command


# ----------------------------------------------------------------------------- derive


def _compile_and_import(folder: Path, stem: str) -> None:
    """The emitted C compiles with strict warnings and the NumPy module imports."""
    import shutil

    cc = shutil.which("gcc")
    assert cc, "gcc is required to check the emitted C"
    c_dir, py_dir = folder / "c", folder / "numpy"
    proc = subprocess.run(
        [
            cc,
            "-std=c99",
            "-O2",
            "-Wall",
            "-Wextra",
            "-Werror",
            "-pedantic",
            "-c",
            f"{stem}.c",
            "-o",
            f"{stem}.o",
        ],
        cwd=c_dir,
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stderr
    check = (
        "import importlib.util, sys\n"
        f"spec = importlib.util.spec_from_file_location('m', {str(py_dir / (stem + '.py'))!r})\n"
        "m = importlib.util.module_from_spec(spec); spec.loader.exec_module(m)\n"
        "print(m.N)\n"
    )
    run = subprocess.run([sys.executable, "-c", check], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr


@pytest.mark.parametrize("name", sorted(EXAMPLES))
def test_derive_every_builtin_scene_compiles_and_imports(tmp_path: Path, name: str):
    out = tmp_path / "out"
    proc = symmech("derive", name, "--emit", "c", "--emit", "numpy", "-o", str(out), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    printed = set(proc.stdout.split())
    stem = f"symmech_{name}"
    for f in (f"c/{stem}.c", f"c/{stem}.h", f"numpy/{stem}.py"):
        assert str(out / f) in printed, f
    assert re.search(r"generating c code", proc.stderr)
    _compile_and_import(out, stem)


def test_derive_without_a_scene_emits_the_bouncing_ellipse_in_c(tmp_path: Path):
    proc = symmech("derive", "--quiet", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    folder = tmp_path / "bouncing_ellipse_c"
    assert sorted(p.name for p in folder.iterdir()) == [
        "symmech_bouncing_ellipse.c",
        "symmech_bouncing_ellipse.h",
    ]
    assert "hypot(" in (folder / "symmech_bouncing_ellipse.c").read_text()


def test_derive_a_scene_file_with_a_strategy(tmp_path: Path):
    scene = tmp_path / "oscillator.toml"
    scene.write_text(
        'coordinates = ["x", "y"]\n'
        'metric = [["m + c", "c"], ["c", "m + c"]]\n'
        'potential = "k*(x**2 + y**2)/2"\n'
        "[parameters]\nm = 2\nc = 0.5\nk = 1\n"
    )
    proc = symmech(
        "derive",
        str(scene),
        "--strategy",
        "linear_solve",
        "--emit",
        "numpy",
        "-o",
        "gen",
        cwd=tmp_path,
    )
    assert proc.returncode == 0, proc.stderr
    text = (tmp_path / "gen" / "symmech_oscillator.py").read_text()
    assert "Strategy: linear_solve" in text
    assert "out = M^-1 f by a Cholesky factorisation of M, unrolled" in text
    assert "Li0 = 1.0/numpy.sqrt(" in text  # the factorisation in the generated code


def test_derive_refuses_an_unknown_strategy(tmp_path: Path):
    proc = symmech("derive", "car", "--strategy", "fastest", cwd=tmp_path)
    assert proc.returncode == 2
    assert "invalid choice" in proc.stderr


# ---------------------------------------------------------------------------------------
# terminals that cannot write Unicode


def test_an_ascii_terminal_gets_escapes_not_a_crash(tmp_path: Path):
    proc = symmech("examples", cwd=tmp_path, env={"PYTHONIOENCODING": "ascii"})
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.isascii()
    names = [line.split(None, 1)[0] for line in proc.stdout.splitlines()]
    assert set(REQUIRED_SCENES) <= set(names)
    # "text 001 §3.1" with the section sign written as a backslash escape
    assert "text 001 \\xa73.1" in proc.stdout
    # verify's table names the examples with "§" too
    proc = symmech("verify", "-k", "spinning", cwd=tmp_path, env={"PYTHONIOENCODING": "ascii"})
    assert proc.returncode == 0, proc.stderr
    assert re.search(r"^2 passed, 0 failed$", proc.stdout, re.M)


def test_a_latin1_terminal_gets_ascii_pretty_printing(tmp_path: Path):
    env = {"PYTHONIOENCODING": "latin-1"}
    proc = symmech("--quiet", "show", "carnot_3_7", cwd=tmp_path, env=env, encoding="latin-1")
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    ascii_art = sp.pretty(sp.diag(M, M, M * K**2), use_unicode=False, wrap_line=False)
    assert ascii_art in proc.stdout
    assert "⎡" not in proc.stdout and "θ" not in proc.stdout
    # an error naming a file with non-Latin characters is still one line
    missing = symmech("show", "θ/κ.toml", cwd=tmp_path, env=env, encoding="latin-1")
    assert_one_line_error(missing, "\\u03b8/\\u03ba.toml: no such scene file")


# ---------------------------------------------------------------------------------------
# show for more than MAX_DETAILED_N coordinates

# polar coordinates (r, th) and five free coordinates: 7 coordinates, and the Christoffel
# symbols of the plane in polar coordinates (slides 000): Gamma^r_thth = -r,
# Gamma^th_rth = 1/r; the free particle's acceleration r'' = r th'^2, th'' = -2 r' th'/r
POLAR7 = (
    'coordinates = ["r", "th", "z1", "z2", "z3", "z4", "z5"]\nmetric = [1, "r**2", 1, 1, 1, 1, 1]\n'
)


def test_show_says_what_it_leaves_out_and_full_prints_it(tmp_path: Path):
    scene = tmp_path / "polar7.toml"
    scene.write_text(POLAR7, encoding="utf-8")
    proc = symmech("--quiet", "show", str(scene), cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout
    for title in ("== Christoffel symbols\n", "== acceleration v_dot\n"):
        section = out.split(title, 1)[1].split("\n\n", 1)[0]
        assert section.startswith("not derived for n = 7 > 6 coordinates ("), section
        assert "'symmech show --full'" in section
    assert "Gamma^" not in out
    full = symmech("--quiet", "show", str(scene), "--full", cwd=tmp_path)
    assert full.returncode == 0, full.stderr
    r = sp.Symbol("r", real=True)
    rd, thd = (sp.Symbol(s, real=True) for s in ("rdot", "thdot"))
    assert f"Gamma^r_th,th = {_pretty(-r)}\n" in full.stdout
    assert f"Gamma^th_r,th = {_pretty(1 / r)}\n" in full.stdout
    accel = sp.Matrix([r * thd**2, -2 * rd * thd / r, 0, 0, 0, 0, 0])
    assert f"== acceleration v_dot\n{_pretty(accel)}\n" in full.stdout
    assert "not derived" not in full.stdout
    latex = symmech("--quiet", "show", str(scene), "--latex", cwd=tmp_path)
    assert latex.returncode == 0, latex.stderr
    note = "\\paragraph{Christoffel symbols}\nnot derived for n = 7 \\textgreater{} 6 coordinates"
    assert note in latex.stdout
