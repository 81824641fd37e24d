"""Printing rules of the generated code: powers, folded constants, literals.

The rules are documented in :mod:`symmech.codegen.printers`: integer powers up to
``MAX_PRODUCT_POWER`` are products in every function, ``pow`` beyond; a baked float
constant with an integral or half-integral value behaves like the exact number; every
symbol-free subexpression becomes one correctly rounded literal.
"""

from __future__ import annotations

import re

import mpmath as mp
import numpy as np
import pytest
import sympy as sp
from codegen_support import require_c_compiler

import symmech as sm
from symmech import codegen
from symmech.codegen.printers import (
    MAX_PRODUCT_POWER,
    SymmechCPrinter,
    correctly_rounded,
    fold_numbers,
)


def _power_scene(potential_of) -> sm.Scene:
    x, y = sm.coordinates("x y")
    k, c = sp.symbols("k c", positive=True)
    return sm.Scene((x, y), metric=sp.eye(2), potential=potential_of(x, y, k, c), name="powers")


def _sources(scene: sm.Scene, **options) -> tuple[str, str]:
    c_src = codegen.generate(scene, "c", **options).files["symmech_powers.c"]
    np_src = codegen.generate(scene, "numpy", **options).files["symmech_powers.py"]
    return c_src, np_src


def _code_lines(src: str) -> str:
    """The statements of a generated file (comments and docstrings dropped)."""
    lines = [
        ln for ln in src.splitlines() if re.match(r"\s+(const double|out|tmp|[A-Za-z_]+\[)", ln)
    ]
    return "\n".join(lines)


@pytest.mark.parametrize("k", [2.0, 3.0, 0.5, 1.5])
def test_baked_float_exponents_print_like_exact_numbers(k):
    """V = sqrt(k) x^k + c y with k = 2.0 baked in used to give pow(q_x, 2.0) in the
    energy and pow(q_x, 1.0) in the forcing, and sqrt(2.0) computed on every call."""
    scene = _power_scene(lambda x, y, k, c: sp.sqrt(k) * x**k + c * y)
    c_src, np_src = _sources(scene, constants={"k": k})
    c_code, np_code = _code_lines(c_src), _code_lines(np_src)
    assert "pow(" not in c_code and "**" not in np_code
    assert "numpy.sqrt(2.0" not in np_code and "sqrt(2.0)" not in c_code
    if k in (0.5, 1.5):
        assert "numpy.sqrt(q_x)" in np_code  # x**0.5 and x**1.5 = sqrt(x) x
    mod = codegen.generate(scene, "numpy", constants={"k": k}).load()
    x = 0.3
    np.testing.assert_allclose(
        mod.energy([x, 0.5], [0.0, 0.0], [2.0]), np.sqrt(k) * x**k + 1.0, rtol=4e-16
    )
    np.testing.assert_allclose(
        mod.forcing([x, 0.5], [0.0, 0.0], [2.0]),
        [-np.sqrt(k) * k * x ** (k - 1), -2.0],
        rtol=4e-16,
    )


def test_integer_powers_follow_one_rule_in_every_function():
    """x^5 in the energy and 5 x^4 in the forcing are both products; x^9 (above
    MAX_PRODUCT_POWER = 8) is pow in the energy while 9 x^8 in the forcing is a product."""
    assert MAX_PRODUCT_POWER == 8
    c_src, np_src = _sources(_power_scene(lambda x, y, k, c: k * x**5 + c * y**9))
    c_code, np_code = _code_lines(c_src), _code_lines(np_src)
    # the energy and its batch loop's per-state body (symmech.codegen.batch_split)
    assert c_code.count("pow(") == 2 and "pow(q_y, 9.0)" in c_code
    # the vectorised energy and its one-state variant _one_energy
    assert np_code.count("**") == 2 and "q_y**9.0" in np_code
    printer = SymmechCPrinter({sp.Symbol("x"): "x"})
    x = sp.Symbol("x")
    for k in range(-MAX_PRODUCT_POWER, MAX_PRODUCT_POWER + 1):
        if k:
            text = printer.doprint(x**k)
            assert "pow" not in text, text
    assert printer.doprint(x**8) == "(((x*x)*(x*x))*((x*x)*(x*x)))"
    assert printer.doprint(x ** sp.Rational(-5, 2)) == "(1.0/(sqrt(x)*(x*x)))"
    assert "pow(x, 9.0)" == printer.doprint(x**9)


