"""Numerical evaluation of sympy expressions at sample points (for validation checks).

Validation evaluates metrics, frames and constraint rows at a few random points.  Rebuilding
a large sympy tree with ``subs``/``evalf`` costs far more than the check itself, so this
module walks the tree once, memoising shared subtrees:

* :func:`evaluate` / :func:`evaluate_matrix` in float64 (Python's ``cmath``);
* :func:`evaluate_matrix_mp` in mpmath (arbitrary exponent range), the fallback when a
  value overflows float64 (``exp(1000)``);
* :func:`vanishes` decides "identically zero" by exact-input, 50-digit evaluation at the
  sample points, comparing the value with the size of the terms that cancel in it (cheap
  and bounded, unlike ``sympy.simplify``);
* :func:`classify_symmetric` tells positive definite / singular / indefinite, after
  scaling the matrix to unit diagonal so that neither huge nor tiny entries overflow;
* :func:`proven_sign` proves an expression positive from its structure alone (sums and
  products of positive terms, ``exp`` of a real argument), without evaluating anything:
  sympy's ``is_positive`` may evaluate numerically, and on ``exp(exp(exp(1000)))`` it
  raises an OverflowError.

Every failure (overflow, division by zero, a value that is not finite, an atom without a
value) raises :class:`EvaluationError`; no floating-point warning escapes.  Point values
may be given for any atom, not only symbols: an undefined function ``g(x)`` or a
derivative ``Derivative(g(x), x)`` is then evaluated as that value.
"""

from __future__ import annotations

import cmath
import math
import threading
from collections import OrderedDict
from collections.abc import Mapping, Sequence
from functools import lru_cache
from typing import Any, ClassVar

import mpmath
import numpy as np
import sympy as sp
from sympy.core.function import AppliedUndef

__all__ = [
    "EvaluationError",
    "classify_symmetric",
    "evaluate",
    "evaluate_matrix",
    "evaluate_matrix_mp",
    "proven_real",
    "proven_sign",
    "real_values",
    "vanishes",
]

#: Working precision (decimal digits) of the mpmath evaluations.
MP_DIGITS = 50
# |value| <= _ZERO_RELATIVE * (size of the cancelling terms) counts as zero at MP_DIGITS.
_ZERO_RELATIVE = mpmath.mpf(10) ** -30
# |value| below this (absolute) counts as zero whatever the terms (underflow guard).
_ZERO_ABSOLUTE = mpmath.mpf(10) ** -300
# Eigenvalues of a metric scaled to unit diagonal within this of 0 count as 0.
_TOLERANCE = 1e-10


class EvaluationError(ArithmeticError):
    """An expression has no finite numeric value at a point.

    ``reason`` says why ("overflows float64", "is not finite", "cannot be evaluated: ...");
    ``index`` is the matrix entry (i, j) when raised by a matrix evaluation.
    """

    def __init__(self, reason: str, index: tuple[int, int] | None = None):
        self.reason = reason
        self.index = index
        where = f"entry [{index[0]},{index[1]}] " if index is not None else ""
        super().__init__(f"{where}{reason}")


# -- float64 -------------------------------------------------------------------------------

_FUNCS = {
    sp.sin: cmath.sin,
    sp.cos: cmath.cos,
    sp.tan: cmath.tan,
    sp.exp: cmath.exp,
    sp.log: cmath.log,
    sp.asin: cmath.asin,
    sp.acos: cmath.acos,
    sp.atan: cmath.atan,
    sp.sinh: cmath.sinh,
    sp.cosh: cmath.cosh,
    sp.tanh: cmath.tanh,
    sp.cot: lambda x: 1 / cmath.tan(x),
    sp.sec: lambda x: 1 / cmath.cos(x),
    sp.csc: lambda x: 1 / cmath.sin(x),
}

_ARITHMETIC = (OverflowError, ZeroDivisionError, ValueError, RecursionError)
_NOT_FINITE = (sp.oo, -sp.oo, sp.zoo, sp.nan)
_INFINITE = "is infinite or undefined (oo, zoo or nan)"


