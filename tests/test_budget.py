"""Budgets of the symbolic stages (symmech.algebra.budget) and how code generation uses them.

The bounds are checked against sympy's own expansion and determinant (independent
routes: ``Poly(expand(e))``, ``Matrix.det`` expanded, a brute-force permanent); the time
limit against a computation that cannot finish in time; code generation against its
rules: an over-budget closed form is never attempted silently (``auto`` falls back to
``linear_solve`` and says so, ``closed_form`` raises a ``CodegenError`` naming the stage
and the budget), and ``linear_solve`` derives no closed form at all.
"""

from __future__ import annotations

import ast
import itertools
import random
import signal
import threading
import time
from pathlib import Path

import pytest
import sympy as sp
from scale_support import DENSE_TRIG_3, POWER_64, cart_with_tip_wall, chaplygin_ball_wall

import symmech as sm
from symmech import codegen
from symmech.algebra import budget
from symmech.algebra.budget import BudgetExceeded
from symmech.algebra.field import RationalField
from symmech.algebra.stability import stable_coefficient
from symmech.codegen.plan import CodegenError
from symmech.examples import bouncing_ellipse, carnot_3_7, pendulum_on_cart

PKG = Path(__file__).resolve().parents[1] / "symmech"
a, b, c, x, y, z = sp.symbols("a b c x y z", real=True)


# ---------------------------------------------------------------------------------------
# one module, one exception


def test_no_other_budget_exception_or_threshold_in_the_symbolic_layers():
    """Budgets live in symmech/budget.py: no other module of the symbolic layers defines
    an exception class or a module-level numeric threshold named like a budget."""
    offenders = []
    for folder in ("geometry", "constraints", "impacts"):
        for path in (PKG / folder).rglob("*.py"):
            tree = ast.parse(path.read_text())
            for node in tree.body:
                if isinstance(node, ast.ClassDef) and "Budget" in node.name:
                    offenders.append(f"{path.name}: class {node.name}")
                if isinstance(node, ast.Assign) and isinstance(node.value, ast.Constant):
                    for target in node.targets:
                        name = getattr(target, "id", "")
                        if isinstance(node.value.value, int) and any(
                            key in name for key in ("_OPS", "_TERMS", "BUDGET", "MAX_N")
                        ):
                            offenders.append(f"{path.name}: {name}")
    plan = ast.parse((PKG / "codegen" / "plan.py").read_text())
    for node in plan.body:
        if isinstance(node, ast.Assign) and isinstance(node.value, ast.Constant):
            name = getattr(node.targets[0], "id", "")
            if "MAX" in name or "OPS" in name:
                offenders.append(f"plan.py: {name}")
    assert not offenders, offenders


def test_budget_exceeded_names_stage_budget_and_value():
    exc = BudgetExceeded("impact map of wall 'w'", "IMPACT_TERMS", "terms", 10, 25)
    assert isinstance(exc, sm.SymmechError)
    text = str(exc)
    assert "impact map of wall 'w'" in text and "IMPACT_TERMS = 10 terms" in text
    assert "25 terms" in text
    assert (exc.stage, exc.budget, exc.measure, exc.limit, exc.measured) == (
        "impact map of wall 'w'",
        "IMPACT_TERMS",
        "terms",
        10,
        25,
    )


# ---------------------------------------------------------------------------------------
# the structural bounds


def _random_expr(rng: random.Random, depth: int = 0) -> sp.Expr:
    atoms = [a, b, x, sp.sin(x), sp.cos(y), sp.Integer(2), sp.Rational(-1, 3)]
    if depth >= 3 or rng.random() < 0.25:
        return rng.choice(atoms)
    kind = rng.choice(["add", "mul", "pow"])
    if kind == "add":
        return sp.Add(*[_random_expr(rng, depth + 1) for _ in range(rng.randint(2, 3))])
    if kind == "mul":
        return sp.Mul(*[_random_expr(rng, depth + 1) for _ in range(2)])
    return _random_expr(rng, depth + 1) ** rng.randint(2, 4)


def test_expanded_terms_bounds_the_expansion():
    rng = random.Random(13)
    for _ in range(60):
        e = _random_expr(rng)
        terms, degree = budget.expanded_terms(e)
        gens = sorted(e.free_symbols, key=str) + sorted(e.atoms(sp.sin, sp.cos), key=str)
        expanded = sp.expand(e)
        if expanded.is_number:
            assert terms >= 1
            continue
        poly = sp.Poly(expanded.xreplace({}), *gens) if gens else None
        actual = len(poly.terms()) if poly is not None else 1
        assert actual <= terms, (e, actual, terms)
        assert poly is None or poly.total_degree() <= degree, (e, degree)


