"""Loading generated code: the C library and its CPython extension built, or the NumPy
module imported, and either wrapped in a :class:`~symmech.codegen.module.SceneModule`.
"""

from __future__ import annotations

import hashlib
import importlib.util
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from symmech.codegen.build import (
    DEFAULT_FLAGS,
    cache_dir,
    compile_library,
    load_library,
    trusted_file,
)
from symmech.codegen.callers import c_raw, numpy_fast, numpy_raw
from symmech.codegen.extension import build_extension
from symmech.codegen.module import SceneModule
from symmech.files import write_text_atomic

if TYPE_CHECKING:
    from symmech.codegen.generate import GeneratedCode

__all__ = ["load_generated"]


def _import_numpy_module(code: GeneratedCode, folder: Path):
    text = code.files[f"{code.stem}.py"]
    key = hashlib.sha256(text.encode()).hexdigest()[:16]
    path = folder / f"{code.stem}_{key}.py"
    # the cache folder may be shared: a file there is used only if it is trusted (a
    # regular file of this user that no one else may write) holding exactly this text,
    # else it is replaced
    fresh = trusted_file(path)
    if not fresh or path.read_text(encoding="utf-8") != text:
        write_text_atomic(path, text)
    name = f"_symmech_generated_{code.stem}_{key}"
    if name in sys.modules:
        return sys.modules[name], path
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    sys.modules[name] = module
    return module, path


def load_generated(
    code: GeneratedCode,
    *,
    compiler: str | None = None,
    flags: Sequence[str] | None = None,
    cache: str | Path | None = None,
    extension: bool = True,
) -> SceneModule:
    """Build (C) or import (NumPy) ``code`` and wrap it in a :class:`SceneModule`.

    For C, one-state calls of the functions of the state and the parameters go through a
    CPython extension (``extension=True`` and the Python and NumPy headers present), else
    through ctypes; :attr:`SceneModule.fast_path` says which and why.  Both give the same
    doubles: they call the same compiled function.  The extension is compiled with the
    generated sources into one shared object, which ctypes loads too (one compilation);
    without the extension the library is compiled alone.
    """
    if code.target == "numpy":
        module, path = _import_numpy_module(code, cache_dir(cache))
        raw = {f.name: numpy_raw(getattr(module, f.name), f) for f in code.functions}
        n_parameters = len(code.plan.parameters)
        fast = {
            f.name: numpy_fast(
                getattr(module, f"_one_{f.name}"),
                f,
                code.plan.n,
                n_parameters,
                code.parameter_rules,
            )
            for f in code.functions
            if f.scalar is not None and hasattr(module, f"_one_{f.name}")
        }
        out = SceneModule(code, raw, path, fast)
        out.fast_path = "NumPy module (one state: plain floats and math)"
        return out
    kwargs: dict[str, Any] = {"compiler": compiler, "cache": cache}
    if flags is not None:
        kwargs["flags"] = tuple(flags)
    ext, how, library = None, "ctypes (extension=False)", None
    if extension:
        # one build: the extension's shared object holds the library's functions too
        ext, how, library = build_extension(
            code, compiler, kwargs.get("flags", DEFAULT_FLAGS), cache
        )
    if library is None:
        library = compile_library(dict(code.files), **kwargs)
    lib = load_library(library)
    prefix = f"{code.stem}_"
    n_inputs = len(code.plan.inputs)
    n_par = len(code.plan.parameters)
    rules = code.parameter_rules
    callers = {
        f.name: c_raw(lib, prefix, f, code.plan.n, n_inputs, n_par, rules) for f in code.functions
    }
    raw = {name: general for name, (general, _) in callers.items()}
    fast = {name: quick for name, (_, quick) in callers.items() if quick is not None}
    if ext is not None:
        fast.update({name: getattr(ext, name) for name in fast if hasattr(ext, name)})
    module = SceneModule(code, raw, library, fast)
    module._library = lib  # keep the library alive as long as the module
    module.fast_path = how
    return module
