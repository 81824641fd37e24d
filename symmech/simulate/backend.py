"""The simulator's backends: one interface, three implementations of the hybrid loop.

A :class:`Backend` says what it is (``name``), which generated code it runs on
(``target``: the system is built for ``"c"`` or ``"numpy"``), which integration methods it
has (``methods``; ``implicit`` ones need the generated Jacobian), what else it can do
(``capabilities``), and runs one trajectory (:meth:`Backend.run`) from a checked state and
:class:`~symmech.simulate.options.RunOptions`.  ``simulate`` picks one by name from
:data:`BACKENDS`; ``simulate_batch`` and ``sweep`` need the ``"batch"`` capability.

* ``"c"`` (:class:`CBackend`): the whole loop in generated C (:mod:`.csim`, :mod:`.c_run`).
* ``"numpy"`` (:class:`NumpyBackend`): the loop of :mod:`.hybrid` in Python over the
  generated NumPy module and symmech's steppers (:mod:`.steppers`): the reference of the
  C loop, and the home of the linearly implicit ``rodas4``.
* ``"scipy"`` (:class:`ScipyBackend`): the same Python loop around SciPy's ``OdeSolver``
  classes over the generated C right-hand side.

The capabilities: ``"batch"`` (many runs in one call of compiled code: ``simulate_batch``
and ``sweep``), ``"implicit"`` (methods that use the generated Jacobian).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np

from symmech.simulate.csim import C_METHODS
from symmech.simulate.flow import AugmentedFlow, RKFlow
from symmech.simulate.functions import Functions
from symmech.simulate.hybrid import run
from symmech.simulate.options import RunOptions
from symmech.simulate.result import SimulationResult
from symmech.simulate.scipy_flow import ScipyFlow
from symmech.simulate.steppers import METHODS as STEPPER_METHODS
from symmech.simulate.system import HybridSystem, SimulationError

__all__ = ["BACKENDS", "Backend", "CBackend", "NumpyBackend", "ScipyBackend", "backend_named"]


@dataclass(frozen=True)
class Backend(ABC):
    """A simulator backend (see the module docstring)."""

    name: str
    target: str
    methods: tuple[str, ...]
    implicit: tuple[str, ...] = ()
    capabilities: frozenset[str] = frozenset()
    #: method names are matched without regard to case (SciPy's ``"DOP853"``, ``"dop853"``)
    case_insensitive: bool = False

    def method(self, name: str) -> str:
        """``name`` as this backend spells it, or a SimulationError with the choices."""
        if self.case_insensitive and isinstance(name, str):
            spelled = {m.lower(): m for m in self.methods}.get(name.lower())
            if spelled is not None:
                return spelled
        elif name in self.methods:
            return name
        if self.name == "c" and isinstance(name, str) and name.lower() in _IMPLICIT_ELSEWHERE:
            raise SimulationError(
                f"method {name!r} is not available with backend='c': it is implicit and runs"
                " on backend 'numpy' (rodas4) or 'scipy' (Radau, BDF, LSODA) with the"
                f" generated Jacobian; the C loop's methods are {self.methods}"
            )
        raise SimulationError(
            f"method {name!r} is not available with backend={self.name!r}: choose one of"
            f" {self.methods}"
        )

    def is_implicit(self, method: str) -> bool:
        """Whether ``method`` (as :meth:`method` spells it) uses the Jacobian."""
        return method in self.implicit

    @abstractmethod
    def run(
        self,
        system: HybridSystem,
        fns: Functions,
        values: dict[str, float],
        y0: np.ndarray,
        t_end: float,
        opts: RunOptions,
    ) -> SimulationResult:
        """One run from ``y0`` at ``opts.t0`` to ``t_end``, inputs already checked."""


#: implicit methods of the Python-loop backends, named in the C backend's refusal
_IMPLICIT_ELSEWHERE = ("rodas4", "radau", "bdf", "lsoda")


class CBackend(Backend):
    """The whole loop in generated C."""

    def run(
        self,
        system: HybridSystem,
        fns: Functions,
        values: dict[str, float],
        y0: np.ndarray,
        t_end: float,
        opts: RunOptions,
    ) -> SimulationResult:
        from symmech.simulate.c_run import run_c

        return run_c(
            system,
            values,
            y0,
            opts.t0,
            opts.loop(t_end),
            method=opts.method,
            max_step=opts.step_cap(t_end),
        )


class _PythonLoop(Backend):
    """The loop of :mod:`.hybrid` in Python over a flow this backend makes."""

    @abstractmethod
    def flow_factory(self, opts: RunOptions, t_end: float) -> Callable[..., Any]:
        """``make(f, jac=None)``: the flow integrating ``y' = f(t, y)``."""

    def run(
        self,
        system: HybridSystem,
        fns: Functions,
        values: dict[str, float],
        y0: np.ndarray,
        t_end: float,
        opts: RunOptions,
    ) -> SimulationResult:
        make = self.flow_factory(opts, t_end)
        jac = fns.flow_jac if self.is_implicit(opts.method) else None
        n = fns.n
        flow = (
            AugmentedFlow(
                make,
                fns.flow_rhs,
                fns.flow_rates,
                fns.gaps,
                2 * n,
                jac,
                bind=lambda: fns.augmented_in(fns.mode),
            )
            if fns.walls
            else make(fns.flow_rhs, jac)
        )
        return run(fns, flow, opts.t0, y0, opts.loop(t_end))


