"""The ``symmech`` command line (also ``python -m symmech``).

Commands:

``symmech derive [SCENE] [--emit c|numpy ...] [-o DIR]``
    Derive the scene and emit its code (:func:`symmech.codegen.generate`) into DIR; print the
    files written.  Default SCENE: the bouncing ellipse; default target: c; default DIR:
    ``<scene>_<target>`` in the current folder (with several ``--emit``, one sub-folder per
    target inside ``-o DIR``).
``symmech show [SCENE] [--latex] [--full]``
    Print the derived quantities: metric, forcing, Christoffel symbols (or the frame's
    connection coefficients), constrained equations, each wall's impact map and its Carnot
    residual (or energy change for the energy law), as text or LaTeX.  Above
    :data:`symmech.derivation.MAX_DETAILED_N` coordinates the Christoffel symbols (or
    connection coefficients) and the acceleration are left out, with a line saying so,
    unless ``--full``.
``symmech examples``
    List the built-in scenes.
``symmech verify [-k TEXT]``
    Run the textbook checks (slides 000, text 001, the Carnot paper 002) and print a table
    ``example | quantity | result``; ``-k`` keeps the checks whose example or quantity
    contains TEXT.
``symmech export [SCENE] [-o FILE]``
    Write a scene as a TOML scene file (to start a new scene from a built-in one).

``symmech simulate SCENE``
    Simulate a scene (:mod:`symmech.bench.simulate_command`).
``symmech bench CASE``, ``symmech stress``
    Print a case's error against run time, run the stiff and extreme cases
    (:mod:`symmech.bench.commands`).
``symmech sweep SCENE --grid FILE --out FILE``
    Run the scene for every row of a grid (:mod:`symmech.sweep.command`).
``symmech gait NAME [--routes ...] [--continue P=A:B]``
    A built-in gait's fixed point and multipliers by each route, or their continuation in
    a parameter (:mod:`symmech.gait.gait_command`).

SCENE is a scene file (TOML, :mod:`symmech.scenefile`) or the name of a built-in scene.
With no command, ``show`` runs on the bouncing ellipse.  Progress (stage and elapsed time)
goes to stderr; ``--quiet`` silences it.  Errors print one line and exit non-zero, with no
traceback unless ``--debug``.  Exit codes: 0 success, 1 a verification failed, 2 bad input
(unknown scene, refused scene file, usage), 3 an internal error,
130 interrupted.  Output that the terminal's encoding cannot represent is written with
backslash escapes (``PYTHONIOENCODING=ascii``), and ``show`` then pretty-prints in ASCII.

The report that ``show`` prints is also available as an object,
:func:`symmech.derivation.derivation`, which renders as Markdown with LaTeX in Jupyter; the
textbook checks of ``verify`` are :mod:`symmech.verify`, against the reference values of
:mod:`symmech.references`.  This module only parses the command line and dispatches.
"""

from __future__ import annotations

import argparse
import io
import os
import sys
import time
import traceback
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import NoReturn

import sympy as sp

from symmech.bench.commands import COMMANDS, add_commands, run_command
from symmech.bench.simulate_command import add_command as add_simulate_command
from symmech.bench.simulate_command import run_command as run_simulate_command
from symmech.codegen.escape import file_name, terminal
from symmech.derivation import MAX_DETAILED_N, Derivation, derivation
from symmech.errors import SceneError, SymmechError
from symmech.examples import EXAMPLES, example
from symmech.files import write_text_atomic
from symmech.gait.gait_command import add_command as add_gait_command
from symmech.gait.gait_command import run_gait_command
from symmech.scenefile import (
    SceneFile,
    builtin_scene_names,
    dump_scene,
    read_scene,
)
from symmech.sweep.command import add_command as add_sweep_command
from symmech.sweep.command import run_command as run_sweep_command
from symmech.verify import Check, checks
from symmech.verify import verify as run_checks

