"""The fast routes of the derivation return exactly what the plain sympy routes return.

* :func:`symmech.algebra.canonical.mul` / :func:`~symmech.algebra.canonical.add` against
  ``sympy.Mul`` / ``sympy.Add`` (``srepr`` equal) on random expressions, odd ones included;
* the forcing and the metric of the pendulum on a cart against the same algorithms written
  with ``sympy.Mul``, ``sympy.Add`` and the operators;
* :func:`symmech.algebra.numeric.evaluate_matrix` (a compiled program) against the walk of
  :func:`symmech.algebra.numeric._eval`, errors and their entries included;
* :mod:`symmech.algebra.walk` against sympy's ``free_symbols``, ``atoms`` and ``xreplace``.
"""

from __future__ import annotations

import random
from collections import defaultdict

import numpy as np
import pytest
import sympy as sp

from symmech.algebra import canonical, numeric
from symmech.algebra.canonical import fast_add as add
from symmech.algebra.canonical import fast_mul as mul
from symmech.algebra.walk import atoms, free_symbols, free_symbols_of, xreplace
from symmech.examples import pendulum_on_cart
from symmech.geometry.connection import forcing

x, y, z = sp.symbols("x y z", real=True)
m, ell = sp.symbols("m l", positive=True)
a = sp.Symbol("a")
d = sp.Dummy("d")
A, B = sp.symbols("A B", commutative=False)
w = sp.Symbol("w", infinite=True)
f = sp.Function("f")

NUMBERS = [sp.S(0), sp.S(1), sp.S(-1), sp.S(2), sp.S(-3), sp.Rational(1, 2), sp.Rational(-2, 3)]
ODD = [sp.Float(1.5), sp.oo, sp.pi, sp.I, sp.sqrt(2), sp.cbrt(2), sp.zoo, sp.nan, A, B, sp.E, w]
ATOMS = [x, y, z, m, ell, a, d, sp.sin(x), sp.cos(x), sp.cos(y), f(x), sp.exp(x), sp.log(m)]
ATOMS += [sp.tan(z), sp.Derivative(f(x), x)]


def _random_expr(rng: random.Random, depth: int, odd: bool) -> sp.Expr:
    if depth <= 0 or rng.random() < 0.3:
        if odd and rng.random() < 0.08:
            return rng.choice(ODD)
        return rng.choice(NUMBERS) if rng.random() < 0.3 else rng.choice(ATOMS)
    parts = [_random_expr(rng, depth - 1, odd) for _ in range(rng.randint(1, 4))]
    r = rng.random()
    if r < 0.4:
        return sp.Mul(*parts)
    if r < 0.8:
        return sp.Add(*parts)
    e = rng.choice([2, 3, -1, -2, sp.Rational(1, 2), sp.Rational(-3, 2), y, m])
    return sp.Pow(parts[0], e)


def _outcome(build, args):
    try:
        out = build(*args)
    except Exception as exc:  # the two routes must fail alike
        return ("raised", type(exc).__name__)
    return (type(out).__name__, sp.srepr(out))


def test_the_fast_routes_are_taken_only_on_a_checked_sympy() -> None:
    version = ".".join(sp.__version__.split(".")[:2])
    assert canonical.FAST == (canonical._INTERNALS and version in canonical.CHECKED_SYMPY)
    args = (sp.Rational(1, 2), x, sp.cos(y))
    assert canonical.mul(*args) == sp.Mul(*args) and canonical.add(*args) == sp.Add(*args)


@pytest.mark.parametrize("seed", range(4))
def test_mul_and_add_are_sympys(seed: int) -> None:
    """On the installed sympy, whichever release: a release that orders or stores its
    arguments otherwise fails here (then the fast routes stay off for it)."""
    rng = random.Random(seed)
    for _ in range(600):
        args = [_random_expr(rng, rng.randint(0, 3), rng.random() < 0.3) for _ in range(5)]
        args = args[: rng.randint(1, 5)]
        cases = [
            args,
            [sp.Rational(1, 2), args[0]],
            [args[0], sp.S.NegativeOne],
            [sp.S(2), sp.Mul(3, args[0])],
            [sp.S.Zero, *args],
        ]
        for case in cases:
            assert _outcome(mul, case) == _outcome(sp.Mul, case), case
            assert _outcome(add, case) == _outcome(sp.Add, case), case


