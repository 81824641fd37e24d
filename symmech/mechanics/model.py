"""The parts of a ``sympy.physics.mechanics`` model the import reads (KanesMethod,
LagrangesMethod or System): coordinates, velocity basis and frame ``q_dot = S u``, bodies,
loads (a System's actuators included), constraints and, for Lagrange models, the
Lagrangian.  How each is turned into a scene: :mod:`symmech.mechanics.convert`."""

from __future__ import annotations

import warnings
from typing import Any

import sympy as sp

from symmech.errors import SceneError, SymmechWarning
from symmech.mechanics.refusals import refuse_non_smooth

__all__ = ["Model", "mechanics"]


def mechanics() -> Any:
    """``sympy.physics.mechanics``, imported when a model is read."""
    from sympy.physics import mechanics

    return mechanics


def model_kind(model: object) -> str:
    me = mechanics()
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


def _warn_potential_energies(bodies: list[Any], who: str) -> None:
    """Kane's equations do not read ``potential_energy`` (sympy's KanesMethod forms the
    generalized active forces from the loads alone), so neither does the import of a Kane
    model; say so when a body has one, which the user may have meant to count."""
    named = [str(b) for b in bodies if getattr(b, "potential_energy", 0) != 0]
    if named:
        warnings.warn(
            f"from_mechanics: {who} ignores the potential_energy of {named} (its"
            " equations come from the loads), and so does the import; apply the force as"
            " a load, or form the equations with LagrangesMethod",
            SymmechWarning,
            stacklevel=4,
        )


