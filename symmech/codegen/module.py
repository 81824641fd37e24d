"""A loaded generated module: the same Python API over the C library and the NumPy module.

:class:`SceneModule` wraps the raw generated functions (calls into the compiled library,
or the functions of the imported NumPy module) and gives both backends one API.  A C
function of the state and the parameters called for one state goes through a CPython
extension compiled with the library into one shared object (template
``c/python_module.c.jinja``: about half a microsecond of overhead), batches and
everything else through ctypes (the same shared object); a mapping of
parameters whose keys are exactly their names, and a time given to a function that does
not read it, take that route too.  :meth:`SceneModule.bind` binds the parameters once
(:mod:`symmech.codegen.bound`) for callers that evaluate at the same parameters many times:

>>> import symmech as sm, numpy as np
>>> from symmech.examples import carnot_3_7
>>> mod = sm.codegen.generate(carnot_3_7(), target="numpy").load()
>>> mod.parameters
('R', 'alpha', 'k', 'm')
>>> mod.impact([0.0, 1.0, 0.0], [1.0, -2.0, 0.0], {"R": 1, "alpha": 0.5, "k": 1, "m": 2})
array([0.5, 1. , 0.5])

A state argument is an array of shape ``(n,)`` (one state) or ``(N, n)`` (a batch of N
states; NumPy also accepts any leading shape); ``params`` is a sequence in the order of
:attr:`SceneModule.parameters` or a mapping from their names; ``t`` and ``inputs`` (the
values of the scene's arbitrary functions of time, :attr:`SceneModule.inputs`) are needed
only by the functions that use them (``params`` too: a function that reads no parameter
accepts ``params=None``).  The raw generated functions take only the arguments they read;
this wrapper gives every function the same signature.  A wall is given by its index or
its name (``wall="left wall"``; the generated names use the sanitised ``left_wall``).  A
failure at some state (a matrix that must be positive definite is not, or an output is
not finite) raises :class:`NumericalError`.

Every function but ``projectors`` takes ``out=``: a preallocated, C-contiguous, writeable
float64 array of exactly the output's shape, which the output is written into and which
is returned (the C batch writes straight into it; see :meth:`SceneModule.call`).

Every argument is converted to float64 (any byte order, layout or real number type) or
refused with a :class:`~symmech.codegen.plan.CodegenError` naming it (complex, boolean,
string, masked, ragged, shapes that do not broadcast); a batch of N = 0 states gives an
empty result.  The parameters are checked once per call against the ranges their
declaration gives (:mod:`symmech.codegen.runtime_checks`: a sign, a restitution in
[0, 1]): a value outside raises :class:`NumericalError` naming the parameter, a
non-finite one a ``CodegenError``:

>>> try:
...     mod.impact([0.0, 1.0, 0.0], [1.0, -2.0, 0.0], {"R": 1, "alpha": 5, "k": 1, "m": 2})
... except sm.codegen.NumericalError as exc:
...     print(exc)  # doctest: +NORMALIZE_WHITESPACE
params: parameter 'alpha' = 5.0 breaks 0 <= alpha <= 1
(declared nonnegative; the restitution of wall 'rough_wall')
"""

from __future__ import annotations

import ctypes
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import sympy as sp

from symmech.codegen.bound import BoundModule
from symmech.codegen.callers import (
    PLAIN_TIMES,
    Fast,
    NumericalError,
    Raw,
    check_out,
)
from symmech.codegen.extension import extension_source
from symmech.codegen.plan import CodegenError
from symmech.codegen.runtime_checks import (
    ParameterRule,
    check_parameters,
    named_columns,
    real_array,
)

if TYPE_CHECKING:
    from symmech.codegen.generate import GeneratedCode

__all__ = ["NumericalError", "SceneModule", "extension_source"]

