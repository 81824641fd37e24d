"""Import a ``sympy.physics.mechanics`` model: KanesMethod, LagrangesMethod or System.

The model's bodies and loads are read, not its formed equations: symmech derives the
equations itself from the same kinematics, so the import costs the partial velocities and
dot products of the bodies, not the elimination Kane's method performs.

Velocity basis.  For ``KanesMethod`` and a ``System`` with generalized speeds, the speeds u
are the quasi-velocities: the kinematic differential equations, solved for ``q_dot``, must
read ``q_dot = S(q) u`` (linear, no term free of u); S is the frame.  A speed that no
kinematic equation reaches (a wheel's spin whose angle the model never introduced) gets an
ignorable coordinate ``q_<u>`` with ``q_<u>_dot = u``, so that S is square.  For
``LagrangesMethod`` (and a ``System`` without speeds) the basis is ``q_dot``.

Kinetic metric (slides 000, Kane's method): with the partial velocities ``v_P,r =
dv_P/du^r`` of each mass centre and ``w_B,r = dw_B/du^r`` of each rigid body's angular
velocity in the inertial frame,
``M_rs = sum_bodies m v_P,r . v_P,s + w_B,r . I_B . w_B,s`` (I_B the central inertia),
so ``T = 1/2 u^T M u``.  Velocities with a part free of the speeds (a point driven along
a prescribed path, a moving frame) are refused: symmech's systems are scleronomic.  A
metric singular only off the constraints (dependent speeds no body's velocity uses) gets
``mu^T mu`` added (:func:`_regular_metric`); one singular on them is refused, naming the
velocities of its kernel.  Bodies' ``potential_energy`` is ignored, as KanesMethod
ignores it.

Lagrange models (``LagrangesMethod``, a ``System`` with ``eom_method=LagrangesMethod``
or whose joints' speeds are the q_dots) are read from their Lagrangian L (for the
System, ``Lagrangian(frame, *bodies)``, which holds the bodies' potential energies):
M is its Hessian in q_dot, V minus its value at q_dot = 0; ``frame=`` is needed only
for loads.

Loads.  A force R at P contributes Kane's generalized active force ``F_r = R . v_P,r``; a
torque on B, ``tau . w_B,r``.  A force constant in the inertial frame is conservative:
it becomes the potential ``-R . r_OP`` (O the point P's position is measured from) when
``F = -S^T dV/dq`` holds identically (checked at random points; it fails, and the load
stays a force, when P's velocity was set by a rolling constraint that the position does
not follow).  Every other load is an applied force (velocity- or input-dependent ones too:
``tau(t)`` becomes a run-time input); q_dot in a load is replaced by ``S u``, as
KanesMethod does.  A ``System``'s actuators contribute their ``to_loads()``, as
``System.form_eoms`` adds them (``System.loads`` leaves them out).

Constraints.  Velocity (non-holonomic) constraints ``k_nh u + f_nh = 0`` must be
homogeneous (``f_nh = 0``); holonomic constraints ``f_h(q) = 0`` enter by their
differentiated form ``df_h/dq S u = 0`` (the configuration then stays on ``f_h = 0`` only
as well as the integration keeps it: symmech does not project positions).  Rows that
depend on the others (the model often gives both a holonomic constraint and its
derivative) are dropped.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import sympy as sp

from symmech.algebra.numeric import EvaluationError, evaluate_matrix
from symmech.algebra.rank import rank_at
from symmech.algebra.walk import atoms
from symmech.algebra.zero import is_zero
from symmech.declaration.checks import Points
from symmech.declaration.dynamic import DynamicTranslation
from symmech.errors import SceneError
from symmech.geometry.derivatives import Derivative
from symmech.mechanics.model import Model, mechanics
from symmech.mechanics.rates import (
    TimeDerivative,
    dyadic_dot,
    expanded_dots,
    speed_partials,
    time_derivative,
    vector_cross,
    vector_dot,
)
from symmech.mechanics.refusals import non_smooth_in, reading, refuse_non_smooth

__all__ = ["scene_arguments"]


def _in_basis(vec: Any, model: Model) -> Any:
    """A velocity vector with q_dot replaced by S u (the Kane case)."""
    qmap = model._qdot_map()
    return vec.xreplace(qmap) if qmap else vec


def _partials(vec: Any, model: Model, what: str) -> list[Any]:
    """The partial velocities d vec / d w^r, after checking vec is linear with no offset
    (computed once per vector, whatever the caller: the metric, the loads and the inertia
    forces share them; ``what`` names it in the error of the first)."""
    hit = model.partials.get(vec)
    if hit is None:
        hit = model.partials[vec] = _partials_of(vec, model, what)
    return hit


def _partials_of(vec: Any, model: Model, what: str) -> list[Any]:
    frame = model.frame
    vec = _in_basis(vec, model)
    if model.speed_symbols is None:
        plain = [sp.Dummy(str(w)) for w in model.basis]
        model.speed_symbols = (dict(zip(model.basis, plain, strict=True)), Derivative(plain))
    parts = speed_partials(vec, *model.speed_symbols)
    rest = vec.xreplace({w: 0 for w in model.basis})
    if rest != 0 and rest.to_matrix(frame).applyfunc(sp.expand) != sp.zeros(3, 1):
        # (a position through Abs: its derivative's re, im and sign are not velocities)
        refuse_non_smooth(vec.to_matrix(frame), what, _KINEMATICS_HINT)
        raise SceneError(
            f"from_mechanics: {what} has a part free of the velocities ({rest}); symmech"
            " needs scleronomic kinematics (no prescribed motion)"
        )
    return parts


_KINEMATICS_HINT = (
    "write the positions and velocities without them (sqrt(q**2) is |q|: keep the"
    " quantity it stood for, or a branch of it valid where the model moves)"
)


def _metric(model: Model) -> sp.Matrix:
    """M_rs = sum m v_P,r . v_P,s + w_B,r . I_B . w_B,s (module docstring), each dot
    product expanded (:func:`~symmech.mechanics.rates.expanded_dots`)."""
    me = mechanics()
    n = len(model.basis)
    M = sp.zeros(n, n)
    pairs, where = [], []  # the dot products, and (r, s, factor) each is added to
    for body in model.bodies:
        vel = _partials(body.masscenter.vel(model.frame), model, f"{body}: mass centre velocity")
        for r in range(n):
            for s in range(r, n):
                pairs.append((vel[r], vel[s]))
                where.append((r, s, body.mass))
        if isinstance(body, me.RigidBody):
            w = _partials(body.frame.ang_vel_in(model.frame), model, f"{body}: angular velocity")
            inertia = body.central_inertia
            Iw = [dyadic_dot(inertia, x) if x != 0 else 0 for x in w]
            for r in range(n):
                for s in range(r, n):
                    pairs.append((w[r], Iw[s]))
                    where.append((r, s, None))
    for (r, s, mass), dot in zip(where, expanded_dots(pairs), strict=True):
        M[r, s] += dot if mass is None else mass * dot
    from symmech.algebra.simplification import normal_form

    for r in range(n):
        for s in range(r, n):
            M[r, s] = normal_form(M[r, s])  # the Pythagorean reduction, within its budget
        for s in range(r):
            M[r, s] = M[s, r]
    if non_smooth_in(M):
        _refuse_non_smooth_bodies(model, M)
    return M


def _refuse_non_smooth_bodies(model: Model, M: sp.Matrix) -> None:
    """Refuse the metric ``M`` that holds a non-smooth function, naming the first body
    whose velocities hold one (else the metric itself: a body's mass or inertia)."""
    me = mechanics()
    for body in model.bodies:
        vectors = [("mass centre velocity", body.masscenter.vel(model.frame))]
        if isinstance(body, me.RigidBody):
            vectors.append(("angular velocity", body.frame.ang_vel_in(model.frame)))
        for what, vec in vectors:
            refuse_non_smooth(vec.to_matrix(model.frame), f"{body}: {what}", _KINEMATICS_HINT)
    refuse_non_smooth(M, "the kinetic metric of the bodies (their masses and inertias)")


def _from_lagrangian(model: Model) -> tuple[sp.Matrix, sp.Expr]:
    """(M, V) of a Lagrangian ``L = 1/2 q_dot^T M q_dot - V``: M its Hessian in q_dot, V
    minus its value at q_dot = 0; a part linear in q_dot (gyroscopic, a moving frame) is
    refused."""
    from symmech.algebra.simplification import normal_form

    refuse_non_smooth([model.lagrangian], model.names["lagrangian"], _KINEMATICS_HINT)
    L = sp.expand(model.lagrangian)
    qd = model.basis
    _refuse_non_quadratic(L, qd)
    M = sp.hessian(L, qd).applyfunc(sp.expand)
    L0 = L.xreplace({d: 0 for d in qd})
    return M.applyfunc(normal_form), -L0


def _velocity_degree(term: sp.Expr, qd: set) -> int | None:
    """The degree of one term of an expanded Lagrangian in the velocities ``qd``; None
    when the term is not a monomial in them (a velocity inside a function or a root)."""
    degree = 0
    for factor in sp.Mul.make_args(term):
        base, power = factor.as_base_exp()
        if base in qd:
            if not (power.is_Integer and power > 0):
                return None
            degree += int(power)
        elif factor.has(*qd):
            return None
    return degree


def _refuse_non_quadratic(L: sp.Expr, qd: Sequence[sp.Expr]) -> None:
    """Refuse an expanded Lagrangian that is not ``T - V`` with T a quadratic form in the
    velocities, naming the terms of the wrong degree (read term by term: the Hessian of a
    quartic L depends on the velocities, and ``L - L0 - v^T M v / 2`` then mixes its
    terms)."""
    wrong: dict[str, list[sp.Expr]] = {}
    velocities = set(qd)
    for term in sp.Add.make_args(L):
        degree = _velocity_degree(term, velocities)
        if degree in (0, 2):
            continue
        if degree == 1:
            kind = "linear in the velocities (gyroscopic or a moving frame)"
        elif degree is None:
            kind = "not polynomial in the velocities"
        else:
            kind = f"of degree {degree} in the velocities"
        wrong.setdefault(kind, []).append(term)
    if wrong:
        said = "; ".join(
            f"terms {kind} ({_short(sp.Add(*terms))})" for kind, terms in wrong.items()
        )
        raise SceneError(
            f"from_mechanics: the Lagrangian has {said}; symmech takes L = T - V with T a"
            " quadratic form in the velocities"
        )


def _short(e: sp.Expr, limit: int = 120) -> str:
    text = str(e)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _origin(point: Any, frame: Any) -> Any:
    """A point of ``point``'s position tree whose velocity in ``frame`` is set to zero (the
    point positions are measured from), the nearest first; None if there is none."""
    seen = {point}
    queue = [point]
    while queue:
        p = queue.pop(0)
        v = p._vel_dict.get(frame)
        if v is not None and v == 0:
            return p
        for other in p._pos_dict:
            if other not in seen:
                seen.add(other)
                queue.append(other)
    return None


def _constant_in(vec: Any, frame: Any) -> bool:
    me = mechanics()
    t = me.dynamicsymbols._t
    comps = vec.to_matrix(frame)
    return not any(e.has(t) for e in comps)


def _loads(model: Model) -> tuple[sp.Expr, list[sp.Expr]]:
    """(V, F): the potential of the verified conservative forces and the other loads'
    generalized active forces (module docstring)."""
    me = mechanics()
    n = len(model.basis)
    V = sp.S.Zero
    F = [sp.S.Zero] * n
    for load in model.loads:
        # q_dot in a load is replaced by S u, as KanesMethod does (its _form_fr)
        where, vector = load[0], _in_basis(load[1], model)
        refuse_non_smooth(vector.to_matrix(model.frame), f"the load on {where}")
        if isinstance(where, me.ReferenceFrame):
            w = _partials(where.ang_vel_in(model.frame), model, f"torque on {where}")
            F = [a + b for a, b in zip(F, expanded_dots([(vector, x) for x in w]), strict=True)]
            continue
        try:
            velocity = where.vel(model.frame)
        except ValueError:  # sympy: "Velocity of point Q has not been defined in ..."
            raise SceneError(
                f"from_mechanics: the load on point {where}: its velocity in the frame"
                f" {model.frame} is not defined (give it with {where}.set_vel or"
                " v2pt_theory before building the model)"
            ) from None
        vel = _partials(velocity, model, f"force at {where}")
        Fr = expanded_dots([(vector, b) for b in vel])
        if _constant_in(vector, model.frame):
            origin = model.origin if model.origin is not None else _origin(where, model.frame)
            candidate = None
            if origin is not None:
                try:
                    candidate = -sp.expand(vector & where.pos_from(origin))
                except ValueError:
                    candidate = None
            if candidate is not None and _is_gradient(candidate, Fr, model):
                V += candidate
                continue
        F = [a + b for a, b in zip(F, Fr, strict=True)]
    return V, F


def _identically_zero(exprs: Sequence[sp.Expr]) -> bool:
    """Whether every expression vanishes identically (:func:`symmech.algebra.zero.is_zero`,
    sampled at the points of :class:`~symmech.declaration.checks.Points`, which give
    dynamic symbols and their derivatives values of their own); one that cannot be
    evaluated counts as not zero.  The smallest (fewest distinct subexpressions) are
    judged first: a non-zero one ends the check, and the cost of a judgement grows with
    the size."""
    points = Points([])
    ordered = sorted(exprs, key=lambda e: len(atoms(e, (sp.Basic,))))
    return all(is_zero(e, points.for_(e)) is True for e in ordered)


def _is_gradient(V: sp.Expr, Fr: Sequence[sp.Expr], model: Model) -> bool:
    """Whether ``F_r = -(S^T dV/dq)_r`` holds at random points (ties the candidate potential
    to the force's generalized active force).  ``(S^T dV/dq)_r`` is the derivative of V
    along the r-th column of S (:class:`~symmech.geometry.derivatives.Derivative`, the
    coordinates made plain symbols): only its values are compared."""
    lhs = _along_frame(V, model)
    return _identically_zero([a + b for a, b in zip(lhs, Fr, strict=True)])


def _along_frame(e: sp.Expr, model: Model) -> list[sp.Expr]:
    """``S^T de/dq`` (``de/dq`` without a frame), for judging its values: the derivatives
    along the frame's columns by :class:`~symmech.geometry.derivatives.Derivative`, the
    coordinates made plain symbols (the same values as sympy's ``diff``, written as the
    product rule leaves them)."""
    plain = {c: sp.Dummy(str(c.func)) for c in model.q}
    back = {d: c for c, d in plain.items()}
    S = model.S.xreplace(plain) if model.S is not None else None
    D = Derivative(list(plain.values()), S)
    flat = e.xreplace(plain)
    return [D(flat, r).xreplace(back) for r in range(len(model.basis))]


def _constraint_rows(model: Model) -> list[list[sp.Expr]]:
    """The velocity constraints and the differentiated holonomic ones, independent rows."""
    bad = [e for e in model.velocity_offsets if e != 0]
    if bad:
        raise SceneError(
            f"from_mechanics: {model.names['constraints']}: velocity constraints with a part"
            f" free of the speeds {bad}; symmech takes homogeneous constraints mu(q) v = 0"
            " (a constraint with a prescribed rate is prescribed motion)"
        )
    # the differentiated holonomic rows are judged by their values (_along_frame), and
    # formed by sympy's diff and expanded once kept (a dropped one, often the derivative
    # of a velocity constraint the model also gives, is never formed)
    rows = [list(r) for r in model.velocity_rows]
    rows += [_along_frame(h, model) for h in model.holonomic]
    if not rows:
        return []
    M = sp.Matrix(rows)
    point = Points([]).for_(M)[0]
    kept: list[int] = []
    for a in range(len(rows)):
        if rank_at(M.extract([*kept, a], list(range(M.cols))), point) == len(kept) + 1:
            kept.append(a)
    first = len(model.velocity_rows)
    return [
        rows[a] if a < first else _holonomic_row(model.holonomic[a - first], model) for a in kept
    ]


def _holonomic_row(h: sp.Expr, model: Model) -> list[sp.Expr]:
    """The differentiated holonomic constraint ``dh/dq S``, expanded."""
    grad = sp.Matrix([[sp.diff(h, c) for c in model.q]])
    return [sp.expand(e) for e in (grad * model.S if model.S is not None else grad)]


def _inertia_forcing(model: Model) -> list[sp.Expr]:
    """Kane's generalized inertia forces without the u_dot terms (slides 000, Kane's
    method): ``-sum m a0_P . v_P,r - (I . alpha0 + w x I . w) . w_r`` where ``a0`` and
    ``alpha0`` are the accelerations with ``u_dot = 0`` (``q_dot = S u`` substituted).
    An acceleration the model set (``a2pt_theory``, ``set_acc``, ``set_ang_acc``) is
    used as set, as KanesMethod uses it, even where it is not the derivative of the
    velocity (sympy's ``test_kane.py::test_aux``: ``a2pt_theory`` through a frame the
    vector is not fixed in)."""
    me = mechanics()
    t = me.dynamicsymbols._t
    frame = model.frame
    n = len(model.basis)
    still = {w.diff(t): 0 for w in model.basis}
    rates = {d.expr: e for d, e in model._qdot_map().items()}
    dt = TimeDerivative(rates, set(model.basis), t)
    f = [sp.S.Zero] * n
    for body in model.bodies:
        v = _in_basis(body.masscenter.vel(frame), model)
        parts = _partials(body.masscenter.vel(frame), model, f"{body}: mass centre velocity")
        given = body.masscenter._acc_dict.get(frame)
        a0 = _as_set(given, model) if given is not None else time_derivative(v, frame, dt)
        a0 = _in_basis(a0.xreplace(still), model)
        for r in range(n):
            f[r] -= body.mass * vector_dot(a0, parts[r])
        if isinstance(body, me.RigidBody):
            w = _in_basis(body.frame.ang_vel_in(frame), model)
            wparts = _partials(body.frame.ang_vel_in(frame), model, f"{body}: angular velocity")
            given = body.frame._ang_acc_dict.get(frame)
            alpha0 = _as_set(given, model) if given is not None else time_derivative(w, frame, dt)
            alpha0 = _in_basis(alpha0.xreplace(still), model)
            inertia = body.central_inertia
            torque = dyadic_dot(inertia, alpha0) + vector_cross(w, dyadic_dot(inertia, w))
            for r in range(n):
                f[r] -= vector_dot(torque, wparts[r])
    return f


def _as_set(acc: Any, model: Model) -> Any:
    """An acceleration the model set, in the velocity basis: ``q_ddot`` replaced by the
    derivative of ``S u`` (the q_dots of the Lagrange basis are the basis itself)."""
    t = mechanics().dynamicsymbols._t
    qdot = model._qdot_map()
    if not qdot:
        return acc
    qddot = {d.diff(t): _in_basis_expr(e.diff(t), model) for d, e in qdot.items()}
    return acc.xreplace(qddot)


def _in_basis_expr(e: sp.Expr, model: Model) -> sp.Expr:
    qmap = model._qdot_map()
    return e.xreplace(qmap) if qmap else e


def _embedded_correction(
    model: Model, tr: DynamicTranslation, M: sp.Matrix, S: sp.Matrix | None
) -> list[sp.Expr] | None:
    """Kane's velocity-quadratic inertia forces minus those the metric ``M`` and frame
    ``S`` (both already in symmech's symbols) give
    (:func:`symmech.geometry.connection.forcing`), in symmech's symbols; None when they
    agree (at random points), as they do when every velocity is the time derivative of a
    position.  They differ when the model's velocities embed a constraint (a contact point
    given zero velocity, ``C.set_vel(N, 0)``, with no coordinates for where it is): the
    velocities are then not those of a configuration space, T(q, u) does not determine the
    motion, and the difference enters as an applied force (it does no work)."""
    from symmech.geometry.connection import forcing
    from symmech.geometry.lie import commutation_coefficients

    q = tr.coordinates
    v: tuple = (
        tr.quasi_velocities or ()
        if S is not None
        else tuple(tr.expr(w, "speeds") for w in model.basis)
    )
    c = commutation_coefficients(S, q) if S is not None else None
    f_geom = forcing(M, sp.S.Zero, q, v, S, c)
    f_kane = [tr.expr(e, "inertia forces") for e in _inertia_forcing(model)]
    # not expanded: the scene adds f_geom back, and its terms cancel structurally
    diff = [a - b for a, b in zip(f_kane, f_geom, strict=True)]
    return None if _identically_zero(diff) else diff


def _singular(M: sp.Matrix) -> tuple[bool, dict]:
    """Whether ``M`` is singular at two sampled points (with the first of them)."""
    points = Points([]).for_(M)[:2]
    try:
        return all(rank_at(M, p) < M.rows for p in points), points[0]
    except EvaluationError:  # no value there: the declaration judges it
        return False, points[0]


def _regular_metric(M: sp.Matrix, rows: list[list[sp.Expr]], model: Model) -> sp.Matrix:
    """``M``, or ``M + mu^T mu`` when M is singular but positive definite on the kernel of
    the constraint rows ``mu``; else a refusal naming the velocities of M's kernel.

    A contact point given the dependent speeds' velocity that no body's velocity uses
    (sympy's ``test_kane5`` rolling disc) leaves M singular, the motion still determined
    on ``mu v = 0``.  The added energy ``|mu v|^2 / 2`` is zero to second order on that
    set, so it changes neither the constrained accelerations (its Euler-Lagrange terms
    ``mu^T d/dt(mu v)`` are constraint forces) nor the impact laws (``g^-1`` of the
    constraint and wall covectors spans the same velocities)."""
    singular, point = _singular(M)
    if not singular:
        return M
    if not model.bodies and model.lagrangian is None:
        raise SceneError(
            "from_mechanics: the model has no bodies (its equations were formed with an"
            " empty body list): there is no kinetic energy, and symmech needs one"
        )
    if rows:
        mu = sp.Matrix(rows)
        augmented = (M + mu.T * mu).applyfunc(sp.expand)
        if not _singular(augmented)[0]:
            return augmented
    A = evaluate_matrix(M, point).real
    _, sing, Vt = np.linalg.svd(A)
    kernel = Vt[sing <= sing[0] * 1e-9] if sing[0] > 0 else Vt
    involved = [w for k, w in enumerate(model.basis) if np.abs(kernel[:, k]).max() > 1e-8]
    where = " on the constraints' kernel" if rows else ""
    if model.lagrangian is not None:
        raise SceneError(_singular_lagrangian(model, involved, where))
    raise SceneError(
        f"from_mechanics: the kinetic metric of the model's bodies is singular{where}: no"
        f" body's kinetic energy fixes the velocities {involved} (sympy issue 24887: three"
        " speeds for a particle's orientation); symmech needs a positive definite metric"
        " (give those motions inertia, or leave out the speeds they do not need)"
    )


def _singular_lagrangian(model: Model, involved: list, where: str) -> str:
    """Why the Hessian of a Lagrangian in the velocities is singular, for the refusal."""
    L = sp.sympify(model.lagrangian, strict=True)
    missing = [w for w in involved if not L.has(w)]
    if missing:
        t = mechanics().dynamicsymbols._t
        speeds = sorted(
            {str(d) for d in atoms(L, sp.Function) if d.args == (t,) and d not in model.q},
        )
        hint = (
            f" (it is written in the speeds {speeds}, not in the q_dots: LagrangesMethod"
            " needs bodies whose velocities are given in the q_dots)"
            if speeds
            else ""
        )
        return (
            f"from_mechanics: the Lagrangian does not depend on the velocities {missing}:"
            f" it has no kinetic energy in them{hint}; symmech needs T positive definite"
        )
    return (
        f"from_mechanics: the kinetic energy of the Lagrangian is singular{where}: it vanishes"
        f" for a motion of the velocities {involved}; symmech needs T positive definite"
    )


def scene_arguments(model: object, *, walls: Sequence = (), name: str | None = None) -> dict:
    """The keyword arguments of :class:`symmech.Scene` for a mechanics model (module
    docstring): coordinates, metric, potential, forces, constraints, frame and
    quasi-velocities.  The model's dynamic symbols are translated to symmech's
    (:class:`~symmech.declaration.dynamic.DynamicTranslation`, walls included) here, once,
    as the declaration would translate them: the correction of the inertia forces needs
    the metric and frame in symmech's symbols, and the declaration then has nothing left
    to translate."""
    kind = type(model).__name__
    with reading(kind, "its coordinates, speeds and kinematic equations"):
        model_ = Model(model)
    with reading(kind, "its bodies and loads"):
        return _arguments(model_, kind, walls, name)


def _arguments(model_: Model, kind: str, walls: Sequence, name: str | None) -> dict:
    """:func:`scene_arguments` of the model read."""
    framed = model_.S is not None
    tr = DynamicTranslation(
        model_.q, model_.basis if framed else None, mechanics().dynamicsymbols._t
    )

    def plain(value: Any, field: str) -> Any:
        return tr.expr(value, field)

    S = plain(model_.S, "frame") if framed else None
    with reading(kind, "the constraints"):
        model_rows = _constraint_rows(model_)
    if model_.lagrangian is not None:
        with reading(kind, "its Lagrangian"):
            M, V0 = _from_lagrangian(model_)
            M = _regular_metric(M, model_rows, model_)
        with reading(kind, "the loads"):
            V, F = _loads(model_)
        M, V, F = plain(M, "metric"), plain(V + V0, "potential"), plain(F, "forces")
    else:
        with reading(kind, "the bodies' masses, inertias and velocities"):
            M = plain(_regular_metric(_metric(model_), model_rows, model_), "metric")
        with reading(kind, "the loads"):
            V, F = _loads(model_)
        V, F = plain(V, "potential"), plain(F, "forces")
        with reading(kind, "Kane's inertia forces"):
            correction = _embedded_correction(model_, tr, M, S)
        if correction is not None:
            F = [a + b for a, b in zip(F, correction, strict=True)]
    rows = [plain(r, f"constraints[{a}]") for a, r in enumerate(model_rows)]
    # (after the translation to real symbols, where sqrt(q**2) becomes Abs(q))
    refuse_non_smooth(
        [e for r in rows for e in r],
        f"a velocity or configuration constraint ({model_.names['constraints']})",
        _KINEMATICS_HINT,
    )
    out: dict[str, Any] = {
        "metric": M,
        "potential": V,
        "forces": F if any(e != 0 for e in F) else None,
        "constraints": rows,
        "walls": [tr.wall(w, f"walls[{k}]") for k, w in enumerate(walls)],
        "name": name,
    }
    if framed:
        out["frame"] = S
        out["quasi_velocities"] = list(tr.quasi_velocities or ())
    return {"coordinates": list(tr.coordinates), **out}
