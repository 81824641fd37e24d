"""The builders of the function plans, one per kind of generated function.

:func:`symmech.codegen.plan.build_plan` runs every builder of :data:`SCENE_BUILDERS` on a
:class:`BuildContext`, then every builder of :data:`WALL_BUILDERS` for each wall, in that
order (the order of the generated functions and of the ``omitted`` notes).  A builder
derives what its function needs from the scene (never a closed form that ``linear_solve``
does not emit), adds the function with :meth:`BuildContext.add`, and records in
:attr:`BuildContext.omitted` what it leaves out and why.  A new kind of function (a
Jacobian, a contact mode) is a new builder in one of the two tuples.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import sympy as sp

from symmech.algebra import budget as limits
from symmech.algebra.budget import BudgetExceeded
from symmech.codegen.blocks import (
    Block,
    CodegenError,
    matrix_block,
    scalar_block,
    vector_block,
    wall_function_name,
)
from symmech.codegen.forcing_notes import forcing_notes
from symmech.declaration.symbols import t as TIME

if TYPE_CHECKING:
    from symmech.declaration.spec import ResolvedWall
    from symmech.impacts import ImpactMap
    from symmech.scene import Scene

__all__ = ["DYNAMICS_DOC", "DYNAMICS_EQUATION", "SCENE_BUILDERS", "WALL_BUILDERS", "BuildContext"]


@dataclass
class BuildContext:
    """What the builders share: the scene, what was asked for, the strategy, the notes,
    and ``add`` (which prepares the blocks and appends the function's plan; its arguments
    are those of :class:`~symmech.codegen.plan.FunctionPlan`)."""

    scene: Scene
    wanted: set[str]
    closed: bool
    omitted: list[str]
    add: Callable[..., None]
    #: functions of the state given as expressions, ``(name, doc, matrix)`` (``extra=``)
    extra: tuple[tuple[str, str, sp.Matrix], ...] = ()
    M: sp.Matrix = field(init=False)
    f: sp.Matrix = field(init=False)
    mu: sp.Matrix = field(init=False)
    diag: int = field(init=False)
    M_block: Block = field(init=False)

    def __post_init__(self) -> None:
        scene = self.scene
        self.M = sp.Matrix(scene.mass_matrix())
        self.f = sp.Matrix(scene.forcing())
        n = scene.n
        # a structurally diagonal metric is not factored: the solves divide by its diagonal
        self.diag = int(all(self.M[i, j] == 0 for i in range(n) for j in range(n) if i != j))
        self.mu = sp.Matrix(scene.constraint_matrix)
        self.M_block = matrix_block("M", self.M)  # one block for every solve, built once

    @property
    def n(self) -> int:
        return self.scene.n

    @property
    def m(self) -> int:
        return self.mu.rows

    @property
    def needs_acceleration(self) -> bool:
        return bool({"acceleration", "rhs", "augmented_rhs"} & self.wanted)

    def constrained_blocks(self) -> list[Block]:
        """g, f, the constraint one-forms and mu_dot v: the constrained system's inputs."""
        return [
            self.M_block,
            vector_block("f", self.f),
            matrix_block("mu", self.mu),
            vector_block("rate", self.scene.constraint_rate()),
        ]


# ----------------------------------------------------------------------- scene functions


def _mass_matrix(c: BuildContext) -> None:
    if "mass_matrix" in c.wanted:
        c.add(
            "mass_matrix",
            "mass_matrix",
            "kinetic metric g(q) in the velocity basis",
            "T = 1/2 v^T g v",
            ("q",),
            [matrix_block("out", c.M)],
            (c.n, c.n),
        )


