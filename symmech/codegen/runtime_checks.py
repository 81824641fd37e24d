"""Run-time checks of generated code: the parameter vector and the arrays a caller passes.

**Parameters.**  The declaration constrains some parameters: a symbol's assumptions give
its sign (``positive``, ``nonnegative``, ``negative``, ``nonpositive``, ``nonzero``; a
scene file's ``sign``), and a wall's symbolic restitution ``alpha`` must lie in [0, 1]
(Carnot paper eqs. 8-9; ``alpha > 1`` gains energy, ``alpha < 0`` passes through the
wall).  :func:`parameter_rules` turns these into one :class:`ParameterRule` per run-time
parameter; every parameter must also be finite.  The rules are checked once per call,
never per state (they concern the parameter vector only):

* by the generated C function ``<prefix>check_parameters(p)`` (returns 0, or 1 + the index
  of the first parameter that breaks its rule), which the CPython extension calls before
  every one-state call (on failure it hands over to the general path, which explains);
* by :func:`check_parameters` in Python, for every call of a loaded module that is not
  served by the extension (NumPy backend, ctypes, batches): a non-finite value raises
  :class:`~symmech.codegen.plan.CodegenError`, a value outside its range
  :class:`~symmech.codegen.module.NumericalError`, each naming the parameter.

A C user calling the generated functions directly calls ``check_parameters`` once per
parameter vector; the generated functions themselves do not (they take the parameters as
given, as a BLAS routine takes its arguments).

**Arrays.**  :func:`real_array` converts what a caller passes (state arrays, parameters,
t, inputs) to float64, or raises a :class:`CodegenError` naming the argument: complex,
boolean, string, datetime and masked values are refused instead of being truncated,
counted as 0/1, parsed or unmasked; any byte order and memory layout is converted.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import sympy as sp

from symmech.codegen.plan import CodegenError

__all__ = [
    "ParameterRule",
    "check_parameters",
    "named_columns",
    "parameter_rules",
    "real_array",
]


@dataclass(frozen=True)
class ParameterRule:
    """What a run-time parameter ``p[index]`` must satisfy: finite, and
    ``lower < p`` (``lower <= p`` when ``closed_lower``), ``p < upper`` (``<=`` when
    ``closed_upper``), ``p != 0`` when ``nonzero``; ``why`` says where the rule comes
    from (its declaration, a wall's restitution)."""

    index: int
    name: str
    lower: float | None = None
    closed_lower: bool = True
    upper: float | None = None
    closed_upper: bool = True
    nonzero: bool = False
    why: str = ""

    @property
    def text(self) -> str:
        """The rule as a range, ``0 < m``, ``0 <= alpha <= 1``, ``m finite``."""
        parts = []
        if self.lower is not None:
            parts.append(f"{self.lower:g} {'<=' if self.closed_lower else '<'}")
        parts.append(self.name)
        if self.upper is not None:
            parts.append(f"{'<=' if self.closed_upper else '<'} {self.upper:g}")
        if self.nonzero:
            parts.append("!= 0")
        return " ".join(parts) if len(parts) > 1 else f"{self.name} finite"

    def c_condition(self, ref: str) -> str:
        """The C99 condition (an operand of ``!``) that holds exactly when the value ``ref``
        satisfies the rule: ``isfinite(p[0])``, ``(p[0] > 0.0 && isfinite(p[0]))``."""
        terms = []
        if self.lower is not None:
            terms.append(f"{ref} {'>=' if self.closed_lower else '>'} {_c_float(self.lower)}")
        if self.upper is not None:
            terms.append(f"{ref} {'<=' if self.closed_upper else '<'} {_c_float(self.upper)}")
        if self.nonzero:
            terms.append(f"{ref} != 0.0")
        terms.append(f"isfinite({ref})")
        return f"({' && '.join(terms)})" if len(terms) > 1 else terms[0]

    def numpy_condition(self, ref: str) -> str:
        """The NumPy expression (elementwise) of :meth:`c_condition`."""
        terms = [f"numpy.isfinite({ref})"]
        if self.lower is not None:
            terms.append(f"({ref} {'>=' if self.closed_lower else '>'} {_c_float(self.lower)})")
        if self.upper is not None:
            terms.append(f"({ref} {'<=' if self.closed_upper else '<'} {_c_float(self.upper)})")
        if self.nonzero:
            terms.append(f"({ref} != 0.0)")
        return " & ".join(terms)

    def holds_value(self, x: float) -> bool:
        """Whether one finite value satisfies the range (plain float comparisons)."""
        if self.lower is not None and not (
            x >= self.lower if self.closed_lower else x > self.lower
        ):
            return False
        if self.upper is not None and not (
            x <= self.upper if self.closed_upper else x < self.upper
        ):
            return False
        return not (self.nonzero and x == 0.0)

    def holds(self, values: np.ndarray) -> np.ndarray:
        """Elementwise: whether the finite ``values`` satisfy the range."""
        ok = np.ones(values.shape, dtype=bool)
        if self.lower is not None:
            ok &= values >= self.lower if self.closed_lower else values > self.lower
        if self.upper is not None:
            ok &= values <= self.upper if self.closed_upper else values < self.upper
        if self.nonzero:
            ok &= values != 0.0
        return ok


def _c_float(x: float) -> str:
    text = repr(float(x))
    return text if any(c in text for c in ".en") else text + ".0"


def parameter_rules(
    parameters: Sequence[sp.Symbol],
    restitutions: Mapping[sp.Symbol, Sequence[str]],
    assumed_positive: Sequence[sp.Symbol] = (),
) -> tuple[ParameterRule, ...]:
    """One rule per run-time parameter (module docstring): its sign from its assumptions
    (or positive when the declaration assumed it, ``assumed_positive``: a parameter without a
    sign that the metric needs positive), and [0, 1] if it is the restitution of the walls
    named in ``restitutions[p]``."""
    rules = []
    for i, p in enumerate(parameters):
        lower: float | None = None
        upper: float | None = None
        closed_lower = closed_upper = True
        nonzero = False
        why: list[str] = []
        if p.is_positive:
            lower, closed_lower, why = 0.0, False, ["declared positive"]
        elif p in assumed_positive:
            lower, closed_lower = 0.0, False
            why = ["declared without a sign; the metric is positive definite only for it > 0"]
        elif p.is_nonnegative:
            lower, why = 0.0, ["declared nonnegative"]
        elif p.is_negative:
            upper, closed_upper, why = 0.0, False, ["declared negative"]
        elif p.is_nonpositive:
            upper, why = 0.0, ["declared nonpositive"]
        elif p.is_nonzero:
            nonzero, why = True, ["declared nonzero"]
        walls = restitutions.get(p, ())
        if walls:
            if lower is None or lower < 0.0:
                lower, closed_lower = 0.0, True
            if upper is None or upper > 1.0:
                upper, closed_upper = 1.0, True
            nonzero = nonzero and lower == 0.0 and closed_lower
            names = ", ".join(repr(w) for w in walls)
            why.append(f"the restitution of wall{'s' if len(walls) > 1 else ''} {names}")
        rules.append(
            ParameterRule(
                i, p.name, lower, closed_lower, upper, closed_upper, nonzero, "; ".join(why)
            )
        )
    return tuple(rules)


def check_parameters(
    rules: Sequence[ParameterRule], p: np.ndarray, error: type[Exception], where: str
) -> None:
    """Check the parameter array ``p`` (shape (k,) or (..., k)) against ``rules`` once:
    a non-finite value raises :class:`CodegenError`, a value outside its range ``error``
    (``NumericalError``), each naming the parameter, its value and the rule."""
    if p.ndim == 1:  # one parameter vector: plain floats, no array operations
        values = p.tolist()
        for rule in rules:
            x = values[rule.index]
            if not math.isfinite(x):
                raise CodegenError(f"{where}: parameter {rule.name!r} = {x!r} is not finite")
            if not rule.holds_value(x):
                why = f" ({rule.why})" if rule.why else ""
                raise error(f"{where}: parameter {rule.name!r} = {x!r} breaks {rule.text}{why}")
        return
    for rule in rules:
        column = p[..., rule.index]
        finite = np.isfinite(column)
        if not finite.all():
            bad = float(column[~finite].flat[0])
            raise CodegenError(f"{where}: parameter {rule.name!r} = {bad!r} is not finite")
        ok = rule.holds(column)
        if not ok.all():
            bad = column[~ok].flat[0]
            why = f" ({rule.why})" if rule.why else ""
            raise error(
                f"{where}: parameter {rule.name!r} = {float(bad)!r} breaks {rule.text}{why}"
            )


_REFUSED_SCALARS = (bool, np.bool_, str, bytes, complex, np.complexfloating)
_PLAIN = (float, int)  # exact types: bool is not among them


def real_array(value: object, what: str) -> np.ndarray:
    """``value`` as a float64 array (native byte order; any layout), or a
    :class:`CodegenError` naming ``what``: real numbers of any NumPy or Python type are
    converted (integers, float16/32, long double, big-endian), while complex, boolean,
    string, bytes, datetime and masked values are refused, as is anything NumPy cannot
    turn into a regular array of numbers."""
    if type(value) is np.ndarray and value.dtype == np.float64 and value.dtype.isnative:
        return value
    if (type(value) is list or type(value) is tuple) and all(type(x) in _PLAIN for x in value):
        try:
            return np.array(value, dtype=np.float64)  # a flat list of Python floats and ints
        except OverflowError:
            raise CodegenError(f"{what}: an integer beyond the float64 range") from None
    if isinstance(value, np.ma.MaskedArray) and np.ma.is_masked(value):
        raise CodegenError(f"{what}: masked values (a masked array with a mask set)")
    if isinstance(value, _REFUSED_SCALARS):
        raise CodegenError(f"{what}: {type(value).__name__} {value!r} is not a real number")
    try:
        if isinstance(value, list | tuple):
            a = np.asarray(value, dtype=object)
            if a.dtype != object:  # pragma: no cover - numpy always honours dtype=object
                a = a.astype(object)
        else:
            a = np.asarray(value)
    except (ValueError, TypeError) as exc:
        raise CodegenError(f"{what}: not a regular array of real numbers ({exc})") from None
    dkind = a.dtype.kind
    if dkind in "fiu":
        return a.astype(np.float64, copy=False)
    if dkind == "O":
        for x in a.flat:
            if isinstance(x, _REFUSED_SCALARS) or not isinstance(x, numbers.Real | sp.Basic):
                raise CodegenError(
                    f"{what}: {type(x).__name__} {x!r} is not a real number"
                    if not isinstance(x, np.ndarray)
                    else f"{what}: a ragged or nested array"
                )
        try:
            return a.astype(np.float64)
        except (TypeError, ValueError, OverflowError) as exc:
            raise CodegenError(f"{what}: not an array of real numbers ({exc})") from None
    kinds = {"b": "booleans", "c": "complex numbers", "U": "strings", "S": "bytes"}
    raise CodegenError(
        f"{what}: {kinds.get(dkind, 'values')} of dtype {a.dtype} are not real numbers"
    )


def _key_name(key: object, aliases: Mapping[str, str], what: str) -> str:
    """The name a mapping key stands for: a string, a Symbol, or an input's sympy object."""
    if isinstance(key, sp.Symbol):
        name = key.name
    elif isinstance(key, sp.Basic):
        name = str(key)
    elif isinstance(key, str):
        name = key
    else:
        raise CodegenError(f"{what}: key {key!r} is not a name")
    return aliases.get(name, name)


def named_columns(
    values: Mapping, names: Sequence[str], aliases: Mapping[str, str], what: str
) -> np.ndarray:
    """``{name: array}`` as one float64 array (..., len(names)) in the order of ``names``;
    the arrays broadcast against each other."""
    given: dict[str, object] = {}
    for key, val in values.items():
        name = _key_name(key, aliases, what)
        if name in given:
            raise CodegenError(f"{what}: {name!r} is given twice")
        given[name] = val
    missing = [p for p in names if p not in given]
    extra = sorted(set(given) - set(names))
    if missing or extra:
        raise CodegenError(f"{what}: missing {missing}, unknown {extra}; expected {list(names)}")
    columns = [real_array(given[p], f"{what}[{p!r}]") for p in names]
    try:
        columns = list(np.broadcast_arrays(*columns))
    except ValueError:
        shapes = {p: c.shape for p, c in zip(names, columns, strict=True)}
        raise CodegenError(f"{what}: the values' shapes do not broadcast: {shapes}") from None
    return np.stack(columns, axis=-1)