def _eval(expr: sp.Basic, env: Mapping, memo: dict) -> complex:
    hit = memo.get(expr)
    if hit is not None:
        return hit
    value = env.get(expr)
    if value is not None:
        val = _complex(value)
    elif expr.is_Number or expr.is_NumberSymbol or expr is sp.zoo:
        if expr in _NOT_FINITE:
            raise EvaluationError(_INFINITE)
        val = complex(expr)
    elif expr.is_Add:
        val = sum((_eval(a, env, memo) for a in expr.args), 0j)
    elif expr.is_Mul:
        val = 1 + 0j
        for a in expr.args:
            val *= _eval(a, env, memo)
    elif expr.is_Pow:
        base = _eval(expr.base, env, memo)
        e = expr.exp
        val = base ** int(e) if e.is_Integer else base ** _eval(e, env, memo)
    elif type(expr) in _FUNCS:
        val = _FUNCS[type(expr)](_eval(expr.args[0], env, memo))
    elif isinstance(expr, sp.atan2):
        y, x = (_eval(a, env, memo) for a in expr.args)
        val = complex(math.atan2(y.real, x.real))
    else:
        val = complex(_evalf(expr, env, 17))
    if not cmath.isfinite(val):
        raise EvaluationError("is not finite in float64 (an overflow or a division by zero)")
    memo[expr] = val
    return val


def _complex(value: Any) -> complex:
    """``complex(value)``; for a sympy rational the same number without the real and
    imaginary part functions sympy's ``__complex__`` builds (a real 15-digit ``evalf``:
    note that this is not ``float(value)``, which rounds differently), remembered for the
    next evaluation at the same sample point."""
    if isinstance(value, sp.Rational):
        return _complex_rational(value)
    return complex(value)


@lru_cache(maxsize=4096)  # numbers: their == is cheap, kept across runs
def _complex_rational(value: sp.Rational) -> complex:
    return complex(float(value.evalf()), 0.0)


def _evalf(expr: sp.Basic, env: Mapping, digits: int) -> sp.Expr:
    """Last resort for functions the walkers do not know: sympy's evalf at the point, a
    finite sympy number (else EvaluationError)."""
    missing = [a for a in expr.free_symbols if a not in env]
    if missing:
        raise EvaluationError(f"cannot be evaluated: no value for {sorted(map(str, missing))}")
    try:
        # subs, not xreplace: it leaves bound variables (of an Integral, say) alone
        value = sp.N(expr.subs({k: sp.Float(v, digits + 3) for k, v in env.items()}), digits)
        re, im = value.as_real_imag()
        if not (re.is_Float or re.is_zero) or not (im.is_Float or im.is_zero):
            raise TypeError(f"the value {_short(value)} is not a finite number")
        return value
    except (TypeError, AttributeError, *_ARITHMETIC) as exc:
        raise EvaluationError(f"cannot be evaluated ({_short(expr)}: {exc})") from None


def _short(expr: object, limit: int = 40) -> str:
    s = str(expr)
    return s if len(s) <= limit else s[: limit - 3] + "..."


def _reason(exc: BaseException) -> str:
    if isinstance(exc, OverflowError):
        return "overflows float64"
    if isinstance(exc, ZeroDivisionError):
        return "divides by zero"
    if isinstance(exc, RecursionError):
        return "is nested too deeply to evaluate"
    return f"is undefined ({exc})"


def evaluate(expr: sp.Basic, point: Mapping) -> complex:
    """``expr`` at ``point`` (atom -> number) as a complex float; raises EvaluationError."""
    try:
        return _eval(sp.sympify(expr, strict=True), dict(point), {})
    except _ARITHMETIC as exc:
        raise EvaluationError(_reason(exc)) from None


def evaluate_matrix(M: sp.MatrixBase, point: Mapping) -> np.ndarray:
    """Every entry of ``M`` at ``point``, as a complex numpy array (shared subtrees once).

    Raises :class:`EvaluationError` with the entry's index when an entry has no finite
    float64 value.  The entries are evaluated by their :class:`_Program` (the same
    operations, in the same order, as the tree walk), kept for the next point with the
    same atoms; trees nested too deeply for it are walked.
    """
    env: dict = dict(point)
    out = np.empty((M.rows, M.cols), dtype=complex)
    program = _Program.of(M, env)
    if program is not None:
        program.run(env, out)
        return out
    memo: dict = {}
    for i in range(M.rows):
        for j in range(M.cols):
            try:
                out[i, j] = _eval(M[i, j], env, memo)
            except EvaluationError as exc:
                raise EvaluationError(exc.reason, (i, j)) from None
            except _ARITHMETIC as exc:
                raise EvaluationError(_reason(exc), (i, j)) from None
    return out


