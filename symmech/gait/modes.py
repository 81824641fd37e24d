"""Hybrid systems with modes: the declaration of a gait.

A :class:`Gait` is a set of *modes*, each a :class:`~symmech.Scene` (its own coordinates,
metric, potential, forces and permanent constraints), and *transitions* between them
(Grizzle et al., "Feedback Control of Dynamic Bipedal Robot Locomotion", 2007, ch. 3;
``../shared/design/gaits.md``).  A :class:`Transition` from mode ``j`` to mode ``k``

* fires on a *guard*: a wall ``psi`` of mode ``j``'s scene reached from above
  (``psi -> 0`` with ``d psi/dt < 0``), and only where its *condition* ``c(q) > 0`` holds
  (the swing foot ahead of the stance foot; scuffing at mid-stance is ignored);
* maps the state by a :class:`Reset` ``x+ = R(x-)``: symbolic expressions of the source
  state ``(q, v)`` and the parameters giving the target state.

A reset is usually an impact followed by a relabelling (:func:`impact_reset`): the source
state is embedded into the coordinates of an *impact scene* (the walker with its hip or
its feet free), the closed-form impact map of one of its walls is applied (restitution
and impulsive constraints, e.g. the new stance foot sticks: Carnot paper eqs. 10 and 17),
and a coordinate map takes the result into the target mode (the leg swap).  The energy
check of the impact part is the impact map's own (:meth:`~symmech.impacts.ImpactMap.
energy_change`), decided on the scene's parameters.  :func:`pinned_scene` derives a mode
from an impact scene by a holonomic embedding (the pull-back of its metric, potential,
forces and walls), so mode and impact scene describe one body.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import sympy as sp

from symmech.declaration.symbols import velocities
from symmech.declaration.wall import Wall
from symmech.errors import SceneError
from symmech.scene import Scene

__all__ = ["Gait", "Reset", "Transition", "impact_reset", "pinned_scene"]


@dataclass(frozen=True)
class Reset:
    """``x+ = R(x-)``: ``position`` (the target's coordinates) and ``velocity`` (its
    velocities) as expressions in the source's coordinates and velocities and the
    parameters.  ``impact`` names the impact it contains (for messages); ``dissipative``
    records the energy check of that impact (True: ``T(v+) <= T(v-)`` decided)."""

    position: sp.ImmutableMatrix
    velocity: sp.ImmutableMatrix
    impact: str = ""
    dissipative: bool | None = None

    @property
    def state(self) -> sp.ImmutableMatrix:
        """``R`` as one column ``(q+, v+)``."""
        return sp.ImmutableMatrix.vstack(self.position, self.velocity)

    def jacobian(self, source: Scene) -> sp.ImmutableMatrix:
        """``DR = d(q+, v+)/d(q-, v-)`` (the reset's part of the saltation matrix)."""
        y = [*source.coordinates, *source.velocities]
        return sp.ImmutableMatrix(self.state.jacobian(y))


@dataclass(frozen=True)
class Transition:
    """A transition ``source -> target`` on the wall ``guard`` of the source mode, where
    ``condition > 0`` (None: everywhere), mapping the state by ``reset``."""

    source: str
    target: str
    guard: str
    reset: Reset
    condition: sp.Expr | None = None
    name: str = ""

    @property
    def label(self) -> str:
        return self.name or f"{self.source}->{self.target} on {self.guard}"


@dataclass(frozen=True)
class Gait:
    """Modes (scenes by name) and transitions; see the module docstring.

    Checked when made: every guard is a wall of its source mode, every condition and
    reset a function of the source's state and the parameters, every reset of the
    target's size, every mode has a transition out of it and none depends on the time.
    The parameters are the union of the modes' (and the resets'), by name."""

    name: str
    modes: Mapping[str, Scene]
    transitions: tuple[Transition, ...]
    parameters: tuple[sp.Symbol, ...] = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "modes", dict(self.modes))
        object.__setattr__(self, "transitions", tuple(self.transitions))
        problems: list[str] = []
        if not self.modes:
            problems.append("no modes")
        for tr in self.transitions:
            problems += _transition_problems(self, tr)
        for mode, scene in self.modes.items():
            if not any(tr.source == mode for tr in self.transitions):
                problems.append(f"mode {mode!r} has no transition out of it")
            if scene.time_dependent:
                problems.append(
                    f"mode {mode!r} depends on the time t (its potential, forces or walls):"
                    " a stride map needs autonomous modes"
                )
        if problems:
            raise SceneError([f"gait {self.name!r}: {p}" for p in problems])
        names: dict[str, sp.Symbol] = {}
        for scene in self.modes.values():
            for p in scene.parameters:
                names.setdefault(p.name, p)
        for tr in self.transitions:
            for e in (*tr.reset.state, *([tr.condition] if tr.condition is not None else [])):
                for s in sorted(e.free_symbols, key=str):
                    if s.name not in names and s not in _state_symbols(self.modes[tr.source]):
                        names[s.name] = s
        object.__setattr__(self, "parameters", tuple(names[k] for k in sorted(names)))

    def transition(self, key: int | str) -> Transition:
        """A transition by index or name."""
        if isinstance(key, int):
            return self.transitions[key]
        for tr in self.transitions:
            if key in (tr.name, tr.label):
                return tr
        raise SceneError(f"gait {self.name!r}: no transition {key!r}")

    def outgoing(self, mode: str) -> tuple[Transition, ...]:
        return tuple(tr for tr in self.transitions if tr.source == mode)


