"""The C batch loop's split of a function: what reads only the parameters, once per batch.

A ``*_batch`` function evaluates ``count`` states with one parameter vector ``p``.  The
one-state body (the printed lines of :class:`~symmech.codegen.lower.LoweredFunction`:
the unpacked entries, the temporaries after CSE, the assignments and the unrolled solve)
is split here, line by line in order, into

* ``once``: each local ``const double x = e;`` whose expression ``e`` reads only ``p``,
  constants and locals already in ``once`` (in the Ex. 3.13 impact, ``k^2 + r^2`` and the
  reciprocals and square roots of the Cholesky factor of ``A M^-1 A^T``);
* ``checks``: the terms of a run-time check (``isfinite(x)``, ``x > 0.0``) that read only
  such locals: evaluated once per batch;
* ``state``: every other line, in its order, reading the ``once`` locals it needs (the
  ``fields``) from an array filled once per batch.

When the state lines store every output entry once and read none back, each store
``out[k] = e;`` becomes a local ``sm_out_k``, stored after the last line, and the
finiteness check of the outputs is made on those locals without a branch per entry:
``x - x`` is 0 for a finite ``x`` and NaN otherwise, so the sum of ``sm_out_k - sm_out_k``
is 0 exactly when every output is finite (``finite``: the lines of that check, or of the
check that reads ``out`` back when the stores cannot be moved).  The impact map of a
static wall is evaluated for ``w = v 2^-e`` and scaled back by ``2^e`` (``FUNCTION.c.jinja``);
its per-state body scales the locals back itself, ``(x * u1) * u2``, and checks them once:
an output that is not finite before the exact scaling by normal powers of two is not
finite after it, so the one-state function's two checks fail on the same states.  Its
batch loop runs in blocks of 64 states: the scalings of the block's states first, then
the states, so that no state waits on one long chain of dependent operations.

Same operations on the same operands in the same order, so every state gets the doubles
the one-state function returns, bit for bit.  A failing ``checks`` term fails every state:
the one-state function reaches it for every state (the code is straight-line; only
a failure returns early), so the batch returns 1 (the first state) as the loop would.
The split is conservative: a name it does not know (a state array, ``t``, ``u``, a
macro) makes its line a ``state`` line.  The exported one-state function keeps the
whole body; the batch loop calls a ``static`` per-state function the compiler can inline.
The body is so printed twice, which doubles its compile time: a body longer than
:data:`MAX_SPLIT_CHARACTERS` (an imported bicycle's functions, where the batch gains
little against the work of each state) is not split, and its batch loop calls the
exported function for each state.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass

from symmech.codegen.lower import LoweredFunction

__all__ = ["MAX_SPLIT_CHARACTERS", "BatchSplit", "batch_split"]

#: The longest one-state body (characters of its printed lines) that the batch loop
#: prints a second time, split (module docstring): the 4-link pendulum on a cart's
#: acceleration has 5,300 and is split; the 8-link one's 15,000 and the imported
#: bicycle's functions (15,000 to 45,000: printing them twice doubled the compile time
#: from the model to loaded C) are not.
MAX_SPLIT_CHARACTERS = 10_000

_LET = re.compile(r"^const double (\w+) = (.*);$")
_CHECK = re.compile(r"^if \(!\((.*)\)\) return (SYMMECH_\w+);$")
_STORE = re.compile(r"^out\[(\d+)\] = (.*);$")
# a name: not part of a number (1.0e-5) or of a longer name, and not a called function
_NAME = re.compile(r"(?<![\w.])([A-Za-z_]\w*)\b(?!\s*\()")


@dataclass(frozen=True)
class BatchSplit:
    """The lines of one function's batch loop (see the module docstring)."""

    once: tuple[str, ...]  # C statements run once per batch (they read p)
    checks: tuple[str, ...]  # C conditions on ``once`` locals: all must hold
    fields: tuple[str, ...]  # the ``once`` locals the per-state lines read
    state: tuple[str, ...]  # C statements of the per-state body, in order
    finite: tuple[str, ...]  # C statements: return SYMMECH_NONFINITE unless out is finite

    @property
    def hoisted(self) -> bool:
        """Whether there is work once per batch (a ``pre`` array, a ``sm_once_`` call)."""
        return bool(self.once or self.checks)


def _names(text: str) -> set[str]:
    return set(_NAME.findall(text))


def _conjuncts(condition: str) -> list[str]:
    """The terms of a top-level ``a && b && ...`` (one term if there is no such ``&&``)."""
    terms, depth, start = [], 0, 0
    for i, ch in enumerate(condition):
        depth += (ch == "(") - (ch == ")")
        if depth == 0 and condition.startswith(" && ", i):
            terms.append(condition[start:i])
            start = i + 4
    terms.append(condition[start:])
    return terms