class Model:
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
    lagrangian: sp.Expr | None = None  # L = T - V of a Lagrange model (its own, or its bodies')
    #: the model's attributes that hold each part, for the refusals ("kinematics":
    #: q_dot = S u; "constraints": velocity and configuration constraints)
    names: dict[str, str]
    #: the speeds as plain symbols and the memoised derivatives along them (set by the
    #: first partial velocity, :func:`symmech.mechanics.convert._speed_partials`)
    speed_symbols: tuple[dict, Any] | None = None

    def __init__(self, model: object):
        self.partials: dict = {}
        self.velocity_rows, self.velocity_offsets = [], []
        self.holonomic = []
        self.names = {}
        kind = model_kind(model)
        if kind == "kane":
            self._kane(model)
        elif kind == "lagrange":
            self._lagrange(model, "LagrangesMethod")
        else:
            self._system(model)
        if not self.q:
            raise SceneError(
                f"from_mechanics: the {type(model).__name__} has no generalized coordinates"
                " (q): symmech needs one coordinate per degree of freedom (a System's"
                " joints add theirs, or add_coordinates)"
            )
        if self.S is None:
            self._check_basis_names()

    def _kane(self, k: Any) -> None:
        if len(k._uaux):
            raise SceneError(
                f"from_mechanics: KanesMethod.u_auxiliary {list(k._uaux)}: auxiliary speeds"
                " (for constraint forces) are not supported; build the KanesMethod without"
                " u_auxiliary (its equations of motion do not depend on them)"
            )
        if not len(k.u):
            raise SceneError(
                "from_mechanics: the KanesMethod has no generalized speeds (u_ind=[]):"
                " symmech needs one speed per degree of freedom"
            )
        if getattr(k, "_qdot_u_map", None) is None:
            raise SceneError(
                "from_mechanics: the KanesMethod has no kinematic differential equations"
                " (kd_eqs=): symmech needs q_dot in terms of the speeds"
            )
        if k.bodies is None:
            raise SceneError(
                "from_mechanics: the KanesMethod has no bodies: its kanes_equations(bodies,"
                " loads) were never formed and no bodies= were given; form them first"
            )
        self.names = {
            "kinematics": "KanesMethod.kd_eqs",
            "constraints": "KanesMethod.velocity_constraints / configuration_constraints",
        }
        self.q = list(k.q)
        self.frame = k._inertial
        self.bodies = list(k.bodies or [])
        _warn_potential_energies(self.bodies, "KanesMethod")
        self.loads = list(k.loads or [])
        self._speeds(list(k.u), k.kindiffdict(), "KanesMethod")
        if k._k_nh is not None and k._k_nh.rows:
            self._rows_from(k._k_nh, k._f_nh)
        self.holonomic = list(k._f_h) if k._f_h is not None else []

    def _lagrange(self, lm: Any, source: str) -> None:
        """A LagrangesMethod: its equations come from its Lagrangian (bodies= only records
        the bodies, their potential energies are in L) and its loads; the q_dot basis."""
        t = mechanics().dynamicsymbols._t
        self.names = {
            "lagrangian": f"the Lagrangian of the {source}",
            "constraints": f"{source}: hol_coneqs / nonhol_coneqs",
        }
        self.q = list(lm.q)
        self.frame = lm.inertial
        self.bodies = list(lm._bodies or [])
        self.loads = list(lm.forcelist or [])
        if self.frame is None and self.loads:
            raise SceneError(
                f"from_mechanics: {source} has loads (forcelist) but no frame=; the loads'"
                " generalized forces need the inertial frame: pass frame=N"
            )
        self.basis = [c.diff(t) for c in self.q]
        self.S = None
        if lm.coneqs:
            cons = sp.Matrix(lm.coneqs)
            K = cons.jacobian(self.basis)
            self._rows_from(K, cons - K * sp.Matrix(self.basis))
        # LagrangesMethod differentiates its holonomic constraints into coneqs
        L = lm._L
        self.lagrangian = L[0] if isinstance(L, sp.MatrixBase) else sp.sympify(L, strict=True)

    def _system(self, s: Any) -> None:
        me = mechanics()
        t = me.dynamicsymbols._t
        if s.u_aux.shape[0]:
            raise SceneError(
                f"from_mechanics: System.u_aux {list(s.u_aux)}: auxiliary speeds are not"
                " supported; build the System without them"
            )
        if isinstance(s.eom_method, me.LagrangesMethod):
            self._lagrange(s.eom_method, "System (eom_method=LagrangesMethod)")
            self.origin = s.fixed_point
            return
        self.names = {
            "kinematics": "System.kdes",
            "lagrangian": "the Lagrangian of the System's bodies",
            "constraints": "System.nonholonomic_constraints / holonomic_constraints",
        }
        self.q = list(s.q)
        self.frame = s.frame
        self.origin = s.fixed_point
        self.bodies = list(s.bodies)
        # System.loads leaves the actuators out; form_eoms adds their loads the same way
        self.loads = [*s.loads, *(load for act in s.actuators for load in act.to_loads())]
        qd = [c.diff(t) for c in self.q]
        if s.u.shape[0] and set(s.u) <= set(qd) and not s.kdes.shape[0]:
            # joints whose speeds are the q_dots: a System built for LagrangesMethod
            self.basis, self.S = qd, None
            self.lagrangian = me.Lagrangian(self.frame, *self.bodies)
        elif s.u.shape[0]:
            _warn_potential_energies(self.bodies, "A System formed with KanesMethod")
            sol = sp.solve(list(s.kdes), qd, dict=True)
            if len(sol) != 1:
                raise SceneError(
                    "from_mechanics: the System's kinematic differential equations (kdes) do"
                    " not give q_dot uniquely"
                )
            self._speeds(list(s.u), sol[0], "System")
        else:
            self.basis, self.S = qd, None
        nh = sp.Matrix(s.nonholonomic_constraints)
        if nh.rows:
            nh = nh.xreplace(self._qdot_map())
            K = nh.jacobian(self.basis)
            self._rows_from(K, nh - K * sp.Matrix(self.basis))
        self.holonomic = list(s.holonomic_constraints)

    # -- helpers --------------------------------------------------------------------------
    def _speeds(self, u: list[sp.Expr], qdot_map: dict, source: str) -> None:
        me = mechanics()
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
                f"from_mechanics: {self.names['kinematics']}: the kinematic differential"
                f" equations must read q_dot = S(q) u; {list(offset)} is left over (a part"
                " free of the speeds: prescribed motion, which symmech's scleronomic systems"
                " do not have); make the speeds' definitions homogeneous in the speeds"
            )
        if any(a.has(*u) or a.has(*qd) for a in S):
            raise SceneError(
                f"from_mechanics: {self.names['kinematics']}: q_dot = S u with S depending on"
                " the speeds; symmech needs q_dot linear in the speeds"
            )
        refuse_non_smooth(
            S,
            f"{self.names['kinematics']} (q_dot = S(q) u)",
            "write the kinematic differential equations without them",
        )
        # speeds no kinematic equation reaches get an ignorable coordinate
        extra = [r for r in range(len(u)) if all(S[i, r] == 0 for i in range(S.rows))]
        if S.rows > len(u):
            raise SceneError(
                f"from_mechanics: {source} has {len(self.q)} coordinates {self.q} and only"
                f" {len(u)} speeds: coordinates tied by a configuration constraint (a unit"
                " quaternion, or q_dependent) are not supported, symmech needs q_dot = S(q) u"
                " with S square; use as many coordinates as speeds (for an orientation, three"
                " angles, e.g. orient_body_fixed)"
            )
        if S.rows + len(extra) != len(u):
            raise SceneError(
                f"from_mechanics: {self.names['kinematics']}: {len(self.q)} coordinates and"
                f" {len(u)} speeds; the speeds {[u[r] for r in extra]} reach no coordinate,"
                " which leaves the frame S non-square (give each speed a coordinate whose"
                " rate it sets, or leave it out)"
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