def _state_symbols(scene: Scene) -> set[sp.Symbol]:
    return {*scene.coordinates, *scene.velocities}


def _transition_problems(gait: Gait, tr: Transition) -> list[str]:
    label = f"transition {tr.label!r}"
    if tr.source not in gait.modes or tr.target not in gait.modes:
        return [f"{label}: modes {tr.source!r} and {tr.target!r} must both be declared"]
    source, target = gait.modes[tr.source], gait.modes[tr.target]
    out = []
    if tr.guard not in {w.name for w in source.walls}:
        walls = [w.name for w in source.walls]
        out.append(f"{label}: the guard {tr.guard!r} is not a wall of mode {tr.source!r} {walls}")
    if tr.reset.position.shape != (target.n, 1) or tr.reset.velocity.shape != (target.n, 1):
        out.append(
            f"{label}: the reset gives {tr.reset.position.rows} coordinates and"
            f" {tr.reset.velocity.rows} velocities; mode {tr.target!r} has {target.n}"
        )
    params = {p.name for p in (*source.parameters, *target.parameters)}
    allowed = _state_symbols(source)
    if tr.condition is not None and tr.condition.free_symbols & set(source.velocities):
        out.append(f"{label}: the condition depends on velocities; it is a function of q")
    for what, exprs in (
        ("reset", tr.reset.state),
        ("condition", [] if tr.condition is None else [tr.condition]),
    ):
        stray = {s for e in exprs for s in e.free_symbols - allowed if s.name not in params}
        if stray:
            out.append(
                f"{label}: the {what} uses {sorted(map(str, stray))}, which are neither the"
                f" state of mode {tr.source!r} nor parameters"
            )
    return out


def pinned_scene(
    impact_scene: Scene,
    embedding: Mapping[sp.Symbol, sp.Expr],
    coordinates: Sequence[sp.Symbol],
    *,
    name: str,
    walls: Sequence[str] | None = None,
) -> Scene:
    """The mode whose configurations are ``Q = E(q)`` in ``impact_scene``: the pull-back
    ``g_q = J^T G(E(q)) J`` of the metric (``J = dE/dq``), ``V(E(q))``, the forces
    ``J^T F`` and the walls ``psi(E(q))`` (the named ones; default all), for the holonomic
    embedding ``E`` given as ``{Q_i: expression in q}`` for every coordinate of the
    impact scene (a stance foot pinned: the hip's position a function of the leg angles).

    The metric's entries are simplified (``trigsimp``): ``sin^2 + cos^2`` from a rigid
    leg collapse, which keeps the generated code small.  Frames and permanent constraints
    of the impact scene are refused (the embedding is the mode's constraint)."""
    Q = list(impact_scene.coordinates)
    missing = [str(s) for s in Q if s not in embedding]
    if missing or len(embedding) != len(Q):
        raise SceneError(
            f"pinned_scene {name!r}: the embedding must give every coordinate of scene"
            f" {impact_scene.name!r} {[str(s) for s in Q]}; missing {missing}"
        )
    if impact_scene.frame is not None or impact_scene.is_constrained:
        raise SceneError(
            f"pinned_scene {name!r}: scene {impact_scene.name!r} has a frame or constraints;"
            " give the impact scene in coordinate velocities without permanent constraints"
        )
    q = list(coordinates)
    E = sp.Matrix([embedding[s] for s in Q])
    J = E.jacobian(q)
    sub = dict(zip(Q, E, strict=True))
    G = sp.Matrix(impact_scene.mass_matrix()).xreplace(sub)
    g = (J.T * G * J).applyfunc(lambda e: sp.trigsimp(sp.expand(e)))
    V = sp.trigsimp(sp.sympify(impact_scene.potential, strict=True).xreplace(sub))
    F = sp.Matrix(impact_scene.forces)
    forces = None
    if any(e != 0 for e in F):
        Qdot = list(impact_scene.velocities)
        qdot_sub = dict(zip(Qdot, J * sp.Matrix(velocities(tuple(q))), strict=True))
        forces = list(J.T * F.xreplace(sub).xreplace(qdot_sub))
    chosen = [w for w in impact_scene.walls if walls is None or w.name in walls]
    pulled = [
        Wall(sp.trigsimp(w.psi.xreplace(sub)), restitution=w.restitution, name=w.name)
        for w in chosen
    ]
    return Scene(
        q,
        metric=g,
        potential=V,
        forces=forces,
        walls=pulled,
        name=name,
    )


