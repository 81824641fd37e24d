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
a prescribed path, a moving frame) are refused: symmech's systems are scleronomic.

Loads.  A force R at P contributes Kane's generalized active force ``F_r = R . v_P,r``; a
torque on B, ``tau . w_B,r``.  A force constant in the inertial frame is conservative:
it becomes the potential ``-R . r_OP`` (O the point P's position is measured from) when
``F = -S^T dV/dq`` holds identically (checked at random points; it fails, and the load
stays a force, when P's velocity was set by a rolling constraint that the position does
not follow).  Every other load is an applied force (velocity- or input-dependent ones too:
``tau(t)`` becomes a run-time input).

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

import sympy as sp

from symmech.algebra.rank import rank_at
from symmech.algebra.walk import atoms
from symmech.algebra.zero import is_zero
from symmech.declaration.checks import Points
from symmech.declaration.dynamic import DynamicTranslation
from symmech.errors import SceneError

__all__ = ["scene_arguments"]


def _me():
    from sympy.physics import mechanics

    return mechanics


def _model_kind(model: object) -> str:
    me = _me()
    if isinstance(model, me.KanesMethod):
        return "kane"
    if isinstance(model, me.LagrangesMethod):
        return "lagrange"
    if isinstance(model, me.System):
        return "system"
    raise SceneError(
        f"from_mechanics: expected a KanesMethod, LagrangesMethod or System, got"
        f" {type(model).__name__}"
    )


class _Model:
    """What the import needs from any of the three model kinds."""

    q: list[sp.Expr]
    basis: list[sp.Expr]  # u, or q_dot (Derivative(q(t), t))
    S: sp.Matrix | None  # q_dot = S u; None for the q_dot basis
    frame: Any
    bodies: list[Any]
    loads: list[Any]
    velocity_rows: list[list[sp.Expr]]  # k u + f = 0 rows, checked homogeneous
    velocity_offsets: list[sp.Expr]
    holonomic: list[sp.Expr]
    origin: Any = None
    lagrangian: sp.Expr | None = None  # a LagrangesMethod built from L alone (no bodies)

    def __init__(self, model: object):
        self.partials: dict = {}
        me = _me()
        t = me.dynamicsymbols._t
        kind = _model_kind(model)
        if kind == "kane":
            k: Any = model
            self.q = list(k.q)
            self.frame = k._inertial
            self.bodies = list(k.bodies or [])
            self.loads = list(k.loads or [])
            self._speeds(list(k.u), k.kindiffdict(), "KanesMethod")
            self.velocity_rows, self.velocity_offsets = [], []
            if k._k_nh is not None and k._k_nh.rows:
                self._rows_from(k._k_nh, k._f_nh)
            self.holonomic = list(k._f_h) if k._f_h is not None else []
        elif kind == "lagrange":
            lm: Any = model
            self.q = list(lm.q)
            self.frame = lm.inertial
            if self.frame is None:
                raise SceneError("from_mechanics: LagrangesMethod needs its frame= (inertial)")
            self.bodies = list(lm._bodies or [])
            self.loads = list(lm.forcelist or [])
            self.basis = [c.diff(t) for c in self.q]
            self.S = None
            self.velocity_rows, self.velocity_offsets = [], []
            if lm.coneqs:
                cons = sp.Matrix(lm.coneqs)
                K = cons.jacobian(self.basis)
                self._rows_from(K, cons - K * sp.Matrix(self.basis))
            self.holonomic = []  # LagrangesMethod differentiates them into coneqs
            if not self.bodies:
                L = lm._L
                self.lagrangian = (
                    L[0] if isinstance(L, sp.MatrixBase) else sp.sympify(L, strict=True)
                )
        else:
            s: Any = model
            self.q = list(s.q)
            self.frame = s.frame
            self.origin = s.fixed_point
            self.bodies = list(s.bodies)
            self.loads = list(s.loads)
            if s.u_aux.shape[0]:
                raise SceneError("from_mechanics: auxiliary speeds are not supported")
            if s.u.shape[0]:
                sol = sp.solve(list(s.kdes), [c.diff(t) for c in self.q], dict=True)
                if len(sol) != 1:
                    raise SceneError(
                        "from_mechanics: the System's kinematic differential equations do not"
                        " give q_dot uniquely"
                    )
                self._speeds(list(s.u), sol[0], "System")
            else:
                self.basis = [c.diff(t) for c in self.q]
                self.S = None
            self.velocity_rows, self.velocity_offsets = [], []
            nh = sp.Matrix(s.nonholonomic_constraints)
            if nh.rows:
                nh = nh.xreplace(self._qdot_map())
                K = nh.jacobian(self.basis)
                self._rows_from(K, nh - K * sp.Matrix(self.basis))
            self.holonomic = list(s.holonomic_constraints)
        if self.S is None:
            self._check_basis_names()

    # -- helpers --------------------------------------------------------------------------
    def _speeds(self, u: list[sp.Expr], qdot_map: dict, source: str) -> None:
        me = _me()
        t = me.dynamicsymbols._t
        qd = [c.diff(t) for c in self.q]
        missing = [d for d in qd if d not in qdot_map]
        if missing:
            raise SceneError(
                f"from_mechanics: the {source} kinematic differential equations do not give"
                f" {missing}"
            )
        rhs = sp.Matrix([qdot_map[d] for d in qd])
        S = rhs.jacobian(u)
        offset = (rhs - S * sp.Matrix(u)).applyfunc(sp.expand)
        if any(e != 0 for e in offset):
            raise SceneError(
                f"from_mechanics: the kinematic differential equations must read q_dot = S(q) u;"
                f" {list(offset)} is left over (a part free of the speeds)"
            )
        if any(a.has(*u) or a.has(*qd) for a in S):
            raise SceneError("from_mechanics: q_dot = S u with S depending on the speeds")
        # speeds no kinematic equation reaches get an ignorable coordinate
        extra = [r for r in range(len(u)) if all(S[i, r] == 0 for i in range(S.rows))]
        if S.rows + len(extra) != len(u):
            raise SceneError(
                f"from_mechanics: {len(self.q)} coordinates and {len(u)} speeds; the speeds"
                f" {[u[r] for r in extra]} reach no coordinate, which leaves the frame S"
                " non-square"
            )
        taken = {str(c.func) for c in (*self.q, *u)}
        for r in extra:
            name = f"q_{u[r].func}"
            while name in taken:
                name += "_"
            taken.add(name)
            self.q.append(me.dynamicsymbols(name))
            S = S.col_join(sp.Matrix([[1 if c == r else 0 for c in range(len(u))]]))
        self.basis, self.S = u, S
        self._qdot = dict(zip([c.diff(t) for c in self.q], list(S * sp.Matrix(u)), strict=True))

    def _qdot_map(self) -> dict:
        return getattr(self, "_qdot", {})

    def _rows_from(self, K: sp.Matrix, offset: sp.Matrix) -> None:
        for a in range(K.rows):
            self.velocity_rows.append(list(K.row(a)))
            self.velocity_offsets.append(sp.expand(offset[a]))

    def _check_basis_names(self) -> None:
        names = [str(c.func) for c in self.q]
        if len(set(names)) != len(names):
            raise SceneError(f"from_mechanics: repeated coordinate names {names}")


def _in_basis(vec: Any, model: _Model) -> Any:
    """A velocity vector with q_dot replaced by S u (the Kane case)."""
    qmap = model._qdot_map()
    return vec.xreplace(qmap) if qmap else vec


def _partials(vec: Any, model: _Model, what: str) -> list[Any]:
    """The partial velocities d vec / d w^r, after checking vec is linear with no offset
    (computed once per vector, whatever the caller: the metric, the loads and the inertia
    forces share them; ``what`` names it in the error of the first)."""
    hit = model.partials.get(vec)
    if hit is None:
        hit = model.partials[vec] = _partials_of(vec, model, what)
    return hit


def _partials_of(vec: Any, model: _Model, what: str) -> list[Any]:
    frame = model.frame
    vec = _in_basis(vec, model)
    parts = [vec.diff(w, frame, var_in_dcm=False) for w in model.basis]
    rest = vec.xreplace({w: 0 for w in model.basis})
    if rest != 0 and rest.to_matrix(frame).applyfunc(sp.expand) != sp.zeros(3, 1):
        raise SceneError(
            f"from_mechanics: {what} has a part free of the velocities ({rest}); symmech"
            " needs scleronomic kinematics (no prescribed motion)"
        )
    return parts


def _dot(a: Any, b: Any, expand: bool = True) -> sp.Expr:
    """``a . b``; with ``expand``, expanded and summed term by term: ``b_i D_ij a_j`` over
    the frame components of a and b with ``D`` the direction cosines between their frames
    (what ``sympy.physics.vector`` multiplies as matrices).  The expansion of a polynomial
    in the same atoms is the same expression whichever way its terms were grouped, so
    this is ``sp.expand(a & b)`` without the matrix products."""
    if a == 0 or b == 0:
        return sp.S.Zero
    if not expand:
        return a & b
    terms = []
    for ca, fa in a.args:
        for cb, fb in b.args:
            D = fb.dcm(fa)
            terms += [
                cb[i] * D[i, j] * ca[j]
                for i in range(3)
                if cb[i] != 0
                for j in range(3)
                if D[i, j] != 0 and ca[j] != 0
            ]
    return sp.expand(sp.Add(*terms))


def _metric(model: _Model) -> sp.Matrix:
    """M_rs = sum m v_P,r . v_P,s + w_B,r . I_B . w_B,s (module docstring)."""
    me = _me()
    n = len(model.basis)
    M = sp.zeros(n, n)
    for body in model.bodies:
        vel = _partials(body.masscenter.vel(model.frame), model, f"{body}: mass centre velocity")
        for r in range(n):
            for s in range(r, n):
                M[r, s] += body.mass * _dot(vel[r], vel[s])
        if isinstance(body, me.RigidBody):
            w = _partials(body.frame.ang_vel_in(model.frame), model, f"{body}: angular velocity")
            inertia = body.central_inertia
            Iw = [(inertia & x) if x != 0 else 0 for x in w]
            for r in range(n):
                for s in range(r, n):
                    M[r, s] += _dot(w[r], Iw[s])
    from symmech.algebra.simplification import normal_form

    for r in range(n):
        for s in range(r, n):
            M[r, s] = normal_form(M[r, s])  # the Pythagorean reduction, within its budget
        for s in range(r):
            M[r, s] = M[s, r]
    return M


def _from_lagrangian(model: _Model) -> tuple[sp.Matrix, sp.Expr]:
    """(M, V) of a Lagrangian ``L = 1/2 q_dot^T M q_dot - V``: M its Hessian in q_dot, V
    minus its value at q_dot = 0; a part linear in q_dot (gyroscopic, a moving frame) is
    refused."""
    L = sp.expand(model.lagrangian)
    qd = model.basis
    M = sp.hessian(L, qd).applyfunc(sp.expand)
    L0 = L.xreplace({d: 0 for d in qd})
    linear = sp.expand(L - L0 - (sp.Matrix(qd).T * M * sp.Matrix(qd))[0] / 2)
    if linear != 0:
        raise SceneError(
            f"from_mechanics: the Lagrangian has terms linear in the velocities ({linear});"
            " symmech takes L = T - V with T quadratic"
        )
    return M, -L0


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
    me = _me()
    t = me.dynamicsymbols._t
    comps = vec.to_matrix(frame)
    return not any(e.has(t) for e in comps)


def _loads(model: _Model) -> tuple[sp.Expr, list[sp.Expr]]:
    """(V, F): the potential of the verified conservative forces and the other loads'
    generalized active forces (module docstring)."""
    me = _me()
    n = len(model.basis)
    V = sp.S.Zero
    F = [sp.S.Zero] * n
    for load in model.loads:
        where, vector = load[0], load[1]
        if isinstance(where, me.ReferenceFrame):
            w = _partials(where.ang_vel_in(model.frame), model, f"torque on {where}")
            F = [a + _dot(vector, b) for a, b in zip(F, w, strict=True)]
            continue
        vel = _partials(where.vel(model.frame), model, f"force at {where}")
        Fr = [_dot(vector, b) for b in vel]
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


def _is_gradient(V: sp.Expr, Fr: Sequence[sp.Expr], model: _Model) -> bool:
    """Whether ``F_r = -(S^T dV/dq)_r`` holds at random points (ties the candidate potential
    to the force's generalized active force)."""
    grad = sp.Matrix([sp.diff(V, c) for c in model.q])
    lhs = model.S.T * grad if model.S is not None else grad
    return _identically_zero([a + b for a, b in zip(lhs, Fr, strict=True)])


def _constraint_rows(model: _Model) -> list[list[sp.Expr]]:
    """The velocity constraints and the differentiated holonomic ones, independent rows."""
    bad = [e for e in model.velocity_offsets if e != 0]
    if bad:
        raise SceneError(
            f"from_mechanics: velocity constraints with a part free of the speeds {bad}; symmech"
            " takes homogeneous constraints mu(q) v = 0"
        )
    rows = [list(r) for r in model.velocity_rows]
    for h in model.holonomic:
        grad = sp.Matrix([[sp.diff(h, c) for c in model.q]])
        rows.append(list(grad * model.S if model.S is not None else grad))
    if not rows:
        return []
    M = sp.Matrix(rows)
    point = Points([]).for_(M)[0]
    kept: list[int] = []
    for a in range(len(rows)):
        if rank_at(M.extract([*kept, a], list(range(M.cols))), point) == len(kept) + 1:
            kept.append(a)
    # the differentiated holonomic rows are expanded once kept (a dropped one, often the
    # derivative of a velocity constraint the model also gives, is never expanded)
    first = len(model.velocity_rows)
    return [rows[a] if a < first else [sp.expand(e) for e in rows[a]] for a in kept]


def _inertia_forcing(model: _Model) -> list[sp.Expr]:
    """Kane's generalized inertia forces without the u_dot terms (slides 000, Kane's
    method): ``-sum m a0_P . v_P,r - (I . alpha0 + w x I . w) . w_r`` where ``a0`` and
    ``alpha0`` are the accelerations with ``u_dot = 0`` (``q_dot = S u`` substituted)."""
    me = _me()
    t = me.dynamicsymbols._t
    frame = model.frame
    n = len(model.basis)
    still = {w.diff(t): 0 for w in model.basis}
    f = [sp.S.Zero] * n
    for body in model.bodies:
        v = _in_basis(body.masscenter.vel(frame), model)
        parts = _partials(body.masscenter.vel(frame), model, f"{body}: mass centre velocity")
        a0 = _in_basis(v.dt(frame).xreplace(still), model)
        for r in range(n):
            f[r] -= body.mass * _dot(a0, parts[r], expand=False)
        if isinstance(body, me.RigidBody):
            w = _in_basis(body.frame.ang_vel_in(frame), model)
            wparts = _partials(body.frame.ang_vel_in(frame), model, f"{body}: angular velocity")
            alpha0 = _in_basis(w.dt(frame).xreplace(still), model)
            inertia = body.central_inertia
            torque = (inertia & alpha0) + (w ^ (inertia & w))
            for r in range(n):
                f[r] -= _dot(torque, wparts[r], expand=False)
    return f


def _embedded_correction(
    model: _Model, tr: DynamicTranslation, M: sp.Matrix, S: sp.Matrix | None
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


def scene_arguments(model: object, *, walls: Sequence = (), name: str | None = None) -> dict:
    """The keyword arguments of :class:`symmech.Scene` for a mechanics model (module
    docstring): coordinates, metric, potential, forces, constraints, frame and
    quasi-velocities.  The model's dynamic symbols are translated to symmech's
    (:class:`~symmech.declaration.dynamic.DynamicTranslation`, walls included) here, once,
    as the declaration would translate them: the correction of the inertia forces needs
    the metric and frame in symmech's symbols, and the declaration then has nothing left
    to translate."""
    model_ = _Model(model)
    framed = model_.S is not None
    tr = DynamicTranslation(model_.q, model_.basis if framed else None, _me().dynamicsymbols._t)

    def plain(value: Any, field: str) -> Any:
        return tr.expr(value, field)

    S = plain(model_.S, "frame") if framed else None
    if model_.lagrangian is not None:
        M, V0 = _from_lagrangian(model_)
        V, F = _loads(model_)
        M, V, F = plain(M, "metric"), plain(V + V0, "potential"), plain(F, "forces")
    else:
        M = plain(_metric(model_), "metric")
        V, F = _loads(model_)
        V, F = plain(V, "potential"), plain(F, "forces")
        correction = _embedded_correction(model_, tr, M, S)
        if correction is not None:
            F = [a + b for a, b in zip(F, correction, strict=True)]
    rows = [plain(r, f"constraints[{a}]") for a, r in enumerate(_constraint_rows(model_))]
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
