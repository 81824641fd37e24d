"""Lowering a :class:`~symmech.codegen.plan.FunctionPlan` to printed lines for a template.

One common-subexpression elimination (:func:`sympy.cse`) runs over *all* block entries
of a function; the temporaries and the entries are printed by the backend's printer
(:mod:`symmech.codegen.printers`) after :func:`~symmech.codegen.printers.safe_rewrite`.
The result is a frozen :class:`LoweredFunction` of already-printed lines: templates only
lay them out.

Linear-algebra steps (:data:`~symmech.codegen.plan.STEPS`), implemented once per backend
in its ``linalg`` template, all with Cholesky factorisations ``A = L L^T``:

``spd_solve``                 ``out = M^-1 f``
``constrained_acceleration``  ``X = M^-1 [mu^T | f]``, ``C = mu X_mu``,
                              ``lambda = C^-1 (-rate - mu X_f)``, ``out = X_f + X_mu lambda``
``constrained_multipliers``   the same, ``out = lambda``
``impact_kkt``                ``Y = M^-1 A^T``, ``G = A Y``, ``r = b - A v`` with
                              ``b = (0_m, -alpha dpsi(v) - (1 + alpha) psi_t, nu V)``,
                              ``nu V = -psi_t G[i, m] / G[m, m]``, ``out = v + Y G^-1 r``
                              (the impulse-momentum system of the Carnot paper, eqs. 6,
                              15 and 20, by its Schur complement)
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import sympy as sp

from symmech.codegen.plan import CodegenError, FunctionPlan, ScenePlan
from symmech.codegen.printers import identifier, safe_rewrite
from symmech.declaration.symbols import t as TIME

__all__ = ["LoweredFunction", "Names", "lower"]


@dataclass(frozen=True)
class Names:
    """Generated identifiers of the scene's symbols (one table for all functions)."""

    q: tuple[str, ...]
    v: tuple[str, ...]
    p: tuple[str, ...]
    u: tuple[str, ...]
    table: Mapping[sp.Symbol, str]

    @classmethod
    def of(cls, plan: ScenePlan) -> Names:
        taken: set[str] = {"t", "q", "v", "y", "p", "u", "out"}
        table: dict[sp.Symbol, str] = {TIME: "t"}
        qn = tuple(identifier(s.name, "q", taken) for s in plan.coordinates)
        vn = tuple(identifier(s.name, "v", taken) for s in plan.velocities)
        pn = tuple(identifier(s.name, "p", taken) for s in plan.parameters)
        un = tuple(identifier(str(a), "u", taken) for _, a in plan.inputs)
        table.update(zip(plan.coordinates, qn, strict=True))
        table.update(zip(plan.velocities, vn, strict=True))
        table.update(zip(plan.parameters, pn, strict=True))
        table.update(zip((d for d, _ in plan.inputs), un, strict=True))
        return cls(qn, vn, pn, un, table)


@dataclass(frozen=True)
class LoweredFunction:
    """A function as printed lines (see the module docstring)."""

    name: str
    kind: str
    doc: str
    equation: str
    wall: str | None
    state: tuple[str, ...]
    takes_parameters: bool
    takes_time: bool
    takes_inputs: bool
    unpack: tuple[tuple[str, int, str], ...]  # (array "q"/"v"/"p"/"u", index, local name)
    unused: tuple[str, ...]  # argument arrays the function does not read
    temporaries: tuple[tuple[str, str], ...]  # (name, printed expression)
    blocks: tuple[tuple[str, int], ...]  # local arrays: (name, size), excluding "out"
    assignments: tuple[tuple[str, int, str, tuple[int, ...]], ...]  # (block, flat, expr, idx)
    block_shapes: tuple[tuple[str, tuple[int, ...]], ...]
    step: str | None
    step_args: tuple[int, ...]
    calls: str | None
    out_shape: tuple[int, ...]
    out_size: int
    operations: int
    n_temporaries: int
    expressions: tuple[sp.Expr, ...] = ()  # after CSE: the temporaries, then the entries


