"""Backends: a backend is a config (template folder, templates to render, printer).

Adding a backend is a recipe (SymForce style):

1. a printer subclassing a sympy code printer, in :mod:`symmech.codegen.printers`, and a
   :class:`~symmech.codegen.unroll.Dialect` printing the unrolled linear algebra;
2. a template folder ``templates/<name>/`` with a module template and
   ``function/FUNCTION.<ext>.jinja``, holding loops and conditionals only;
3. a :class:`Backend` entry in :data:`BACKENDS` naming the templates and output files.

Templates are rendered by a strict Jinja environment (``StrictUndefined``, ``trim_blocks``,
``lstrip_blocks``, ``keep_trailing_newline``); every output file starts with a stamp naming
the templates it was rendered from (its template and those it includes or imports, see
:func:`templates_used`) and saying it must not be edited.  Text of the scene (names,
printed expressions, notes) reaches a template raw and is escaped there for the place it
lands in by the filters of :data:`ESCAPE_FILTERS` (:mod:`symmech.codegen.escape`):
``c_comment``, ``c_string``, ``py_doc`` (docstrings), ``py_comment``.  Everything else a
template prints is code built by symmech (identifiers, printed expressions, integers).
"""

from __future__ import annotations

import importlib.resources
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import jinja2
import jinja2.meta
import sympy as sp

from symmech.codegen import c_signatures
from symmech.codegen.batch_split import batch_split
from symmech.codegen.dialects import CDialect, Dialect, NumPyDialect, ScalarDialect
from symmech.codegen.escape import c_comment, c_string, python_comment, python_docstring
from symmech.codegen.printers import SymmechCPrinter, SymmechMathPrinter, SymmechNumPyPrinter

__all__ = [
    "BACKENDS",
    "ESCAPE_FILTERS",
    "STEP_DOCS",
    "Backend",
    "environment",
    "template_root",
    "templates_used",
]

#: The Jinja filters escaping text for the place it lands in (one per target).
ESCAPE_FILTERS: dict[str, Callable[[object], str]] = {
    "c_comment": c_comment,
    "c_string": c_string,
    "py_doc": python_docstring,
    "py_comment": python_comment,
}

#: One-line descriptions of the linear-algebra steps, printed in function headers.
STEP_DOCS = {
    "spd_solve": "out = M^-1 f by a Cholesky factorisation of M",
    "constrained_acceleration": (
        "Cholesky solves of M and of C = mu M^-1 mu^T: lambda = C^-1 (-rate - mu M^-1 f),"
        " out = M^-1 (f + mu^T lambda)"
    ),
    "constrained_multipliers": (
        "Cholesky solves of M and of C = mu M^-1 mu^T: out = lambda = C^-1 (-rate - mu M^-1 f)"
    ),
    "constrained_dynamics": (
        "Cholesky solves of M and of C = mu M^-1 mu^T: lambda = C^-1 (-rate - mu M^-1 f),"
        " out = (M^-1 (f + mu^T lambda), lambda)"
    ),
    "impact_kkt": (
        "the impulse-momentum system by Cholesky solves of M and of G = A M^-1 A^T:"
        " out = v + M^-1 A^T G^-1 (b - A v)"
    ),
}


@dataclass(frozen=True)
class Backend:
    """A code-generation target.

    ``templates`` are (template path, output file name pattern) pairs; the pattern is
    formatted with ``stem`` (``symmech_<scene>``).  ``make_printer(names)`` returns the
    expression printer for a name table; ``dialect`` prints the unrolled linear-algebra
    steps (:mod:`symmech.codegen.unroll`).
    """

    name: str
    templates: tuple[tuple[str, str], ...]
    function_template: str
    make_printer: Callable[[Mapping[sp.Symbol, str]], sp.printing.printer.Printer]
    dialect: Dialect
    description: str
    #: a printer and a dialect for one-state variants of the functions (NumPy), or None
    scalar: (
        tuple[Callable[[Mapping[sp.Symbol, str]], sp.printing.printer.Printer], Dialect] | None
    ) = None

    def template_dir(self) -> Path:
        return template_root() / self.name

    def templates_to_render(self, stem: str) -> list[tuple[str, str]]:
        return [(t, pattern.format(stem=stem)) for t, pattern in self.templates]


BACKENDS: dict[str, Backend] = {
    "c": Backend(
        name="c",
        templates=(("c/header.h.jinja", "{stem}.h"), ("c/source.c.jinja", "{stem}.c")),
        function_template="c/function/FUNCTION.c.jinja",
        make_printer=SymmechCPrinter,
        dialect=CDialect(),
        description="C99, compiled with the system compiler and loaded with ctypes",
    ),
    "numpy": Backend(
        name="numpy",
        templates=(("numpy/module.py.jinja", "{stem}.py"),),
        function_template="numpy/function/FUNCTION.py.jinja",
        make_printer=SymmechNumPyPrinter,
        dialect=NumPyDialect(),
        description="a NumPy module, vectorised over leading axes",
        scalar=(SymmechMathPrinter, ScalarDialect()),
    ),
}


def template_root() -> Path:
    """The folder of the templates: those of the tree this code was imported from.

    In an installed package they are the package data ``symmech/templates`` (the top-level
    ``templates/`` folder mapped into the wheel); when symmech is imported from a source
    checkout (tests run from the repository root, an editable install), they are that
    checkout's ``templates/`` folder next to the package.  Only when neither exists is
    the resource ``symmech.templates`` asked for: a template from another installation
    than the code (an editable install's, while a second checkout is imported) would not
    match the code that fills it.
    """
    here = Path(__file__).resolve().parents[1]
    candidates = [here / "templates", here.parent / "templates"]
    try:
        candidates.append(Path(str(importlib.resources.files("symmech.templates"))))
    except ModuleNotFoundError:
        pass
    for path in candidates:
        if (path / "c" / "source.c.jinja").is_file():
            return path
    raise FileNotFoundError(
        "symmech templates not found (looked in "
        + ", ".join(str(c) for c in candidates)
        + "); the installation is incomplete"
    )


@cache
def environment() -> jinja2.Environment:
    """The strict Jinja environment over :func:`template_root`, with the escape filters
    of :data:`ESCAPE_FILTERS` and the C argument lists of :mod:`symmech.codegen.c_signatures`
    as globals."""
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(template_root())),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
        autoescape=False,
    )
    env.filters.update(ESCAPE_FILTERS)
    env.globals.update(
        c_parameters=c_signatures.parameters,
        c_batch_parameters=c_signatures.batch_parameters,
        c_call_arguments=c_signatures.call_arguments,
        c_scaled_arguments=c_signatures.scaled_arguments,
        c_batch_split=batch_split,
    )
    return env


@cache
def templates_used(template: str) -> tuple[str, ...]:
    """``template`` and every template it includes or imports, recursively, in the order
    first met (the templates an output file is rendered from)."""
    env = environment()
    order = [template]
    i = 0
    while i < len(order):
        source = env.loader.get_source(env, order[i])[0]  # type: ignore[union-attr]
        for ref in jinja2.meta.find_referenced_templates(env.parse(source)):
            if ref is None:
                raise ValueError(f"template {order[i]} references a template by a variable")
            if ref not in order:
                order.append(ref)
        i += 1
    return tuple(order)
