"""Numerically stable closed forms for impact maps (the "stabilising step").

Impact maps are evaluated in float64 by generated code.  Written the way the projector
algebra produces them, their entries are often differences of nearly equal terms, e.g.
``1 - m R^2/(I + m R^2)`` (which is ``I/(I + m R^2)``), or text 001's (section 3.2) rebound
coefficient ``I/m - I^2 R^2/I1^2 - I^3/(m I1^2)`` with ``I1 = I + m R^2``, which equals
``I R^2/I1`` and loses every digit in float64 when ``m R^2 << I``.

The stabilising step implemented here is:

1. **Per-coefficient normal form.** An expression linear (or quadratic) in the velocities
   is split into its coefficients (functions of q, t and the parameters only); each
   coefficient is put over a common denominator with :func:`sympy.cancel` (this is what
   combines ``1 - x/(x + y)`` into ``y/(x + y)``) and its numerator and denominator are
   factored with :func:`sympy.factor` (so a product is not expanded into a sum of
   monomials that cancel each other numerically).  The velocities themselves are never
   put over a common denominator, because that would mix terms of very different sizes.
2. **Sums of squares for square roots.** The energy law (text 001, section 3.2) needs
   ``sqrt(b^T C^{-1} b / (C^{-1})_{00})``.  The argument is written as
   ``y_0^2 + sum_A (D_0/D_A) y_A^2`` from an LDL^T factorisation of C (see
   :func:`symmech.impacts.energy_law`), a sum of non-negative terms which cannot cancel
   and is never negative in floating point.

Expressions above :data:`symmech.algebra.budget.STABLE_OPS` operations are left as they are (the
cost of ``factor`` grows quickly); this mirrors :mod:`symmech.algebra.simplification`.
Expressions in more than :data:`symmech.algebra.budget.STABLE_FACTOR_GENERATORS`
generators (symbols, function values, fractional powers; an entry of a bicycle's metric
has 26) skip the factorisation as a whole and keep step 1's per-coefficient factoring
only: like terms are combined exactly, and each state monomial's parameter coefficient is
factored, which is where differences of nearly equal terms arise.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import sympy as sp
from sympy.core.mul import _keep_coeff

from symmech.algebra import budget as limits
from symmech.algebra.memo import expression_cache
from symmech.algebra.zero import evidently_nonzero, is_zero

__all__ = ["stable_coefficient", "stable_entry", "stable_linear", "stable_matrix"]


@expression_cache(maxsize=4096)
def _factor(e: sp.Expr) -> sp.Expr:
    """``sympy.factor(e)``, memoised until sympy's cache is cleared: the entries of a
    metric or a constraint matrix share parameter coefficients (the bicycle's 28 stable
    entries factor 37 distinct polynomials in 138 calls).  A polynomial that is
    irreducible by :func:`_evidently_irreducible` is returned as ``factor`` writes it
    without the search for factors."""
    if e.is_Atom:
        return e
    quick = _evidently_irreducible(e)
    return sp.factor(e) if quick is None else quick


def _evidently_irreducible(e: sp.Expr) -> sp.Expr | None:
    """``sympy.factor(e)`` when, once its integer and monomial contents are taken out, the
    integer polynomial ``e`` has a generator of degree one in exactly one of its terms
    (``x A + B`` with A a monomial: a common factor of A and B would divide every term,
    and there is none left, so the rest is irreducible); else None.  Written as
    ``factor`` writes it: content, then the monomial, then the primitive part with a
    positive leading coefficient (``dmp_zz_factor``).  Most parameter coefficients of a
    metric (sums of inertias and masses times lengths) are of this kind, and the
    multivariate factorisation costs far more than this test."""
    try:
        p = sp.Poly(e)
    except (sp.PolynomialError, sp.GeneratorsNeeded):
        return None
    if not p.domain.is_ZZ or not all(g.is_Symbol or g.is_Function for g in p.gens):
        return None
    monomial, rest = p.terms_gcd()
    content, rest = rest.primitive()
    if rest.LC() < 0:
        content, rest = -content, -rest
    terms = rest.monoms()
    if len(terms) < 2:
        return None
    linear = any(
        sum(1 for m in terms if m[k]) == 1 and max(m[k] for m in terms) == 1
        for k in range(len(rest.gens))
    )
    if not linear:
        return None
    powers = [g**k for g, k in zip(rest.gens, monomial, strict=True)]
    return _keep_coeff(content.as_expr(), sp.Mul(rest.as_expr(), *powers))


def stable_entry(expr: sp.Expr, state: Iterable[sp.Symbol]) -> sp.Expr:
    """The form in which generated code evaluates a velocity-free entry (a metric, a
    constraint one-form, a wall's gradient): :func:`stable_coefficient`, except for a sum
    holding a radical of the state (:func:`_state_radical`) and products of sums (its
    expansion, :func:`symmech.algebra.budget.expanded_terms`, has more terms than it
    has), which is kept as written, or 0 when it is identically zero
    (:func:`symmech.algebra.zero.is_zero`).

    ``stable_coefficient`` puts a sum over the common denominator of its terms and expands
    the numerator; for such a sum that multiplies the radical and the products of sums of
    state functions into every term (the Whipple bicycle's rolling constraints grow from
    about 150 to 375 operations) and combines no parameter terms.  A flat sum over a
    radical, such as a wall's gradient ``a^2 sin cos / root - b^2 sin cos / root``, is
    still written stably: ``(a - b)(a + b) sin cos / root``.
    """
    st = frozenset(state)
    if (
        isinstance(expr, sp.Add)
        and _state_radical(expr, st)
        and limits.expanded_terms(expr)[0] > len(expr.args)
    ):
        return expr if evidently_nonzero(expr) or not is_zero(expr) else sp.S.Zero
    return stable_coefficient(expr, st)


def _state_radical(expr: sp.Expr, state: Iterable[sp.Symbol]) -> bool:
    """Whether ``expr`` holds a fractional power of an expression of the ``state``
    (``sqrt(1 - sin(q2)^2 cos(q5)^2)``, a rolling contact's normal)."""
    st = frozenset(state)
    return any(
        not node.exp.is_Integer and bool(node.base.free_symbols & st) for node in expr.atoms(sp.Pow)
    )


def _state_generators(expr: sp.Expr, state: frozenset) -> list[sp.Expr]:
    """Generators of ``expr`` that depend on the state: state symbols and function
    atoms (sin(theta), sqrt(...), f(t)) whose arguments contain a state symbol."""
    gens: set[sp.Expr] = {s for s in expr.free_symbols if s in state}
    for node in sp.preorder_traversal(expr):
        if isinstance(node, (sp.Function, sp.Derivative)) or (
            isinstance(node, sp.Pow) and not node.exp.is_Integer
        ):
            if node.free_symbols & state:
                gens.add(node)
    return sorted(gens, key=sp.default_sort_key)


def _collect_factor(f: sp.Expr, state: frozenset) -> sp.Expr:
    """An irreducible sum, written as ``sum_k c_k(params) * monomial_k(state)`` with each
    parameter coefficient factored (``a^4 - 2 a^2 b^2 + b^4 -> (a - b)^2 (a + b)^2``)."""
    if not isinstance(f, sp.Add) or not state:
        return f
    gens = _state_generators(f, state)
    if not gens:
        return f
    try:
        poly = sp.Poly(f, *gens)
    except sp.PolynomialError:  # pragma: no cover - non-polynomial in the generators
        return f
    if len(poly.terms()) < 2:
        return f
    out = sp.S.Zero
    for monom, coeff in poly.terms():
        term = _factor(coeff)
        for gen, power in zip(gens, monom, strict=True):
            term *= gen**power
        out += term
    return out


def _generators(expr: sp.Expr) -> set[sp.Expr]:
    """The generators ``factor`` works over: the symbols, function values and fractional
    powers reached through sums, products and integer powers (each distinct subtree is
    visited once)."""
    found: set[sp.Expr] = set()
    seen: set[sp.Expr] = set()
    stack = [expr]
    while stack:
        e = stack.pop()
        if e in seen or e.is_Number:
            continue
        seen.add(e)
        if e.is_Add or e.is_Mul:
            stack.extend(e.args)
        elif e.is_Pow and e.exp.is_Integer:
            stack.append(e.base)
        else:
            found.add(e)
    return found


def _polynomial(expr: sp.Expr) -> bool:
    """Whether every power in ``expr`` (function arguments included) has a positive
    integer exponent: a polynomial in its symbols and function values, with nothing for
    ``together`` to put over a common denominator."""
    return all(p.exp.is_Integer and p.exp > 0 for p in expr.atoms(sp.Pow))


def _gathered(part: sp.Expr, state: frozenset) -> sp.Expr:
    """The stable form of a numerator or denominator in many symbols, without factoring
    it as a whole: expanded (like terms combine exactly) and written as a sum over its
    state monomials with factored parameter coefficients (:func:`_collect_factor`)."""
    return _collect_factor(sp.expand(part), state)


def _refactor(product: sp.Expr, state: frozenset) -> sp.Expr:
    if isinstance(product, sp.Mul):
        return sp.Mul(*[_refactor(a, state) for a in product.args])
    if isinstance(product, sp.Pow) and product.exp.is_Integer:
        return _refactor(product.base, state) ** product.exp
    return _collect_factor(product, state)


def stable_coefficient(expr: sp.Expr, state: Iterable[sp.Symbol] = ()) -> sp.Expr:
    """Return ``factor(numerator)/factor(denominator)`` of ``cancel(expr)``.

    Combines differences of nearly equal rational terms (``1 - x/(x+y) -> y/(x+y)``) and
    keeps numerator and denominator as products.  An irreducible factor that involves the
    ``state`` (coordinates, time) is written as a sum over its state monomials with
    factored parameter coefficients, so ``I + m (a^4 - 2 a^2 b^2 + b^4) sin^2`` becomes
    ``I + m (a - b)^2 (a + b)^2 sin^2`` (no cancellation when a ~ b).  Returned unchanged:
    expressions already in that form (a cheap structural test, :func:`_already_stable`),
    and those over the budgets :data:`symmech.algebra.budget.STABLE_OPS` (operations) or
    :data:`symmech.algebra.budget.STABLE_TERMS` (terms of their expansion).  An expression
    in more than :data:`symmech.algebra.budget.STABLE_FACTOR_GENERATORS` generators
    (:func:`_generators`) is not factored as a whole (the cost of ``factor`` grows
    quickly with their number): its numerator and denominator over a common denominator
    are each written as a sum over their state monomials with factored coefficients
    (:func:`_gathered`).

    >>> import sympy as sp
    >>> I, m, R = sp.symbols("I m R", positive=True)
    >>> I1 = I + m*R**2
    >>> stable_coefficient(I/m - I**2*R**2/I1**2 - I**3/(m*I1**2))
    I*R**2/(I + R**2*m)
    """
    expr = sp.sympify(expr, strict=True)
    if expr.is_number or expr.is_Symbol:
        return sp.nsimplify(expr) if isinstance(expr, sp.Float) else expr
    limits.checkpoint()
    if not limits.affordable(expr, limits.STABLE_OPS):
        return expr
    st = frozenset(state)
    if _already_stable(expr, st) or limits.expanded_terms(expr)[0] > limits.STABLE_TERMS:
        return expr
    # exponentials are opaque generators: the polynomial algebra would split exp(a + b)
    # into exp(a) exp(b), and exp(-(x - c)^2/s^2) into exp(2cx/s^2) exp(-x^2/s^2)
    # exp(-c^2/s^2), whose factors overflow where the exponential itself is tiny
    expr, opaque = _opaque_exponentials(expr)
    st = st | {d for d, e in opaque.items() if e.free_symbols & st}
    if len(_generators(expr)) > limits.STABLE_FACTOR_GENERATORS:
        if _polynomial(expr):  # (together only pulls out common factors, expand undoes)
            return _gathered(expr, st).xreplace(opaque)
        num, den = sp.fraction(sp.together(expr))
        return (_gathered(num, st) / _gathered(den, st)).xreplace(opaque)
    c = sp.cancel(sp.together(expr))
    num, den = sp.fraction(c)
    try:
        num, den = _factor(num), _factor(den)
    except sp.PolynomialError:  # pragma: no cover - factor refuses some exotic generators
        return c.xreplace(opaque)
    return (_refactor(num, st) / _refactor(den, st)).xreplace(opaque)


def _opaque_exponentials(expr: sp.Expr) -> tuple[sp.Expr, dict[sp.Dummy, sp.Expr]]:
    """``expr`` with every ``exp(...)`` replaced by a dummy symbol, and the map back."""
    opaque: dict[sp.Dummy, sp.Expr] = {}
    found = sorted(expr.atoms(sp.exp), key=sp.default_sort_key)
    if not found:
        return expr, opaque
    subs = {}
    for e in found:
        d = sp.Dummy("exp")
        subs[e] = d
        opaque[d] = e
    return expr.xreplace(subs), opaque


def _linear(e: sp.Expr) -> bool:
    """A sum of distinct symbols with numeric coefficients (and a constant): degree one,
    hence irreducible."""
    for term in e.args:
        _, rest = term.as_coeff_Mul()
        if not (rest.is_Symbol or rest == 1):
            return False
    return True


def _already_stable(expr: sp.Expr, state: frozenset) -> bool:
    """True when ``expr`` is already in the form the stabilising step produces, decided on
    its tree without any polynomial arithmetic: a sum of terms whose state monomials
    differ, or whose coefficients on a shared state monomial form a linear sum of
    distinct symbols (nothing to combine or factor) or are all positive by structure
    (:func:`_positive`: a sum of positive terms cannot cancel), each term the product of a number,
    positive integer powers of symbols, of state generators (state symbols, functions of
    the state) and of linear sums of symbols free of the state (irreducible: ``factor``
    returns them unchanged), with no denominator.  ``cancel`` and ``factor`` would only
    regroup such an expression (no difference of nearly equal terms is left to combine),
    at a cost that grows quickly with its number of symbols; the test costs one walk
    over the top two levels of the tree."""
    groups: dict[sp.Expr, list[sp.Expr]] = {}
    for term in sp.Add.make_args(expr):
        monomial = []
        for factor in sp.Mul.make_args(term):
            if factor.is_Number:
                continue
            base, exp = factor.as_base_exp()
            if not (exp.is_Integer and exp > 0):
                return False
            if base.free_symbols & state:
                if base.is_Add or base.is_Mul:
                    return False
                monomial.append(factor)
            elif not (base.is_Symbol or (base.is_Add and _linear(base))):
                return False
        key = sp.Mul(*monomial)
        groups.setdefault(key, []).append(term / key)
    # terms sharing a state monomial: their coefficients must form a linear sum, or all be
    # positive (a sum of positive terms is evaluated without cancellation)
    return all(
        len(c) == 1 or _linear(sp.Add(*c)) or all(_positive(t) for t in c) for c in groups.values()
    )


def _positive(e: sp.Expr) -> bool:
    """True when ``e`` is positive by its structure: a product of positive numbers,
    symbols declared positive, even powers, and sums of such terms."""
    for factor in sp.Mul.make_args(e):
        if factor.is_Number:
            if not factor > 0:
                return False
            continue
        base, exp = factor.as_base_exp()
        if exp.is_Integer and exp % 2 == 0:
            continue
        if base.is_Symbol:
            if base.is_positive is not True:
                return False
        elif base.is_Add:
            if not all(_positive(t) for t in base.args):
                return False
        else:
            return False
    return True


def stable_linear(
    expr: sp.Expr, velocities: Sequence[sp.Symbol], state: Iterable[sp.Symbol] = ()
) -> sp.Expr:
    """Stable form of an expression affine in ``velocities``: ``sum_j c_j v_j + c_0``.

    Each coefficient ``c_j`` goes through :func:`stable_coefficient`; the velocities are
    not put over a common denominator.  Raises ``ValueError`` if ``expr`` is not affine.
    """
    expr = sp.sympify(expr, strict=True)
    v = list(velocities)
    present = [vj for vj in v if vj in expr.free_symbols]
    if not present:
        return stable_coefficient(expr, state)
    coeffs = [sp.diff(expr, vj) for vj in present]
    if any(c.free_symbols & set(v) for c in coeffs):
        raise ValueError(f"stable_linear: {expr} is not affine in {v}")
    constant = expr.subs(dict.fromkeys(present, 0))
    out = stable_coefficient(constant, state)
    for vj, c in zip(present, coeffs, strict=True):
        out += stable_coefficient(c, state) * vj
    return out


def stable_matrix(M: sp.MatrixBase, state: Iterable[sp.Symbol] = ()) -> sp.Matrix:
    """Apply :func:`stable_coefficient` to every entry of ``M``."""
    st = tuple(state)
    return sp.Matrix(M.rows, M.cols, [stable_coefficient(e, st) for e in M])