def _forcing(c: BuildContext) -> None:
    if "forcing" in c.wanted:
        c.add(
            "forcing",
            "forcing",
            "forcing f(q, v, t) of the unconstrained equations g v_dot = f",
            "f_k = -Gamma_kij v^i v^j - dV/dq^k (first kind, no inverse)",
            ("q", "v"),
            [vector_block("out", c.f)],
            (c.n,),
        )
    if "forcing" in c.wanted or c.needs_acceleration:
        c.omitted.extend(forcing_notes(c.f, c.scene.velocities, c.scene.frame is not None))


def _dynamics(c: BuildContext) -> None:
    """``dynamics``: out = (v_dot, lambda), by one solve or, for ``closed_form``, as the
    closed forms (``acceleration`` and ``multipliers`` become its parts when their code is
    large: :mod:`symmech.codegen.sharing`)."""
    n, m = c.n, c.m
    if "dynamics" not in c.wanted or not m:
        return
    if c.closed:
        both = sp.Matrix(c.scene.acceleration()).col_join(sp.Matrix(c.scene.multipliers()))
        c.add(
            "dynamics",
            "dynamics",
            "acceleration v_dot and Lagrange multipliers lambda (closed forms)",
            "out = (v_dot, lambda), lambda = C^-1 (-mu_dot v - mu g^-1 f) (Carnot 2.2)",
            ("q", "v"),
            [vector_block("out", both)],
            (n + m,),
        )
        return
    c.add(
        "dynamics",
        "dynamics",
        DYNAMICS_DOC,
        DYNAMICS_EQUATION,
        ("q", "v"),
        c.constrained_blocks(),
        (n + m,),
        step="constrained_dynamics",
        step_args=(n, m, c.diag),
    )


#: What ``dynamics`` (one solve) computes, for its header (also when made by sharing).
DYNAMICS_DOC = "acceleration v_dot and Lagrange multipliers lambda, one solve in the code"
DYNAMICS_EQUATION = (
    "g v_dot = f + mu^T lambda, mu v_dot = -mu_dot v; out = (v_dot, lambda) (Carnot paper eq. 5)"
)


def _acceleration(c: BuildContext) -> None:
    if not c.needs_acceleration:
        return
    n, m = c.n, c.m
    if c.closed:
        acc = sp.Matrix(c.scene.acceleration())
        c.add(
            "acceleration",
            "acceleration",
            "acceleration v_dot (closed form)",
            "g v_dot = f + mu^T lambda, mu v = 0 (Carnot paper eq. 5)",
            ("q", "v"),
            [vector_block("out", acc)],
            (n,),
        )
    elif m:
        c.add(
            "acceleration",
            "acceleration",
            "acceleration v_dot, constrained system solved in the code",
            "g v_dot = f + mu^T lambda, mu v_dot = -mu_dot v (Carnot paper eq. 5)",
            ("q", "v"),
            c.constrained_blocks(),
            (n,),
            step="constrained_acceleration",
            step_args=(n, m, c.diag),
        )
    else:
        c.add(
            "acceleration",
            "acceleration",
            "acceleration v_dot, g v_dot = f solved in the code (Cholesky)",
            "g v_dot = f (Carnot paper eq. 2)",
            ("q", "v"),
            [c.M_block, vector_block("f", c.f)],
            (n,),
            step="spd_solve",
            step_args=(n, c.diag),
        )


def _rhs(c: BuildContext) -> None:
    if "rhs" in c.wanted:
        qdot = sp.Matrix(c.scene.kinematics())
        c.add(
            "rhs",
            "rhs",
            "first-order system y = (q, v): y_dot = (q_dot, v_dot)",
            "q_dot = S(q) v, v_dot = acceleration(q, v)",
            ("y",),
            [vector_block("out", qdot)],
            (2 * c.n,),
            calls="acceleration",
        )