#: A state or time argument: anything NumPy converts to float64 (checked on the way in).
ArrayLike = object
#: The parameters: a sequence in the order of :attr:`SceneModule.parameters`, an array
#: (..., k), or a mapping from their names (or Symbols).
Params = Mapping[Any, Any] | Sequence[Any] | np.ndarray | None
#: The run-time inputs: a sequence in the order of :attr:`SceneModule.inputs`, an array
#: (..., k), or a mapping from their names (or their sympy objects).
Inputs = Mapping[Any, Any] | Sequence[Any] | np.ndarray | None


class SceneModule:
    """Generated functions of one scene (see the module docstring)."""

    def __init__(
        self,
        code: GeneratedCode,
        raw: Mapping[str, Raw],
        path: Path,
        fast: Mapping[str, Fast] | None = None,
    ):
        self.code = code
        self.backend = code.target
        self.path = path
        plan = code.plan
        self.n = plan.n
        self.m = plan.m
        self.parameters = tuple(str(p) for p in plan.parameters)
        #: Names of the run-time inputs, in slot order: ``f`` for ``f(t)``, ``f'`` for its
        #: derivative (``f''`` ...); ``inputs=`` takes a sequence in this order or a mapping
        #: from these names (or from the sympy objects, or their ``str``).
        self.inputs = tuple(input_name(a) for _, a in plan.inputs)
        self._input_aliases = {str(a): input_name(a) for _, a in plan.inputs}
        self.walls = plan.walls
        self._raw = dict(raw)
        self._fast = dict(fast or {})
        #: How one-state calls are made (set by :func:`load_generated`).
        self.fast_path = "general path"
        self._spec = {f.name: f for f in code.functions}
        self._by_wall = {(f.kind, f.wall_index): f.name for f in code.functions if f.wall}
        self._rules: tuple[ParameterRule, ...] = code.parameter_rules
        #: the loaded C library, kept alive as long as the module (None for NumPy)
        self._library: object = None

    @property
    def functions(self) -> tuple[str, ...]:
        """Names of the generated functions."""
        return tuple(self._spec)

    def __repr__(self) -> str:
        return (
            f"SceneModule({self.code.scene_name!r}, backend={self.backend!r},"
            f" functions={list(self._spec)})"
        )

    def c_function(self, name: str) -> tuple[int, tuple[str, ...]]:
        """The address of the generated C function ``name`` (its one-state form) and the
        names of the arguments it takes before ``out`` (``("y", "p")``, ...; see
        :mod:`symmech.codegen.c_signatures`), for C code that calls it through a pointer
        (:mod:`symmech.gait.native`).  The module must stay alive while the address is
        used."""
        if self._library is None:
            raise CodegenError(f"{self!r}: only a loaded C module has C functions")
        spec = self._spec.get(name)
        if spec is None:
            raise CodegenError(f"{self!r} has no function {name!r}")
        symbol = getattr(self._library, f"{self.code.stem}_{name}")
        return ctypes.cast(symbol, ctypes.c_void_p).value or 0, tuple(spec.arguments)

    # -- argument handling ----------------------------------------------------------------
    def _params(self, params: object, needed: bool = True) -> np.ndarray | None:
        """The parameter array (k,) or (..., k) as float64, checked once against the
        declaration's rules (:mod:`symmech.codegen.runtime_checks`)."""
        k = len(self.parameters)
        if not needed and params is None:
            return None
        if k == 0:
            given = params is not None and (
                len(params) if isinstance(params, Mapping) else real_array(params, "params").size
            )
            if given:
                raise CodegenError(
                    f"scene {self.code.scene_name!r} has no run-time parameters; got {params!r}"
                )
            return None
        if params is None:
            raise CodegenError(f"params required: {list(self.parameters)}")
        if isinstance(params, Mapping):
            p = named_columns(params, self.parameters, {}, "params")
        else:
            p = real_array(params, "params")
        if p.shape[-1:] != (k,):
            raise CodegenError(
                f"params: expected {k} values {list(self.parameters)}, got shape {p.shape}"
            )
        check_parameters(self._rules, p, NumericalError, "params")
        return np.ascontiguousarray(p)

    def _listed(self, params: dict) -> object:
        """A dict of parameters as the list of its values in the order of
        :attr:`parameters` when its keys are exactly their names (the fast path then checks
        the values), else the dict itself (for the general path to convert or explain)."""
        names = self.parameters
        if len(params) != len(names):
            return params
        try:
            return [params[name] for name in names]
        except KeyError:
            return params

    def bind(self, params: Params = None) -> BoundModule:
        """The generated functions with ``params`` bound: converted and checked once (the
        errors of a call with these parameters), then each function is an attribute taking
        only its state arrays, ``bound.rhs(y)``, that goes straight to the compiled
        function for one plain state (see :class:`~symmech.codegen.bound.BoundModule`)."""
        return BoundModule(self, params)

    def _inputs(self, inputs: object) -> np.ndarray:
        """The inputs u as float64 (..., k): a sequence in :attr:`inputs` order or a mapping
        from their names."""
        if isinstance(inputs, Mapping):
            if not self.inputs:
                if inputs:
                    raise CodegenError(
                        f"scene {self.code.scene_name!r} has no run-time inputs; got {inputs!r}"
                    )
                return np.zeros(0)
            return named_columns(inputs, self.inputs, self._input_aliases, "inputs")
        return self._state(inputs, len(self.inputs), "inputs")

    def _state(self, value: object, size: int, what: str) -> np.ndarray:
        a = real_array(value, what)
        if a.ndim == 0 or a.shape[-1] != size:
            raise CodegenError(f"{what}: expected shape (..., {size}), got {a.shape}")
        return a

    def _call(
        self, name: str, state: Sequence[np.ndarray], params, t, inputs, out=None
    ) -> np.ndarray:
        spec = self._spec.get(name)
        if spec is None:
            reasons = [o for o in self.code.omitted if name.split("_")[0] in o]
            raise CodegenError(
                f"{name} was not generated for scene {self.code.scene_name!r}"
                + (f" ({'; '.join(reasons)})" if reasons else "")
            )
        p = self._params(params, spec.takes_parameters)
        if spec.takes_time and t is None:
            raise CodegenError(f"{name} depends on time: pass t=")
        if spec.takes_inputs and inputs is None:
            raise CodegenError(f"{name} needs the inputs u = {list(self.inputs)}: pass inputs=")
        # t and the inputs are checked when given, even to a function that does not read them
        u = None if inputs is None else self._inputs(inputs)
        tt = None if t is None else real_array(t, "t")
        u = u if spec.takes_inputs else None
        tt = tt if spec.takes_time else None
        leads = {f"argument {arg}": a.shape[:-1] for arg, a in zip(spec.state, state, strict=True)}
        if p is not None:
            leads["params"] = p.shape[:-1]
        if tt is not None:
            leads["t"] = tt.shape
        if u is not None:
            leads["inputs"] = u.shape[:-1]
        try:
            lead = np.broadcast_shapes(*leads.values())
        except ValueError:
            raise CodegenError(f"{name}: the batch shapes do not broadcast: {leads}") from None
        if out is None:
            return self._raw[name](tuple(state), p, tt, u)
        return self._raw[name](
            tuple(state), p, tt, u, check_out(name, out, (*lead, *spec.out_shape))
        )

    # -- the API ----------------------------------------------------------------------------
    def call(
        self,
        name: str,
        *state: object,
        params: Params = None,
        t: ArrayLike | None = None,
        inputs: Inputs = None,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """Call the generated function ``name`` with its state arrays (q, v, or y).

        ``out``: an array the output is written into and returned (a C-contiguous,
        writeable float64 array of exactly the output's shape, batch axes first; else a
        CodegenError saying what was expected).  The C batch writes into it directly (no
        allocation, no first touch of fresh memory); the NumPy module computes the output
        and copies it in.  ``out`` may be an argument's own memory (``mod.impact(Q, V,
        out=V)``): the output is then computed aside and copied.  After a NumericalError
        its contents are unspecified."""
        fast = self._fast.get(name)
        if (
            out is None
            and fast is not None
            and inputs is None
            and (t is None or type(t) in PLAIN_TIMES)
        ):
            # the plain one-state case (a time given to a function of the state and the
            # parameters only is a real number, as the general path would check)
            out = fast(state, self._listed(params) if type(params) is dict else params)
            if out is not None:
                return out
        spec = self._spec.get(name)
        sizes = [2 * self.n if s == "y" else self.n for s in (spec.state if spec else ())]
        labels = spec.state if spec else ()
        arrays = [
            self._state(a, k, f"{name} argument {labels[i] if i < len(labels) else i}")
            for i, (a, k) in enumerate(zip(state, sizes, strict=False))
        ]
        if spec is not None and len(arrays) != len(spec.state):
            raise CodegenError(f"{name} takes {len(spec.state)} state arrays {spec.state}")
        return self._call(name, arrays, params, t, inputs, out)

    def mass_matrix(
        self,
        q: ArrayLike,
        params: Params = None,
        *,
        t: ArrayLike | None = None,
        inputs: Inputs = None,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """g(q) in the velocity basis, shape (..., n, n)."""
        return self.call("mass_matrix", q, params=params, t=t, inputs=inputs, out=out)

    def forcing(
        self,
        q: ArrayLike,
        v: ArrayLike,
        params: Params = None,
        *,
        t: ArrayLike | None = None,
        inputs: Inputs = None,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """f(q, v, t) with g v_dot = f (unconstrained)."""
        return self.call("forcing", q, v, params=params, t=t, inputs=inputs, out=out)

    def acceleration(
        self,
        q: ArrayLike,
        v: ArrayLike,
        params: Params = None,
        *,
        t: ArrayLike | None = None,
        inputs: Inputs = None,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """v_dot (constrained if the scene has constraints)."""
        return self.call("acceleration", q, v, params=params, t=t, inputs=inputs, out=out)

    def rhs(
        self,
        y: ArrayLike,
        params: Params = None,
        *,
        t: ArrayLike | None = None,
        inputs: Inputs = None,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """(q_dot, v_dot) for y = (q, v)."""
        return self.call("rhs", y, params=params, t=t, inputs=inputs, out=out)

    def energy(
        self,
        q: ArrayLike,
        v: ArrayLike,
        params: Params = None,
        *,
        t: ArrayLike | None = None,
        inputs: Inputs = None,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """T + V."""
        return self.call("energy", q, v, params=params, t=t, inputs=inputs, out=out)

    def multipliers(
        self,
        q: ArrayLike,
        v: ArrayLike,
        params: Params = None,
        *,
        t: ArrayLike | None = None,
        inputs: Inputs = None,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """The Lagrange multipliers lambda (constrained scenes)."""
        return self.call("multipliers", q, v, params=params, t=t, inputs=inputs, out=out)

    def dynamics(
        self,
        q: ArrayLike,
        v: ArrayLike,
        params: Params = None,
        *,
        t: ArrayLike | None = None,
        inputs: Inputs = None,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """(v_dot, lambda) from one solve of the constrained system (constrained scenes)."""
        return self.call("dynamics", q, v, params=params, t=t, inputs=inputs, out=out)

    def constraint_residual(
        self,
        q: ArrayLike,
        v: ArrayLike,
        params: Params = None,
        *,
        t: ArrayLike | None = None,
        inputs: Inputs = None,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """mu(q) v (constrained scenes)."""
        return self.call("constraint_residual", q, v, params=params, t=t, inputs=inputs, out=out)

    def projectors(
        self,
        q: ArrayLike,
        params: Params = None,
        *,
        t: ArrayLike | None = None,
        inputs: Inputs = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """(P, Q), generated with ``projectors=True``."""
        P = self.call("projector_P", q, params=params, t=t, inputs=inputs)
        Q = self.call("projector_Q", q, params=params, t=t, inputs=inputs)
        return P, Q

    def _wall(self, wall: int | str) -> int:
        """The index of a wall given by its index or its name."""
        if isinstance(wall, str):
            hits = [i for i, name in enumerate(self.walls) if name == wall]
            if not hits:
                raise CodegenError(f"no wall named {wall!r}; walls are {list(self.walls)}")
            if len(hits) > 1:
                raise CodegenError(f"walls {hits} are all named {wall!r}; pass the index")
            return hits[0]
        if type(wall) is not int:  # the common case first: a plain int
            if isinstance(wall, bool | np.bool_) or not isinstance(wall, int | np.integer):
                raise CodegenError(f"wall must be an index or a name, got {wall!r}")
            wall = int(wall)
        if not -len(self.walls) <= wall < len(self.walls):
            raise CodegenError(f"wall index {wall} out of range: {len(self.walls)} walls")
        return wall % len(self.walls)

    def _wall_function(self, kind: str, wall: int | str) -> str:
        index = self._wall(wall)
        name = self._by_wall.get((kind, index))
        if name is None:
            raise CodegenError(
                f"the {kind} function of wall {self.walls[index]!r} was not generated for"
                f" scene {self.code.scene_name!r} (functions: {list(self._spec)})"
            )
        return name

    def psi(
        self,
        q: ArrayLike,
        params: Params = None,
        wall: int | str = 0,
        *,
        t: ArrayLike | None = None,
        inputs: Inputs = None,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """The gap psi(t, q) of a wall (admissible side psi >= 0)."""
        name = self._wall_function("psi", wall)
        return self.call(name, q, params=params, t=t, inputs=inputs, out=out)

    def dpsi(
        self,
        q: ArrayLike,
        params: Params = None,
        wall: int | str = 0,
        *,
        t: ArrayLike | None = None,
        inputs: Inputs = None,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """d psi / d q of a wall (coordinates)."""
        name = self._wall_function("dpsi", wall)
        return self.call(name, q, params=params, t=t, inputs=inputs, out=out)

    def psi_t(
        self,
        q: ArrayLike,
        params: Params = None,
        wall: int | str = 0,
        *,
        t: ArrayLike | None = None,
        inputs: Inputs = None,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """d psi / d t of a wall (zero for a static wall)."""
        index = self._wall(wall)
        if not self.code.plan.moving_walls[index]:
            q = self._state(q, self.n, "psi_t argument 0")
            if out is None:
                return np.zeros(q.shape[:-1])
            check_out(f"psi_t of wall {self.walls[index]!r}", out, q.shape[:-1])[...] = 0.0
            return out
        name = self._wall_function("psi_t", index)
        return self.call(name, q, params=params, t=t, inputs=inputs, out=out)

    def impact(
        self,
        q: ArrayLike,
        v: ArrayLike,
        params: Params = None,
        wall: int | str = 0,
        *,
        t: ArrayLike | None = None,
        inputs: Inputs = None,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """The post-impact velocity v+ at a wall for the pre-impact velocity v."""
        name = self._wall_function("impact", wall)
        return self.call(name, q, v, params=params, t=t, inputs=inputs, out=out)


def input_name(atom: sp.Basic) -> str:
    """The name of a run-time input: ``f`` for ``f(t)``, ``f'`` for ``Derivative(f(t), t)``,
    ``f''`` for the second derivative."""
    if isinstance(atom, sp.Derivative):
        return input_name(atom.expr) + "'" * int(atom.derivative_count)
    if isinstance(atom, sp.Function | sp.core.function.AppliedUndef):
        return str(atom.func)
    return str(atom)
