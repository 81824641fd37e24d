"""The hybrid loop in generated C (``backend="c"``): emit, compile, load and run it.

The simulator template ``c/simulator.c.jinja`` is the loop of :mod:`.hybrid` in C: same
flow (:class:`~.flow.RKFlow` over :class:`~.flow.AugmentedFlow`, the walls' gaps in the
state), same event search (samples of the dense output, the divided gap, the parabola dip
check, Anderson-Bjorck location), same impact, accumulation, contact and release rules,
same statistics.  The template holds the algorithm; this module prints what depends on
the scene into a small frozen :class:`SimulatorSpec`: the call of every generated function
by its C name with the arguments it takes, the locked contacts' normal force
``lambda_N`` from the statics ``A^T lambda = -f(q, 0)`` (printed by symmech's C printer),
the Butcher tableaux as exact doubles (``repr`` of a float reads back to the same double).

The generated C of the free flight and of every static wall's contact mode
(:class:`~.system.HybridSystem`) is compiled with the simulator into one shared library,
cached by content (:func:`symmech.codegen.build.compile_library`) and, once loaded, on the
system object.  A scene generated for its equations alone (:func:`symmech.codegen.generate`)
gets no simulator code: only this module renders the template.

A run allocates its work arrays once (``new``) and writes its accepted steps, dense-output
segments and events into buffers given by the caller (:mod:`.c_run`); when they run short
the C loop pauses at the top of an iteration and the caller continues it, so a run's
length is bounded by memory only.
"""

from __future__ import annotations

import ctypes
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import sympy as sp

from symmech.codegen.backends import environment, templates_used
from symmech.codegen.build import DEFAULT_FLAGS, compile_library, load_library
from symmech.codegen.printers import SymmechCPrinter
from symmech.declaration.symbols import t as TIME
from symmech.simulate.c_tableaux import c_tableau
from symmech.simulate.functions import Functions
from symmech.simulate.hybrid import COND_LIMIT, RESTART_FLOOR, Options
from symmech.simulate.impulses import MAX_SIMULTANEOUS
from symmech.simulate.protocol import (
    FUNCTIONS,
    INFO,
    INFO_HEAD,
    OPTIONS,
    REASONS,
    RUN_STATES,
    c_enums,
    slot,
)
from symmech.simulate.steppers import ExplicitRK, stepper
from symmech.simulate.system import HybridSystem, Mode, SimulationError

__all__ = [
    "C_METHODS",
    "SIMULATOR_FLAGS",
    "CLibrary",
    "SimulatorSpec",
    "library",
    "parameter_vector",
    "simulator_source",
]

#: Methods of the C loop, in the order of the template's tableaux.
C_METHODS = ("dop853", "tsit5", "rk45", "rk4")

#: info[status] and info[reason] of a run that reached t_end: every other row needs :func:`decode`
FINISHED_CODE, REACHED_END_CODE = slot(RUN_STATES, "finished"), slot(REASONS, "end")
_WALL_KINDS = ("psi", "dpsi", "psi_t", "impact")
_TEMPLATE = "c/simulator.c.jinja"


@dataclass(frozen=True)
class SimulatorSpec:
    """What the simulator template prints for one scene: sizes, flags and the call lines
    (``calls``: rhs, wall, energy, projector, residual, force), all already printed."""

    scene: str
    prefix: str
    headers: tuple[str, ...]
    n: int
    walls: int
    constrained: int
    energy_conserved: int
    moving: tuple[int, ...]
    #: the contact modes compiled in (mode id -> its walls) and which of them lock the body
    modes: tuple[Mode, ...]
    locked: tuple[int, ...]
    simultaneous: tuple[int, ...]
    normal_index: int
    wall_names: tuple[str, ...]
    m: int
    has_frame: int
    calls: dict[str, Any]
    parameter_layout: tuple[tuple[str, ...], ...]

    @property
    def info_size(self) -> int:
        return INFO_HEAD + 2 * self.n


def _call(module: Any, name: str, args: dict[str, str], offset: int) -> str:
    """The C call of generated function ``name`` of ``module`` with the arguments it takes."""
    spec = {f.name: f for f in module.code.functions}[name]
    out = []
    for a in spec.arguments:
        if a == "p":
            out.append(f"P + {offset}")
        elif a == "u":
            raise SimulationError(
                f"{name} of scene {module.code.scene_name!r} reads inputs u: the C loop runs"
                " scenes without arbitrary functions of time (give definitions=)"
            )
        else:
            out.append(args[a])
    out.append(args["out"])
    return f"{module.code.stem}_{name}({', '.join(out)})"


