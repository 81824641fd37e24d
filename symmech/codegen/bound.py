"""Generated functions with their parameters bound (:meth:`SceneModule.bind
<symmech.codegen.module.SceneModule.bind>`), for callers that evaluate one function
millions of times at the same parameters: an integrator of their own, an MPC loop, an
optimiser.

The parameters are converted and checked once, when bound, with the errors of a call of
the module (a value outside its declared range is a ``NumericalError`` naming it, a
non-finite one a ``CodegenError``), and kept as a read-only float64 copy.  Each generated
function is then an attribute taking only its state arrays (and ``t=``, ``inputs=`` when
it reads them): ``bound.rhs(y)`` equals ``module.rhs(y, params)``, and for one plain state
(a float64 vector or a list of floats of the right length) of a function of the state and
the parameters only it goes straight to the compiled function (the CPython extension;
ctypes or the NumPy module's one-state variant where there is none).  Anything else takes
the module's general path with the bound parameters, which converts, broadcasts or
explains exactly as :meth:`SceneModule.call` does.

>>> import symmech as sm, numpy as np
>>> from symmech.examples import carnot_3_7
>>> mod = sm.codegen.generate(carnot_3_7(), target="numpy").load()
>>> bound = mod.bind({"R": 1, "alpha": 0.5, "k": 1, "m": 2})
>>> bound.impact_rough_wall([0.0, 1.0, 0.0], [1.0, -2.0, 0.0])
array([0.5, 1. , 0.5])
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from symmech.codegen.callers import PLAIN_TIMES

__all__ = ["BoundModule"]


class BoundModule:
    """The functions of a loaded module with one parameter vector bound (module docstring).

    ``params`` is the checked float64 copy (None for a scene without parameters); each
    name of ``module.functions`` is an attribute; :meth:`call` calls one by name.
    """

    def __init__(self, module: Any, params: object):
        self.module = module
        p = module._params(params)
        if p is not None:
            p = np.array(p, dtype=np.float64, order="C")
            p.setflags(write=False)
        self.params: np.ndarray | None = p
        #: name -> the bound function, made on first use (a run reads a few of them)
        self._bound: dict[str, Callable[..., np.ndarray]] = {}

    def call(
        self,
        name: str,
        *state: object,
        t: object = None,
        inputs: object = None,
        out: np.ndarray | None = None,
    ):
        """The generated function ``name`` at the bound parameters (``out``: as
        :meth:`SceneModule.call <symmech.codegen.module.SceneModule.call>`)."""
        fn = self._function(name)
        if fn is None:
            return self.module.call(name, *state, params=self.params, t=t, inputs=inputs, out=out)
        return fn(*state, t=t, inputs=inputs, out=out)

    def _function(self, name: str) -> Callable[..., np.ndarray] | None:
        """The bound function ``name`` (None: not generated)."""
        fn = self._bound.get(name)
        if fn is None and name in self.module.functions:
            fn = self._bound[name] = _bind(self.module, name, self.params)
        return fn

    def plain(self, name: str) -> Callable[..., list | None] | None:
        """``name`` at the bound parameters over plain lists of floats, one state (its
        state arrays as lists), returning its output as a flat list, or None where the
        evaluation fails or is not finite (then call the attribute, which explains); None
        when the module has no such variant (a C module, a function of t or the inputs).
        A loop that converts a state once and calls several functions on it skips the
        per-call conversions of the attribute."""
        fast = self.module._fast.get(name)
        make = getattr(fast, "plain", None)
        return None if make is None else make(self.params)

    def __getattr__(self, name: str):
        # only reached for a name that is not an attribute: a generated function (bound
        # now, then an attribute), or say what there is
        module = self.__dict__.get("module")
        if module is None or name.startswith("_"):
            raise AttributeError(name)
        fn = self._function(name)
        if fn is not None:
            setattr(self, name, fn)
            return fn
        raise AttributeError(
            f"{name} was not generated for scene {module.code.scene_name!r}"
            f" (functions: {list(module.functions)})"
        )

    def __dir__(self) -> list[str]:
        return sorted({*super().__dir__(), *self.module.functions})

    def __repr__(self) -> str:
        return f"BoundModule({self.module!r}, params={self.params!r})"


def _bind(module: Any, name: str, p: np.ndarray | None) -> Callable[..., np.ndarray]:
    """``name`` of ``module`` at the parameters ``p`` (already checked)."""
    fast = module._fast.get(name)
    general = module.call

    if fast is None:

        def bound(
            *state: object, t: object = None, inputs: object = None, out: object = None
        ) -> np.ndarray:
            return general(name, *state, params=p, t=t, inputs=inputs, out=out)

    else:
        # the NumPy backend's one-state caller takes the checked parameters once, as
        # plain floats (the extension reads the array in place and checks it in C)
        binder = getattr(fast, "bind", None)
        one = binder(p) if binder is not None else lambda state: fast(state, p)

        def bound(
            *state: object, t: object = None, inputs: object = None, out: object = None
        ) -> np.ndarray:
            if out is None and inputs is None and (t is None or type(t) in PLAIN_TIMES):
                value = one(state)
                if value is not None:
                    return value
            return general(name, *state, params=p, t=t, inputs=inputs, out=out)

    bound.__name__ = bound.__qualname__ = name
    bound.__doc__ = f"{name} of scene {module.code.scene_name!r} at the bound parameters."
    return bound
