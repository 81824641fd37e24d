"""Cost budgets of the symbolic stages, in one place, and the one exception they raise.

Every symbolic stage of symmech that can grow without bound (expanding into a polynomial
domain, Laplace expansion, adjugates, gcds, ``factor``, ``simplify``, the closed forms of
code generation) is bounded by a budget below, measured in one of

* **terms**: monomials of a polynomial (or the bound :func:`expanded_terms` gives for an
  expression before it is expanded);
* **operations**: ``sympy.count_ops`` of an expression;
* **size**: the order of a matrix block;
* **degree**: the total degree of an expansion (:func:`expanded_terms` reports it);
* **generators**: the symbols, function values and fractional powers a polynomial
  algebra takes as its variables;
* **seconds**: wall-clock time of a stage (:func:`time_limit`, :func:`checkpoint`).

Two kinds of reaction, chosen by the stage and documented with each limit:

* *skip*: an optional step (a gcd, ``factor``, ``simplify``, an exact normal form) is not
  taken; the result stays exact, only less simplified (e.g. :data:`FIELD_TERMS`: the
  rational-function field declines and plain sympy arithmetic is used);
* *stop*: :class:`BudgetExceeded` is raised, naming the stage, the budget and the value
  measured.  Code generation turns it into the ``linear_solve`` fallback (strategy
  ``auto``) or a :class:`~symmech.codegen.plan.CodegenError` (strategy ``closed_form``).

The limits are module attributes read when a stage runs: a user who accepts a longer
derivation sets, e.g., ``symmech.algebra.budget.CLOSED_FORM_SECONDS = 60``.  A test
(``tests/test_budget.py``) checks that no module of the symbolic layers defines another
budget exception or threshold.
"""

from __future__ import annotations

import signal
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar

import sympy as sp

from symmech.algebra.block_structure import diagonal_blocks
from symmech.algebra.opcount import count_ops
from symmech.errors import SymmechError

__all__ = [
    "CARNOT_FIELD_OPS",
    "CARNOT_FIELD_SECONDS",
    "CLOSED_FORM_MAX_N",
    "CLOSED_FORM_SECONDS",
    "CLOSED_FORM_TERMS",
    "EXPAND_TERMS",
    "FIELD_BLOCK_MAX_N",
    "FIELD_DEGREE",
    "FIELD_GCD_TERMS",
    "FIELD_GENERATORS",
    "FIELD_MINOR_TERMS",
    "FIELD_TERMS",
    "FULL_SIMPLIFY_OPS",
    "IMPACT_FULL_OPS",
    "IMPACT_GCD_NUMERATOR_TERMS",
    "IMPACT_GCD_TERMS",
    "IMPACT_TERMS",
    "LIGHT_SIMPLIFY_OPS",
    "LINEARIZE_OPS",
    "NOTE_EXPAND_TERMS",
    "QUADRATIC_SIMPLIFY_OPS",
    "ROOTS_OPS",
    "ROOTS_SECONDS",
    "SINGULAR_FACTOR_OPS",
    "STABLE_ENTRY_OPS",
    "STABLE_FACTOR_GENERATORS",
    "STABLE_OPS",
    "STABLE_TERMS",
    "ZERO_EXACT_OPS",
    "ZERO_TEST_OPS",
    "BudgetExceeded",
    "affordable",
    "checkpoint",
    "determinant_terms",
    "expand_affordable",
    "expanded_terms",
    "propagate_time",
    "remaining",
    "time_limit",
]

