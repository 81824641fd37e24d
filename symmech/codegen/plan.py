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

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import sympy as sp
from sympy.core.function import AppliedUndef

from symmech.algebra import budget as limits
from symmech.algebra.budget import BudgetExceeded
from symmech.codegen.closed_form_budget import closed_form_cost
from symmech.codegen.printers import identifier
from symmech.declaration.symbols import t as TIME
from symmech.errors import SymmechError
from symmech.impacts.stability import stable_coefficient

if TYPE_CHECKING:
    from symmech.impacts import ImpactMap
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
STEPS = ("spd_solve", "constrained_acceleration", "constrained_multipliers", "impact_kkt")

#: Function kinds a user may ask for (``functions=``); wall functions are per wall.
FUNCTIONS = (
    "mass_matrix",
    "forcing",
    "acceleration",
    "rhs",
    "energy",
    "multipliers",
    "constraint_residual",
    "psi",
    "dpsi",
    "psi_t",
    "impact",
    "projectors",
    "jacobian",
)

#: Name prefixes of the per-wall functions, by kind: prefix-free (module docstring).
WALL_PREFIXES = {"psi": "psi_", "dpsi": "dpsi_", "psi_t": "psit_", "impact": "impact_"}

#: Suffix of the C batch function of each generated function.
BATCH_SUFFIX = "_batch"


class CodegenError(SymmechError, ValueError):
    """Code cannot be generated as asked (bad option, unsupported expression, ...)."""


@dataclass(frozen=True)
class Block:
    """A named array of expressions: ``shape`` (), (k,) or (r, c); ``entries`` row-major."""

    name: str
    shape: tuple[int, ...]
    entries: tuple[sp.Expr, ...]

    @property
    def size(self) -> int:
        return len(self.entries)


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
    function whose result fills the tail of ``out`` (``rhs`` calls ``acceleration``).
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
    wall: str | None = None
    wall_index: int | None = None
    uses_time: bool = False
    uses_inputs: bool = False
    uses_parameters: bool = False

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


def _matrix_block(name: str, M: sp.MatrixBase) -> Block:
    """A matrix block, always two-dimensional (a 1 x 1 metric stays (1, 1))."""
    M = sp.Matrix(M)
    return Block(name, (M.rows, M.cols), tuple(M))


def _vector_block(name: str, x: sp.MatrixBase | Sequence[sp.Expr]) -> Block:
    """A vector block of shape (k,), from a column, a row or a sequence."""
    entries = tuple(x)
    return Block(name, (len(entries),), entries)


def wall_ids(names: Sequence[str]) -> tuple[str, ...]:
    """Sanitised, unique identifiers for wall names (module docstring), by index."""
    taken: set[str] = set()
    out = []
    for name in names:
        wid = identifier(name, "", taken, part=True)
        if wid == BATCH_SUFFIX[1:] or wid.endswith(BATCH_SUFFIX):
            taken.discard(wid)
            wid = identifier(wid + "_w", "", taken, part=True)
        out.append(wid)
    return tuple(out)


def wall_function_name(kind: str, wall_id: str) -> str:
    """The generated name of the ``kind`` function (psi, dpsi, psi_t, impact) of a wall."""
    return WALL_PREFIXES[kind] + wall_id


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


def _scalar_block(name: str, e: sp.Expr) -> Block:
    return Block(name, (), (sp.sympify(e),))