# operations of a _Program
_LOAD, _CONST, _ADD, _MUL, _POWI, _POW, _FUNC, _ATAN2, _EVALF = range(9)


class _Program:
    """The entries of a matrix as a straight-line program for :func:`_eval`'s float64
    arithmetic: one operation per distinct node, in the order the recursive walk of the
    entries (row by row, shared subtrees once) first completes the nodes, each computing
    what :func:`_eval` computes there from the values of the node's children.  Running it
    at a point therefore gives the same numbers, and raises the same error at the same
    node (reported for the entry whose walk first reached it), without the cost of the
    walk (dictionary look-ups and calls per visited node).

    A program depends on the matrix and on which atoms the point gives values to (they
    are loaded, not walked into); :meth:`of` keeps the last few.  Trees deeper than
    :data:`_MAX_DEPTH` frames of the walk get no program: the walk would run out of stack
    (a RecursionError it reports as "nested too deeply") where a program would not.
    """

    _MAX_DEPTH: ClassVar[int] = 200
    _cache: ClassVar[OrderedDict[tuple, tuple[_Program, tuple]]] = OrderedDict()
    _CACHE_SIZE: ClassVar[int] = 8
    #: guards the cache (scenes may be declared in several threads at once)
    _lock: ClassVar[threading.Lock] = threading.Lock()

    def __init__(self, ops: list[tuple], entries: list[tuple[int, int, int]]):
        self.ops = ops  # (kind, entry index (i, j) of the walk reaching it first, data...)
        self.entries = entries  # (i, j, slot of its value)

    @classmethod
    def of(cls, M: sp.MatrixBase, env: Mapping) -> _Program | None:
        """The program of ``M`` for points with the atoms of ``env`` (None: walk)."""
        if any(v is None for v in env.values()):
            return None  # (the walk takes an atom given None as an atom without a value)
        # keyed by the identity of the entries (kept alive with the program, so their ids
        # are not reused while cached): a structurally equal matrix built anew (a scene
        # declared again after sympy's cache was cleared) would otherwise be compared
        # with == node by node, which visits shared subtrees once per path (exponential
        # in the depth of a DAG); it compiles its own program instead, in linear time
        entries = tuple(e for row in M.tolist() for e in row)
        key = (M.rows, M.cols, tuple(map(id, entries)), frozenset(env))
        with cls._lock:
            hit = cls._cache.get(key)
            if hit is not None:
                cls._cache.move_to_end(key)
                return hit[0]
        program = cls._compile(M, env)
        if program is not None:
            with cls._lock:
                cls._cache[key] = (program, entries)
                while len(cls._cache) > cls._CACHE_SIZE:
                    cls._cache.popitem(last=False)
        return program

    @classmethod
    def _compile(cls, M: sp.MatrixBase, env: Mapping) -> _Program | None:
        ops: list[tuple] = []
        slots: dict[sp.Basic, int] = {}
        too_deep = False

        def visit(expr: sp.Basic, where: tuple[int, int], depth: int) -> int:
            # mirrors _eval: a node's operation follows those of its children
            nonlocal too_deep
            hit = slots.get(expr)
            if hit is not None:
                return hit
            if depth > cls._MAX_DEPTH:
                too_deep = True
                return -1
            if expr in env:
                op: tuple = (_LOAD, where, expr)
            elif expr.is_Number or expr.is_NumberSymbol or expr is sp.zoo:
                try:
                    if expr in _NOT_FINITE:
                        raise EvaluationError(_INFINITE)
                    op = (_CONST, where, complex(expr))
                except Exception as exc:  # raised when the walk would reach it
                    op = (_CONST, where, exc)
            elif expr.is_Add:  # sum(generator): two frames per level
                op = (_ADD, where, [visit(a, where, depth + 2) for a in expr.args])
            elif expr.is_Mul:
                op = (_MUL, where, [visit(a, where, depth + 1) for a in expr.args])
            elif expr.is_Pow:
                base = visit(expr.base, where, depth + 1)
                e = expr.exp
                if e.is_Integer:
                    op = (_POWI, where, base, int(e))
                else:
                    op = (_POW, where, base, visit(e, where, depth + 1))
            elif type(expr) in _FUNCS:
                op = (_FUNC, where, _FUNCS[type(expr)], visit(expr.args[0], where, depth + 1))
            elif isinstance(expr, sp.atan2):
                y, x = (visit(a, where, depth + 2) for a in expr.args)
                op = (_ATAN2, where, y, x)
            else:
                op = (_EVALF, where, expr)
            if too_deep:
                return -1
            slots[expr] = len(ops)
            ops.append(op)
            return len(ops) - 1

        entries = []
        for i in range(M.rows):
            for j in range(M.cols):
                slot = visit(M[i, j], (i, j), 1)
                if too_deep:
                    return None
                entries.append((i, j, slot))
        return cls(ops, entries)

    def run(self, env: Mapping, out: np.ndarray) -> None:
        """Fill ``out`` with the entries at the point ``env``; raises as
        :func:`evaluate_matrix` does."""
        vals: list[complex] = []
        push = vals.append
        isfinite = cmath.isfinite
        op: tuple = ()
        try:
            for op in self.ops:
                kind = op[0]
                if kind == _MUL:
                    val = 1 + 0j
                    for a in op[2]:
                        val *= vals[a]
                elif kind == _ADD:
                    val = sum([vals[a] for a in op[2]], 0j)
                elif kind == _POWI:
                    val = vals[op[2]] ** op[3]
                elif kind == _FUNC:
                    val = op[2](vals[op[3]])
                elif kind == _LOAD:
                    val = _complex(env[op[2]])
                elif kind == _CONST:
                    val = op[2]
                    if isinstance(val, Exception):
                        raise val
                elif kind == _POW:
                    val = vals[op[2]] ** vals[op[3]]
                elif kind == _ATAN2:
                    val = complex(math.atan2(vals[op[2]].real, vals[op[3]].real))
                else:
                    val = complex(_evalf(op[2], env, 17))
                if not isfinite(val):
                    raise EvaluationError(
                        "is not finite in float64 (an overflow or a division by zero)"
                    )
                push(val)
        except EvaluationError as exc:
            raise EvaluationError(exc.reason, op[1]) from None
        except _ARITHMETIC as exc:
            raise EvaluationError(_reason(exc), op[1]) from None
        for i, j, slot in self.entries:
            out[i, j] = vals[slot]


