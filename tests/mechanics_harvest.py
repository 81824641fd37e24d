"""Every ``sympy.physics.mechanics`` model that sympy's own tests, docstring examples and
``sympy.physics.mechanics.models`` build with the installed sympy, collected as built.

The installed sympy's test functions and doctests are run (sympy's code, not user
input) with ``KanesMethod.kanes_equations``, ``LagrangesMethod.form_lagranges_equations``
and ``System.form_eoms`` wrapped to record each model whose equations were formed, in
the state the user had it then.  A model formed inside a System's ``form_eoms`` is
recorded once, as the System.  Test functions that fail (or are skipped) record what they
formed before failing.
"""

from __future__ import annotations

import contextlib
import doctest
import importlib
import inspect
import io
import pkgutil
import time
from collections.abc import Iterator
from dataclasses import dataclass

from sympy.physics import mechanics as me


@dataclass
class Harvested:
    """A model whose equations were formed, and where (``source``: module and test or
    docstring, ``#k`` the k-th model formed there)."""

    source: str
    model: object


_FORMERS = (
    (me.KanesMethod, "kanes_equations"),
    (me.LagrangesMethod, "form_lagranges_equations"),
    (me.System, "form_eoms"),
)


@contextlib.contextmanager
def _recording(out: list[object]) -> Iterator[None]:
    depth = [0]
    originals = {cls: getattr(cls, name) for cls, name in _FORMERS}

    def wrap(cls, name):
        original = originals[cls]

        def formed(self, *args, **kwargs):
            depth[0] += 1
            try:
                result = original(self, *args, **kwargs)
            finally:
                depth[0] -= 1
            if depth[0] == 0 and all(m is not self for m in out):
                out.append(self)
            return result

        return formed

    for cls, name in _FORMERS:
        setattr(cls, name, wrap(cls, name))
    try:
        yield
    finally:
        for cls, name in _FORMERS:
            setattr(cls, name, originals[cls])


def _test_functions() -> Iterator[tuple[str, object]]:
    import sympy.physics.mechanics.tests as tests

    for info in sorted(pkgutil.iter_modules(tests.__path__), key=lambda i: i.name):
        module = importlib.import_module(f"{tests.__name__}.{info.name}")
        for name, fn in sorted(vars(module).items()):
            if name.startswith("test_") and callable(fn):
                yield f"{info.name}::{name}", fn
            elif name.startswith("Test") and isinstance(fn, type):
                yield from _test_methods(info.name, name, fn)


def _test_methods(module: str, name: str, cls: type) -> Iterator[tuple[str, object]]:
    """The test methods of a test class that need no fixture (``self`` alone), each on a
    fresh instance (sympy's ``TestSystemExamples``)."""
    for method, fn in sorted(vars(cls).items()):
        if method.startswith("test_") and callable(fn):
            if list(inspect.signature(fn).parameters) == ["self"]:
                yield f"{module}::{name}::{method}", lambda fn=fn: fn(cls())


def _doctests() -> Iterator[tuple[str, object]]:
    finder = doctest.DocTestFinder(exclude_empty=True)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    for info in sorted(pkgutil.iter_modules(me.__path__), key=lambda i: i.name):
        if info.name == "tests":
            continue
        module = importlib.import_module(f"{me.__name__}.{info.name}")
        for test in sorted(finder.find(module), key=lambda t: t.name):

            def run(test=test):
                with contextlib.redirect_stdout(io.StringIO()):
                    runner.run(test, out=lambda _text: None)

            yield f"{info.name} docstring {test.name}", run


def _models_module() -> Iterator[tuple[str, object]]:
    from sympy.physics.mechanics import models

    for n in (1, 2, 3):
        yield (
            f"models.multi_mass_spring_damper({n})",
            lambda n=n: models.multi_mass_spring_damper(n),
        )
        yield (
            f"models.multi_mass_spring_damper({n}, gravity, external forces)",
            lambda n=n: models.multi_mass_spring_damper(n, True, True),
        )
        yield f"models.n_link_pendulum_on_cart({n})", lambda n=n: models.n_link_pendulum_on_cart(n)
        yield (
            f"models.n_link_pendulum_on_cart({n}, joint torques)",
            lambda n=n: models.n_link_pendulum_on_cart(n, True, True),
        )


def harvest(skip: tuple[str, ...] = ()) -> tuple[list[Harvested], dict[str, float]]:
    """The models formed by sympy's mechanics tests, doctests and models module (sources
    containing any string of ``skip`` are not run), and the seconds each source took."""
    found: list[Harvested] = []
    seconds: dict[str, float] = {}
    for source, run in [*_test_functions(), *_doctests(), *_models_module()]:
        if any(s in source for s in skip):
            continue
        formed: list[object] = []
        t0 = time.perf_counter()
        with _recording(formed), contextlib.suppress(Exception):
            run()
        seconds[source] = time.perf_counter() - t0
        found += [Harvested(f"{source}#{k}", m) for k, m in enumerate(formed)]
    return found, seconds