def _unpack_entries(names: Names, used: set[str]) -> tuple[tuple[str, int, str], ...]:
    out: list[tuple[str, int, str]] = []
    for kind, locals_ in (("q", names.q), ("v", names.v), ("p", names.p), ("u", names.u)):
        for i, name in enumerate(locals_):
            if name in used:
                out.append((kind, i, name))
    return tuple(out)


def lower(
    f: FunctionPlan,
    plan: ScenePlan,
    names: Names,
    make_printer: Callable[[Mapping[sp.Symbol, str]], sp.printing.printer.Printer],
    *,
    cse: bool = True,
) -> LoweredFunction:
    """CSE and print ``f`` for one backend (``make_printer(names)`` builds its printer)."""
    entries: list[sp.Expr] = []
    where: list[tuple[str, int, tuple[int, ...]]] = []
    for b in f.blocks:
        for flat, e in enumerate(b.entries):
            e = safe_rewrite(e)
            if e.has(sp.zoo, sp.nan, sp.oo, -sp.oo):
                raise CodegenError(
                    f"{f.name}: {b.name}[{flat}] is not finite ({e}); the closed form is"
                    " singular for every state"
                )
            entries.append(e)
            if not b.shape:
                idx: tuple[int, ...] = ()
            elif len(b.shape) == 1:
                idx = (flat,)
            else:
                idx = divmod(flat, b.shape[1])
            where.append((b.name, flat, tuple(idx)))
    nonconst = [i for i, e in enumerate(entries) if not e.is_number]
    if cse and nonconst:
        replacements, reduced = sp.cse(
            [entries[i] for i in nonconst],
            symbols=sp.numbered_symbols("tmp", real=True),
            order="canonical",
        )
    else:
        replacements, reduced = [], [entries[i] for i in nonconst]
    final = list(entries)
    for i, e in zip(nonconst, reduced, strict=True):
        final[i] = e
    table = dict(names.table)
    for s, _ in replacements:
        table[s] = s.name
    printer = make_printer(table)

    def pr(e: sp.Expr) -> str:
        try:
            return printer.doprint(e)
        except ValueError as exc:
            raise CodegenError(f"{f.name}: cannot print {e}: {exc}") from None

    temporaries = tuple((s.name, pr(e)) for s, e in replacements)
    assignments = tuple(
        (blk, flat, pr(e), idx) for (blk, flat, idx), e in zip(where, final, strict=True)
    )
    ops = sum(sp.count_ops(e) for _, e in replacements) + sum(
        sp.count_ops(e) for e in final if not e.is_number
    )
    used_syms: set = set()
    for _, e in replacements:
        used_syms |= e.free_symbols
    for e in final:
        used_syms |= e.free_symbols
    used = {names.table[s] for s in used_syms if s in names.table}
    unpack = _unpack_entries(names, used)
    unused = []
    read_kinds = {k for k, _, _ in unpack}
    if f.step == "impact_kkt":
        read_kinds.add("v")
    if f.calls is not None:
        read_kinds |= {"q", "v", "p"}
    for arg in f.state:
        if arg == "y":
            continue
        if arg not in read_kinds:
            unused.append(arg)
    if plan.parameters and "p" not in read_kinds:
        unused.append("p")
    if f.uses_inputs and "u" not in read_kinds and f.calls is None:
        unused.append("u")
    if f.uses_time and "t" not in {names.table.get(s) for s in used_syms} and f.calls is None:
        unused.append("t")
    return LoweredFunction(
        name=f.name,
        kind=f.kind,
        doc=f.doc,
        equation=f.equation,
        wall=f.wall,
        state=f.state,
        takes_parameters=bool(plan.parameters),
        takes_time=f.uses_time,
        takes_inputs=f.uses_inputs,
        unpack=unpack,
        unused=tuple(unused),
        temporaries=temporaries,
        blocks=tuple((b.name, b.size) for b in f.blocks if b.name != "out"),
        assignments=assignments,
        block_shapes=tuple((b.name, b.shape) for b in f.blocks),
        step=f.step,
        step_args=f.step_args,
        calls=f.calls,
        out_shape=f.out_shape,
        out_size=f.out_size,
        operations=int(ops),
        n_temporaries=len(replacements),
        expressions=tuple(e for _, e in replacements) + tuple(final),
    )