def _locked_force_lines(system: HybridSystem, mode: Mode, offset: int) -> list[str]:
    """``lambda_N`` of the wall at position ``pos`` of a locked contact mode
    (:meth:`~symmech.simulate.system.HybridSystem.locked_force_expression`) printed in C;
    a mode whose statics cannot be solved (indeterminate) returns -1."""
    scene = system.scene
    decl = scene.declaration
    try:
        exprs = system.locked_force_expression(mode)
    except SimulationError:
        return ["{ *out = NAN; return -1; }"]
    temps, bodies = sp.cse(exprs, symbols=sp.numbered_symbols("lf"))
    names: dict[sp.Symbol, str] = {TIME: "t"}
    names.update({s: f"q[{i}]" for i, s in enumerate(decl.coordinates)})
    names.update({s: f"P[{offset + j}]" for j, s in enumerate(scene.parameters)})
    names.update({s: str(s) for s, _ in temps})
    printer = SymmechCPrinter(names)
    lines = ["{"]
    lines += [f"    const double {s} = {printer.doprint(e)};" for s, e in temps]
    lines += ["    switch (pos) {"]
    lines += [f"    case {k}: *out = {printer.doprint(b)}; return 0;" for k, b in enumerate(bodies)]
    lines += ["    default: *out = NAN; return -1;", "    }", "}"]
    return lines


@dataclass
class _ModeCalls:
    """The C calls of the flow modes: free flight (-1) and each compiled contact mode."""

    rhs: list[tuple[int, str]] = field(default_factory=list)
    projector: list[tuple[int, str]] = field(default_factory=list)
    residual: list[tuple[int, int, str]] = field(default_factory=list)
    force: list[tuple[int, list[str]]] = field(default_factory=list)


_QV = {"q": "q", "v": "v", "y": "y", "t": "t"}


def _add_mode(
    calls: _ModeCalls, case: int, mod: Any, offset: int, normal: int | None, rhs: bool = True
) -> None:
    """The rhs (unless ``rhs`` is False), projector, residual (and, with the index of the
    first normal multiplier, the force) calls of module ``mod`` as mode ``case``."""
    if rhs:
        calls.rhs.append((case, _call(mod, "rhs", {**_QV, "out": "out"}, offset)))
    calls.projector.append((case, _call(mod, "projector_P", {**_QV, "out": "out"}, offset)))
    size = {f.name: f.out_size for f in mod.code.functions}["constraint_residual"]
    line = _call(mod, "constraint_residual", {**_QV, "out": "out"}, offset)
    calls.residual.append((case, size, line))
    if normal is not None:
        call = _call(mod, "multipliers", {**_QV, "out": "lam"}, offset)
        body = f"{{ int st = {call}; *out = lam[{normal} + pos]; return st; }}"
        calls.force.append((case, [body]))


def _wall_calls(free: Any, walls: int, moving: tuple[int, ...]) -> list[tuple[int, str]]:
    """The calls of the walls' functions (psi, dpsi, psi_t of moving walls, impact)."""
    by_wall = {(f.kind, f.wall_index): f.name for f in free.code.functions if f.wall}
    out = []
    for w in range(walls):
        for k, kind in enumerate(_WALL_KINDS):
            if kind == "psi_t" and not moving[w]:
                continue
            out.append((k * walls + w, _call(free, by_wall[(kind, w)], {**_QV, "out": "out"}, 0)))
    return out


