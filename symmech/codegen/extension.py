"""The CPython extension of a C target: the entry points of its functions of the state and
the parameters for one state (template ``c/python_module.c.jinja``), compiled with the
library's sources into one shared object, imported by
:func:`symmech.codegen.loading.load_generated`, which also loads that object through
ctypes for the general path (so the generated code is compiled once, not twice)."""

from __future__ import annotations

import hashlib
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from symmech.codegen.build import compile_library
from symmech.codegen.callers import NumericalError
from symmech.errors import SymmechError

if TYPE_CHECKING:
    from symmech.codegen.generate import GeneratedCode

__all__ = ["build_extension", "extension_source"]


def extension_source(code: GeneratedCode, module: str) -> str:
    """The C source of the CPython extension ``module`` of ``code``: its
    :attr:`~symmech.codegen.generate.GeneratedCode.extension` with the module name
    defined."""
    return f"#define SYMMECH_EXT_MODULE {module}\n" + code.extension


def build_extension(
    code: GeneratedCode,
    compiler: str | None,
    flags: Sequence[str],
    cache: str | Path | None,
) -> tuple[Any, str, Path | None]:
    """The CPython extension of ``code`` (see :func:`extension_source`), a description,
    and the path of its shared object (which holds the library's functions as well, for
    ctypes); or (None, why not, None)."""
    import importlib.machinery
    import sysconfig

    from symmech.codegen.build import extension_includes, find_compiler, library_key

    includes, missing = extension_includes()
    if missing:
        return None, f"ctypes (no CPython extension: {missing})", None
    if not code.extension:
        return None, "ctypes (no function of the state and parameters only)", None
    cc = find_compiler(compiler)
    # the key covers the extension's own source (its template may change while the
    # library's sources do not), rendered with a placeholder module name
    digest = hashlib.sha256(
        "\0".join(
            [
                library_key(cc, flags, code.files),
                extension_source(code, "_symmech_ext"),
                sys.version,
                np.__version__,
                *includes,
            ]
        ).encode()
    )
    name = f"_symmech_ext_{digest.hexdigest()[:20]}"
    sources = {**code.files, f"{name}.c": extension_source(code, name)}
    suffix = sysconfig.get_config_var("EXT_SUFFIX") or ".so"
    try:
        path = compile_library(
            sources,
            compiler=compiler,
            flags=[*flags, *(f"-I{d}" for d in includes)],
            cache=cache,
            filename=f"{name}{suffix}",
        )
        if name in sys.modules:
            ext = sys.modules[name]
        else:
            loader = importlib.machinery.ExtensionFileLoader(name, str(path))
            spec = importlib.util.spec_from_file_location(name, path, loader=loader)
            assert spec is not None
            ext = importlib.util.module_from_spec(spec)
            loader.exec_module(ext)
            sys.modules[name] = ext
    except (SymmechError, ImportError, OSError) as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        return None, f"ctypes (the CPython extension failed: {first})", None
    ext._configure(NumericalError)
    return ext, f"CPython extension {path.name} (one state), ctypes (batches)", path