class _Inputs:
    """Arbitrary functions of time f(t) and their derivatives -> input slots u[k]."""

    def __init__(self, definitions: Mapping):
        self.definitions = dict(definitions)
        self.slots: dict[sp.Expr, sp.Symbol] = {}

    def _key(self, atom: sp.Expr) -> tuple[str, int]:
        if isinstance(atom, sp.Derivative):
            return (atom.expr.func.__name__, atom.derivative_count)
        return (atom.func.__name__, 0)

    def substitute(self, e: sp.Expr) -> sp.Expr:
        e = sp.sympify(e)
        if self.definitions:
            e = e.subs(self.definitions).doit()
        atoms = [a for a in e.atoms(sp.Derivative) if isinstance(a.expr, AppliedUndef)]
        atoms += list(e.atoms(AppliedUndef))
        rule = {}
        for a in atoms:
            f = a.expr if isinstance(a, sp.Derivative) else a
            if f.args != (TIME,):
                raise CodegenError(
                    f"{a}: only functions of t alone can become run-time inputs; define it"
                    " with definitions={...}"
                )
            if a not in self.slots:
                name, order = self._key(a)
                self.slots[a] = sp.Dummy(f"{name}{'_' + 'd' * order if order else ''}", real=True)
            rule[a] = self.slots[a]
        e = e.xreplace(rule) if rule else e
        leftover = sorted(map(str, e.atoms(sp.Derivative)))
        if leftover:
            raise CodegenError(f"unevaluated derivatives {leftover} cannot be generated")
        return e

    def ordered(self) -> tuple[tuple[sp.Symbol, sp.Expr], ...]:
        items = sorted(self.slots.items(), key=lambda kv: self._key(kv[0]))
        return tuple((d, a) for a, d in items)


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


