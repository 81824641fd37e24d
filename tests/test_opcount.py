"""symmech.algebra.opcount.count_ops is sympy.count_ops as an integer, on the shapes the
budgets and the generated files' headers count."""

from __future__ import annotations

import random

import sympy as sp

from symmech.algebra.opcount import count_ops

x, y, z = sp.symbols("x y z")
f = sp.Function("f")

SHAPES = [
    -x, -x - y, -x + y, x - y, -2 * x / 3, x / (y + 1), -x / y, 1 / x, sp.exp(x), sp.E,
    sp.exp(-x) * y, 2**x, x**-2, -((x + y) ** -1), sp.sqrt(x), f(x) + 1,
    sp.Derivative(f(x), x), sp.Rational(-1, 3), sp.S.One, sp.S.Zero, sp.Integer(-5),
    3 * x * y, -3 * x * y / (z - 1), sp.sin(x) ** 2 - 1, x * y**-1 * z**-2,
    sp.Float(-1.5) * x, sp.I * x, -sp.I, sp.pi * x, sp.Max(x, y) + 1,
    sp.Abs(x) - sp.sign(y), sp.Piecewise((x, x > 0), (y, True)), x ** sp.Rational(-1, 2),
    (x + y) ** -3 - x, sp.Eq(x, y), sp.Matrix([x + y, -x]), sp.Tuple(x, -y),
]  # fmt: skip


def _random_expression(rng: random.Random, depth: int) -> sp.Expr:
    if depth == 0:
        return rng.choice([x, y, z, sp.Integer(rng.randint(-3, 3)), sp.Rational(-1, 2)])
    a, b = _random_expression(rng, depth - 1), _random_expression(rng, depth - 1)
    return rng.choice(
        [a + b, a - b, a * b, -a * b, a / (b + 2), sp.sin(a) * b, sp.exp(a) - b, a**2 * b]
    )


def test_count_ops_is_sympys():
    rng = random.Random(5)
    shapes = SHAPES + [_random_expression(rng, rng.randint(1, 5)) for _ in range(300)]
    for e in shapes:
        assert count_ops(e) == sp.count_ops(e), e
    memo: dict = {}  # shared between calls: the same counts
    assert [count_ops(e, memo) for e in shapes] == [sp.count_ops(e) for e in shapes]