def simulator_spec(system: HybridSystem) -> SimulatorSpec:
    """The :class:`SimulatorSpec` of ``system`` (the contact modes of
    :attr:`~symmech.simulate.system.HybridSystem.c_modes` are generated here)."""
    scene = system.scene
    free = system.free
    walls = len(scene.walls)
    fns = Functions(system, {str(p): 1.0 for p in scene.parameters})
    moving = tuple(int(m) for m in fns.moving)
    modes = system.c_modes
    contacts = {mode: system.contact(mode) for mode in modes}
    layout: list[tuple[str, ...]] = [free.parameters]
    offsets: dict[Mode, int] = {}
    size = len(free.parameters)
    for mode, mod in contacts.items():
        if mod is not None:
            offsets[mode] = size
            layout.append(mod.parameters)
            size += len(mod.parameters)
    scene_offset = size
    layout.append(tuple(str(p) for p in scene.parameters))
    calls = _ModeCalls()
    calls.rhs.append((-1, _call(free, "rhs", {**_QV, "out": "out"}, 0)))
    mass_matrix = ""
    if fns.constrained:
        mass_matrix = _call(free, "mass_matrix", {**_QV, "out": "out"}, 0)
        _add_mode(calls, -1, free, 0, None, rhs=False)
    m = scene.constraint_matrix.rows
    for case, mode in enumerate(modes):
        mod = contacts[mode]
        if mod is None:
            calls.force.append((case, _locked_force_lines(system, mode, scene_offset)))
        else:
            _add_mode(calls, case, mod, offsets[mode], m)
    headers = [f"{free.code.stem}.h"] + [
        f"{mod.code.stem}.h" for mod in contacts.values() if mod is not None
    ]
    return SimulatorSpec(
        scene=scene.name,
        prefix=f"{free.code.stem}_sim_",
        headers=tuple(headers),
        n=scene.n,
        walls=walls,
        constrained=int(fns.constrained),
        energy_conserved=int(fns.energy_conserved),
        moving=moving,
        modes=modes,
        locked=tuple(int(contacts[mode] is None) for mode in modes),
        simultaneous=tuple(int(x) for x in fns.simultaneous),
        normal_index=m,
        wall_names=fns.wall_names,
        m=m,
        has_frame=int(scene.declaration.frame is not None),
        calls={
            "rhs": calls.rhs,
            "wall": _wall_calls(free, walls, moving),
            "energy": _call(free, "energy", {**_QV, "out": "out"}, 0),
            "mass_matrix": mass_matrix,
            "projector": calls.projector,
            "residual": calls.residual,
            "force": calls.force,
        },
        parameter_layout=tuple(layout),
    )


def _tableaux() -> list[dict[str, Any]]:
    """The methods' coefficients as C literals (``repr``: the same double read back)."""
    out = []
    for kind_name in C_METHODS:
        tab = c_tableau(kind_name)
        st = stepper(kind_name)
        assert isinstance(st, ExplicitRK)  # C_METHODS are explicit
        name = f"m_{kind_name}"
        extra = [(k, [repr(v) for v in tab[k]]) for k in tab if k not in ("c", "a", "b")]
        refs = [
            f"{name}_{k}" if k in tab else "NULL"
            for k in ("e", "e3", "dense", "c_extra", "a_extra", "d")
        ]
        out.append(
            {
                "name": name,
                "stages": st.tableau.stages,
                "error_order": st.error_order,
                "adaptive": int(st.adaptive),
                "kind": 0 if kind_name == "dop853" else 2 if kind_name == "rk4" else 1,
                "c": [repr(v) for v in tab["c"]],
                "a": [repr(v) for v in tab["a"]],
                "b": [repr(v) for v in tab["b"]],
                "extra": extra,
                "refs": refs,
            }
        )
    return out


def simulator_source(system: HybridSystem) -> dict[str, str]:
    """Every source file of the simulator library of ``system``: the generated modules'
    ``.c``/``.h`` files and the rendered simulator (``<stem>_simulator.c``)."""
    if system.target != "c":
        raise SimulationError(
            f"the C simulator needs a system built for target 'c', got {system.target!r}"
        )
    spec = simulator_spec(system)
    from symmech import __version__

    stamp = (
        f"Generated by symmech {__version__} from template"
        f" {', '.join(templates_used(_TEMPLATE))}; do not edit."
    )
    text = (
        environment()
        .get_template(_TEMPLATE)
        .render(
            stamp=stamp,
            scene=spec.scene,
            prefix=spec.prefix,
            headers=spec.headers,
            n=spec.n,
            walls=spec.walls,
            constrained=spec.constrained,
            energy_conserved=spec.energy_conserved,
            moving=spec.moving,
            modes=spec.modes,
            max_mode_size=max((len(mode) for mode in spec.modes), default=0),
            locked=spec.locked,
            normal_index=spec.normal_index,
            m=spec.m,
            has_frame=spec.has_frame,
            cond_limit=repr(COND_LIMIT),
            restart_floor=repr(RESTART_FLOOR),
            max_simultaneous=MAX_SIMULTANEOUS,
            simultaneous=spec.simultaneous,
            enums=c_enums(),
            calls=spec.calls,
            methods=C_METHODS,
            tableaux=_tableaux(),
            info_size=spec.info_size,
        )
    )
    files: dict[str, str] = {}
    for mod in system.modules.values():
        if mod is not None:
            files.update(mod.code.files)
    files[f"{system.free.code.stem}_simulator.c"] = text
    return files


