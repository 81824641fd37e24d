"""Round trips of imported ``sympy.physics.mechanics`` models: the accelerations of the
imported scene (symmech's M, f and constraints, solved numerically) against the model's
own ``mass_matrix_full \\ forcing_full`` at random states (the independent route)."""

from __future__ import annotations

import numpy as np
import sympy as sp
from sympy.physics import mechanics as me

import symmech as sm

T = me.dynamicsymbols._t


def _parameter_values(scene: sm.Scene, values: dict) -> dict:
    """The values of the scene's parameters by name; one the model's equations do not
    contain (a constant of the potential) gets 0.7: it must not matter."""
    byname = {k.name: v for k, v in values.items() if isinstance(k, sp.Symbol)}
    return {p: byname.get(p.name, 0.7) for p in scene.parameters}


def scene_accelerations(scene: sm.Scene, values: dict, qs, vs) -> np.ndarray:
    """v_dot from symmech's M, f, mu and mu_dot v, solved numerically (bordered system)."""
    sub = _parameter_values(scene, values)
    sub |= dict(zip(scene.coordinates, qs, strict=True))
    sub |= dict(zip(scene.velocities, vs, strict=True))
    inputs = {a: v for a, v in values.items() if isinstance(a, sp.core.function.AppliedUndef)}
    for a, v in inputs.items():
        sub[sp.Function(str(a.func), real=True)(sm.t)] = v

    def num(M):
        return np.array(sp.Matrix(M).xreplace(sub).evalf(30), dtype=float)

    M = num(scene.mass_matrix())
    f = num(scene.forcing()).ravel()
    m = scene.declaration.m
    if not m:
        return np.linalg.solve(M, f)
    mu = num(scene.constraint_matrix)
    rate = num(scene.constraint_rate()).ravel()
    K = np.block([[M, mu.T], [mu, np.zeros((m, m))]])
    return np.linalg.solve(K, np.concatenate([f, -rate]))[: scene.n]


def model_basis(model) -> list:
    """The model's velocities: its generalized speeds, or the q_dots (Lagrange; a System
    formed with LagrangesMethod orders them as its q, not as its joints' speeds)."""
    if isinstance(getattr(model, "eom_method", None), me.LagrangesMethod):
        return [c.diff(T) for c in model.q]
    u = getattr(model, "u", None)
    return list(u) if u is not None and len(u) else [c.diff(T) for c in model.q]


def model_accelerations(model, values: dict, qs, vs, basis) -> np.ndarray:
    """The rates of ``basis`` from the model's own ``mass_matrix_full`` and
    ``forcing_full`` (Lagrange multipliers, if any, dropped)."""
    sub = dict(values)
    sub |= dict(zip(list(model.q), qs, strict=False))
    sub |= dict(zip(basis, vs, strict=True))
    MM = np.array(model.mass_matrix_full.xreplace(sub).evalf(30), dtype=float)
    FF = np.array(model.forcing_full.xreplace(sub).evalf(30), dtype=float).ravel()
    k = len(model.q)
    return np.linalg.solve(MM, FF)[k : k + len(basis)]


def consistent_speeds(scene: sm.Scene, values: dict, qs, rng) -> np.ndarray:
    """Random speeds in the constraints' kernel (the constraint rows at qs)."""
    n, m = scene.n, scene.declaration.m
    v = rng.uniform(-1, 1, n)
    if not m:
        return v
    sub = _parameter_values(scene, values)
    sub |= dict(zip(scene.coordinates, qs, strict=True))
    mu = np.array(scene.constraint_matrix.xreplace(sub).evalf(30), dtype=float)
    _, _, Vt = np.linalg.svd(mu)
    kernel = Vt[m:].T
    return kernel @ rng.uniform(-1, 1, n - m)


def worst_difference(model, scene: sm.Scene, values: dict, *, seed: int = 7, states: int = 3):
    """The largest difference between the scene's accelerations and the model's own at
    ``states`` random states (time-dependent inputs of the model given random values)."""
    rng = np.random.default_rng(seed)
    basis = model_basis(model)
    k = len(model.q)
    values = dict(values)
    seen = set(model.q) | set(basis)
    for e in model.forcing_full:
        for a in e.atoms(sp.core.function.AppliedUndef):
            if a.args == (T,) and a not in seen and a not in values:
                values[a] = rng.uniform(-1, 1)
    worst = 0.0
    for _ in range(states):
        qs = rng.uniform(-0.8, 0.8, scene.n)
        vs = consistent_speeds(scene, values, qs, rng)
        ours = scene_accelerations(scene, values, qs, vs)
        theirs = model_accelerations(model, values, qs[:k], vs, basis)
        worst = max(worst, float(np.max(np.abs(ours - theirs) / (1 + np.abs(theirs)))))
    return worst


def random_values(model, seed: int = 11) -> dict:
    """Values in [0.5, 1.5] for the symbols of the model's equations (its parameters)."""
    rng = np.random.default_rng(seed)
    symbols = set()
    for e in (*model.mass_matrix_full, *model.forcing_full):
        symbols |= {s for s in e.free_symbols if isinstance(s, sp.Symbol) and s != T}
    return {s: float(rng.uniform(0.5, 1.5)) for s in sorted(symbols, key=str)}


def round_trip(model, name: str = "model") -> tuple[str, object]:
    """``("imported", worst difference)`` or ``("refused", the SceneError's message)``."""
    values = random_values(model)
    try:
        scene = sm.Scene.from_mechanics(model, name=name)
    except sm.SceneError as exc:
        return "refused", str(exc)
    return "imported", worst_difference(model, scene, values)


def c_worst_difference(model, scene: sm.Scene, values: dict, *, seed: int = 3, states: int = 3):
    """The largest difference between the accelerations of the scene's generated C
    (``rhs``) and the model's own at ``states`` random states (time-dependent inputs of
    the model given random values)."""
    mod = sm.codegen.generate(scene, target="c", functions=["rhs"]).load()
    basis = model_basis(model)
    inputs = sorted(
        {a for e in model.forcing_full for a in e.atoms(sp.core.function.AppliedUndef)}
        - set(model.q)
        - set(basis),
        key=str,
    )
    rng = np.random.default_rng(seed)
    byname = {str(k): v for k, v in values.items()}
    params = {p: byname.get(p, 0.7) for p in mod.parameters}
    given = {str(a.func): float(rng.uniform(-1, 1)) for a in inputs}
    model_values = {**values, **{a: given[str(a.func)] for a in inputs}}
    worst = 0.0
    for _ in range(states):
        qs = rng.uniform(-0.8, 0.8, scene.n)
        vs = consistent_speeds(scene, values, qs, rng)
        ours = mod.rhs(np.concatenate([qs, vs]), params, inputs=given or None)[scene.n :]
        theirs = model_accelerations(model, model_values, qs[: len(model.q)], vs, basis)
        worst = max(worst, float(np.max(np.abs(ours - theirs) / (1 + np.abs(theirs)))))
    return worst