# -- mpmath --------------------------------------------------------------------------------

_MP_FUNCS = {
    sp.sin: mpmath.sin,
    sp.cos: mpmath.cos,
    sp.tan: mpmath.tan,
    sp.exp: mpmath.exp,
    sp.log: mpmath.log,
    sp.asin: mpmath.asin,
    sp.acos: mpmath.acos,
    sp.atan: mpmath.atan,
    sp.sinh: mpmath.sinh,
    sp.cosh: mpmath.cosh,
    sp.tanh: mpmath.tanh,
    sp.cot: mpmath.cot,
    sp.sec: mpmath.sec,
    sp.csc: mpmath.csc,
}


def _mp_number(x: sp.Basic) -> mpmath.mpc:
    if x in _NOT_FINITE:
        raise EvaluationError(_INFINITE)
    if x.is_Integer:
        return mpmath.mpc(int(x))
    if x.is_Rational:
        return mpmath.mpc(mpmath.mpf(int(x.p)) / int(x.q))
    if x.is_Float:
        return mpmath.mpc(mpmath.mpf(x._mpf_))
    try:
        re, im = (sp.Float(part, mpmath.mp.dps) for part in sp.N(x, mpmath.mp.dps).as_real_imag())
        return mpmath.mpc(mpmath.mpf(re._mpf_), mpmath.mpf(im._mpf_))
    except (TypeError, AttributeError, ValueError) as exc:
        raise EvaluationError(f"cannot be evaluated ({_short(x)}: {exc})") from None


