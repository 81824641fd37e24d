"""Lowering a :class:`~symmech.codegen.plan.FunctionPlan` to printed lines for a template.

One common-subexpression elimination (:func:`sympy.cse`) runs over *all* block entries
of a function, after :func:`~symmech.codegen.printers.safe_rewrite` and
:func:`~symmech.codegen.printers.fold_numbers`; the compound base of a power printed as a
product (``(a + b)**3``) then gets a temporary of its own, so it is evaluated once.  The
temporaries and the entries are printed by the backend's printer
(:mod:`symmech.codegen.printers`).  The result is a frozen :class:`LoweredFunction` of
already-printed lines: templates only lay them out.  The functions of one scene share
their entries (the metric and the forcing recur in every solve): a
:class:`~symmech.codegen.elimination.Memo` kept for one ``generate`` call rewrites and
folds each entry once, and runs one CSE per distinct list of entries.

A generated function takes its state arrays (``q``, ``v``, or ``y``: they fix the batch
shape; C marks one it does not read ``(void)``) and, only when it reads them, the
run-time parameters ``p``, the time ``t`` and the inputs ``u`` (``rhs`` takes those its
call of ``acceleration`` needs).

Linear-algebra steps (:data:`~symmech.codegen.plan.STEPS`), all with Cholesky
factorisations ``A = L L^T``, unrolled into each function (:mod:`symmech.codegen.unroll`)
and printed by the backend's :class:`~symmech.codegen.unroll.Dialect`:

``spd_solve``                 ``out = M^-1 f``
``constrained_acceleration``  ``X = M^-1 [mu^T | f]``, ``C = mu X_mu``,
                              ``lambda = C^-1 (-rate - mu X_f)``, ``out = X_f + X_mu lambda``
``constrained_multipliers``   the same, ``out = lambda``
``constrained_dynamics``      the same, ``out = (X_f + X_mu lambda, lambda)``
``impact_kkt``                ``Y = M^-1 A^T``, ``G = A Y``, ``r = b - A v`` with
                              ``b = (0_m, -alpha dpsi(v) - (1 + alpha) psi_t, nu V)``,
                              ``nu V = -psi_t G[i, m] / G[m, m]``, ``out = v + Y G^-1 r``
                              (the impulse-momentum system of the Carnot paper, eqs. 6,
                              15 and 20, by its Schur complement)

A function without a step that evaluates a closed form holding ``g^-1`` (acceleration,
multipliers, impact maps and projectors of the strategy ``closed_form``, the energy law's
impact) carries the metric as a block ``M`` (see :func:`symmech.codegen.generate.generate`):
its entries are checked finite and its Cholesky pivots positive, unrolled as for
``spd_solve`` (``SYMMECH_NOT_SPD``, ``LinAlgError``: the error a linear solve raises), so a
metric that the run-time parameters or the state make indefinite is never inverted
silently (``metric_check``).

The impact map of a static wall is linear in v (homogeneous of degree 1 for the energy
law), so it is evaluated scale-invariantly (``scaled``): for ``w = v 2^-e`` with
``2^(e-1) <= max|v_i| < 2^e`` and scaled back by ``2^e``, exact powers of two, so a tiny or
huge speed never under- or overflows in an intermediate (a moving wall's map is affine in
v, with the term of ``psi_t``, and is evaluated as it is).

The steps are unrolled at generation time into straight-line code over the entries that
are not exact constants (:mod:`symmech.codegen.unroll`: same operations in the same order
as the loop algorithms, minus those whose result IEEE arithmetic fixes in advance, such as
products with a structural zero); :func:`symmech.codegen.flops.step_flops` counts the
operations of the loop algorithm on a dense problem, the header of every function states
the operations its unrolled code performs (``solve_flops``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import sympy as sp

from symmech.codegen.dialects import Dialect
from symmech.codegen.elimination import Memo, NotFinite, eliminate
from symmech.codegen.flops import step_flops, step_sizes
from symmech.codegen.plan import CodegenError, FunctionPlan, ScenePlan
from symmech.codegen.printers import (
    correctly_rounded,
    identifier,
)
from symmech.codegen.unroll import STEP_INPUTS, Program, trace_step
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
    wall_index: int | None
    state: tuple[str, ...]
    takes_parameters: bool
    takes_time: bool
    takes_inputs: bool
    unpack: tuple[tuple[str, int, str], ...]  # (array "q"/"v"/"p"/"u", index, local name)
    unused: tuple[str, ...]  # state arrays the function does not read
    temporaries: tuple[tuple[str, str], ...]  # (name, printed expression)
    blocks: tuple[tuple[str, int], ...]  # local arrays: (name, size), excluding "out"
    assignments: tuple[tuple[str, int, str, tuple[int, ...]], ...]  # (block, flat, expr, idx)
    block_shapes: tuple[tuple[str, tuple[int, ...]], ...]
    step: str | None
    step_args: tuple[int, ...]
    calls: str | None
    out_shape: tuple[int, ...]
    out_size: int
    #: (name, offset): ``out`` is entries offset ... of that function's (no body of its own)
    part_of: tuple[str, int] | None
    operations: int
    n_temporaries: int
    solve_flops: int = 0  # operations of the unrolled step (symmech.codegen.unroll)
    solve: tuple[str, ...] = ()  # the unrolled step as printed lines (inputs, checks, out)
    cost: str = ""  # the header's cost line: operations, temporaries, solve, call
    expressions: tuple[sp.Expr, ...] = ()  # after CSE: the temporaries, then the entries
    metric_check: bool = False  # the closed form's metric is checked positive definite
    scaled: bool = False  # evaluated for v / 2^e and scaled back (a static wall's impact)
    #: the one-state variant's body (NumPy backend: plain floats, ``math``), or None
    scalar: tuple[str, ...] | None = None
    #: the end of the entries the called function writes, ``out[n:call_stop]``; None when
    #: they are the tail of ``out`` (``rhs``)
    call_stop: int | None = None

    @property
    def printed_characters(self) -> int:
        """The characters of its printed body: temporaries, entries and unrolled solve."""
        return (
            sum(len(text) for _, text in self.temporaries)
            + sum(len(a[2]) for a in self.assignments)
            + sum(len(line) for line in self.solve)
        )

    @property
    def one_state_fast(self) -> bool:
        """Whether one-state calls may take the fast path (a function of the state arrays
        and the parameters only: no time, no inputs)."""
        return not self.takes_time and not self.takes_inputs

    @property
    def arguments(self) -> tuple[str, ...]:
        """The argument names in order: the state arrays, then p, t, u if taken (``out``
        follows in C).  The one description of a generated function's argument list: the C
        and NumPy signatures, the batch loops, the CPython extension and the callers of a
        loaded module (:mod:`symmech.codegen.callers`) are all built from it."""
        extra = (
            ("p",) * self.takes_parameters + ("t",) * self.takes_time + ("u",) * self.takes_inputs
        )
        return (*self.state, *extra)

    def argument_sizes(self, n: int, n_parameters: int, n_inputs: int) -> tuple[int, ...]:
        """The length of each of :attr:`arguments` for one state (0 for the scalar ``t``):
        ``y`` 2n, ``q`` and ``v`` n, ``p`` and ``u`` their counts."""
        size = {"y": 2 * n, "q": n, "v": n, "p": n_parameters, "t": 0, "u": n_inputs}
        return tuple(size[a] for a in self.arguments)


# ----------------------------------------------------------------------------- lowering


def _unpack_entries(names: Names, used: set[str]) -> tuple[tuple[str, int, str], ...]:
    out: list[tuple[str, int, str]] = []
    for kind, locals_ in (("q", names.q), ("v", names.v), ("p", names.p), ("u", names.u)):
        for i, name in enumerate(locals_):
            if name in used:
                out.append((kind, i, name))
    return tuple(out)


def _constant(e: sp.Expr) -> float | None:
    """The double of a symbol-free entry (as the printed literal evaluates: rationals and
    folded numbers are correctly rounded), or None for a run-time value."""
    return correctly_rounded(e) if e.is_number else None


def lower(
    f: FunctionPlan,
    plan: ScenePlan,
    names: Names,
    make_printer: Callable[[Mapping[sp.Symbol, str]], sp.printing.printer.Printer],
    *,
    dialect: Dialect,
    cse: bool = True,
    callee: LoweredFunction | None = None,
    scalar: tuple[Callable[[Mapping[sp.Symbol, str]], sp.printing.printer.Printer], Dialect]
    | None = None,
    memo: Memo | None = None,
) -> LoweredFunction:
    """CSE and print ``f`` for one backend (``make_printer(names)`` builds its printer,
    ``dialect`` prints its unrolled linear algebra); ``callee`` is the lowered function
    that ``f`` calls (``rhs``: ``acceleration``) or is part of.  ``scalar`` (a printer and
    a dialect) also prints the one-state variant of a function of the state and the
    parameters (:func:`_scalar_body`).  ``memo`` carries what the functions of one scene
    share (:class:`Memo`; a fresh one when omitted)."""
    memo = memo if memo is not None else Memo()
    if f.callee is not None and (callee is None or callee.name != f.callee):
        raise CodegenError(f"{f.name} calls {f.callee}: lower it first and pass it as callee")
    entries, where = _gathered(f, memo)
    check = f.step is None and any(b.name == "M" for b in f.blocks)
    program, entries, where = _traced(f, check, entries, where)
    replacements, final, ops = eliminate(entries, cse, memo)
    table = {**names.table, **{s: s.name for s, _ in replacements}}
    pr = _printing(f.name, make_printer(table), memo.texts(make_printer, names))
    temporaries = tuple((s.name, pr(e)) for s, e in replacements)
    printed = tuple(
        (blk, flat, pr(e), idx) for (blk, flat, idx), e in zip(where, final, strict=True)
    )
    used = _used_names(names, (*(e for _, e in replacements), *final))
    unpack = _unpack_entries(names, used)
    layout = _laid_out(f, check, program, printed, dialect)
    read = {k for k, _, _ in unpack} | ({"v"} if layout.reads_v else set())
    if f.callee is not None:
        read |= {"q", "v"}
    takes_p, takes_t, takes_u = _takes(names, used, callee)
    cost, ops, flops = _cost(f, ops, len(replacements), layout.flops, check, callee)
    call_stop = _call_stop(f, plan.n, callee)
    scalar_body = None
    if scalar is not None and not (takes_t or takes_u):
        scalar_body = _scalar_body(
            f,
            plan.n,
            unpack,
            replacements,
            where,
            final,
            program,
            check,
            table,
            scalar,
            (callee, call_stop),
        )
    return LoweredFunction(
        name=f.name,
        kind=f.kind,
        doc=f.doc,  # raw text: the templates escape it (symmech.codegen.escape)
        equation=f.equation,
        wall=f.wall,
        wall_index=f.wall_index,
        state=f.state,
        takes_parameters=takes_p,
        takes_time=takes_t,
        takes_inputs=takes_u,
        unpack=unpack,
        unused=tuple(arg for arg in f.state if arg != "y" and arg not in read),
        temporaries=temporaries,
        blocks=layout.blocks,
        assignments=layout.assignments,
        block_shapes=layout.block_shapes,
        step=f.step,
        step_args=f.step_args,
        calls=f.calls,
        out_shape=f.out_shape,
        out_size=f.out_size,
        part_of=f.part_of,
        operations=ops,
        n_temporaries=len(replacements),
        solve_flops=flops,
        solve=layout.solve,
        cost=cost + ".",
        expressions=tuple(e for _, e in replacements) + tuple(final),
        metric_check=check,
        scaled=f.kind == "impact" and not plan.moving_walls[f.wall_index or 0],
        scalar=scalar_body,
        call_stop=call_stop,
    )


def _used_names(names: Names, expressions: Sequence[sp.Expr]) -> set[str]:
    """The printed names (state entries, p, t, u) that ``expressions`` read."""
    symbols: set = set()
    for e in expressions:
        symbols |= e.free_symbols
    return {names.table[s] for s in symbols if s in names.table}


def _takes(names: Names, used: set[str], callee: LoweredFunction | None) -> tuple[bool, bool, bool]:
    """Whether the function takes p, t and u: when its printed code reads them (an
    unrolled solve may read fewer than the plan's blocks mention) or its callee does."""
    takes_p = any(name in used for name in names.p) or bool(callee and callee.takes_parameters)
    takes_t = "t" in used or bool(callee and callee.takes_time)
    takes_u = any(name in used for name in names.u) or bool(callee and callee.takes_inputs)
    return takes_p, takes_t, takes_u


Where = list[tuple[str, int, tuple[int, ...]]]


def _printing(
    name: str, printer: sp.printing.printer.Printer, texts: dict[sp.Expr, str]
) -> Callable[[sp.Expr], str]:
    """Print an expression with ``printer``, once: ``texts`` keeps what was printed (shared
    by the functions of a scene with the same names); a failure names the function."""

    def pr(e: sp.Expr) -> str:
        text = texts.get(e)
        if text is None:
            try:
                text = texts[e] = printer.doprint(e)
            except ValueError as exc:
                raise CodegenError(f"{name}: cannot print {e}: {exc}") from None
        return text

    return pr


def _gathered(f: FunctionPlan, memo: Memo) -> tuple[list[sp.Expr], Where]:
    """Every entry of ``f``'s blocks as it is printed (:meth:`Memo.printable`), and
    where it goes: (block, flat index, index)."""
    entries: list[sp.Expr] = []
    where: Where = []
    for b in f.blocks:
        for flat, e in enumerate(b.entries):
            try:
                e = memo.printable(e)
            except NotFinite as exc:
                raise CodegenError(
                    f"{f.name}: {b.name}[{flat}] is not finite ({exc.args[0]}); the closed"
                    " form is singular for every state"
                ) from None
            except ValueError as exc:
                raise CodegenError(f"{f.name}: {b.name}[{flat}]: {exc}") from None
            entries.append(e)
            if not b.shape:
                idx: tuple[int, ...] = ()
            elif len(b.shape) == 1:
                idx = (flat,)
            else:
                idx = divmod(flat, b.shape[1])
            where.append((b.name, flat, tuple(idx)))
    return entries, where


def _traced(
    f: FunctionPlan, check: bool, entries: list[sp.Expr], where: Where
) -> tuple[Program | None, list[sp.Expr], Where]:
    """The unrolled program of ``f``'s step, or of its closed form's metric check, and the
    entries it reads (the others are dropped); (None, entries, where) for neither."""
    if check:
        # the closed form's metric: finite entries and positive Cholesky pivots, traced as
        # the factorisation of spd_solve with a zero right-hand side, whose stores of
        # constant zeros are dropped; only the entries it reads are kept
        M_block = next(b for b in f.blocks if b.name == "M")
        n_m = M_block.shape[0]
        consts = [_constant(e) for (blk, _, _), e in zip(where, entries, strict=True) if blk == "M"]
        off = [consts[i * n_m + j] for i in range(n_m) for j in range(n_m) if i != j]
        diag = int(all(c == 0.0 for c in off))
        program = trace_step(
            "spd_solve", (n_m, diag), {"M": (M_block.shape, consts), "f": ((n_m,), [0.0] * n_m)}
        )
        program.statements = [st for st in program.statements if st[0] != "out"]
        needed = {(i.block, i.flat) for i in program.inputs}
        keep = [i for i, (blk, flat, _) in enumerate(where) if blk != "M" or (blk, flat) in needed]
    elif f.step is not None:
        # unroll the step over the structure of its inputs, then keep only the entries
        # it reads (they become locals; constants are folded into the unrolled code)
        shapes = {b.name: b.shape for b in f.blocks}
        values: dict[str, list[float | None]] = {name: [] for name in STEP_INPUTS[f.step]}
        for (blk, _, _), e in zip(where, entries, strict=True):
            if blk in values:
                values[blk].append(_constant(e))
        structure: dict[str, tuple[tuple[int, ...], Sequence[float | None]]] = {
            name: (shapes[name], values[name]) for name in values
        }
        program = trace_step(f.step, f.step_args, structure)
        needed = {(i.block, i.flat) for i in program.inputs}
        keep = [i for i, (blk, flat, _) in enumerate(where) if (blk, flat) in needed]
    else:
        return None, entries, where
    return program, [entries[i] for i in keep], [where[i] for i in keep]


@dataclass(frozen=True)
class _Layout:
    """How a function's printed entries are laid out: the unrolled step (``solve``, its
    ``flops``), the stores into local blocks and ``out`` (``assignments``), the local
    blocks, and whether the step reads the state ``v`` itself (``impact_kkt``)."""

    solve: tuple[str, ...] = ()
    flops: int = 0
    assignments: tuple[tuple[str, int, str, tuple[int, ...]], ...] = ()
    blocks: tuple[tuple[str, int], ...] = ()
    block_shapes: tuple[tuple[str, tuple[int, ...]], ...] = ()
    reads_v: bool = False


def _laid_out(
    f: FunctionPlan,
    check: bool,
    program: Program | None,
    printed: tuple[tuple[str, int, str, tuple[int, ...]], ...],
    dialect: Dialect,
) -> _Layout:
    """The :class:`_Layout` of ``f``: a metric check prints the metric's entries into its
    unrolled factorisation and stores the others; a step prints every entry into its
    unrolled code; else every entry is stored."""
    if check:
        assert program is not None
        exprs = {(blk, flat): text for blk, flat, text, _ in printed if blk == "M"}
        return _Layout(
            solve=tuple(dialect.lines(program, f.out_shape, exprs)),
            flops=program.flops,
            assignments=tuple(a for a in printed if a[0] != "M"),
            blocks=tuple((b.name, b.size) for b in f.blocks if b.name not in ("out", "M")),
            block_shapes=tuple((b.name, b.shape) for b in f.blocks if b.name != "M"),
        )
    if program is not None:
        exprs = {(blk, flat): text for blk, flat, text, _ in printed}
        return _Layout(
            solve=tuple(dialect.lines(program, f.out_shape, exprs)),
            flops=program.flops,
            reads_v=program.reads_state("v"),
        )
    return _Layout(
        assignments=printed,
        blocks=tuple((b.name, b.size) for b in f.blocks if b.name != "out"),
        block_shapes=tuple((b.name, b.shape) for b in f.blocks),
    )


def _cost(
    f: FunctionPlan,
    ops: int,
    temporaries: int,
    flops: int,
    check: bool,
    callee: LoweredFunction | None,
) -> tuple[str, int, int]:
    """The header's cost line of ``f``, and its operations and flops (a part's are those
    of the function it is part of)."""
    cost = f"Operations after CSE: {ops} (sympy.count_ops); temporaries: {temporaries}"
    if f.step:
        cost += (
            f"; solve: {flops} flops ({step_sizes(f.step, f.step_args)}; dense:"
            f" {step_flops(f.step, f.step_args)})"
        )
    if check:
        cost += f"; metric check: {flops} flops"
    if f.part_of is not None and callee is not None:  # its cost is the whole's
        cost = f"Entries {f.part_of[1]} ... {f.part_of[1] + f.out_size - 1} of {callee.name}"
        ops, flops = callee.operations, callee.solve_flops
    if callee is not None:
        cost += f"; then the call of {callee.name}: {callee.operations} operations"
        if callee.solve_flops:
            cost += f" + {callee.solve_flops} flops"
    return cost, ops, flops


def _scalar_body(
    f: FunctionPlan,
    n: int,
    unpack: tuple[tuple[str, int, str], ...],
    replacements: Sequence[tuple[sp.Symbol, sp.Expr]],
    where: list[tuple[str, int, tuple[int, ...]]],
    final: list[sp.Expr],
    program: Program | None,
    check: bool,
    table: Mapping[sp.Symbol, str],
    scalar: tuple[Callable[[Mapping[sp.Symbol, str]], sp.printing.printer.Printer], Dialect],
    call: tuple[LoweredFunction | None, int | None],
) -> tuple[str, ...] | None:
    """The body of the one-state variant ``_one_<name>`` of a NumPy function: the same
    expressions, operations and order on plain floats (the state arrays and p as lists),
    ``math`` in place of ``numpy``, the output a list (``return out`` follows).  None when
    it cannot be printed so (a function ``math`` lacks, a local block, a callee without a
    variant).  ``call``: the callee and the end of the entries it writes (``call_stop``)."""
    make_printer, dialect = scalar
    callee, stop = call
    if callee is not None and callee.scalar is None:
        return None
    if f.part_of is not None and callee is not None:
        start = f.part_of[1]
        whole = f"_one_{callee.name}({', '.join(callee.arguments)})"
        return (f"out = {whole}[{start}:{start + f.out_size}]",)
    if (program is None or check) and any(blk not in ("out", "M") for blk, _, _ in where):
        return None  # a local block other than the output
    printer = make_printer(table)
    try:
        temporaries = [f"{s.name} = {printer.doprint(e)}" for s, e in replacements]
        printed = [
            (blk, flat, printer.doprint(e)) for (blk, flat, _), e in zip(where, final, strict=True)
        ]
    except (ValueError, NotImplementedError):
        # the strict math printer refuses what ``math`` cannot evaluate (ValueError) or
        # print (NotImplementedError: e.g. an undefined function): no variant, and the
        # module's vectorised function serves every call
        return None
    lines: list[str] = []
    if f.state == ("y",):
        lines += [f"q = y[:{n}]", f"v = y[{n}:]"]
    lines += [f"{name} = {array}[{i}]" for array, i, name in unpack]
    lines += temporaries
    if program is not None and not check:
        exprs = {(blk, flat): text for blk, flat, text in printed}
        lines += dialect.lines(program, f.out_shape, exprs)
    else:
        lines.append(f"out = [0.0] * {math.prod(f.out_shape)}")
        lines += [f"out[{flat}] = {text}" for blk, flat, text in printed if blk == "out"]
        if check:
            assert program is not None
            exprs = {(blk, flat): text for blk, flat, text in printed if blk == "M"}
            lines += dialect.lines(program, f.out_shape, exprs)
    if callee is not None:
        args = ", ".join(callee.arguments)
        lines.append(f"out[{n}:{'' if stop is None else stop}] = _one_{callee.name}({args})")
    return tuple(lines)


def _call_stop(f: FunctionPlan, n: int, callee: LoweredFunction | None) -> int | None:
    """The end of the entries ``out[n:]`` that the function ``f`` calls writes, where they
    are not the tail of ``out`` (``augmented_rhs``: the walls' rates follow v_dot)."""
    if f.calls is None or callee is None or n + callee.out_size >= f.out_size:
        return None
    return n + callee.out_size