# -- the pendulum's forcing and metric, by the same algorithms in plain sympy ------------


def _partial(expr: sp.Expr, qa: sp.Symbol) -> sp.Expr:
    """The product-rule derivative as symmech formed it with sympy.Add and sympy.Mul."""
    if expr == qa:
        return sp.S.One
    if qa not in expr.free_symbols:
        return sp.S.Zero
    if expr.is_Add:
        return sp.Add(*[_partial(t, qa) for t in expr.args])
    if expr.is_Mul:
        args = expr.args
        out = []
        for k, fk in enumerate(args):
            if qa in fk.free_symbols:
                df = _partial(fk, qa)
                if df is not sp.S.Zero:
                    out.append(sp.Mul(*args[:k], df, *args[k + 1 :]))
        return sp.Add(*out)
    if expr.is_Pow and qa not in expr.exp.free_symbols:
        return expr.exp * expr.base ** (expr.exp - 1) * _partial(expr.base, qa)
    if isinstance(expr, sp.Function) and len(expr.args) == 1:
        return expr.fdiff(1) * _partial(expr.args[0], qa)
    return sp.diff(expr, qa)


def _reference_forcing(G: sp.MatrixBase, V: sp.Expr, q, v) -> sp.Matrix:
    n = len(q)
    acc: list[dict] = [defaultdict(list) for _ in range(n)]

    def put(k: int, i: int, j: int, term: sp.Expr) -> None:
        acc[k][(i, j) if i <= j else (j, i)].append(term)

    for i in range(n):
        for j in range(i, n):
            for a_ in range(n):
                dd = _partial(G[i, j], q[a_])
                if dd == 0:
                    continue
                if i == j:
                    put(a_, i, i, dd / 2)
                    put(i, a_, i, -dd)
                else:
                    put(a_, i, j, dd)
                    put(i, a_, j, -dd)
                    put(j, a_, i, -dd)
    rows = []
    for k in range(n):
        terms = [sp.Mul(sp.Add(*c), v[i], v[j]) for (i, j), c in acc[k].items()]
        rows.append(sp.Add(*terms) - _partial(V, q[k]))
    return sp.Matrix(rows)


@pytest.mark.parametrize("n", [1, 2, 4])
def test_pendulum_forcing_is_the_plain_sympy_one(n: int) -> None:
    scene = pendulum_on_cart(n)
    decl = scene.declaration
    ref = _reference_forcing(decl.metric, decl.potential, decl.coordinates, decl.velocities)
    got = forcing(decl.metric, decl.potential, decl.coordinates, decl.velocities)
    assert [sp.srepr(e) for e in got] == [sp.srepr(e) for e in ref]


def test_pendulum_metric_is_the_plain_sympy_one() -> None:
    # the grouping of metric_from_kinetic_energy, every product and sum formed by sympy
    from symmech.declaration import kinetic_metric

    scene = pendulum_on_cart(3)
    saved = kinetic_metric.mul, kinetic_metric.add
    try:
        kinetic_metric.mul, kinetic_metric.add = sp.Mul, sp.Add
        T = _kinetic_energy(scene)
        ref = kinetic_metric.metric_from_kinetic_energy(T, scene.velocities, scene.coordinates)
    finally:
        kinetic_metric.mul, kinetic_metric.add = saved
    assert sp.srepr(sp.ImmutableMatrix(ref)) == sp.srepr(scene.declaration.metric)


def _kinetic_energy(scene) -> sp.Expr:
    """The kinetic energy pendulum_on_cart declares (built the same way)."""
    q, qd = scene.coordinates, scene.velocities
    n = len(q) - 1
    ms = sp.symbols(f"m0:{n + 1}", positive=True)
    ls = sp.symbols(f"l0:{n}", positive=True)
    T = ms[0] * qd[0] ** 2 / 2
    vx, vy = qd[0], sp.S.Zero
    for i in range(n):
        vx += ls[i] * sp.cos(q[i + 1]) * qd[i + 1]
        vy += ls[i] * sp.sin(q[i + 1]) * qd[i + 1]
        T += ms[i + 1] * (vx**2 + vy**2) / 2
    return T