def _mp_eval(expr: sp.Basic, env: Mapping, memo: dict) -> tuple[mpmath.mpc, mpmath.mpf]:
    """(value, size): size bounds the magnitude of the terms combined into the value, so a
    value far below its size is a cancellation to zero (rounding error ~ size * 10^-dps)."""
    hit = memo.get(expr)
    if hit is not None:
        return hit
    value = env.get(expr)
    if value is not None:
        val = _mp_number(sp.sympify(value, strict=True))
        size = abs(val)
    elif expr.is_Number or expr.is_NumberSymbol or expr is sp.I or expr is sp.zoo:
        val = _mp_number(expr)
        size = abs(val)
    elif expr.is_Add:
        val, size = mpmath.mpc(0), mpmath.mpf(0)
        for a in expr.args:
            v, s = _mp_eval(a, env, memo)
            val, size = val + v, size + s
    elif expr.is_Mul:
        val, size = mpmath.mpc(1), mpmath.mpf(1)
        for a in expr.args:
            v, s = _mp_eval(a, env, memo)
            val, size = val * v, size * s
    elif expr.is_Pow:
        base, bsize = _mp_eval(expr.base, env, memo)
        e = expr.exp
        if e.is_Integer and int(e) >= 0:
            val, size = base ** int(e), bsize ** int(e)
        else:
            if base == 0:
                raise EvaluationError("divides by zero")
            if e.is_Integer:
                ev, esize, val = int(e), 0, base ** int(e)
            else:
                ev, esize = _mp_eval(e, env, memo)
                val = base**ev
            # relative error of the base (bsize/|base|) is amplified |e| times
            size = abs(val) * (1 + abs(ev) * bsize / abs(base) + esize * abs(mpmath.log(base)))
    elif type(expr) in _MP_FUNCS:
        arg, asize = _mp_eval(expr.args[0], env, memo)
        val = _MP_FUNCS[type(expr)](arg)
        # an error e in the argument moves the value by about |f'| e; |f'| <= |f| + 1 for
        # the functions where it matters (sin, cos, exp, sinh, cosh)
        size = abs(val) + (abs(val) + 1) * asize
    elif isinstance(expr, sp.atan2):
        (y, ys), (x, xs) = (_mp_eval(a, env, memo) for a in expr.args)
        val = mpmath.mpc(mpmath.atan2(y.real, x.real))
        size = abs(val) + (ys + xs) / max(abs(y) + abs(x), _ZERO_ABSOLUTE)
    else:
        val = _mp_number(_evalf(expr, env, mpmath.mp.dps))
        size = abs(val)
    if not (mpmath.isfinite(val.real) and mpmath.isfinite(val.imag)):
        raise EvaluationError("is not finite")
    memo[expr] = (val, size)
    return val, size


def evaluate_matrix_mp(
    M: sp.MatrixBase, point: Mapping, digits: int = MP_DIGITS
) -> list[list[mpmath.mpc]]:
    """Every entry of ``M`` at ``point`` in mpmath (``digits`` decimal digits).

    mpmath numbers have an unbounded exponent, so ``exp(1000)`` is fine; raises
    :class:`EvaluationError` with the entry's index when an entry cannot be evaluated
    (``exp(exp(exp(1000)))`` has more digits in its exponent than memory holds).
    """
    env: dict = dict(point)
    memo: dict = {}
    rows = []
    with mpmath.workdps(digits):
        for i in range(M.rows):
            row = []
            for j in range(M.cols):
                try:
                    row.append(_mp_eval(M[i, j], env, memo)[0])
                except EvaluationError as exc:
                    raise EvaluationError(exc.reason, (i, j)) from None
                except (*_ARITHMETIC, MemoryError) as exc:
                    raise EvaluationError(
                        f"cannot be evaluated in {digits}-digit arithmetic ({exc})", (i, j)
                    ) from None
            rows.append(row)
    return rows