def _augmented_rhs(c: BuildContext) -> None:
    """The right-hand side of the simulator's flow, whose state carries the walls' gaps
    (:class:`symmech.simulate.flow.AugmentedFlow`): ``(q_dot, v_dot, r_1 .. r_W)`` with
    ``r_w = d psi_w/dt = dpsi_w(q) q_dot + psi_t`` along the motion (the chain rule), in
    one call; v_dot by the call of acceleration."""
    walls = c.scene.walls
    if "augmented_rhs" not in c.wanted:
        return
    if not walls:
        c.omitted.append("augmented_rhs: the scene has no walls (rhs is its flow)")
        return
    qdot = sp.Matrix(c.scene.kinematics())
    rates = [(_gradient(c, w) * qdot)[0, 0] + sp.diff(w.psi, TIME) for w in walls]
    c.add(
        "augmented_rhs",
        "augmented_rhs",
        "first-order system with the walls' gaps z: (q_dot, v_dot, dz_w/dt for each wall)",
        "q_dot = S(q) v, v_dot = acceleration(q, v), dz_w/dt = dpsi_w(q) q_dot + psi_t,w",
        ("y",),
        # entries n .. 2n - 1 are the call's (zero until it writes them)
        [vector_block("out", [*qdot, *[sp.S.Zero] * c.n, *rates])],
        (2 * c.n + len(walls),),
        calls="acceleration",
    )


def _jacobian(c: BuildContext) -> None:
    if "jacobian" not in c.wanted:
        return
    jac = jacobian(c.scene)
    if isinstance(jac, str):
        c.omitted.append(jac)
        return
    c.add(
        "jacobian",
        "jacobian",
        "Jacobian d(y_dot)/dy of the first-order system y = (q, v) (closed form)",
        "J = d(S(q) v, v_dot(q, v))/d(q, v), v_dot the closed-form acceleration",
        ("y",),
        [matrix_block("out", jac)],
        (2 * c.n, 2 * c.n),
    )


def _acceleration_note(c: BuildContext) -> None:
    if "acceleration" not in c.wanted and c.needs_acceleration:
        callers = " and ".join(k for k in ("rhs", "augmented_rhs") if k in c.wanted)
        verb = "call" if " and " in callers else "calls"
        c.omitted.append(f"acceleration was not asked for but is emitted: {callers} {verb} it")


def _energy_function(c: BuildContext) -> None:
    if "energy" in c.wanted:
        c.add(
            "energy",
            "energy",
            "total energy T + V",
            "E = 1/2 v^T g v + V(q, t)",
            ("q", "v"),
            [scalar_block("out", energy(c.M, c.scene.velocities, c.scene.potential))],
            (),
        )


def _constrained(c: BuildContext) -> None:
    """Multipliers, the constraint residual and the projectors of a constrained scene."""
    n, m = c.n, c.m
    if not m:
        c.omitted.append(
            "dynamics, multipliers, constraint residual, projectors: the scene has no constraints"
        )
        return
    if "multipliers" in c.wanted:
        if c.closed:
            c.add(
                "multipliers",
                "multipliers",
                "Lagrange multipliers lambda (closed form)",
                "lambda = C^-1 (-mu_dot v - mu g^-1 f), C = mu g^-1 mu^T (Carnot 2.2)",
                ("q", "v"),
                [vector_block("out", c.scene.multipliers())],
                (m,),
            )
        else:
            c.add(
                "multipliers",
                "multipliers",
                "Lagrange multipliers lambda, solved in the code",
                "lambda = C^-1 (-mu_dot v - mu g^-1 f), C = mu g^-1 mu^T (Carnot 2.2)",
                ("q", "v"),
                c.constrained_blocks(),
                (m,),
                step="constrained_multipliers",
                step_args=(n, m, c.diag),
            )
    if "constraint_residual" in c.wanted:
        c.add(
            "constraint_residual",
            "constraint_residual",
            "constraint residual mu(q) v (zero on the constraint distribution D)",
            "r_a = mu^a_i(q) v^i",
            ("q", "v"),
            [vector_block("out", c.mu * sp.Matrix(c.scene.velocities))],
            (m,),
        )
    if "projectors" in c.wanted:
        P, Q = c.scene.projectors()
        for label, mat, what in (("P", P, "onto D"), ("Q", Q, "onto D^perp")):
            c.add(
                f"projector_{label}",
                "projectors",
                f"g-orthogonal projector {label} {what}",
                "Q = Z C^-1 mu, P = I - Q (Carnot paper section 2.2)",
                ("q",),
                [matrix_block("out", mat)],
                (n, n),
            )