# -- float64 evaluation: the compiled program against the walk ----------------------------


def _walk(M: sp.MatrixBase, point: dict) -> np.ndarray:
    env, memo = dict(point), {}
    out = np.empty((M.rows, M.cols), dtype=complex)
    for i in range(M.rows):
        for j in range(M.cols):
            try:
                out[i, j] = numeric._eval(M[i, j], env, memo)
            except numeric.EvaluationError as exc:
                raise numeric.EvaluationError(exc.reason, (i, j)) from None
            except numeric._ARITHMETIC as exc:
                raise numeric.EvaluationError(numeric._reason(exc), (i, j)) from None
    return out


def _evaluated(evaluate, M, point):
    try:
        return ("value", repr(evaluate(M, point).tolist()))
    except Exception as exc:
        return ("raised", type(exc).__name__, str(exc), getattr(exc, "index", None))


@pytest.mark.parametrize("seed", range(3))
def test_compiled_evaluation_is_the_walk(seed: int) -> None:
    rng = random.Random(seed)
    g = sp.Function("g")
    leaves = [x, y, z, m, g(x), sp.Derivative(g(x), x)]
    consts = [sp.S(0), sp.S(2), sp.Rational(-1, 3), sp.pi, sp.Float(1.5), sp.oo, sp.zoo]
    consts += [sp.Integer(10) ** 400, sp.I]
    unary = [sp.sin, sp.cos, sp.exp, sp.log, sp.tan, sp.atan, sp.sqrt]
    unary += [lambda u: sp.atan2(u, x), lambda u: u * sp.gamma(y)]

    def expr(depth: int) -> sp.Expr:
        if depth == 0 or rng.random() < 0.25:
            return rng.choice(consts) if rng.random() < 0.15 else rng.choice(leaves)
        r = rng.random()
        if r < 0.3:
            return sp.Add(*[expr(depth - 1) for _ in range(rng.randint(2, 3))])
        if r < 0.6:
            return sp.Mul(*[expr(depth - 1) for _ in range(rng.randint(2, 3))])
        if r < 0.8:
            return sp.Pow(expr(depth - 1), rng.choice([2, -1, 3, sp.Rational(1, 2), y]))
        return rng.choice(unary)(expr(depth - 1))

    outcomes = set()
    for _ in range(150):
        k = rng.randint(1, 3)
        M = sp.Matrix(k, k, [expr(rng.randint(0, 4)) for _ in range(k * k)])
        point = {s: sp.Rational(rng.randint(-3000, 3000), 1000) for s in leaves}
        for _ in range(2):  # compiled, then from the kept program
            got = _evaluated(numeric.evaluate_matrix, M, point)
            assert got == _evaluated(_walk, M, point)
        outcomes.add(got[0])
    assert outcomes == {"value", "raised"}


def test_compiled_evaluation_from_many_threads() -> None:
    """The kept programs are shared by every thread (scenes may be declared in several
    at once): more matrices than the cache keeps, evaluated concurrently, give the walk's
    values."""
    from concurrent.futures import ThreadPoolExecutor

    matrices = [
        sp.Matrix([[sp.cos(x) ** k + m, x * y], [x * y, sp.sin(y) ** k + m]]) for k in range(20)
    ]
    point = {x: sp.Rational(1, 3), y: sp.Rational(-2, 7), m: sp.Rational(5, 2)}
    expected = [_evaluated(_walk, M, point) for M in matrices]

    def evaluate(k: int) -> tuple:
        return _evaluated(numeric.evaluate_matrix, matrices[k % 20], point)

    with ThreadPoolExecutor(8) as pool:
        got = list(pool.map(evaluate, range(400)))
    assert got == [expected[k % 20] for k in range(400)]


def test_deep_trees_are_walked() -> None:
    e = x
    for k in range(300):
        e = sp.sin(e) + k if k % 2 else sp.cos(e) * y
    M = sp.Matrix([[e, x], [x, e]])
    point = {x: sp.Rational(1, 3), y: sp.Rational(1, 2)}
    assert _evaluated(numeric.evaluate_matrix, M, point) == _evaluated(_walk, M, point)