def test_expanded_terms_of_the_hostile_power_is_a_binomial():
    e = (sp.sin(x) + sp.cos(y) + x * y * z + 1) ** 64
    # monomials of degree 64 in 4 terms: C(67, 3); a cap stops large binomials early
    assert budget.expanded_terms(e) == (sp.binomial(67, 3), 64 * 3)
    assert budget.expanded_terms((x + y) ** (10**6), cap=1000)[0] == 1000


def test_permanent_against_brute_force():
    rng = random.Random(5)
    for n in range(1, 6):
        w = [[rng.randint(0, 3) for _ in range(n)] for _ in range(n)]
        brute = sum(
            sp.prod([w[i][p[i]] for i in range(n)]) for p in itertools.permutations(range(n))
        )
        assert budget._permanent(w) == brute


def test_determinant_terms_bounds_the_determinant_by_blocks():
    # block-diagonal: the bound is the larger block's, and bounds sympy's expanded det
    M = sp.Matrix(
        [
            [a + b, x, 0, 0],
            [x, a * sp.cos(y), 0, 0],
            [0, 0, 1 + x**2, a],
            [0, 0, a, b],
        ]
    )
    bound = budget.determinant_terms(M)
    for block in (M[:2, :2], M[2:, 2:]):
        assert len(sp.Add.make_args(sp.expand(block.det()))) <= bound
    assert bound == max(budget._permanent([[2, 1], [1, 1]]), budget._permanent([[2, 1], [1, 1]]))
    # a diagonal metric is n blocks of size one at any n
    assert budget.determinant_terms(sp.eye(200)) == 1


# ---------------------------------------------------------------------------------------
# time


def test_time_limit_stops_a_long_library_call_and_restores_the_handler():
    before = signal.getsignal(signal.SIGALRM)
    start = time.perf_counter()
    with pytest.raises(BudgetExceeded) as info:
        with budget.time_limit("a long factorisation", 0.3):
            sp.factor(sp.expand((x + y + z + a + 1) ** 30) - 1)
    assert time.perf_counter() - start < 5
    assert info.value.stage == "a long factorisation" and info.value.measure == "seconds"
    assert signal.getsignal(signal.SIGALRM) == before
    assert signal.getitimer(signal.ITIMER_REAL)[0] == 0
    assert budget.remaining() is None


def test_checkpoint_and_nested_limits_keep_the_earlier_deadline():
    budget.checkpoint()  # outside a limit: nothing
    with pytest.raises(BudgetExceeded) as info:
        with budget.time_limit("outer", 0.05):
            with budget.time_limit("inner", 100):
                remaining = budget.remaining()
                assert remaining is not None and remaining <= 0.05
                time.sleep(0.2)  # the real-time timer of the outer limit interrupts
                budget.checkpoint()
    assert info.value.stage == "outer"


def test_checkpoint_outside_the_main_thread():
    """Without the real-time timer (not the main thread) the loops' checkpoints stop."""
    caught: list[BaseException] = []

    def work() -> None:
        try:
            with budget.time_limit("threaded stage", 0.02):
                time.sleep(0.05)
                budget.checkpoint()
        except BudgetExceeded as exc:
            caught.append(exc)

    thread = threading.Thread(target=work)
    thread.start()
    thread.join()
    assert len(caught) == 1 and caught[0].stage == "threaded stage"


def test_a_term_budget_inside_does_not_swallow_the_deadline(monkeypatch):
    """A stage that skips an optional step over its own term budget (the field solve)
    re-raises a time limit instead of treating it as its own budget."""
    monkeypatch.setattr(budget, "CLOSED_FORM_SECONDS", 1e-3)
    with pytest.raises(CodegenError, match="CLOSED_FORM_SECONDS"):
        codegen.generate(bouncing_ellipse(), "numpy", strategy="closed_form")


# ---------------------------------------------------------------------------------------
# skip budgets: the result stays exact


def test_field_declines_an_input_whose_expansion_is_over_budget():
    V = (sp.sin(x) + sp.cos(y) + x * y * z + 1) ** 64
    start = time.perf_counter()
    field = RationalField([sp.diff(V, x)])
    assert time.perf_counter() - start < 2
    assert field.K is None and "FIELD_TERMS" in field.declined
    small = RationalField([(x + 1) ** 3])
    assert small.K is not None and small.declined is None


