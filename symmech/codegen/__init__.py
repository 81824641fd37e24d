"""Code generation: a Scene to self-contained C or NumPy code through Jinja templates.

>>> import symmech as sm
>>> from symmech.examples import bouncing_ellipse
>>> code = sm.codegen.generate(bouncing_ellipse(), target="c")
>>> sorted(code.files)
['symmech_bouncing_ellipse.c', 'symmech_bouncing_ellipse.h']

``code.write(folder)`` saves the files; ``code.load()`` compiles the C with the system
compiler into a cached shared library and loads it (or imports the NumPy module) and
returns a :class:`SceneModule` with the same API for both backends.  See
:mod:`symmech.codegen.plan` for what is generated, :mod:`symmech.codegen.lower` for CSE and
the linear-algebra steps, :mod:`symmech.codegen.backends` for adding a backend.
"""

from symmech.codegen.backends import BACKENDS, Backend
from symmech.codegen.build import CompileError, compile_library
from symmech.codegen.generate import GeneratedCode, generate
from symmech.codegen.module import NumericalError, SceneModule
from symmech.codegen.plan import FUNCTIONS, STRATEGIES, CodegenError

__all__ = [
    "BACKENDS",
    "FUNCTIONS",
    "STRATEGIES",
    "Backend",
    "CodegenError",
    "CompileError",
    "GeneratedCode",
    "NumericalError",
    "SceneModule",
    "compile_library",
    "generate",
]
