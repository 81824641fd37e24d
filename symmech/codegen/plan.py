"""What to generate for a scene: the symbolic plan of every function, backend-neutral.

:func:`build_plan` turns a :class:`~symmech.Scene` into a :class:`ScenePlan`: the list of
:class:`FunctionPlan` s the scene needs and, in ``omitted``, what was left out and why.  A
function plan holds sympy expressions only (named *blocks* of entries, each a vector or
a row-major matrix) and at most one linear-algebra *step* from a fixed menu
(:data:`STEPS`), which every backend implements once in its template.  Lowering to a
language (CSE, printing) is :mod:`symmech.codegen.lower`.

Functions (velocity basis v: the coordinate velocities, or the quasi-velocities of a
frame ``q_dot = S(q) v``; all equations cite :class:`~symmech.Scene`):

``mass_matrix``       g(q), n x n (slides 000; T = 1/2 v^T g v)
``forcing``           f(q, v, t) with ``g v_dot = f`` unconstrained: ``-Gamma_kij v^i v^j - dV``
``acceleration``      v_dot: closed form, or ``g v_dot = f (+ mu^T lambda)`` solved in the code
``rhs``               the first-order system y = (q, v): ``(S v, v_dot)``
``energy``            T + V
``multipliers``       lambda of Carnot paper section 2.2 (constrained scenes)
``constraint_residual``  mu(q) v (constrained scenes)
``psi_<w>``, ``dpsi_<w>``, ``psit_<w>``  the guard psi(t, q), d psi/d q, d psi/d t
``impact_<w>``        v+ (Carnot paper eq. 10, Prop. 3.4, eq. 17, Prop. 4.2; text 001)
``projector_P``, ``projector_Q``  Carnot paper section 2.2 (only when asked)

Function names cannot collide.  ``<w>`` is the wall's name sanitised by
:func:`~symmech.codegen.printers.identifier` (``left wall -> left_wall``), made unique
among the walls, never ending in ``_batch`` (the C batch functions are ``<name>_batch``);
the wall prefixes ``psi_``, ``dpsi_``, ``psit_``, ``impact_`` are prefix-free (none
starts another) and no scene-level name starts with one, so a name determines its
kind and wall.  (``psi_t_<w>`` would not: the ``psi_t`` of wall ``floor`` and the ``psi``
of wall ``t_floor`` would both be ``psi_t_floor``.)  :func:`check_unique_names` verifies
this for every plan and raises :class:`CodegenError` naming the colliding functions.

Functions of time left arbitrary in a scene (``f(t)`` in ``psi = x - f(t)``, Carnot paper
example 4.4) and their derivatives become run-time *inputs* ``u`` (see
:attr:`ScenePlan.inputs`), unless ``definitions`` gives them an expression.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import sympy as sp

from symmech.algebra import budget as limits
from symmech.algebra.budget import BudgetExceeded
from symmech.algebra.opcount import count_ops
from symmech.algebra.stability import stable_entry
from symmech.algebra.walk import free_symbols
from symmech.codegen.blocks import (
    BATCH_SUFFIX,
    Block,
    CodegenError,
    wall_function_name,
    wall_ids,
)
from symmech.codegen.closed_form_budget import closed_form_cost
from symmech.codegen.definitions import InputSlots, definition_rules
from symmech.codegen.kinds import SCENE_BUILDERS, WALL_BUILDERS, BuildContext
from symmech.declaration.admissible import expression_problems
from symmech.declaration.symbols import t as TIME

if TYPE_CHECKING:
    from symmech.scene import Scene

__all__ = [
    "FUNCTIONS",
    "STEPS",
    "STRATEGIES",
    "Block",
    "CodegenError",
    "FunctionPlan",
    "ScenePlan",
    "build_plan",
    "check_unique_names",
    "wall_function_name",
    "wall_ids",
]

STRATEGIES = ("auto", "closed_form", "linear_solve")

#: Linear-algebra steps a backend implements (see the module docstring of
#: :mod:`symmech.codegen.lower` for their exact equations).
STEPS = (
    "spd_solve",
    "constrained_acceleration",
    "constrained_multipliers",
    "constrained_dynamics",
    "impact_kkt",
)

#: Function kinds a user may ask for (``functions=``); wall functions are per wall.
FUNCTIONS = (
    "mass_matrix",
    "forcing",
    "acceleration",
    "rhs",
    "augmented_rhs",
    "energy",
    "multipliers",
    "dynamics",
    "constraint_residual",
    "psi",
    "dpsi",
    "psi_t",
    "impact",
    "projectors",
    "jacobian",
)


@dataclass(frozen=True)
class FunctionPlan:
    """One generated function.

    ``state`` is the tuple of state arguments it takes, among ``"q"``, ``"v"`` and
    ``"y"`` (``y = (q, v)`` for ``rhs``); ``step_args`` are the sizes of the step and, last,
    1 when the metric is structurally diagonal (0 otherwise); ``uses_time`` / ``uses_inputs`` /
    ``uses_parameters`` say whether ``t``, the inputs ``u`` and the run-time parameters
    ``p`` appear.  The function evaluates ``blocks`` and then either returns the block
    named ``"out"`` (``step is None``) or runs ``step`` on the blocks (``step_args`` are
    the integer sizes it needs), writing ``out_shape`` entries.  ``calls`` names another
    function whose result fills ``out[n : n + its size]`` (``rhs`` and ``augmented_rhs``
    call ``acceleration``);
    ``part_of`` = (name, offset): the function has no blocks, its ``out`` is entries
    ``offset ...`` of another's (``acceleration`` and ``multipliers`` of ``dynamics``).
    ``wall`` and ``wall_index`` name the wall of a per-wall function (psi, dpsi, psi_t,
    impact).
    """

    name: str
    kind: str
    doc: str
    equation: str
    state: tuple[str, ...]
    blocks: tuple[Block, ...]
    out_shape: tuple[int, ...]
    step: str | None = None
    step_args: tuple[int, ...] = ()
    calls: str | None = None
    part_of: tuple[str, int] | None = None
    wall: str | None = None
    wall_index: int | None = None
    uses_time: bool = False
    uses_inputs: bool = False
    uses_parameters: bool = False

    @property
    def callee(self) -> str | None:
        """The function this one calls (``calls``) or is part of (``part_of``): it is
        lowered first, and what it reads (t, inputs, parameters) this one reads too."""
        return self.calls or (self.part_of[0] if self.part_of else None)

    @property
    def out_size(self) -> int:
        size = 1
        for s in self.out_shape:
            size *= s
        return size


@dataclass(frozen=True)
class ScenePlan:
    """Everything a backend needs to emit code for one scene."""

    scene_name: str
    n: int
    m: int
    coordinates: tuple[sp.Symbol, ...]
    velocities: tuple[sp.Symbol, ...]
    parameters: tuple[sp.Symbol, ...]  # run-time parameters p, in order
    constants: tuple[tuple[sp.Symbol, sp.Expr], ...]  # parameters baked in
    inputs: tuple[tuple[sp.Symbol, sp.Expr], ...]  # (dummy, f(t) or f'(t)) in slot order
    walls: tuple[str, ...]  # the walls' names, by index
    wall_ids: tuple[str, ...]  # their sanitised identifiers, by index
    moving_walls: tuple[bool, ...]  # whether psi depends on t, by index
    strategy: str
    functions: tuple[FunctionPlan, ...]
    omitted: tuple[str, ...] = field(default=())
    #: why strategy ``auto`` fell back to ``linear_solve`` (a budget), else None
    fallback: str | None = None

    def function(self, name: str) -> FunctionPlan:
        for f in self.functions:
            if f.name == name:
                return f
        raise KeyError(name)


# ---------------------------------------------------------------------------------------


def check_unique_names(functions: Sequence[FunctionPlan]) -> None:
    """Raise :class:`CodegenError` unless every generated name is unique.

    The names checked are the functions' names and their C batch names
    (``<name>_batch``): all are symbols of one C file and one Python module."""
    seen: dict[str, str] = {}
    clashes: list[str] = []
    for f in functions:
        origin = f"{f.kind} of wall {f.wall!r} (index {f.wall_index})" if f.wall else f.kind
        for name, what in ((f.name, origin), (f.name + BATCH_SUFFIX, f"batch form of {origin}")):
            if name in seen:
                clashes.append(f"{name!r} names both the {seen[name]} and the {what}")
            else:
                seen[name] = what
    if clashes:
        raise CodegenError("generated function names collide: " + "; ".join(clashes))


def _check_constants(scene: Scene, constants: Mapping) -> dict[sp.Symbol, sp.Expr]:
    out: dict[sp.Symbol, sp.Expr] = {}
    by_name = {p.name: p for p in scene.parameters}
    for key, value in constants.items():
        sym = by_name.get(key) if isinstance(key, str) else key
        if sym is None or sym not in scene.parameters:
            raise CodegenError(
                f"constants: {key!r} is not a parameter of scene {scene.name!r}"
                f" (parameters: {[p.name for p in scene.parameters]})"
            )
        if isinstance(value, bool):
            raise CodegenError(f"constants: {sym} = {value!r} is not a real number")
        try:
            val = sp.sympify(value, strict=True)
        except (sp.SympifyError, TypeError):
            raise CodegenError(f"constants: {sym} = {value!r} is not a real number") from None
        if not val.is_number or not val.is_real or not val.is_finite:
            raise CodegenError(f"constants: {sym} = {value!r} is not a finite real number")
        if sym.is_positive and not val.is_positive:
            raise CodegenError(f"constants: {sym} is declared positive, got {val}")
        if sym.is_nonnegative and val.is_negative:
            raise CodegenError(f"constants: {sym} is declared non-negative, got {val}")
        out[sym] = val
    return out


#: Prefixes an extra function's name may not start with (the per-wall kinds).
_WALL_PREFIXES = ("psi_", "dpsi_", "psit_", "impact_")


def extra_functions(extra: Mapping[str, tuple[str, Any]]) -> tuple[tuple[str, str, sp.Matrix], ...]:
    """``extra`` of :func:`build_plan` checked: ``(name, doc, matrix)`` per function.

    A name is a lower-case identifier (``[a-z][a-z0-9_]*``), not a kind of
    :data:`FUNCTIONS` and not starting with a wall prefix (names stay prefix-free, see the
    module docstring); the expression a non-empty vector or matrix of sympy expressions
    whose entries the scene's fields could hold (:mod:`symmech.declaration.admissible`).
    The symbols are checked against the scene's state and parameters when the function is
    added."""
    if not isinstance(extra, Mapping):
        raise CodegenError(f"extra: expected a mapping {{name: (doc, expression)}}, got {extra!r}")
    out = []
    for name, item in extra.items():
        if not isinstance(name, str) or not re.fullmatch(r"[a-z][a-z0-9_]{0,62}", name):
            raise CodegenError(f"extra: the name {name!r} is not a lower-case identifier")
        if name in FUNCTIONS or name.startswith(_WALL_PREFIXES) or name.endswith(BATCH_SUFFIX):
            raise CodegenError(f"extra: the name {name!r} is taken by a generated kind")
        if not (isinstance(item, tuple) and len(item) == 2 and isinstance(item[0], str)):
            raise CodegenError(f"extra[{name!r}]: expected (doc, expression), got {item!r}")
        doc, value = item
        try:
            expr = sp.Matrix(value)
        except (TypeError, ValueError, sp.SympifyError):
            raise CodegenError(f"extra[{name!r}]: not a vector or matrix of expressions") from None
        if expr.rows == 0 or expr.cols == 0:
            raise CodegenError(f"extra[{name!r}]: empty")
        problems = sorted({p for e in expr for p in expression_problems(e)})
        if problems:
            raise CodegenError(f"extra[{name!r}]: {'; '.join(problems)}")
        out.append((name, doc, expr))
    return tuple(out)


def build_plan(
    scene: Scene,
    *,
    strategy: str = "auto",
    functions: Sequence[str] | None = None,
    constants: Mapping | None = None,
    definitions: Mapping | None = None,
    projectors: bool = False,
    jacobian: bool = False,
    extra: Mapping[str, tuple[str, Any]] | None = None,
) -> ScenePlan:
    """The :class:`ScenePlan` of ``scene`` (see the module docstring).

    ``strategy``: ``"closed_form"`` evaluates the symbolic acceleration, multipliers and
    impact maps; ``"linear_solve"`` emits g, f, the constraint and wall one-forms and
    solves the linear systems in the generated code, and derives nothing else (no
    closed form; only the energy law of text 001, which is not linear, keeps its closed
    impact map); ``"auto"`` (default) is closed form up to
    :data:`symmech.algebra.budget.CLOSED_FORM_MAX_N` coordinates when the closed forms fit their
    budgets, else ``linear_solve``.

    Budgets (:mod:`symmech.algebra.budget`).  The closed forms are first sized from the structure
    (:func:`symmech.codegen.closed_form_budget.closed_form_cost`, at once), then derived
    within :data:`symmech.algebra.budget.CLOSED_FORM_SECONDS`.  Over either budget, ``"auto"``
    takes ``linear_solve`` and says so in ``omitted`` and :attr:`ScenePlan.fallback`;
    ``"closed_form"`` raises :class:`CodegenError` naming the stage and the budget.
    ``functions`` restricts the kinds
    emitted (names from :data:`FUNCTIONS`; all but ``dynamics`` and ``augmented_rhs`` by
    default: ``dynamics``, out = (v_dot, lambda) from one solve, is made by
    :mod:`symmech.codegen.sharing` when acceleration and multipliers are large, or when
    asked for; ``augmented_rhs``, the simulator's right-hand side with the walls' gaps,
    when asked for).  ``constants`` bakes
    parameter values in (folded into the expressions); the other parameters are run-time
    inputs ``p``.
    ``definitions`` maps arbitrary functions of time (``f`` or ``f(t)``) to expressions in
    t and the parameters.  ``projectors`` adds P and Q (constrained scenes); ``jacobian``
    adds the Jacobian d(rhs)/dy of the first-order system (for implicit integrators).
    ``extra`` adds functions of the scene's state y = (q, v), t and the parameters that
    are not derived by the scene itself: ``{name: (doc, expression)}`` with a vector or a
    matrix of sympy expressions (the reset maps of :mod:`symmech.gait` and their
    Jacobians), evaluated as written, with CSE; see :func:`extra_functions`.
    """
    if strategy not in STRATEGIES:
        raise CodegenError(f"strategy must be one of {STRATEGIES}, got {strategy!r}")
    if isinstance(functions, str):  # one name, not its letters
        functions = [functions]
    wanted = set(FUNCTIONS) if functions is None else set(functions)
    if not wanted:
        raise CodegenError(f"functions: empty; choose from {list(FUNCTIONS)} (None: all)")
    unknown = sorted(wanted - set(FUNCTIONS), key=repr)
    if unknown:
        raise CodegenError(f"functions: unknown {unknown}; choose from {list(FUNCTIONS)}")
    if projectors:
        wanted.add("projectors")
    elif functions is None:
        wanted.discard("projectors")
    if jacobian:
        wanted.add("jacobian")
    elif functions is None:
        wanted.discard("jacobian")
    if functions is None:  # (made when acceleration and multipliers share their solve;
        # the simulator's own right-hand side)
        wanted -= {"dynamics", "augmented_rhs"}
    options = (wanted, constants or {}, definitions or {}, extra_functions(extra or {}))
    if strategy == "linear_solve" or (strategy == "auto" and scene.n > limits.CLOSED_FORM_MAX_N):
        return _build(scene, "linear_solve", *options)
    try:
        closed_form_cost(scene, walls="impact" in wanted)
        stage = f"closed forms of scene {scene.name!r}"
        with limits.time_limit(stage, limits.CLOSED_FORM_SECONDS):
            return _build(scene, "closed_form", *options)
    except BudgetExceeded as exc:
        if strategy == "closed_form":
            raise CodegenError(
                f"strategy 'closed_form': {exc}; strategy 'linear_solve' solves the same"
                " equations in the generated code"
            ) from exc  # the budget that stopped it, as data (benchmarks report it)
        note = f"strategy auto: {exc}; linear_solve is used instead of closed forms"
    return _build(scene, "linear_solve", *options, fallback=note)


class _FunctionPlans:
    """The plans of a scene's functions as the builders add them (:meth:`add`, the
    ``add`` of :class:`~symmech.codegen.kinds.BuildContext`): every entry prepared once
    (:meth:`prepare`), the symbols each reads checked and recorded."""

    def __init__(
        self, scene: Scene, baked: Mapping, runtime: tuple[sp.Symbol, ...], inputs: InputSlots
    ) -> None:
        # a float constant is a double: substitute its exact (dyadic) value, so that x**k
        # with k = 2.0 is x**2 and the folding of constants rounds once, at printing
        self.exact = {
            s: sp.Rational(val) if isinstance(val, sp.Float) else val for s, val in baked.items()
        }
        self.runtime, self.inputs = runtime, inputs
        self.state = (*scene.coordinates, TIME)
        self.velocities = set(scene.velocities)
        self.fixed = set(scene.coordinates) | self.velocities | set(runtime) | {TIME}
        self.plans: list[FunctionPlan] = []
        self._prepared: dict[sp.Expr, sp.Expr] = {}
        self._walked: dict = {}  # free symbols of the subtrees walked (algebra.walk)
        self._counted: dict = {}  # operations of the subtrees counted (algebra.opcount)
        self._ready: dict[int, tuple[Block, Block]] = {}

    def prepare(self, e: sp.Expr) -> sp.Expr:
        """Inputs and constants substituted; a velocity-free entry (metric, gradients,
        one-forms, projectors) in stable form: numerator and denominator factored, so a
        difference such as a^2 - b^2 is evaluated as (a - b)(a + b), without cancellation
        (see :mod:`symmech.algebra.stability`).  Velocity-dependent entries keep their
        structure (the sparse forcing, the stable impact maps)."""
        hit = self._prepared.get(e)  # the metric's entries recur: symmetry, every solve
        if hit is not None:
            return hit
        out = self.inputs.substitute(e)
        out = out.xreplace(self.exact) if self.exact else out
        if (
            not out.is_number
            and not (free_symbols(out, self._walked) & self.velocities)
            and count_ops(out, self._counted) <= limits.STABLE_ENTRY_OPS
        ):
            out = stable_entry(out, self.state)
        self._prepared[e] = out
        return out

    def prepare_block(self, b: Block) -> Block:
        """``b`` with every entry prepared; a block shared by several functions (the
        metric of every solve) is prepared once."""
        hit = self._ready.get(id(b))
        if hit is None or hit[0] is not b:
            entries = tuple(self.prepare(e) for e in b.entries)
            hit = self._ready[id(b)] = (b, Block(b.name, b.shape, entries))
        return hit[1]

    def add(
        self,
        name: str,
        kind: str,
        doc: str,
        equation: str,
        state: tuple[str, ...],
        blocks: list[Block],
        out_shape: tuple[int, ...],
        **options: Any,
    ) -> None:
        """Append the plan of a function (the fields of :class:`FunctionPlan`; ``options``
        its optional ones), its blocks prepared; what it reads (t, inputs, parameters)
        from its entries and from the function it calls or is part of.  An entry holding
        a symbol that is neither state nor parameter is a :class:`CodegenError`."""
        prepared = [self.prepare_block(b) for b in blocks]
        syms: set = set().union(
            *[free_symbols(e, self._walked) for b in prepared for e in b.entries]
        )
        slots = set(self.inputs.slots.values())  # (made as the entries are prepared)
        stray = sorted(str(s) for s in syms - self.fixed - slots)
        if stray:
            raise CodegenError(f"{name}: symbols {stray} are neither state nor parameters")
        plan = FunctionPlan(
            name=name,
            kind=kind,
            doc=doc,
            equation=equation,
            state=state,
            blocks=tuple(prepared),
            out_shape=out_shape,
            uses_time=TIME in syms,
            uses_inputs=bool(syms & slots),
            uses_parameters=bool(syms & set(self.runtime)),
            **options,
        )
        if plan.callee is not None:
            callee = next(f for f in self.plans if f.name == plan.callee)
            plan = replace(
                plan,
                uses_time=plan.uses_time or callee.uses_time,
                uses_inputs=plan.uses_inputs or callee.uses_inputs,
                uses_parameters=plan.uses_parameters or callee.uses_parameters,
            )
        self.plans.append(plan)


def _build(
    scene: Scene,
    strategy: str,
    wanted: set[str],
    constants: Mapping,
    definitions: Mapping,
    extra: tuple[tuple[str, str, sp.Matrix], ...] = (),
    fallback: str | None = None,
) -> ScenePlan:
    """The plan with a concrete strategy (``closed_form`` or ``linear_solve``)."""
    n, m = scene.n, scene.constraint_matrix.rows
    baked = _check_constants(scene, constants)
    runtime = tuple(p for p in scene.parameters if p not in baked)
    inputs = InputSlots(definition_rules(scene, definitions))
    q, v = scene.coordinates, scene.velocities
    omitted: list[str] = [fallback] if fallback else []
    adder = _FunctionPlans(scene, baked, runtime, inputs)
    plans = adder.plans
    ctx = BuildContext(
        scene=scene,
        wanted=wanted,
        closed=strategy == "closed_form",
        omitted=omitted,
        add=adder.add,
        extra=extra,
    )
    for builder in SCENE_BUILDERS:
        builder(ctx)
    ids = wall_ids([w.name for w in scene.walls])
    for w, wid in zip(scene.walls, ids, strict=True):
        for wall_builder in WALL_BUILDERS:
            wall_builder(ctx, w, wid)
    if not scene.walls:
        omitted.append("psi, dpsi, impact maps: the scene has no walls")
    if ctx.closed:
        omitted.append("linear-algebra routines: strategy closed_form evaluates closed forms")
    if sp.sympify(scene.potential, strict=True) == 0:
        omitted.append("potential terms: V = 0")
    if not any(p.uses_time for p in plans):
        omitted.append("time argument t: nothing depends on t")
    if baked:
        omitted.append(
            "parameters baked in as constants: "
            + ", ".join(f"{s} = {val}" for s, val in baked.items())
        )
    check_unique_names(plans)
    return ScenePlan(
        scene_name=scene.name,
        n=n,
        m=m,
        coordinates=tuple(q),
        velocities=tuple(v),
        parameters=runtime,
        constants=tuple(baked.items()),
        inputs=inputs.ordered(),
        walls=tuple(w.name for w in scene.walls),
        wall_ids=ids,
        moving_walls=tuple(sp.diff(w.psi, TIME) != 0 for w in scene.walls),
        strategy=strategy,
        functions=tuple(plans),
        omitted=tuple(omitted),
        fallback=fallback,
    )