@pytest.mark.parametrize("target", ["c", "numpy"])
def test_powers_evaluate_to_within_their_rounding_bound(target):
    """x^k for k = -8..9 and x^(p/2): the product forms are within (|k| - 1 + [k < 0]) u
    (repeated squaring, one rounding per product), pow within an ulp."""
    if target == "c":
        require_c_compiler()
    x, y = sm.coordinates("x y")
    exps = [sp.Integer(k) for k in range(-8, 10) if k] + [sp.Rational(p, 2) for p in (-7, 3, 17)]
    # a wall's gap is one expression on its own: psi = y + x^e evaluates x^e at y = 0
    scene = sm.Scene(
        (x, y),
        metric=sp.eye(2),
        walls=[sm.Wall(y + x**e, restitution=1, name=f"e{i}") for i, e in enumerate(exps)],
        name="powers",
    )
    mod = codegen.generate(scene, target, functions=["psi"]).load()
    xv = 1.2345678901234567
    for i, e in enumerate(exps):
        got = float(mod.psi([xv, 0.0], wall=i))
        with mp.workdps(50):
            exact = mp.power(mp.mpf(xv), mp.mpf(int(e.p)) / int(e.q))
            rel = abs((mp.mpf(got) - exact) / exact)
        if e.is_Integer:
            allowed = abs(int(e)) - 1 + (1 if e < 0 else 0) if abs(e) <= MAX_PRODUCT_POWER else 2
        else:
            allowed = abs(int(e.p)) // 2 + 1 + (1 if e < 0 else 0)
        assert rel <= allowed * 2.0**-53, (e, float(rel) * 2**53, allowed)


def test_compound_bases_of_powers_are_computed_once():
    _, np_src = _sources(_power_scene(lambda x, y, k, c: k * (x + y) ** 3))
    np_code = _code_lines(np_src)
    assert "(q_x + q_y)*(q_x + q_y)" not in np_code
    assert re.search(r"tmp\d+ = q_x \+ q_y", np_code), np_code


def test_symbol_free_subexpressions_become_correctly_rounded_literals():
    x = sp.Symbol("x")
    constants = [sp.sqrt(2), sp.pi / 7, sp.E / 3, sp.sin(1), sp.Rational(1, 3), 3 * sp.sqrt(5) / 7]
    for c in constants:
        with mp.workdps(60):
            expected = float(mp.mpf(sp.N(c, 60)))
        assert correctly_rounded(c) == expected, c
    folded = fold_numbers(3 * sp.sqrt(2) * x + 1 + sp.pi + sp.cos(sp.sqrt(2) * x))
    assert folded.free_symbols == {x}
    numbers = [a for a in sp.preorder_traversal(folded) if a.is_Number]
    assert all(isinstance(a, sp.Float | sp.Integer) for a in numbers), numbers
    assert correctly_rounded(3 * sp.sqrt(2)) in [float(a) for a in numbers]
    assert correctly_rounded(1 + sp.pi) in [float(a) for a in numbers]
    # in the generated code: no call computes a constant
    scene = _power_scene(lambda x, y, k, c: sp.sqrt(k) * x**2 + sp.pi * c * y / 3)
    c_src, np_src = _sources(scene, constants={"k": 2})
    assert "sqrt(" not in _code_lines(c_src) and "numpy.sqrt" not in _code_lines(np_src)
    assert repr(float(np.sqrt(2.0))) in np_src
    with pytest.raises(ValueError, match="not a finite real number"):
        correctly_rounded(sp.oo)