# -- geometry: the rational-function field (symmech.algebra.field) -----------------------
#: terms, skip: inputs whose expansion (bound of :func:`expanded_terms`) holds more terms
#: than this are not converted into a polynomial domain (the field declines).
FIELD_TERMS = 20_000
#: degree, skip: ... or whose expansion has a larger total degree.
FIELD_DEGREE = 128
#: generators, skip: ... or that need more generators (symbols, and sin, cos, other
#: functions and radicals as dummies) in all: every term of the domain carries one
#: exponent per generator (a potential of 400 trigonometric terms needs 1600).
FIELD_GENERATORS = 64
#: size, skip: largest diagonal block solved fraction-free by Laplace expansion.
FIELD_BLOCK_MAX_N = 8
#: terms, skip: the minors and cofactors of one block may hold this many terms.
FIELD_MINOR_TERMS = 25_000
#: terms, skip: gcds against a shared denominator with more terms cancel only its
#: monomial and integer content.
FIELD_GCD_TERMS = 400

# -- geometry: the simplification policy (symmech.algebra.simplification) ----------------
#: operations, skip: ``"light"`` normal forms and ``cancel`` of larger expressions.
LIGHT_SIMPLIFY_OPS = 400
#: operations, skip: ``sympy.simplify`` of larger expressions (level ``"full"``).
FULL_SIMPLIFY_OPS = 150

#: terms, skip: every stage budgeted in operations whose step expands (``cancel``,
#: ``factor``, ``simplify``, the exact zero test, a Pythagorean remainder) also declines an
#: expression whose expansion may hold more terms than this (bound of
#: :func:`expanded_terms`; see :func:`affordable`): ``(x + y + zdot + 1)**64`` is 8
#: operations and 10^8 terms.
EXPAND_TERMS = 20_000

# -- declaration: definiteness of the metric (symmech.declaration.definiteness) -----------
#: operations, skip: a diagonal entry or leading minor of the metric in one coordinate that
#: is not a polynomial has its real roots solved exactly (``sympy.solveset``) only when it
#: has at most this many operations ...
ROOTS_OPS = 60
#: seconds, skip: ... and within this time (then the search from the samples decides).
ROOTS_SECONDS = 2.0
#: operations, skip: a leading minor of the metric whose interval bound proves nothing is
#: linearised (products of sin and cos to sums, ``sympy.simplify.fu.TR8``) and bounded
#: again only when it has at most this many operations.
LINEARIZE_OPS = 600

# -- impacts (symmech.impacts) -----------------------------------------------------------
#: terms, skip: the adjugate route gives up when a polynomial it forms is larger (the
#: projectors are then built by plain sympy arithmetic).
IMPACT_TERMS = 200_000
#: terms, skip: final gcds only against shared denominators with at most this many terms
IMPACT_GCD_TERMS = 400
#: terms, skip: ... and only for numerators with at most this many terms.
IMPACT_GCD_NUMERATOR_TERMS = 6000
#: operations, skip: coefficients put in the stable factored form (``factor``).
STABLE_OPS = 600
#: terms, skip: ... and only when their expansion (bound of :func:`expanded_terms`) is at
#: most this large (``cancel`` expands in full).
STABLE_TERMS = 2_000
#: generators, skip: ... and numerator and denominator are factored as wholes (``cancel``
#: and ``factor``, whose cost grows quickly with the number of generators: symbols,
#: function values, fractional powers) only for expressions with at most this many; a
#: larger one is put over a common denominator without a gcd, and each of its numerator
#: and denominator is expanded and written as a sum over its state monomials with
#: factored coefficients (differences of nearly equal parameter terms still combine).
STABLE_FACTOR_GENERATORS = 10
#: operations, skip: ``sympy.simplify`` of an impact-map entry (``simplify="full"``).
IMPACT_FULL_OPS = 150
#: operations, skip: the exact normal-form route of :func:`symmech.algebra.zero.is_zero`.
ZERO_TEST_OPS = 200
#: operations, skip: its randomized exact evaluation (larger: sampled evaluation only).
ZERO_EXACT_OPS = 20_000
#: operations, skip: singular sets - larger expressions are not factored and larger closed
#: forms are not scanned for denominators (symmech.impacts.degeneracy).
SINGULAR_FACTOR_OPS = 400
#: operations, skip: the fraction-field Carnot residual (larger maps: exact evaluation).
CARNOT_FIELD_OPS = 3000
#: seconds, skip: ... and the time it may take (then: exact evaluation).
CARNOT_FIELD_SECONDS = 2.0
#: operations, skip: ``sympy.simplify`` of a quadratic form's coefficients.
QUADRATIC_SIMPLIFY_OPS = 300