__all__ = [
    "DEFAULT_SCENE",
    "TARGETS",
    "Check",
    "Derivation",
    "checks",
    "derivation",
    "main",
    "resolve_scene",
]

DEFAULT_SCENE = "bouncing_ellipse"
#: Code generation targets of ``symmech derive --emit``.
TARGETS = ("c", "numpy")

EXIT_OK, EXIT_FAILED, EXIT_INPUT, EXIT_INTERNAL, EXIT_INTERRUPTED = 0, 1, 2, 3, 130


# ---------------------------------------------------------------------------------------
# progress


class _Progress:
    """Prints ``[symmech  12.34s] stage`` lines on stderr unless quiet."""

    def __init__(self, quiet: bool):
        self.quiet = quiet
        self.start = time.perf_counter()

    def __call__(self, stage: str) -> None:
        if not self.quiet:
            elapsed = time.perf_counter() - self.start
            line = f"[symmech {elapsed:7.2f}s] {terminal(stage)}"
            print(line, file=sys.stderr, flush=True)


# ---------------------------------------------------------------------------------------
# scenes


def resolve_scene(spec: str) -> SceneFile:
    """The scene named by ``spec``: a scene file path, or a built-in scene's name.

    A file that exists is read as a scene file; otherwise a built-in name is looked up,
    first among the shipped scene files (``symmech/scenes/NAME.toml``, which carry default
    parameter values), then among :data:`symmech.examples.EXAMPLES`.  (A folder named like
    a built-in scene, such as the output of ``symmech derive car -o car``, does not hide
    it.)
    """
    path = Path(spec)
    if path.is_file():
        return read_scene(path)
    builtin = spec in builtin_scene_names() or spec in EXAMPLES
    if path.exists() and not builtin:
        raise SceneError(f"{spec}: is not a file")
    if spec in builtin_scene_names():
        return read_scene(spec)
    if spec in EXAMPLES:
        return SceneFile(scene=example(spec), description=EXAMPLES[spec][1])
    if spec.endswith(".toml") or os.sep in spec or "/" in spec:
        raise SceneError(f"{spec}: no such scene file")
    names = sorted(set(EXAMPLES) | set(builtin_scene_names()))
    raise SceneError(
        f"{spec!r} is neither a scene file nor a built-in scene; built-in scenes:"
        f" {', '.join(names)} (see 'symmech examples')"
    )


def _builtin_names() -> list[tuple[str, str]]:
    """(name, description) of every built-in scene, in the order of EXAMPLES."""
    out = [(name, desc) for name, (_, desc) in EXAMPLES.items()]
    for name in builtin_scene_names():
        if name not in EXAMPLES:
            out.append((name, read_scene(name).description))
    return out


# ---------------------------------------------------------------------------------------
# derive


def _derive(
    spec: str,
    targets: Sequence[str],
    out: str | None,
    progress: Callable[[str], None],
    strategy: str = "auto",
) -> list[Path]:
    progress(f"loading scene {spec}")
    scene = resolve_scene(spec).scene
    try:
        from symmech import codegen
    except ImportError as exc:
        raise SceneError(f"code generation is not available in this installation ({exc})") from None
    progress(f"mass matrix and forcing of {scene.name} ({scene.n} coordinates)")
    scene.mass_matrix()
    scene.forcing()
    written: list[Path] = []
    for target in dict.fromkeys(targets):
        if out is None:
            folder = Path(f"{file_name(scene.name)}_{target}")
        elif len(set(targets)) > 1:
            folder = Path(out) / target
        else:
            folder = Path(out)
        progress(f"generating {target} code ({strategy} strategy) into {folder}")
        code = codegen.generate(scene, target, strategy=strategy)
        if code.plan.fallback:
            progress(code.plan.fallback)
        written.extend(code.write(folder))
    return written


# ---------------------------------------------------------------------------------------
# the parser


