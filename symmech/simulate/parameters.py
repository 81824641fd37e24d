"""The parameters of a run, checked once: every parameter given, finite, with the sign its
symbol declares (positive, nonnegative), and every restitution in [0, 1], so that the
loop's evaluations never fail on a bad parameter half way through a run.  Values are real
numbers by the rule of the generated code's arguments
(:func:`symmech.codegen.runtime_checks.real_array`)."""

from __future__ import annotations

import math
import weakref
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import sympy as sp

from symmech.codegen import CodegenError
from symmech.codegen.runtime_checks import real_array
from symmech.scene import Scene
from symmech.simulate.system import SimulationError

__all__ = ["check_parameters", "real_number", "real_scalar", "real_values"]


def real_values(value: object, what: str) -> np.ndarray:
    """``value`` as float64 by the rule of the generated code's arguments
    (:func:`symmech.codegen.runtime_checks.real_array`: real numbers of any NumPy or Python
    type, sympy numbers included; booleans, strings, bytes, complex and masked values
    refused), or a :class:`SimulationError` naming ``what``."""
    try:
        return real_array(value, what)
    except CodegenError as exc:
        raise SimulationError(str(exc)) from None


def real_scalar(value: object, what: str) -> float:
    """One real number (by :func:`real_values`' rule) as a float, finite or not."""
    if type(value) is float:  # the common case, exactly this type
        return value
    a = real_values(value, what)
    if a.ndim != 0:
        raise SimulationError(f"{what}: expected a real number, got {value!r}")
    return float(a)


def real_number(value: object, what: str) -> float:
    """One finite real number (by :func:`real_values`' rule) as a float."""
    x = real_scalar(value, what)
    if not math.isfinite(x):
        raise SimulationError(f"{what}: expected a finite real number, got {value!r}")
    return x


@dataclass(frozen=True)
class _ParameterRules:
    """What :func:`check_parameters` checks, prepared once per scene."""

    names: tuple[str, ...]
    positive: tuple[bool, ...]
    nonnegative: tuple[bool, ...]
    #: (wall name, restitution as printed, its value as a function of the parameters)
    restitutions: tuple[tuple[str, str, Any], ...]
    #: the last plain ``{name: float}`` that passed, and its checked values (a run repeated
    #: with the same parameters is not checked again); one slot, replaced whole
    last: list[tuple[dict[str, float], dict[str, float]]] = field(
        default_factory=list, compare=False
    )


_RULES: weakref.WeakKeyDictionary[Scene, _ParameterRules] = weakref.WeakKeyDictionary()


def _rules(scene: Scene) -> _ParameterRules:
    rules = _RULES.get(scene)
    if rules is None:
        params = list(scene.parameters)
        restitutions = []
        for w in scene.walls:
            alpha = sp.sympify(w.restitution, strict=True)
            fn = sp.lambdify(params, alpha, modules="math")
            restitutions.append((w.name, str(w.restitution), fn))
        rules = _ParameterRules(
            tuple(str(p) for p in params),
            tuple(bool(p.is_positive) or p in scene.declaration.assumed_positive for p in params),
            tuple(bool(p.is_nonnegative) for p in params),
            tuple(restitutions),
        )
        _RULES[scene] = rules
    return rules


def check_parameters(scene: Scene, params: object) -> dict[str, float]:
    """``params`` as ``{name: value}``, every scene parameter given, finite, and with the
    sign its symbol declares (positive, nonnegative) and restitutions in [0, 1]."""
    rules = _rules(scene)
    plain = None
    if type(params) is dict and all(type(x) is float for x in params.values()):
        plain = params
    if plain is not None and rules.last and rules.last[0][0] == plain:
        return dict(rules.last[0][1])
    out = _checked_parameters(rules, params)
    if plain is not None:
        rules.last[:] = [(dict(plain), dict(out))]
    return out


def _checked_parameters(rules: _ParameterRules, params: object) -> dict[str, float]:
    names = list(rules.names)
    if params is None:
        params = {}
    if isinstance(params, Mapping):
        given = {str(k): v for k, v in params.items()}
    else:
        values = list(np.atleast_1d(np.asarray(params, dtype=object)))
        if len(values) != len(names):
            raise SimulationError(
                f"params: expected {len(names)} values for {names}, got {len(values)}"
            )
        given = dict(zip(names, values, strict=True))
    missing = [n for n in names if n not in given]
    unknown = sorted(set(given) - set(names))
    if missing or unknown:
        raise SimulationError(
            f"params: missing {missing}, unknown {unknown}; the scene's parameters are {names}"
        )
    out = {n: real_number(given[n], f"params[{n!r}]") for n in names}
    for name, pos, nonneg in zip(names, rules.positive, rules.nonnegative, strict=True):
        x = out[name]
        if pos and not x > 0:
            raise SimulationError(
                f"params[{name!r}] is declared positive (or, declared without a sign, the"
                f" metric needs it positive), got {x!r}"
            )
        if nonneg and not x >= 0:
            raise SimulationError(f"params[{name!r}] is declared non-negative, got {x!r}")
    values = [out[n] for n in names]
    for wall, printed, fn in rules.restitutions:
        alpha = float(fn(*values))
        if not (0 <= alpha <= 1):
            raise SimulationError(
                f"wall {wall!r}: restitution {printed} = {alpha!r} at these"
                " parameters is outside [0, 1]"
            )
    return out