def build_plan(
    scene: Scene,
    *,
    strategy: str = "auto",
    functions: Sequence[str] | None = None,
    constants: Mapping | None = None,
    definitions: Mapping | None = None,
    projectors: bool = False,
    jacobian: bool = False,
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
    emitted (names from :data:`FUNCTIONS`).  ``constants`` bakes parameter values in
    (folded into the expressions); the other parameters are run-time inputs ``p``.
    ``definitions`` maps arbitrary functions of time (``f`` or ``f(t)``) to expressions in
    t and the parameters.  ``projectors`` adds P and Q (constrained scenes); ``jacobian``
    adds the Jacobian d(rhs)/dy of the first-order system (for implicit integrators).
    """
    if strategy not in STRATEGIES:
        raise CodegenError(f"strategy must be one of {STRATEGIES}, got {strategy!r}")
    wanted = set(FUNCTIONS) if functions is None else set(functions)
    unknown = sorted(wanted - set(FUNCTIONS))
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
    options = (wanted, constants or {}, definitions or {})
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
            ) from None
        note = f"strategy auto: {exc}; linear_solve is used instead of closed forms"
    return _build(scene, "linear_solve", *options, fallback=note)


def _build(
    scene: Scene,
    strategy: str,
    wanted: set[str],
    constants: Mapping,
    definitions: Mapping,
    fallback: str | None = None,
) -> ScenePlan:
    """The plan with a concrete strategy (``closed_form`` or ``linear_solve``)."""
    n, m = scene.n, scene.constraint_matrix.rows
    baked = _check_constants(scene, constants)
    # a float constant is a double: substitute its exact (dyadic) value, so that x**k
    # with k = 2.0 is x**2 and the folding of constants rounds once, at printing
    exact = {s: sp.Rational(val) if isinstance(val, sp.Float) else val for s, val in baked.items()}
    runtime = tuple(p for p in scene.parameters if p not in baked)
    defs: dict = {}
    for key, value in definitions.items():
        f = key(TIME) if isinstance(key, sp.FunctionClass) else key
        if not isinstance(f, AppliedUndef):
            raise CodegenError(f"definitions: {key!r} is not an arbitrary function of t")
        defs[f] = sp.sympify(value)
    inputs = _Inputs(defs)
    q, v = scene.coordinates, scene.velocities
    omitted: list[str] = [fallback] if fallback else []
    plans: list[FunctionPlan] = []

    state = (*q, TIME)
    velocity_set = set(v)

    prepared: dict[sp.Expr, sp.Expr] = {}

    def prepare(e: sp.Expr) -> sp.Expr:
        """Inputs and constants substituted; a velocity-free entry (metric, gradients,
        one-forms, projectors) in stable form: numerator and denominator factored, so a
        difference such as a^2 - b^2 is evaluated as (a - b)(a + b), without cancellation
        (see :mod:`symmech.impacts.stability`).  Velocity-dependent entries keep their
        structure (the sparse forcing, the stable impact maps)."""
        if e in prepared:  # the metric's entries recur: symmetry, and in every solve
            return prepared[e]
        out = inputs.substitute(e)
        out = out.xreplace(exact) if exact else out
        if (
            not out.is_number
            and not (out.free_symbols & velocity_set)
            and sp.count_ops(out) <= limits.STABLE_ENTRY_OPS
        ):
            out = stable_coefficient(out, state)
        prepared[e] = out
        return out

    ready: dict[int, tuple[Block, Block]] = {}

    def prepare_block(b: Block) -> Block:
        """``b`` with every entry prepared; a block shared by several functions (the
        metric of every solve) is prepared once."""
        hit = ready.get(id(b))
        if hit is None or hit[0] is not b:
            hit = ready[id(b)] = (b, Block(b.name, b.shape, tuple(prepare(e) for e in b.entries)))
        return hit[1]

    def add(
        name: str,
        kind: str,
        doc: str,
        equation: str,
        state: tuple[str, ...],
        blocks: list[Block],
        out_shape: tuple[int, ...],
        step: str | None = None,
        step_args: tuple[int, ...] = (),
        calls: str | None = None,
        wall: str | None = None,
        wall_index: int | None = None,
    ) -> None:
        blocks = [prepare_block(b) for b in blocks]
        syms: set = set().union(*[e.free_symbols for b in blocks for e in b.entries])
        slot_syms = set(inputs.slots.values())
        uses_t, uses_u, uses_p = TIME in syms, bool(syms & slot_syms), bool(syms & set(runtime))
        if calls is not None:
            callee = next(f for f in plans if f.name == calls)
            uses_t |= callee.uses_time
            uses_u |= callee.uses_inputs
            uses_p |= callee.uses_parameters
        allowed = set(q) | set(v) | set(runtime) | slot_syms | {TIME}
        stray = sorted(str(s) for s in syms - allowed)
        if stray:
            raise CodegenError(f"{name}: symbols {stray} are neither state nor parameters")
        plans.append(
            FunctionPlan(
                name=name,
                kind=kind,
                doc=doc,
                equation=equation,
                state=state,
                blocks=tuple(blocks),
                out_shape=out_shape,
                step=step,
                step_args=step_args,
                calls=calls,
                wall=wall,
                wall_index=wall_index,
                uses_time=uses_t,
                uses_inputs=uses_u,
                uses_parameters=uses_p,
            )
        )

    M = sp.Matrix(scene.mass_matrix())
    f = sp.Matrix(scene.forcing())
    # a structurally diagonal metric is not factored: the solves divide by its diagonal
    diag = int(all(M[i, j] == 0 for i in range(n) for j in range(n) if i != j))
    mu = sp.Matrix(scene.constraint_matrix)
    closed = strategy == "closed_form"
    M_block = _matrix_block("M", M)  # one block for every solve (n^2 entries, built once)

    def constrained_blocks() -> list[Block]:
        """g, f, the constraint one-forms and mu_dot v: the constrained system's inputs."""
        return [
            M_block,
            _vector_block("f", f),
            _matrix_block("mu", mu),
            _vector_block("rate", scene.constraint_rate()),
        ]

    if "mass_matrix" in wanted:
        add(
            "mass_matrix",
            "mass_matrix",
            "kinetic metric g(q) in the velocity basis",
            "T = 1/2 v^T g v",
            ("q",),
            [_matrix_block("out", M)],
            (n, n),
        )
    if "forcing" in wanted:
        add(
            "forcing",
            "forcing",
            "forcing f(q, v, t) of the unconstrained equations g v_dot = f",
            "f_k = -Gamma_kij v^i v^j - dV/dq^k (first kind, no inverse)",
            ("q", "v"),
            [_vector_block("out", f)],
            (n,),
        )
    need_acc = bool({"acceleration", "rhs"} & wanted)
    if "forcing" in wanted or need_acc:
        omitted.extend(_forcing_notes(f, v, scene.frame is not None))
    if need_acc:
        if closed:
            acc = sp.Matrix(scene.acceleration())
            add(
                "acceleration",
                "acceleration",
                "acceleration v_dot (closed form)",
                "g v_dot = f + mu^T lambda, mu v = 0 (Carnot paper eq. 5)",
                ("q", "v"),
                [_vector_block("out", acc)],
                (n,),
            )
        elif m:
            add(
                "acceleration",
                "acceleration",
                "acceleration v_dot, constrained system solved in the code",
                "g v_dot = f + mu^T lambda, mu v_dot = -mu_dot v (Carnot paper eq. 5)",
                ("q", "v"),
                constrained_blocks(),
                (n,),
                step="constrained_acceleration",
                step_args=(n, m, diag),
            )
        else:
            add(
                "acceleration",
                "acceleration",
                "acceleration v_dot, g v_dot = f solved in the code (Cholesky)",
                "g v_dot = f (Carnot paper eq. 2)",
                ("q", "v"),
                [M_block, _vector_block("f", f)],
                (n,),
                step="spd_solve",
                step_args=(n, diag),
            )
    if "rhs" in wanted:
        qdot = sp.Matrix(scene.kinematics())
        add(
            "rhs",
            "rhs",
            "first-order system y = (q, v): y_dot = (q_dot, v_dot)",
            "q_dot = S(q) v, v_dot = acceleration(q, v)",
            ("y",),
            [_vector_block("out", qdot)],
            (2 * n,),
            calls="acceleration",
        )
    if "jacobian" in wanted:
        jac = _jacobian(scene)
        if isinstance(jac, str):
            omitted.append(jac)
        else:
            add(
                "jacobian",
                "jacobian",
                "Jacobian d(y_dot)/dy of the first-order system y = (q, v) (closed form)",
                "J = d(S(q) v, v_dot(q, v))/d(q, v), v_dot the closed-form acceleration",
                ("y",),
                [_matrix_block("out", jac)],
                (2 * n, 2 * n),
            )
    if "acceleration" not in wanted and need_acc:
        # rhs needs it: keep it, but say so
        omitted.append("acceleration was not asked for but is emitted: rhs calls it")
    if "energy" in wanted:
        add(
            "energy",
            "energy",
            "total energy T + V",
            "E = 1/2 v^T g v + V(q, t)",
            ("q", "v"),
            [_scalar_block("out", _energy(M, v, scene.potential))],
            (),
        )
    if m:
        if "multipliers" in wanted:
            if closed:
                add(
                    "multipliers",
                    "multipliers",
                    "Lagrange multipliers lambda (closed form)",
                    "lambda = C^-1 (-mu_dot v - mu g^-1 f), C = mu g^-1 mu^T (Carnot 2.2)",
                    ("q", "v"),
                    [_vector_block("out", scene.multipliers())],
                    (m,),
                )
            else:
                add(
                    "multipliers",
                    "multipliers",
                    "Lagrange multipliers lambda, solved in the code",
                    "lambda = C^-1 (-mu_dot v - mu g^-1 f), C = mu g^-1 mu^T (Carnot 2.2)",
                    ("q", "v"),
                    constrained_blocks(),
                    (m,),
                    step="constrained_multipliers",
                    step_args=(n, m, diag),
                )
        if "constraint_residual" in wanted:
            add(
                "constraint_residual",
                "constraint_residual",
                "constraint residual mu(q) v (zero on the constraint distribution D)",
                "r_a = mu^a_i(q) v^i",
                ("q", "v"),
                [_vector_block("out", mu * sp.Matrix(v))],
                (m,),
            )
        if "projectors" in wanted:
            P, Q = scene.projectors()
            for label, mat, what in (("P", P, "onto D"), ("Q", Q, "onto D^perp")):
                add(
                    f"projector_{label}",
                    "projectors",
                    f"g-orthogonal projector {label} {what}",
                    "Q = Z C^-1 mu, P = I - Q (Carnot paper section 2.2)",
                    ("q",),
                    [_matrix_block("out", mat)],
                    (n, n),
                )
    else:
        omitted.append("multipliers, constraint residual, projectors: the scene has no constraints")

    S = scene.frame
    ids = wall_ids([w.name for w in scene.walls])
    for w, wid in zip(scene.walls, ids, strict=True):
        label = f"wall {w.name!r}"
        grad = sp.Matrix([[sp.diff(w.psi, qi) for qi in q]])
        psi_t = sp.diff(w.psi, TIME)
        where: dict[str, Any] = {"wall": w.name, "wall_index": w.index}
        if "psi" in wanted:
            add(
                wall_function_name("psi", wid),
                "psi",
                f"gap of {label}; the admissible side is psi >= 0",
                f"psi = {w.psi}",
                ("q",),
                [_scalar_block("out", w.psi)],
                (),
                **where,
            )
        if "dpsi" in wanted:
            add(
                wall_function_name("dpsi", wid),
                "dpsi",
                f"gradient d psi/d q of {label} (coordinates)",
                "dpsi_i = d psi / d q^i",
                ("q",),
                [_vector_block("out", grad)],
                (n,),
                **where,
            )
        if "psi_t" in wanted:
            if psi_t != 0:
                add(
                    wall_function_name("psi_t", wid),
                    "psi_t",
                    f"time derivative d psi/d t of the moving {label}",
                    "psi_t = d psi / d t; d/dt psi(t, q(t)) = psi_t + dpsi(q_dot)",
                    ("q",),
                    [_scalar_block("out", psi_t)],
                    (),
                    **where,
                )
            else:
                omitted.append(
                    f"{wall_function_name('psi_t', wid)}: {label} does not move (d psi/d t = 0)"
                )
        if "impact" in wanted:
            name = wall_function_name("impact", wid)
            if closed or w.law == "energy":
                imp = _energy_law_map(scene, w) if not closed else scene.impact_map(w.index)
                if not closed:
                    omitted.append(
                        f"{name}: the energy law (text 001, 3.2) is not linear;"
                        " its closed form is emitted even with strategy linear_solve"
                    )
                add(
                    name,
                    "impact",
                    f"post-impact velocity at {label} ({w.law} law, closed form)",
                    _impact_equation(imp),
                    ("q", "v"),
                    [_vector_block("out", imp.post_velocity)],
                    (n,),
                    **where,
                )
            else:
                dpsi_v = grad * S if S is not None else grad
                A = mu.col_join(dpsi_v).col_join(sp.Matrix(w.impulsive_matrix))
                k = A.rows
                add(
                    name,
                    "impact",
                    f"post-impact velocity at {label} (Newton law, KKT solved in the code)",
                    "g (v+ - v-) = A^T lambda, A = [mu; dpsi; nu]; mu v+ = 0,"
                    " dpsi v+ + psi_t = -alpha (dpsi v- + psi_t), nu (v+ - V) = 0"
                    " (Carnot paper eqs. 6, 15, 20)",
                    ("q", "v"),
                    [
                        M_block,
                        _matrix_block("A", A),
                        _impact_scalars(w, psi_t, S),
                    ],
                    (n,),
                    step="impact_kkt",
                    step_args=(n, k, m, diag),
                    **where,
                )
    if not scene.walls:
        omitted.append("psi, dpsi, impact maps: the scene has no walls")
    if closed:
        omitted.append("linear-algebra routines: strategy closed_form evaluates closed forms")
    if sp.sympify(scene.potential) == 0:
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


def _energy(M: sp.Matrix, v: Sequence[sp.Symbol], V: sp.Expr) -> sp.Expr:
    """``E = 1/2 v^T g v + V`` as ``sum_i g_ii v_i^2 / 2 + sum_{i<j} g_ij v_i v_j + V``,
    over the non-zero entries and without expanding them (the printed code evaluates
    each entry once; :meth:`Scene.energy` expands, which costs seconds at n = 32)."""
    n = len(v)
    terms = [M[i, i] * v[i] ** 2 / 2 for i in range(n) if M[i, i] != 0]
    terms += [M[i, j] * v[i] * v[j] for i in range(n) for j in range(i + 1, n) if M[i, j] != 0]
    return sp.Add(*terms, V)


def _energy_law_map(scene: Scene, wall) -> ImpactMap:
    """The closed-form impact map of an energy-law wall under ``linear_solve`` (there is
    no linear system to solve for it), within :data:`symmech.algebra.budget.CLOSED_FORM_SECONDS`;
    over budget a :class:`CodegenError` names the wall and the budget."""
    stage = f"closed-form energy-law impact map of wall {wall.name!r}"
    try:
        with limits.time_limit(stage, limits.CLOSED_FORM_SECONDS):
            return scene.impact_map(wall.index)
    except BudgetExceeded as exc:
        raise CodegenError(f"{exc}; the energy law has no linear_solve form") from None


def _jacobian(scene: Scene) -> sp.Matrix | str:
    """``d(S(q) v, v_dot)/d(q, v)`` from the closed-form acceleration (Carnot paper eq. 5),
    derived within :data:`symmech.algebra.budget.CLOSED_FORM_SECONDS`; over budget, the note that
    says why it is left out."""
    stage = f"Jacobian of scene {scene.name!r}"
    try:
        with limits.time_limit(stage, limits.CLOSED_FORM_SECONDS):
            ydot = sp.Matrix(scene.kinematics()).col_join(sp.Matrix(scene.acceleration()))
            return ydot.jacobian(list(scene.coordinates) + list(scene.velocities))
    except BudgetExceeded as exc:
        return f"jacobian: {exc}; not emitted (implicit methods then need another Jacobian)"


def _forcing_notes(f: sp.Matrix, v: Sequence[sp.Symbol], frame: bool) -> list[str]:
    """What the forcing does not compute: the identically zero coefficients of its
    velocity-quadratic part (Gamma_kij, or the connection coefficients omega_kij in a
    frame, symmetrised in i, j: only the symmetric part enters f) and its zero entries."""
    n = len(v)
    index = {s: i for i, s in enumerate(v)}
    total = n * n * (n + 1) // 2
    present: set[tuple[int, int, int]] = set()

    def monomials(k: int, e: sp.Expr, expanded: bool = False) -> None:
        for term in sp.Add.make_args(e):
            idx: list[int] = []
            plain = True
            for factor in sp.Mul.make_args(term):
                base, power = factor.as_base_exp()
                if base in index and power.is_Integer and power > 0:
                    idx += [index[base]] * int(power)
                elif factor.free_symbols & index.keys():
                    plain = False
            if not plain and not expanded and sp.count_ops(term) <= limits.NOTE_EXPAND_OPS:
                monomials(k, sp.expand(term), True)
            elif not plain:
                # too large to expand for a note: count every pair of its velocities as
                # present (the note then gives a lower bound of the zeros)
                inside = sorted(index[s] for s in term.free_symbols & index.keys())
                present.update((k, a, b) for a in inside for b in inside if a <= b)
                bounded.append(k)
            elif len(idx) == 2:
                present.add((k, min(idx), max(idx)))

    bounded: list[int] = []
    for k, e in enumerate(f):
        monomials(k, e)
    nonzero = len(present)
    what = "connection coefficients omega_k(ij)" if frame else "Christoffel symbols Gamma_k(ij)"
    notes = [
        f"forcing: {'at least ' if bounded else ''}{total - nonzero} of the {total} {what}"
        " (symmetrised in i, j) are identically zero and are never computed"
    ]
    zeros = [k for k, e in enumerate(f) if e == 0]
    if zeros:
        notes.append(
            f"forcing: entries {zeros} are identically zero (no velocity or potential term);"
            " they are stored as 0.0 without computation"
        )
    return notes


def _impact_scalars(w, psi_t: sp.Expr, S: sp.Matrix | None) -> Block:
    """The scalars of the KKT impact: alpha, psi_t, and with a declared wall velocity W
    the values ``nu W`` the impulsive constraints hold v+ to (Carnot paper eq. 20; the
    default W gives them from the Gram matrix in the generated code)."""
    values = [sp.sympify(w.restitution), psi_t]
    if w.velocity is not None and w.impulsive_matrix.rows:
        values += list(sp.Matrix(w.impulsive_matrix) * sp.Matrix(w.velocity))
    return Block("s", (len(values),), tuple(values))


def _impact_equation(imp) -> str:
    if imp.law == "energy":
        return "v+ = W + PP (v- - W) + alpha sqrt(...) N (text 001, section 3.2)"
    if imp.moving:
        return "v+ = (PP - alpha T~) (v- - W) + W (Carnot paper eq. 17, Prop. 4.2)"
    return "v+ = (PP - alpha T~) v- (Carnot paper eq. 10, Prop. 3.4)"