def _body_lines(fn: LoweredFunction) -> list[str]:
    """The one-state body of ``fn`` as the C template prints it, between the unused
    arguments and the call of its callee (``FUNCTION.c.jinja``)."""
    lines = [f"const double {name} = {array}[{i}];" for array, i, name in fn.unpack]
    lines += [f"const double {name} = {expr};" for name, expr in fn.temporaries]
    lines += [f"double {name}[{size}];" for name, size in fn.blocks]
    lines += [f"{block}[{flat}] = {expr};" for block, flat, expr, _ in fn.assignments]
    return lines + list(fn.solve)


def _split(lines: Iterable[str], known: set[str]) -> BatchSplit:
    once: list[str] = []
    checks: list[str] = []
    state: list[str] = []
    hoisted: list[str] = []
    for line in lines:
        let = _LET.match(line)
        if let and _names(let.group(2)) <= known:
            known.add(let.group(1))
            hoisted.append(let.group(1))
            once.append(line)
            continue
        check = _CHECK.match(line)
        if check:
            terms = _conjuncts(check.group(1))
            checks += [t for t in terms if _names(t) <= known]
            rest = [t for t in terms if not _names(t) <= known]
            if rest:
                state.append(f"if (!({' && '.join(rest)})) return {check.group(2)};")
            continue
        state.append(line)
    read: set[str] = set()
    for line in state:
        read |= _names(line)
    fields = tuple(name for name in hoisted if name in read)
    return BatchSplit(tuple(once), tuple(checks), fields, tuple(state), ())


def _memory_check(size: int) -> tuple[str, ...]:
    """The finiteness check that reads ``out[0:size]`` back."""
    return (f"if (sm_check_finite({size}, out) != SYMMECH_OK) return SYMMECH_NONFINITE;",)


def _in_registers(
    state: tuple[str, ...], size: int, scaled: bool
) -> tuple[tuple[str, ...], tuple[str, ...]] | None:
    """``state`` with its output stores moved after its last line through locals, and the
    branch-free finiteness check of those locals; with ``scaled``, each output is scaled
    back by ``(x * u1) * u2`` (the arguments of the per-state function) before it is
    stored and checked.  None when some line reads ``out`` or an entry is not stored once."""
    lines: list[str] = []
    stored: dict[int, str] = {}
    for line in state:
        store = _STORE.match(line)
        if store and int(store.group(1)) not in stored:
            name = f"sm_out_{store.group(1)}"
            stored[int(store.group(1))] = name
            lines.append(f"const double {name} = {store.group(2)};")
        elif "out" in _names(line) or "sm_out" in line:
            return None
        else:
            lines.append(line)
    if sorted(stored) != list(range(size)) or size == 0:
        return None
    if scaled:
        for k in range(size):
            lines.append(f"const double sm_up_{k} = ({stored[k]} * u1) * u2;")
            stored[k] = f"sm_up_{k}"
    lines += [f"out[{k}] = {stored[k]};" for k in range(size)]
    total = " + ".join(f"({x} - {x})" for x in stored.values())
    check = (
        f"const double sm_nonfinite = {total};",
        "if (!(sm_nonfinite == 0.0)) return SYMMECH_NONFINITE;",
    )
    return tuple(lines), check


def _prelude(fn: LoweredFunction, n: int, split: BatchSplit) -> list[str]:
    """The first lines of the per-state function: the halves of ``y``, every argument
    marked used (the state lines may read none of them), the ``pre`` fields."""
    lines = ["const double *q = y;", f"const double *v = y + {n};"] if fn.state == ("y",) else []
    names = [*fn.arguments, *(("q", "v") if fn.state == ("y",) else ()), "pre"]
    lines += [f"(void){a};" for a in names if a != "pre" or split.hoisted]
    return lines + [f"const double {x} = pre[{i}];" for i, x in enumerate(split.fields)]


def batch_split(fn: LoweredFunction, n: int) -> BatchSplit | None:
    """The split of ``fn``'s C body for its batch loop (``n`` coordinates; see the module
    docstring), or None for a body longer than :data:`MAX_SPLIT_CHARACTERS`."""
    lines = _body_lines(fn)
    if sum(len(line) for line in lines) > MAX_SPLIT_CHARACTERS:
        return None
    split = _split(lines, {"p"} if fn.takes_parameters else set())
    state: tuple[str, ...] = split.state
    # a scaled function's outputs are checked after they are scaled back (a non-finite
    # one stays non-finite: the factors are normal powers of two)
    finite = _memory_check(fn.out_size)
    if fn.scaled:
        back = f"for (int i = 0; i < {fn.out_size}; ++i) out[i] = (out[i] * u1) * u2;"
        finite = (back, *finite)
    moved = None if fn.calls else _in_registers(split.state, fn.out_size, fn.scaled)
    if moved is not None:  # (a callee stores into out after these lines)
        state, finite = moved
    state = (*_prelude(fn, n, split), *state)
    return BatchSplit(split.once, split.checks, split.fields, state, finite)