def impact_reset(
    source: Scene,
    impact_scene: Scene,
    wall: str,
    embedding: Mapping[sp.Symbol, sp.Expr],
    relabel: Sequence[sp.Expr],
) -> Reset:
    """The reset ``q+ = F(E(q))``, ``v+ = DF (impact map)(E(q), DE v)``.

    ``embedding`` gives the impact scene's coordinates ``Q = E(q)`` in the source mode's
    coordinates (as for :func:`pinned_scene`); the impact is the closed-form map of
    ``wall`` of ``impact_scene`` (its restitution and impulsive constraints: the new
    stance foot sticks with restitution 0 and its tangential velocity held); ``relabel``
    gives the target mode's coordinates ``F(Q)`` in the impact scene's coordinates (the
    leg swap).  The impact's energy change ``T(v+) - T(v-)`` (Carnot paper, section 3)
    is checked: a map that can gain energy is refused."""
    q, v = list(source.coordinates), list(source.velocities)
    Q = list(impact_scene.coordinates)
    if any(s not in embedding for s in Q):
        raise SceneError(
            f"impact_reset: the embedding must give every coordinate of {impact_scene.name!r}"
        )
    E = sp.Matrix([embedding[s] for s in Q])
    sub = dict(zip(Q, E, strict=True))
    imp = impact_scene.impact_map(wall)
    V_pre = E.jacobian(q) * sp.Matrix(v)
    vel_sub = dict(zip(imp.velocities, V_pre, strict=True))
    V_post = sp.Matrix(imp.post_velocity).xreplace(sub).xreplace(vel_sub)
    Fq = sp.Matrix(list(relabel))
    DF = Fq.jacobian(Q)
    position = Fq.xreplace(sub).applyfunc(sp.trigsimp)
    velocity = DF.xreplace(sub) * V_post
    dissipative = _dissipative(imp, wall, impact_scene)
    return Reset(
        position=sp.ImmutableMatrix(position),
        velocity=sp.ImmutableMatrix(velocity),
        impact=f"{impact_scene.name}:{wall}",
        dissipative=dissipative,
    )


def _dissipative(imp: object, wall: str, scene: Scene, samples: int = 24) -> bool:
    """``T(v+) - T(v-) <= 0`` for every pre-impact velocity, checked numerically.

    For ``v+ = A(q) v-`` (Newton law, static wall) the energy change is ``v^T K v / 2``
    with ``K = A^T g A - g``, which must be negative semi-definite.  It is evaluated at
    ``samples`` random configurations in ``[-1, 1]^n`` and parameters in ``[1/2, 2]``
    (positive symbols) or ``[-2, 2]``, with a fixed seed; a positive eigenvalue beyond
    rounding refuses the reset with the point.
    (The Carnot theorems of paper 002 decide the sign symbolically only without impulsive
    constraints or when P(Y^0) lies in F; heel strikes have impulsive constraints.)"""
    import numpy as np

    A = sp.Matrix(imp.matrix)  # type: ignore[attr-defined]
    G = sp.Matrix(scene.mass_matrix())
    syms = sorted(A.free_symbols | G.free_symbols, key=str)
    fA = sp.lambdify(syms, A, modules="numpy", cse=True)
    fG = sp.lambdify(syms, G, modules="numpy", cse=True)
    rng = np.random.default_rng(20261127)
    for _ in range(samples):
        point = [rng.uniform(0.5, 2) if s.is_positive else rng.uniform(-1, 1) for s in syms]
        a, g = np.asarray(fA(*point), dtype=float), np.asarray(fG(*point), dtype=float)
        K = a.T @ g @ a - g  # T(v+) - T(v-) = v^T K v / 2 for v+ = A v
        eig = np.linalg.eigvalsh((K + K.T) / 2)
        scale = max(1.0, float(np.max(np.abs(eig))))
        if eig[-1] > 1e-9 * scale:
            where = ", ".join(f"{s} = {x:.3g}" for s, x in zip(syms, point, strict=True))
            raise SceneError(
                f"impact {scene.name}:{wall}: the impact gains energy at {where}"
                f" (the energy change's form has the eigenvalue {eig[-1]:.3g} > 0)"
            )
    return True