#: The scene-level builders, in the order of the generated functions.
def _extra(c: BuildContext) -> None:
    """The functions given as expressions (``extra=`` of
    :func:`~symmech.codegen.plan.build_plan`), each evaluated as written at y = (q, v)."""
    for name, doc, expr in c.extra:
        vector = expr.cols == 1
        c.add(
            name,
            "extra",
            doc,
            doc,
            ("y",),
            [vector_block("out", expr) if vector else matrix_block("out", expr)],
            (expr.rows,) if vector else (expr.rows, expr.cols),
        )


SCENE_BUILDERS: tuple[Callable[[BuildContext], None], ...] = (
    _mass_matrix,
    _forcing,
    _dynamics,
    _acceleration,
    _rhs,
    _augmented_rhs,
    _jacobian,
    _acceleration_note,
    _energy_function,
    _constrained,
    _extra,
)


# ------------------------------------------------------------------------ wall functions


def _where(w: ResolvedWall) -> dict[str, Any]:
    return {"wall": w.name, "wall_index": w.index}


def _gradient(c: BuildContext, w: ResolvedWall) -> sp.Matrix:
    return sp.Matrix([[sp.diff(w.psi, qi) for qi in c.scene.coordinates]])


def _psi(c: BuildContext, w: ResolvedWall, wid: str) -> None:
    if "psi" in c.wanted:
        c.add(
            wall_function_name("psi", wid),
            "psi",
            f"gap of wall {w.name!r}; the admissible side is psi >= 0",
            f"psi = {w.psi}",
            ("q",),
            [scalar_block("out", w.psi)],
            (),
            **_where(w),
        )


def _dpsi(c: BuildContext, w: ResolvedWall, wid: str) -> None:
    if "dpsi" in c.wanted:
        c.add(
            wall_function_name("dpsi", wid),
            "dpsi",
            f"gradient d psi/d q of wall {w.name!r} (coordinates)",
            "dpsi_i = d psi / d q^i",
            ("q",),
            [vector_block("out", _gradient(c, w))],
            (c.n,),
            **_where(w),
        )


def _psi_t(c: BuildContext, w: ResolvedWall, wid: str) -> None:
    if "psi_t" not in c.wanted:
        return
    psi_t = sp.diff(w.psi, TIME)
    label = f"wall {w.name!r}"
    if psi_t != 0:
        c.add(
            wall_function_name("psi_t", wid),
            "psi_t",
            f"time derivative d psi/d t of the moving {label}",
            "psi_t = d psi / d t; d/dt psi(t, q(t)) = psi_t + dpsi(q_dot)",
            ("q",),
            [scalar_block("out", psi_t)],
            (),
            **_where(w),
        )
    else:
        c.omitted.append(
            f"{wall_function_name('psi_t', wid)}: {label} does not move (d psi/d t = 0)"
        )