# -- code generation (symmech.codegen.plan) ----------------------------------------------
#: size: above this many coordinates strategy ``auto`` does not try closed forms.
CLOSED_FORM_MAX_N = 3
#: seconds, stop: wall-clock budget of all closed forms of one scene (acceleration,
#: multipliers, impact maps, projectors).
CLOSED_FORM_SECONDS = 10.0
#: terms, stop: closed forms are not attempted when the determinant of a connected block
#: of the metric, or of the metric bordered by the constraint and wall one-forms, may
#: expand to more terms than this (:func:`determinant_terms`; see
#: :mod:`symmech.codegen.closed_form_budget`).
CLOSED_FORM_TERMS = 500
#: operations, skip: velocity-free entries put in the stable factored form before
#: printing (larger ones keep the form they were derived in).
STABLE_ENTRY_OPS = 200

#: terms, skip: a term of the forcing is expanded to count its Christoffel symbols for
#: the ``omitted`` note of generated code only when its expansion (bound of
#: :func:`expanded_terms`) has at most this many terms; a larger one counts every pair of
#: its velocities as present.  Measured in terms, not operations: ``(x + v + 1)**64`` is
#: a handful of operations and millions of terms.
NOTE_EXPAND_TERMS = 2_000


class BudgetExceeded(SymmechError):
    """A symbolic stage exceeded its budget.

    ``stage`` names the stage, ``budget`` the limit's name in :mod:`symmech.algebra.budget`,
    ``measure`` its unit, ``limit`` its value and ``measured`` what was found (None when
    unknown, e.g. a time limit hit inside a library call).
    """

    def __init__(
        self,
        stage: str,
        budget: str,
        measure: str,
        limit: float,
        measured: float | None = None,
    ):
        self.stage, self.budget, self.measure = stage, budget, measure
        self.limit, self.measured = limit, measured
        found = "" if measured is None else f": {_number(measured)} {measure}"
        super().__init__(
            f"{stage}: over its budget {budget} = {_number(limit)} {measure}{found}"
            " (symmech.algebra.budget)"
        )


def _number(x: float) -> str:
    return f"{x:g}" if isinstance(x, float) else str(x)


# -- terms and degree of an expansion -------------------------------------------------------


def expanded_terms(expr: sp.Basic, cap: int = 10**9) -> tuple[int, int]:
    """An upper bound ``(terms, degree)`` of ``expr`` expanded as a polynomial in its
    building blocks (symbols, and function applications or fractional powers taken as
    generators), computed on the expression tree without expanding anything:

    * a generator: (1, 1); a number: (1, 0);
    * a sum: the terms add, the degree is the maximum;
    * a product: the terms multiply, the degrees add;
    * an integer power ``b^e``: ``C(t + |e| - 1, |e|)`` terms (monomials of degree |e| in
      t terms) and degree ``|e| deg b`` (a negative power is a denominator of that size).

    Both are capped at ``cap``.  Rule: the number of monomials of a product of sums is at
    most the product of their numbers of monomials, and of a power ``b^e`` at most the
    number of monomials of degree e in the monomials of b.

    >>> x, y = sp.symbols("x y")
    >>> expanded_terms((x + y + 1) ** 3)
    (10, 3)
    """
    memo: dict[sp.Basic, tuple[int, int]] = {}

    def visit(e: sp.Basic) -> tuple[int, int]:
        hit = memo.get(e)
        if hit is not None:
            return hit
        if e.is_Number or e.is_NumberSymbol:
            out = (1, 0)
        elif e.is_Add:
            parts = [visit(a) for a in e.args]
            out = (min(cap, sum(t for t, _ in parts)), max(d for _, d in parts))
        elif e.is_Mul:
            terms, degree = 1, 0
            for a in e.args:
                t, d = visit(a)
                terms, degree = min(cap, terms * t), min(cap, degree + d)
            out = (terms, degree)
        elif e.is_Pow and e.exp.is_Integer:
            t, d = visit(e.base)
            k = abs(int(e.exp))
            terms = cap if k > cap else min(cap, _binomial(t + k - 1, k, cap))
            out = (terms, min(cap, k * d))
        else:  # a symbol, a function application, a fractional power: one generator
            out = (1, 1)
        memo[e] = out
        return out

    return visit(sp.sympify(expr, strict=True))