#: Compiler flags of the simulator library: the code generator's, at -O3 (about 9% faster
#: on the ellipse than -O2).  Floating-point results do not change: C99 mode keeps
#: contraction into FMA off and nothing licenses reassociation, so every route that runs
#: the library (one run, batches, sweeps on Dask workers) computes the same bits.
SIMULATOR_FLAGS: tuple[str, ...] = tuple("-O3" if f == "-O2" else f for f in DEFAULT_FLAGS)


class CLibrary:
    """The loaded simulator library of one :class:`HybridSystem` and its ctypes entry points."""

    def __init__(self, system: HybridSystem, flags: tuple[str, ...] = SIMULATOR_FLAGS):
        self.flags = tuple(flags)
        self.spec = simulator_spec(system)
        self.sources = simulator_source(system)
        self.path = compile_library(self.sources, flags=flags)
        lib = load_library(self.path)
        p, vp = self.spec.prefix, ctypes.c_void_p
        self.new = getattr(lib, p + "new")
        self.new.argtypes = [ctypes.c_int, vp, vp, ctypes.c_int]
        self.new.restype = vp
        self.free = getattr(lib, p + "free")
        self.free.argtypes = [vp]
        self.free.restype = None
        self.begin = getattr(lib, p + "begin")
        self.begin.argtypes = [vp, ctypes.c_double, vp]
        self.begin.restype = None
        self.run = getattr(lib, p + "run")
        self.run.argtypes = [vp, vp, ctypes.c_long, vp, ctypes.c_long, vp, vp, ctypes.c_long, vp]
        self.run.restype = ctypes.c_int
        self.info = getattr(lib, p + "info")
        self.info.argtypes = [vp, vp]
        self.info.restype = None
        self.batch = getattr(lib, p + "batch")
        self.batch.argtypes = [ctypes.c_long, vp, ctypes.c_double, ctypes.c_int, vp, vp, vp]
        self.batch.restype = ctypes.c_int
        self._lib = lib

    def parameters(self, values: dict[str, float]) -> np.ndarray:
        """The flat parameter vector of the library (see :func:`parameter_vector`)."""
        return parameter_vector(self.spec.parameter_layout, values)


def parameter_vector(layout: Sequence[Sequence[str]], values: Mapping[str, float]) -> np.ndarray:
    """The flat parameter vector of a simulator library whose ``parameter_layout`` is
    ``layout``: each module's parameters in its order, then the scene's, then a pad."""
    flat = [values[k] for names in layout for k in names]
    return np.ascontiguousarray([*flat, 0.0], dtype=np.float64)


def library(system: HybridSystem) -> CLibrary:
    """The compiled simulator of ``system`` with its current contact modes
    (:attr:`~symmech.simulate.system.HybridSystem.c_modes`), built once per set of modes
    and kept on the system object."""
    lib = system.__dict__.get("_c_simulator")
    if lib is None or lib.spec.modes != system.c_modes:
        lib = CLibrary(system)
        system.__dict__["_c_simulator"] = lib
    return lib


def missing_mode(info: np.ndarray, modes: tuple[Mode, ...]) -> Mode | None:
    """The contact mode a run stopped for (reason ``mode_missing``: the loop needed the
    mode ``sub`` with wall ``wall`` added, ``why`` 1, or removed), else None."""
    if int(info[INFO.index("reason")]) != REASONS.index("mode_missing"):
        return None
    wall, add, sub = (int(info[INFO.index(k)]) for k in ("wall", "why", "sub"))
    base = set(modes[sub]) if sub >= 0 else set()
    return tuple(sorted(base | {wall} if add else base - {wall}))