def _impact(c: BuildContext, w: ResolvedWall, wid: str) -> None:
    if "impact" not in c.wanted:
        return
    n, m = c.n, c.m
    label = f"wall {w.name!r}"
    name = wall_function_name("impact", wid)
    if c.closed or w.law == "energy":
        imp = energy_law_map(c.scene, w) if not c.closed else c.scene.impact_map(w.index)
        if not c.closed:
            c.omitted.append(
                f"{name}: the energy law (text 001, 3.2) is not linear;"
                " its closed form is emitted even with strategy linear_solve"
            )
        c.add(
            name,
            "impact",
            f"post-impact velocity at {label} ({w.law} law, closed form)",
            impact_equation(imp),
            ("q", "v"),
            [vector_block("out", imp.post_velocity)],
            (n,),
            **_where(w),
        )
        return
    S = c.scene.frame
    grad = _gradient(c, w)
    dpsi_v = grad * S if S is not None else grad
    A = c.mu.col_join(dpsi_v).col_join(sp.Matrix(w.impulsive_matrix))
    c.add(
        name,
        "impact",
        f"post-impact velocity at {label} (Newton law, KKT solved in the code)",
        "g (v+ - v-) = A^T lambda, A = [mu; dpsi; nu]; mu v+ = 0,"
        " dpsi v+ + psi_t = -alpha (dpsi v- + psi_t), nu (v+ - V) = 0"
        " (Carnot paper eqs. 6, 15, 20)",
        ("q", "v"),
        [c.M_block, matrix_block("A", A), impact_scalars(w, sp.diff(w.psi, TIME))],
        (n,),
        step="impact_kkt",
        step_args=(n, A.rows, m, c.diag),
        **_where(w),
    )


#: The per-wall builders, in the order of each wall's generated functions.
WALL_BUILDERS: tuple[Callable[[BuildContext, Any, str], None], ...] = (
    _psi,
    _dpsi,
    _psi_t,
    _impact,
)


# ---------------------------------------------------------------------------- helpers


def energy(M: sp.Matrix, v: Sequence[sp.Symbol], V: sp.Expr) -> sp.Expr:
    """``E = 1/2 v^T g v + V`` as ``sum_i g_ii v_i^2 / 2 + sum_{i<j} g_ij v_i v_j + V``,
    over the non-zero entries and without expanding them (the printed code evaluates
    each entry once; :meth:`Scene.energy` expands, which costs seconds at n = 32)."""
    n = len(v)
    terms = [M[i, i] * v[i] ** 2 / 2 for i in range(n) if M[i, i] != 0]
    terms += [M[i, j] * v[i] * v[j] for i in range(n) for j in range(i + 1, n) if M[i, j] != 0]
    return sp.Add(*terms, V)


def energy_law_map(scene: Scene, wall: ResolvedWall) -> ImpactMap:
    """The closed-form impact map of an energy-law wall under ``linear_solve`` (there is
    no linear system to solve for it), within :data:`symmech.algebra.budget.CLOSED_FORM_SECONDS`;
    over budget a :class:`CodegenError` names the wall and the budget."""
    stage = f"closed-form energy-law impact map of wall {wall.name!r}"
    try:
        with limits.time_limit(stage, limits.CLOSED_FORM_SECONDS):
            return scene.impact_map(wall.index)
    except BudgetExceeded as exc:
        raise CodegenError(f"{exc}; the energy law has no linear_solve form") from None


def jacobian(scene: Scene) -> sp.Matrix | str:
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


def impact_scalars(w: ResolvedWall, psi_t: sp.Expr) -> Block:
    """The scalars of the KKT impact: alpha, psi_t, and with a declared wall velocity W
    the values ``nu W`` the impulsive constraints hold v+ to (Carnot paper eq. 20; the
    default W gives them from the Gram matrix in the generated code)."""
    values = [sp.sympify(w.restitution, strict=True), psi_t]
    if w.velocity is not None and w.impulsive_matrix.rows:
        values += list(sp.Matrix(w.impulsive_matrix) * sp.Matrix(w.velocity))
    return Block("s", (len(values),), tuple(values))


def impact_equation(imp: ImpactMap) -> str:
    if imp.law == "energy":
        return "v+ = W + PP (v- - W) + alpha sqrt(...) N (text 001, section 3.2)"
    if imp.moving:
        return "v+ = (PP - alpha T~) (v- - W) + W (Carnot paper eq. 17, Prop. 4.2)"
    return "v+ = (PP - alpha T~) v- (Carnot paper eq. 10, Prop. 3.4)"