def test_field_declines_inputs_with_too_many_generators_and_the_solve_stays_exact():
    """A potential of 20 trigonometric terms needs 4 * 20 generators (sin and cos of
    k x and k y): over FIELD_GENERATORS the field declines, and the acceleration (an
    identity metric: a = -grad V) comes from the plain route, still exact."""
    V = sp.Add(*[sp.cos(k * x) * sp.sin(k * y) for k in range(1, 21)])
    field = RationalField([sp.diff(V, x), sp.diff(V, y)])
    assert field.K is None and "80 generators" in field.declined
    assert "FIELD_GENERATORS = 64" in field.declined
    scene = sm.Scene([x, y], metric=sp.eye(2), potential=V, name="many_generators")
    acc = scene.acceleration()
    assert sp.expand(acc[0] + sp.diff(V, x)) == 0 and sp.expand(acc[1] + sp.diff(V, y)) == 0
    assert RationalField([sp.cos(x) * sp.sin(y)]).declined is None


def test_stable_coefficient_structural_shortcut_agrees_with_the_full_step():
    scene = pendulum_on_cart(5)
    state = (*scene.coordinates, sm.t)
    g = scene.mass_matrix()
    for e in {g[i, j] for i in range(6) for j in range(i, 6)}:
        fast = stable_coefficient(e, state)
        assert sp.expand(fast - e) == 0
        full = sp.factor(sp.cancel(e))
        assert sp.expand(fast - full) == 0
    # the difference of squares is still factored (no cancellation when a ~ b), also as
    # the coefficient of a state monomial; a sum of positive terms is kept as it is
    assert stable_coefficient(a**2 - b**2) == (a - b) * (a + b)
    s = sp.sin(x) ** 2
    assert stable_coefficient(a**2 * s - b**2 * s + sp.cos(x), (x,)) == (a - b) * (
        a + b
    ) * s + sp.cos(x)
    m, k = sp.symbols("m k", positive=True)
    positive = m**2 * s + m * k * s + sp.cos(x)
    assert stable_coefficient(positive, (x,)) == positive
    assert stable_coefficient(1 - a / (a + b)) == b / (a + b)
    # over the expansion budget: returned as given, at once
    big = (sp.sin(x) + sp.cos(y) + x * y * z + 1) ** 63 * (sp.cos(x) + y * z)
    start = time.perf_counter()
    assert stable_coefficient(big, (x, y, z)) == big
    assert time.perf_counter() - start < 2


# ---------------------------------------------------------------------------------------
# code generation: never attempted silently


@pytest.mark.parametrize(
    ("build", "stage"),
    [
        (lambda: sm.reads_scene(POWER_64).scene, "closed-form acceleration"),
        (lambda: sm.reads_scene(DENSE_TRIG_3).scene, "closed-form inverse of the metric"),
        (lambda: cart_with_tip_wall(3), "closed-form inverse of the metric"),
        (chaplygin_ball_wall, "closed-form inverse of the metric"),
    ],
    ids=["power_64", "dense_trig_3", "cart_3_tip_wall", "chaplygin_ball"],
)
def test_explicit_closed_form_over_budget_is_refused_at_once(build, stage):
    scene = build()
    start = time.perf_counter()
    with pytest.raises(CodegenError) as info:
        codegen.generate(scene, "numpy", strategy="closed_form")
    assert time.perf_counter() - start < 5
    text = str(info.value)
    assert stage in text and "budget" in text and "linear_solve" in text
    assert not any(key[0] in ("impact", "acceleration") for key in scene._cache)


def test_auto_falls_back_to_linear_solve_and_says_so():
    scene = sm.reads_scene(DENSE_TRIG_3).scene
    code = codegen.generate(scene, "numpy")
    assert code.plan.strategy == "linear_solve"
    assert code.plan.fallback is not None and "CLOSED_FORM_TERMS" in code.plan.fallback
    assert code.plan.fallback in code.omitted
    assert "linear_solve" in code.files[f"{code.stem}.py"]


def test_auto_falls_back_when_the_time_budget_runs_out(monkeypatch):
    monkeypatch.setattr(budget, "CLOSED_FORM_SECONDS", 1e-3)
    code = codegen.generate(carnot_3_7(), "numpy")
    assert code.plan.strategy == "linear_solve"
    assert "CLOSED_FORM_SECONDS" in code.plan.fallback and "seconds" in code.plan.fallback
    # within budget the same scene is closed form, without a fallback note
    monkeypatch.undo()
    code = codegen.generate(carnot_3_7(), "numpy")
    assert code.plan.strategy == "closed_form" and code.plan.fallback is None


def test_linear_solve_derives_no_closed_form():
    scene = cart_with_tip_wall(4)
    start = time.perf_counter()
    code = codegen.generate(scene, "numpy", strategy="linear_solve")
    elapsed = time.perf_counter() - start
    assert elapsed < 30, f"{elapsed:.1f} s"
    kinds = {key[0] for key in scene._cache}
    assert not kinds & {"impact", "acceleration", "constrained", "projectors", "lambda"}, kinds
    assert code.plan.function("impact_tip").step == "impact_kkt"
