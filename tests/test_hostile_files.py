"""Output files and the terminal (issue 10, class 8): generated files are written
atomically and never through a link planted in the output folder; names holding terminal
escape sequences reach stderr escaped; a 300-character scene name gives short file names.

The command line is driven as a user drives it (a subprocess, tests/test_cli.py's
helpers); the Python API through GeneratedCode.write and the loaded NumPy module's cache.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from test_cli import EXIT_INPUT, PROGRESS, assert_one_line_error, symmech

import symmech as sm
from symmech.codegen import generate
from symmech.codegen.escape import terminal
from symmech.examples import carnot_3_7
from symmech.files import FILE_MODE, write_text_atomic

ESC = "\x1b[31m\x1b]0;pwned\x07"  # recolour, and retitle the terminal
RAW_CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f-\x9f]")


def _plant(folder: Path, name: str, target: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    link = folder / name
    link.symlink_to(target)
    return link


@pytest.mark.parametrize("target", ["c", "numpy"])
def test_write_replaces_a_planted_link_and_leaves_its_target_alone(tmp_path, target):
    code = generate(carnot_3_7(), target)
    victim = tmp_path / "victim.txt"
    victim.write_text("KEEP")
    out = tmp_path / "out"
    names = list(code.files)
    _plant(out, names[0], victim)  # a link to a file
    if len(names) > 1:
        _plant(out, names[1], tmp_path / "nowhere" / "x")  # a dangling link
    paths = code.write(out)
    assert victim.read_text() == "KEEP"
    assert not (tmp_path / "nowhere").exists()
    for path in paths:
        assert not path.is_symlink() and path.is_file()
        assert path.read_text(encoding="utf-8") == code.files[path.name]
        assert path.stat().st_mode & 0o777 == FILE_MODE
    assert sorted(p.name for p in out.iterdir()) == sorted(names)  # no temporary left


def test_a_link_to_a_folder_is_replaced_and_a_folder_is_refused(tmp_path):
    code = generate(carnot_3_7(), "numpy")
    (name,) = code.files
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    _plant(tmp_path / "a", name, elsewhere)
    (path,) = code.write(tmp_path / "a")
    assert path.is_file() and not path.is_symlink() and list(elsewhere.iterdir()) == []
    (tmp_path / "b" / name).mkdir(parents=True)
    with pytest.raises(IsADirectoryError, match="is a folder"):
        code.write(tmp_path / "b")


def test_a_failed_write_leaves_the_old_file_and_no_temporary(tmp_path, monkeypatch):
    path = tmp_path / "f.c"
    path.write_text("old")

    def fail(src, dst):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "replace", fail)
    with pytest.raises(OSError, match="No space"):
        write_text_atomic(path, "new")
    assert path.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["f.c"]


def test_a_reader_never_sees_a_half_written_file(tmp_path):
    """Rewrites of a large file while another process reads it: every read is one of the
    complete versions (the rename is atomic)."""
    path = tmp_path / "big.py"
    versions = ["a" * 2_000_000, "b" * 3_000_000]
    write_text_atomic(path, versions[0])
    reader = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import sys\nfrom pathlib import Path\np = Path(sys.argv[1])\n"
            "seen = {len(p.read_text()) for _ in range(300)}\nprint(*sorted(seen))",
            str(path),
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    for i in range(40):
        write_text_atomic(path, versions[i % 2])
    out, _ = reader.communicate(timeout=120)
    assert {int(x) for x in out.split()} <= {2_000_000, 3_000_000}, out


def test_the_numpy_module_cache_ignores_a_planted_link(tmp_path):
    """A shared cache folder: a link (or a tampered file) where the generated module goes
    is replaced by the generated text before it is imported."""
    code = generate(carnot_3_7(), "numpy")
    cache = tmp_path / "cache"
    first = code.load(cache=cache)
    (cached,) = [p for p in cache.iterdir() if p.suffix == ".py"]
    evil = tmp_path / "evil.py"
    evil.write_text("raise SystemExit('imported the planted file')\n")
    cached.unlink()
    cached.symlink_to(evil)
    for name in [k for k in sys.modules if k.startswith(f"_symmech_generated_{code.stem}_")]:
        del sys.modules[name]  # import afresh from the cache folder
    second = code.load(cache=cache)
    assert not cached.is_symlink()
    assert cached.read_text(encoding="utf-8") == code.files[f"{code.stem}.py"]
    q, v, p = [0.0, 1.0, 0.0], [1.0, -2.0, 0.0], [1.0, 0.5, 1.0, 2.0]
    np.testing.assert_array_equal(first.impact(q, v, p), second.impact(q, v, p))
    assert evil.read_text().startswith("raise")


def test_a_300_character_scene_name_writes_short_files(tmp_path):
    x = sm.coordinates("x")[0]
    long_name = "very_long_" * 30
    scene = sm.Scene((x,), metric=sp.eye(1), walls=[sm.Wall(x)], name=long_name)
    for target in ("c", "numpy"):
        code = generate(scene, target)
        paths = code.write(tmp_path / target)
        assert all(len(p.name) <= 100 for p in paths)
        assert code.stem.startswith("symmech_very_long_")


def test_terminal_escapes_every_control_character():
    text = f"a{ESC}\r\b\x00\u202e\u2028b\nc"
    out = terminal(text)
    assert not RAW_CONTROL.search(out.replace("\n", ""))
    assert "\u202e" not in out and "\u2028" not in out
    assert out.count("\n") == 1 and out.startswith("a\\x1b[31m")


# ----------------------------------------------------------------- the command line


def _assert_escaped(stderr: str) -> None:
    assert "\x1b" not in stderr and "\x07" not in stderr, stderr
    assert not RAW_CONTROL.search(stderr.replace("\n", "")), repr(stderr)


def test_cli_derive_replaces_a_planted_link(tmp_path):
    victim = tmp_path / "victim"
    victim.write_text("KEEP")
    _plant(tmp_path / "out", "symmech_carnot_3_7.c", victim)
    proc = symmech("derive", "carnot_3_7", "-o", "out", "--quiet", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert victim.read_text() == "KEEP"
    written = tmp_path / "out" / "symmech_carnot_3_7.c"
    assert written.is_file() and not written.is_symlink()
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [
        "symmech_carnot_3_7.c",
        "symmech_carnot_3_7.h",
    ]


def test_cli_export_replaces_a_planted_link(tmp_path):
    victim = tmp_path / "victim"
    victim.write_text("KEEP")
    (tmp_path / "scene.toml").symlink_to(victim)
    proc = symmech("export", "carnot_3_7", "-o", "scene.toml", "--quiet", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert victim.read_text() == "KEEP"
    assert "carnot_3_7" in (tmp_path / "scene.toml").read_text()


def test_cli_refuses_a_folder_where_a_file_goes(tmp_path):
    (tmp_path / "out" / "symmech_carnot_3_7.h").mkdir(parents=True)
    proc = symmech("derive", "carnot_3_7", "-o", "out", cwd=tmp_path)
    assert_one_line_error(proc, "symmech_carnot_3_7.h", "is a folder")


@pytest.mark.parametrize(
    "case",
    ["missing file", "missing name", "bad toml", "bad option", "progress"],
)
def test_cli_escapes_terminal_sequences_of_names_on_stderr(tmp_path, case):
    name = f"scene{ESC}"
    if case == "missing file":
        proc = symmech("derive", f"{name}.toml", cwd=tmp_path)
        line = assert_one_line_error(proc, "no such scene file")
    elif case == "missing name":
        proc = symmech("derive", name, cwd=tmp_path)
        line = assert_one_line_error(proc, "neither a scene file")
    elif case == "bad toml":
        (tmp_path / f"{name}.toml").write_text("coordinates = [\n")
        proc = symmech("derive", f"{name}.toml", cwd=tmp_path)
        line = assert_one_line_error(proc, "not valid TOML")
    elif case == "bad option":
        proc = symmech("derive", "carnot_3_7", "--emit", name, cwd=tmp_path)
        assert proc.returncode == EXIT_INPUT
        line = proc.stderr
    else:
        folder = f"out{ESC}"
        proc = symmech("derive", "carnot_3_7", "-o", folder, cwd=tmp_path)
        assert proc.returncode == 0, proc.stderr
        assert any(PROGRESS.match(x) for x in proc.stderr.splitlines())
        assert "\x1b" not in proc.stdout  # the written paths
        assert (tmp_path / folder / "symmech_carnot_3_7.c").is_file()
        line = proc.stderr
    _assert_escaped(proc.stderr)
    assert "\\x1b[31m" in line, line


def _library_path(folder, code):
    from symmech.codegen.build import DEFAULT_FLAGS, find_compiler, library_key

    return folder / f"symmech_{library_key(find_compiler(), DEFAULT_FLAGS, code.files)}.so"


def test_a_planted_library_in_the_cache_is_rebuilt_not_loaded(tmp_path):
    """A file at the cached library's name that another user could have written (here:
    writable by group and others) is code: it is rebuilt and replaced, not loaded; so is
    one at the name of the shared object that holds the library and its CPython
    extension (the default build, where the headers are)."""
    from symmech.examples import bouncing_ball

    code = sm.codegen.generate(bouncing_ball(), "c")
    names = {False: _library_path(tmp_path, code).name}
    names[True] = code.load(cache=tmp_path / "probe").path.name  # the default build's name
    for extension, name in names.items():
        cache = tmp_path / f"cache_{extension}"
        cache.mkdir(mode=0o700)
        planted = cache / name
        planted.write_bytes(b"not a library")
        planted.chmod(0o666)
        mod = code.load(cache=cache, extension=extension)
        assert mod.path == planted
        params = {"m": 1.0, "g": 2.0, "alpha": 0.5}
        assert mod.call("energy", [1.0], [0.0], params=params) == 2.0
        assert planted.read_bytes()[:4] == b"\x7fELF"
        assert planted.stat().st_mode & 0o022 == 0


def test_a_cache_folder_any_user_may_write_is_refused_unless_sticky(tmp_path):
    from symmech.codegen.build import CompileError, cache_dir

    open_folder = tmp_path / "open"
    open_folder.mkdir()
    open_folder.chmod(0o777)
    with pytest.raises(CompileError, match="writable by other users and not sticky"):
        cache_dir(open_folder)
    sticky = tmp_path / "sticky"
    sticky.mkdir()
    sticky.chmod(0o1777)
    assert cache_dir(sticky) == sticky
    fresh = tmp_path / "new" / "cache"
    assert cache_dir(fresh) == fresh and fresh.stat().st_mode & 0o077 == 0


def test_only_a_private_regular_file_is_trusted(tmp_path):
    from symmech.codegen.build import trusted_file

    own = tmp_path / "own.so"
    own.write_bytes(b"x")
    own.chmod(0o644)
    assert trusted_file(own)
    own.chmod(0o664)
    assert not trusted_file(own)
    link = tmp_path / "link.so"
    link.symlink_to(own)
    own.chmod(0o644)
    assert not trusted_file(link) and not trusted_file(tmp_path / "missing.so")