def vanishes(expr: sp.Basic, points: Sequence[Mapping], digits: int = MP_DIGITS) -> bool | None:
    """Whether ``expr`` is identically zero, judged at ``points`` (exact rational inputs).

    True when it is zero (relative to the terms that cancel in it) at every point where it
    can be evaluated, False as soon as it is not, None when it cannot be evaluated at any
    point.  A generic statement: an expression that vanishes at all the random points is
    taken to vanish identically.  Its cost is a walk of the tree per point, whatever the
    expression (``sympy.simplify`` can take minutes on a few hundred operations).
    """
    expr = sp.sympify(expr, strict=True)
    if expr == 0:
        return True
    if expr.is_Number:
        return False
    judged = False
    with mpmath.workdps(digits):
        for point in points:
            try:
                val, size = _mp_eval(expr, dict(point), {})
            except (EvaluationError, *_ARITHMETIC, MemoryError):
                continue
            judged = True
            if abs(val) > max(_ZERO_RELATIVE * size, _ZERO_ABSOLUTE):
                return False
    return True if judged else None


# -- definiteness --------------------------------------------------------------------------


def classify_symmetric(A: Sequence[Sequence[Any]]) -> tuple[str, str]:
    """Classify a real symmetric matrix: ``("positive definite" | "singular" | "indefinite",
    evidence)``.

    Entries may be floats or mpmath numbers of any size.  A positive definite matrix has a
    positive diagonal; scaling it to unit diagonal, ``B = D^-1/2 A D^-1/2``, keeps its
    signature and bounds every entry by 1, so the eigenvalues of B are computed in float64
    without overflow and compared with a tolerance independent of the units (a metric
    ``diag(1e308, 1e-308)`` is positive definite).  "singular" means an eigenvalue of B
    within 1e-10 of 0.  ``evidence`` is a short text for messages.
    """
    n = len(A)
    if all(isinstance(x, float) for row in A for x in row):
        F = np.array(A, dtype=float)
        fd = np.diag(F)
        if (fd > 0).all():
            fs = np.sqrt(fd)
            with np.errstate(all="ignore"):
                FB = F / fs[:, None] / fs[None, :]
            if np.isfinite(FB).all():
                return _classify_unit_diagonal(FB)
    d = [A[i][i] for i in range(n)]
    neg = [i for i in range(n) if d[i] < 0]
    if neg:
        i = neg[0]
        return "indefinite", f"diagonal entry [{i},{i}] = {mpmath.nstr(d[i], 6)} < 0"
    for i in range(n):
        if d[i] == 0:
            j = next((j for j in range(n) if A[i][j] != 0), None)
            if j is not None:
                return "indefinite", f"diagonal entry [{i},{i}] = 0 but [{i},{j}] != 0"
            return "singular", f"row {i} is zero"
    s = [mpmath.sqrt(mpmath.mpf(x)) for x in d]
    B = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            b = (mpmath.mpf(A[i][j]) / s[i]) / s[j]
            if i != j and abs(b) > 1 + _TOLERANCE:
                # the 2 x 2 principal minor 1 - b^2 is negative
                return "indefinite", f"g[{i},{j}]^2 > g[{i},{i}] g[{j},{j}]"
            B[i, j] = float(b)
    return _classify_unit_diagonal(B)


def _classify_unit_diagonal(B: np.ndarray) -> tuple[str, str]:
    n = B.shape[0]
    off = np.abs(B - np.diag(np.diag(B)))
    if n > 1 and off.max() > 1 + _TOLERANCE:
        i, j = np.unravel_index(np.argmax(off), off.shape)
        return "indefinite", f"g[{i},{j}]^2 > g[{i},{i}] g[{j},{j}]"
    w = np.linalg.eigvalsh(B)
    shown = np.round(w, 6).tolist()
    if w[0] < -_TOLERANCE:
        return "indefinite", f"eigenvalues of the metric scaled to unit diagonal {shown}"
    if w[0] <= _TOLERANCE:
        return "singular", f"eigenvalues of the metric scaled to unit diagonal {shown}"
    return "positive definite", f"eigenvalues of the metric scaled to unit diagonal {shown}"