def test_rational_to_complex_is_complex() -> None:
    rng = random.Random(3)
    for _ in range(3000):
        r = sp.Rational(rng.randint(-(10**9), 10**9), rng.randint(1, 10**6))
        assert repr(numeric._complex(r)) == repr(complex(r))


# -- walks of shared subtrees -------------------------------------------------------------


def test_walks_are_sympys() -> None:
    rng = random.Random(5)
    for _ in range(300):
        e = _random_expr(rng, 4, odd=True)
        assert free_symbols(e) == frozenset(e.free_symbols)
        types = (sp.Function, sp.Max, sp.Min)
        assert atoms(e, types) == e.atoms(*types)
    shared = sp.Integral(x * y, (x, 0, 1)) + sp.Lambda(z, z * y)(x)
    assert free_symbols(shared) == frozenset(shared.free_symbols)
    many = [_random_expr(rng, 4, odd=True) for _ in range(20)] + [shared]
    assert free_symbols_of(many) == set().union(*(e.free_symbols for e in many))
    assert free_symbols_of([]) == set()


def test_xreplace_is_sympys() -> None:
    """Same expression, argument for argument, as sympy's: the largest match first, a node
    rebuilt when anything below it was replaced (a rule mapping a subtree to itself
    included), unevaluated nodes kept as they are when nothing below them changed."""
    from sympy.physics import mechanics as me

    rng = random.Random(7)
    rules = [{x: y}, {x: sp.Integer(2), y: x}, {sp.sin(x): z, x: x}, {y: 1 / z}]
    memos: list[dict] = [{} for _ in rules]
    for _ in range(300):
        e = _random_expr(rng, 4, odd=True)
        for rule, memo in zip(rules, memos, strict=True):
            try:
                expected = sp.srepr(e.xreplace(rule))
            except ValueError:  # a derivative by what became a number: refused alike
                with pytest.raises(ValueError):
                    xreplace(e, rule, memo)
                continue
            assert sp.srepr(xreplace(e, rule, memo)) == expected, (e, rule)
    t = me.dynamicsymbols._t
    q1 = me.dynamicsymbols("q1")
    e = sp.sin(q1) * q1.diff(t) + q1 * t
    rule = {q1.diff(t): y, q1: x, t: z}
    assert sp.srepr(xreplace(e, rule)) == sp.srepr(e.xreplace(rule))
    unevaluated = sp.Add(x, x, evaluate=False)
    assert sp.srepr(xreplace(unevaluated, {y: 1})) == sp.srepr(unevaluated.xreplace({y: 1}))
    assert sp.srepr(xreplace(unevaluated, {x: x})) == sp.srepr(unevaluated.xreplace({x: x}))


def test_memos_of_expressions_are_emptied_with_sympys_cache() -> None:
    """A memo keyed by expressions that outlives sympy's cache compares the twins a new
    run builds with == node by node (issue 27: most of the time of a pendulum declared as
    users write it, after clear_cache): symmech's memos are emptied with sympy's."""
    from sympy.core.cache import clear_cache

    pendulum_on_cart(2).forcing()
    assert canonical._sort_key.cache_info().currsize > 0
    clear_cache()
    assert canonical._sort_key.cache_info().currsize == 0


def test_compiled_programs_are_kept_by_identity_of_the_matrix() -> None:
    """The program of a matrix is reused for the same entries; a structurally equal matrix
    built anew (after sympy's cache is cleared) gets its own, with no deep == between the
    two, and both give the same values."""
    from sympy.core.cache import clear_cache

    env = {x: 0.3, y: -1.2, z: 2.0}

    def build() -> sp.Matrix:
        return sp.Matrix([[sp.sin(x) * y + z**2, sp.exp(x * y)], [x + y + z, sp.cos(z) / y]])

    first = build()
    program = numeric._Program.of(first, env)
    assert program is not None and numeric._Program.of(first, env) is program
    clear_cache()
    twin = build()
    assert twin == first and twin[0, 0] is not first[0, 0]
    assert numeric._Program.of(twin, env) is not program
    assert np.array_equal(numeric.evaluate_matrix(first, env), numeric.evaluate_matrix(twin, env))