class _Parser(argparse.ArgumentParser):
    """An ArgumentParser whose usage errors are one line and exit with code 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_INPUT, f"symmech: error: {terminal(message)} (see 'symmech --help')\n")


def _parser() -> argparse.ArgumentParser:
    common = _Parser(add_help=False)
    common.add_argument(
        "--quiet", action="store_true", default=argparse.SUPPRESS, help="no progress on stderr"
    )
    common.add_argument(
        "--debug",
        action="store_true",
        default=argparse.SUPPRESS,
        help="show the traceback of an error",
    )
    parser = _Parser(
        prog="symmech",
        description="Symbolic geometric mechanics: derive a scene's equations and impact"
        " maps, and emit code.",
        epilog="SCENE is a scene file (TOML) or a built-in scene name ('symmech examples').",
    )
    parser.add_argument("--quiet", action="store_true", help="no progress on stderr")
    parser.add_argument("--debug", action="store_true", help="show the traceback of an error")
    parser.add_argument("--version", action="store_true", help="print the version and exit")
    sub = parser.add_subparsers(dest="command", parser_class=_Parser, metavar="COMMAND")

    derive = sub.add_parser(
        "derive", parents=[common], help="derive a scene and emit C or NumPy code"
    )
    derive.add_argument("scene", nargs="?", default=DEFAULT_SCENE, help="scene file or name")
    derive.add_argument(
        "--emit",
        action="append",
        choices=TARGETS,
        help="code to emit: c (default) or numpy; repeat for both",
    )
    derive.add_argument("-o", "--output", help="output folder (default: <scene>_<target>)")
    derive.add_argument(
        "--strategy",
        choices=("auto", "closed_form", "linear_solve"),
        default="auto",
        help="closed_form evaluates the symbolic solutions; linear_solve solves g v_dot = f"
        " (and the constraint and impact systems) in the generated code; auto: closed form"
        " up to 3 coordinates",
    )

    show = sub.add_parser("show", parents=[common], help="print a scene's derived quantities")
    show.add_argument("scene", nargs="?", default=DEFAULT_SCENE, help="scene file or name")
    show.add_argument("--latex", action="store_true", help="print LaTeX instead of text")
    show.add_argument(
        "--full",
        action="store_true",
        help=f"also above {MAX_DETAILED_N} coordinates, derive and print the Christoffel"
        " symbols and the acceleration",
    )

    sub.add_parser("examples", parents=[common], help="list the built-in scenes")

    verify = sub.add_parser("verify", parents=[common], help="run the textbook checks")
    verify.add_argument("-k", dest="pattern", help="only checks whose name contains TEXT")

    add_simulate_command(sub, common)
    add_commands(sub, common)
    add_sweep_command(sub, common)
    add_gait_command(sub, common)

    export = sub.add_parser("export", parents=[common], help="write a scene as a TOML file")
    export.add_argument("scene", nargs="?", default=DEFAULT_SCENE, help="scene file or name")
    export.add_argument("-o", "--output", help="file to write (default: standard output)")
    return parser


def _one_line(exc: BaseException) -> str:
    """The error as one line safe for a terminal (file and scene names may hold escape
    sequences: :func:`symmech.codegen.escape.terminal`)."""
    problems = getattr(exc, "problems", None)
    if isinstance(problems, list) and len(problems) > 1:
        text = f"{len(problems)} problems: " + "; ".join(problems)
    else:
        text = str(exc)
    return terminal(" ".join(text.split()))


def _run(args: argparse.Namespace, progress: _Progress) -> int:
    command = args.command or "show"
    if command == "examples":
        names = _builtin_names()
        width = max(len(n) for n, _ in names)
        for name, description in names:
            print(f"{name:{width}}  {description}")
        return EXIT_OK
    if command == "verify":
        return EXIT_FAILED if run_checks(args.pattern, progress) else EXIT_OK
    if command == "simulate":
        return run_simulate_command(args, resolve_scene, progress)
    if command in COMMANDS:
        return run_command(args, resolve_scene, progress)
    if command == "sweep":
        return run_sweep_command(args, resolve_scene, progress)
    if command == "gait":
        return run_gait_command(args, progress)
    spec = getattr(args, "scene", DEFAULT_SCENE)
    if command == "derive":
        targets = args.emit or ["c"]
        paths = _derive(spec, targets, args.output, progress, args.strategy)
        for p in paths:
            print(terminal(p))
        progress(f"done: {len(paths)} files")
        return EXIT_OK
    if command == "export":
        sf = resolve_scene(spec)
        text = dump_scene(
            sf.scene,
            defaults=sf.defaults,
            description=sf.description,
            functions={k: e for k, e in sf.functions.items() if not _is_applied(e)},
        )
        if args.output:
            write_text_atomic(args.output, text)
            progress(f"wrote {args.output}")
        else:
            sys.stdout.write(text)
        return EXIT_OK
    # show
    progress(f"loading scene {spec}")
    rep = derivation(resolve_scene(spec).scene, progress, full=getattr(args, "full", False))
    if getattr(args, "latex", False):
        print(rep.latex())
    else:
        print(rep.text(unicode=_can_encode(sys.stdout, "\u23a1\u23a3\u03b8\u22c5")))
    progress("done")
    return EXIT_OK


def _can_encode(stream: object, sample: str) -> bool:
    """Whether ``stream`` (a text stream) can write ``sample`` without escapes."""
    encoding = getattr(stream, "encoding", None) or "utf-8"
    try:
        sample.encode(encoding)
    except (UnicodeEncodeError, LookupError):
        return False
    return True


def _escape_unencodable(streams: Sequence[object]) -> list[tuple[object, str]]:
    """Make each text stream write what its encoding cannot represent as backslash escapes
    (``PYTHONIOENCODING=ascii``, a latin-1 terminal) instead of raising; return what to
    restore."""
    changed = []
    for stream in streams:
        errors = getattr(stream, "errors", None)
        reconfigure = getattr(stream, "reconfigure", None)
        if errors == "strict" and reconfigure is not None:
            try:
                reconfigure(errors="backslashreplace")
            except (ValueError, io.UnsupportedOperation):  # pragma: no cover - exotic stream
                continue
            changed.append((stream, errors))
    return changed


def _is_applied(expr: sp.Expr) -> bool:
    from sympy.core.function import AppliedUndef

    return isinstance(expr, AppliedUndef)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``symmech`` console script (and ``python -m symmech``)."""
    changed = _escape_unencodable([sys.stdout, sys.stderr])
    try:
        return _main(sys.argv[1:] if argv is None else list(argv))
    finally:
        for stream, errors in changed:
            try:
                stream.reconfigure(errors=errors)  # type: ignore[attr-defined]
            except (ValueError, io.UnsupportedOperation):  # pragma: no cover - closed
                pass


def _main(argv: list[str]) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if args.version:
        from symmech import __version__

        print(f"symmech {__version__}")
        return EXIT_OK
    progress = _Progress(args.quiet)
    try:
        return _run(args, progress)
    except SymmechError as exc:
        if args.debug:
            raise
        print(f"symmech: error: {_one_line(exc)}", file=sys.stderr)
        return EXIT_INPUT
    except BrokenPipeError:
        # the reader went away (symmech show | head): stop quietly
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return EXIT_OK
    except OSError as exc:
        if args.debug:
            raise
        where = f" {terminal(exc.filename)}:" if exc.filename else ""
        print(f"symmech: error:{where} {terminal(exc.strerror or exc)}", file=sys.stderr)
        return EXIT_INPUT
    except KeyboardInterrupt:
        print("symmech: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception as exc:
        if args.debug:
            raise
        last = traceback.extract_tb(exc.__traceback__)[-1]
        print(
            f"symmech: internal error: {type(exc).__name__}: {_one_line(exc)}"
            f" (in {Path(last.filename).name}:{last.lineno}; run with --debug for the"
            " traceback)",
            file=sys.stderr,
        )
        return EXIT_INTERNAL


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