def real_values(M: sp.MatrixBase, point: Mapping) -> tuple[list[list], bool]:
    """Entries of M at point as real numbers (float64, or 30-digit mpmath when float64
    overflows) and whether M has a non-negligible imaginary part there.

    Raises :class:`EvaluationError` (with the entry's index) when an entry has no finite
    value in either arithmetic.
    """
    try:
        A = evaluate_matrix(M, point)
        with np.errstate(all="ignore"):
            scale = float(np.abs(A).max(initial=0.0))
            imag = float(np.abs(A.imag).max(initial=0.0))
        if np.isfinite(scale):
            return A.real.tolist(), imag > 1e-12 * scale
        float_reason = "overflows float64"
    except EvaluationError as exc:
        if exc.reason == _INFINITE:
            raise
        float_reason = exc.reason
    try:
        rows = evaluate_matrix_mp(M, point, digits=30)
    except EvaluationError as exc:
        raise EvaluationError(f"{float_reason}, and {exc.reason}", exc.index) from None
    scale = max((abs(x) for r in rows for x in r), default=mpmath.mpf(0))
    imag = max((abs(x.imag) for r in rows for x in r), default=mpmath.mpf(0))
    return [[x.real for x in r] for r in rows], imag > mpmath.mpf(10) ** -12 * scale


# -- signs proven from the structure -------------------------------------------------------


def proven_sign(e: sp.Expr) -> str | None:
    """``"pos"`` or ``"nonneg"`` when the structure of ``e`` proves it, else None.

    Proven positive: positive numbers, pi, E, symbols and undefined functions declared
    positive, sums and products of positive (and nonnegative) terms, positive bases to a
    real power, ``exp`` and ``cosh`` of a real argument; nonnegative: even powers of real
    terms.  Nothing is evaluated, so the cost is one walk of the tree.
    """
    if e.is_Number:
        if e in (sp.nan, sp.oo, sp.zoo, -sp.oo) or not e.is_real:
            return None
        return "pos" if e > 0 else ("nonneg" if e == 0 else None)
    if e.is_NumberSymbol:
        return "pos" if e in (sp.pi, sp.E) else None
    if isinstance(e, sp.Symbol | AppliedUndef):
        if e.is_positive:
            return "pos"
        return "nonneg" if e.is_nonnegative else None
    if e.is_Add or e.is_Mul:
        signs = [proven_sign(a) for a in e.args]
        if None in signs:
            return None
        if e.is_Add:
            return "pos" if "pos" in signs else "nonneg"
        return "pos" if all(s == "pos" for s in signs) else "nonneg"
    if e.is_Pow:
        base = proven_sign(e.base)
        if base == "pos" and _proven_real(e.exp):
            return "pos"
        if e.exp.is_Integer and int(e.exp) % 2 == 0 and _proven_real(e.base):
            return "nonneg" if int(e.exp) > 0 else None
        return "nonneg" if base == "nonneg" and e.exp.is_Rational and e.exp > 0 else None
    if isinstance(e, sp.exp | sp.cosh) and _proven_real(e.args[0]):
        return "pos"
    return None


def _proven_real(e: sp.Expr) -> bool:
    """Whether the structure of ``e`` proves it real (nothing is evaluated)."""
    if e.is_Number:
        return e.is_real is True and e not in (sp.oo, -sp.oo)
    if e.is_NumberSymbol or isinstance(e, sp.Symbol | AppliedUndef):
        return e.is_real is True
    if e.is_Add or e.is_Mul:
        return all(_proven_real(a) for a in e.args)
    if e.is_Pow:
        return (_proven_real(e.base) and e.exp.is_Integer and int(e.exp) >= 0) or (
            proven_sign(e.base) == "pos" and _proven_real(e.exp)
        )
    if isinstance(e, sp.sin | sp.cos | sp.exp | sp.sinh | sp.cosh | sp.tanh | sp.atan):
        return _proven_real(e.args[0])
    return False


def proven_real(e: sp.Expr) -> bool:
    """Whether the structure of ``e`` proves it real wherever it is defined: numbers, real
    symbols, sums and products, integer powers, positive bases to real powers, and sin,
    cos, exp, sinh, cosh, tanh, atan of real arguments (nothing is evaluated)."""
    try:
        return _proven_real(e)
    except RecursionError:
        return False