def affordable(expr: sp.Basic, max_ops: int) -> bool:
    """True when a step that expands ``expr`` fits both of its budgets: at most ``max_ops``
    operations (``sympy.count_ops``) and an expansion of at most :data:`EXPAND_TERMS`
    terms (bound of :func:`expanded_terms`).  The one gate of every operations budget
    whose step expands: an operation count alone misses a power of a sum.  Also a
    :func:`checkpoint` of the deadline (every expensive step passes this gate first)."""
    checkpoint()
    if count_ops(expr) > max_ops:
        return False
    return expanded_terms(expr, EXPAND_TERMS + 1)[0] <= EXPAND_TERMS


def expand_affordable(expr: sp.Basic) -> sp.Basic:
    """``sympy.expand(expr)`` when its expansion may hold at most :data:`EXPAND_TERMS`
    terms (bound of :func:`expanded_terms`), else ``expr`` as it is (skip): for the
    expansions that only tidy a result or a message.  Also a :func:`checkpoint`."""
    checkpoint()
    if expanded_terms(expr, EXPAND_TERMS + 1)[0] > EXPAND_TERMS:
        return expr
    return sp.expand(expr)


def _binomial(n: int, k: int, cap: int) -> int:
    """``C(n, k)`` or ``cap`` when it is larger (without forming huge integers)."""
    k = min(k, n - k)
    if k < 0:
        return 0
    out = 1
    for i in range(1, k + 1):
        out = out * (n - k + i) // i
        if out > cap:
            return cap
    return out


# -- time ------------------------------------------------------------------------------------

_DEADLINE: ContextVar[tuple[str, str, float, float] | None] = ContextVar(
    "symmech_deadline", default=None
)


def remaining() -> float | None:
    """Seconds left in the innermost :func:`time_limit`, or None outside one."""
    active = _DEADLINE.get()
    return None if active is None else active[3] - time.monotonic()


def checkpoint() -> None:
    """Raise :class:`BudgetExceeded` if the active :func:`time_limit` has run out (called
    between the steps of long symbolic loops)."""
    active = _DEADLINE.get()
    if active is not None and time.monotonic() > active[3]:
        stage, name, seconds, _ = active
        raise BudgetExceeded(stage, name, "seconds", seconds)