def options_vector(
    opts: Options, method: str, max_step: float, t0: float
) -> tuple[int, np.ndarray]:
    """The method's index and the C loop's option vector (entries
    :data:`~symmech.simulate.protocol.OPTIONS`, read by the template's ``new``).

    ``rk4`` steps with ``max_step`` when it is shorter than the span, else span/1000 (as
    :func:`symmech.simulate.simulate` chooses for the NumPy loop)."""
    if method not in C_METHODS:
        raise SimulationError(
            f"method {method!r} is not available with backend='c': choose one of {C_METHODS}"
            " (rodas4 runs with backend='numpy'; SciPy's implicit methods with backend='scipy')"
        )
    span = opts.t_end - t0
    fixed = 0.0
    if method == "rk4":
        fixed = max_step if max_step < span else span / 1000
    entries = {
        "rtol": opts.rtol,
        "atol": opts.atol,
        "max_step": max_step,
        "fixed_step": fixed,
        "t_end": opts.t_end,
        "zeno_factor": opts.zeno_factor,
        "max_events": float(opts.max_events),
        "contact_stop": float(opts.contact == "stop"),
        "samples": float(opts.samples),
        "max_steps": float(opts.max_steps),
        "sequential": float(opts.impact_law == "sequential"),
    }
    vec = np.array([entries[k] for k in OPTIONS], dtype=np.float64)
    return C_METHODS.index(method), vec


def info_entry(info: np.ndarray, name: str) -> np.ndarray:
    """Entry ``name`` of :data:`~symmech.simulate.protocol.INFO` of an info row (or of
    every row of a 2-D block)."""
    return info[..., INFO.index(name)]


#: The entries of the event counts in an info row, in the order of the event kinds.
EVENT_COUNTS = slice(INFO.index("impacts"), INFO.index("releases") + 1)


def decode(info: np.ndarray, names: tuple[str, ...], t_end: float) -> tuple[str, str, float | None]:
    """(status, message, accumulation time) of a run's info row, in the words of :mod:`.hybrid`."""
    code = int(info[INFO.index("status")])
    status = RUN_STATES[code] if 0 < code < len(RUN_STATES) else "failed"
    reason_code, wall, why, sub, fn = (
        int(info[INFO.index(k)]) for k in ("reason", "wall", "why", "sub", "function")
    )
    reason = REASONS[reason_code] if 0 <= reason_code < len(REASONS) else "unknown"
    d = [float(info[INFO.index(f"d{i}")]) for i in range(4)]
    walls = len(names)
    if reason == "end":
        return status, f"reached t_end = {t_end!r}", None
    if reason == "max_events":
        return status, f"stopped after {int(d[1])} events at t = {d[0]!r}", None
    if reason == "max_steps":
        return status, f"stopped after {int(d[1])} steps at t = {d[0]!r}", None
    if reason == "sequential":
        return (
            status,
            f"simultaneous impacts at t = {d[0]!r} did not resolve in"
            f" {100 * walls} applications of the sequential rule",
            None,
        )
    if reason == "accumulation":
        why_text = (
            "contact=stop"
            if why == 0
            else "the wall moves (no contact mode for a moving wall)"
            if why == 1
            else f"already in contact with {names[sub]!r}"
        )
        return (
            status,
            f"impacts on wall {names[wall]!r} accumulate at t* = {d[0]!r}"
            f" (last impact at t = {d[1]!r}, rebound speed {d[2]:.3g}); stopped: {why_text}",
            d[0],
        )
    if reason == "rest":
        reason_text = (
            "grazing contact with the wall pressing",
            f"accumulation of impacts (t* ~ {d[1]!r})",
            "initial state at rest on the wall",
        )[sub]
        why_rest = (
            "contact=stop",
            "the wall moves",
            "contact with two walls at once is not supported",
        )
        return (
            status,
            f"the body comes to rest on wall {names[wall]!r} at t = {d[0]!r}"
            f" ({reason_text}); stopped: {why_rest[why]}",
            d[0],
        )
    if reason == "rhs_nonfinite":
        return status, f"the right-hand side is not finite at t = {d[0]!r}", None
    if reason == "step_small":
        return status, f"step size {d[0]:.3g} too small at t = {d[1]!r}", None
    if reason == "fixed_nonfinite":
        return status, f"non-finite state after a fixed step at t = {d[0]!r}", None
    if reason == "condition":
        return (
            status,
            f"wall {names[wall]!r} is nearly dependent on the constraints at"
            f" t = {d[0]!r}: the impact's Gram matrix has condition number"
            f" {d[1]:.3g} > {COND_LIMIT:.3g} (relative error bound 1e-2)",
            None,
        )
    if reason == "mode_missing":
        return status, "the C loop stopped for a contact mode it was built without", None
    if reason == "call_failed":
        name = FUNCTIONS[fn][1] if 0 <= fn < len(FUNCTIONS) else "a generated function"
        return status, f"the generated function {name} failed at t = {d[0]!r}", None
    return "failed", f"the C loop ended without a status (reason {reason_code})", None