class NumpyBackend(_PythonLoop):
    """The Python loop over the generated NumPy module and symmech's steppers."""

    def flow_factory(self, opts: RunOptions, t_end: float) -> Callable[..., Any]:
        cap = opts.step_cap(t_end)
        fixed = None
        if opts.method == "rk4":  # the C loop's rule (csim.options_vector)
            span = t_end - opts.t0
            fixed = cap if cap < span else span / 1000

        def make(f: Any, jac: Any = None) -> Any:
            return RKFlow(f, opts.method, opts.rtol, opts.atol, cap, jac=jac, fixed_step=fixed)

        return make


class ScipyBackend(_PythonLoop):
    """The Python loop around SciPy's ``OdeSolver`` classes over the generated C rhs."""

    def flow_factory(self, opts: RunOptions, t_end: float) -> Callable[..., Any]:
        cap = opts.step_cap(t_end)

        def make(f: Any, jac: Any = None) -> Any:
            return ScipyFlow(f, opts.method, opts.rtol, opts.atol, cap, jac=jac)

        return make


#: The backends by name.
BACKENDS: Mapping[str, Backend] = MappingProxyType(
    {
        "c": CBackend("c", "c", C_METHODS, capabilities=frozenset({"batch"})),
        "numpy": NumpyBackend(
            "numpy",
            "numpy",
            STEPPER_METHODS,
            implicit=("rodas4",),
            capabilities=frozenset({"implicit"}),
        ),
        "scipy": ScipyBackend(
            "scipy",
            "c",
            ScipyFlow.METHODS,
            implicit=("Radau", "BDF", "LSODA"),
            capabilities=frozenset({"implicit"}),
            case_insensitive=True,
        ),
    }
)


def backend_named(name: object, capability: str | None = None) -> Backend:
    """The backend called ``name`` (one with ``capability``, when given), or a
    SimulationError naming the choices."""
    found = BACKENDS.get(name) if isinstance(name, str) else None
    if found is None:
        raise SimulationError(f"backend must be one of {tuple(BACKENDS)}, got {name!r}")
    if capability is not None and capability not in found.capabilities:
        able = tuple(b.name for b in BACKENDS.values() if capability in b.capabilities)
        raise SimulationError(f"backend {found.name!r} has no {capability!r}: use one of {able}")
    return found