@contextmanager
def time_limit(stage: str, seconds: float, budget: str = "CLOSED_FORM_SECONDS") -> Iterator[None]:
    """Bound the wall-clock time of the block to ``seconds``: a cooperative deadline.

    The deadline is held in a context variable, so it belongs to the thread (or task)
    that entered the block, and inside the block :func:`checkpoint` raises
    :class:`BudgetExceeded` once the time is up.  The symbolic loops check it between
    their steps: every gate of an expanding step (:func:`affordable`,
    :func:`expand_affordable`), every entry of the rational-function field
    (:mod:`symmech.algebra.field`) and of the adjugate route, every Laplace minor and
    every stable coefficient.  Each step between two checks is bounded by a budget in
    terms or operations, so the deadline holds in any thread, overshooting by at most one
    budgeted step.

    In the main thread, when no other handler owns ``SIGALRM``, a real-time timer also
    interrupts a single long library call that no term budget foresaw (a sympy
    ``factor`` or ``cancel`` that would not return): the handler raises the same
    exception at the next bytecode, and the timer and handler are restored on exit.  It
    is kept because it costs nothing and bounds what the checks cannot (the inside of one
    library call); it is a second line, never the only one.  Nested limits keep the
    earlier deadline.
    """
    now = time.monotonic()
    outer = _DEADLINE.get()
    end = now + seconds
    if outer is not None and outer[3] <= end:
        entry = outer
    else:
        entry = (stage, budget, seconds, end)
    token = _DEADLINE.set(entry)
    use_alarm = (
        entry is not outer
        and hasattr(signal, "setitimer")
        and threading.current_thread() is threading.main_thread()
        and signal.getsignal(signal.SIGALRM) in (signal.SIG_DFL, signal.SIG_IGN, None)
        and signal.getitimer(signal.ITIMER_REAL)[0] == 0
    )
    previous = None
    if use_alarm:

        def expire(signum: int, frame: object) -> None:
            if _DEADLINE.get() is entry:  # a no-op once the block has been left
                raise BudgetExceeded(entry[0], entry[1], "seconds", entry[2])

        previous = signal.signal(signal.SIGALRM, expire)
        signal.setitimer(signal.ITIMER_REAL, max(1e-3, end - now))
    try:
        yield
    finally:
        try:
            _DEADLINE.reset(token)  # first: a late alarm then does nothing
        finally:
            if use_alarm:
                signal.setitimer(signal.ITIMER_REAL, 0)
                signal.signal(signal.SIGALRM, previous)


def propagate_time(exc: BudgetExceeded) -> None:
    """Re-raise ``exc`` when it is a time limit: a stage that skips an optional step over
    its own term budget must not swallow the deadline of the stage around it."""
    if exc.measure == "seconds":
        raise exc


# -- the size of a closed form, from the structure -----------------------------------------


def determinant_terms(M: sp.MatrixBase) -> int:
    """An upper bound of the number of terms of ``det`` of every connected diagonal block
    of ``M`` (the largest over the blocks), from the structure alone.

    The blocks are the connected components of the non-zero pattern (a diagonal metric
    has n blocks of size 1).  For a block with term counts ``t_ij`` (bound of
    :func:`expanded_terms` of each entry) the Leibniz expansion has at most
    ``perm(t)`` terms (the permanent: every permutation contributes the product of its
    entries' term counts); it is computed exactly by Ryser's formula up to 12 x 12 and
    bounded by the product of the row sums above.  The adjugate and every minor are
    bounded by the same number, so this bounds the size of an exact inverse, a solve,
    or the projectors of an impact (applied to the bordered matrix
    ``[[g, A^T], [A, 0]]``).
    """
    n = M.rows
    weights = [
        [expanded_terms(M[i, j])[0] if M[i, j] != 0 else 0 for j in range(n)] for i in range(n)
    ]
    blocks = diagonal_blocks(n, lambda i, j: bool(weights[i][j]))
    worst = 0
    for block in blocks:
        sub = [[weights[i][j] for j in block] for i in block]
        worst = max(worst, _permanent(sub))
    return worst


def _permanent(w: list[list[int]]) -> int:
    """perm(w) for a non-negative integer matrix (Ryser) up to 12 x 12, else the product
    of the row sums (an upper bound)."""
    n = len(w)
    if n > 12:
        out = 1
        for row in w:
            out *= sum(row)
        return out
    total = 0
    for mask in range(1, 1 << n):
        cols = [j for j in range(n) if mask >> j & 1]
        prod = 1
        for row in w:
            s = sum(row[j] for j in cols)
            if not s:
                prod = 0
                break
            prod *= s
        total += (-1) ** len(cols) * prod
    return abs(total)
