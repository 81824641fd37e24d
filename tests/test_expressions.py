"""Tests of the safe expression parser (symmech.declaration.expressions)."""

from __future__ import annotations

import ast
import builtins
import fractions
import inspect
import time

import numpy as np
import pytest
import sympy as sp
import sympy.parsing.sympy_parser as sympy_parser
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from symmech.declaration import expressions
from symmech.declaration.expressions import (
    ALLOWED_CONSTANTS,
    ALLOWED_FUNCTIONS,
    MAX_DEPTH,
    MAX_DIGITS,
    MAX_EXPONENT,
    MAX_LENGTH,
    MAX_NODES,
    parse_expression,
    to_expression,
)
from symmech.errors import ExpressionError

R = {"real": True}
x, y, z, q, q_1 = sp.symbols("x y z q q_1", **R)
m, g, l, a, b, th = sp.symbols("m g l a b th", **R)
xdot, ydot, theta = sp.symbols("xdot ydot theta", **R)
SYMBOLS = {s.name: s for s in (x, y, z, q, q_1, m, g, l, a, b, th, xdot, ydot, theta)}
FIELD = "walls[0].psi"


def parse(text: str, **kw) -> sp.Expr:
    return parse_expression(text, SYMBOLS, **kw)


# -- ordinary expressions -----------------------------------------------------------------

VALID = [
    ("m*(xdot**2 + ydot**2)/2", m * (xdot**2 + ydot**2) / 2),
    ("-g*l*cos(theta)", -g * l * sp.cos(theta)),
    (
        "sqrt(a**2*cos(th)**2 + b**2*sin(th)**2)",
        sp.sqrt(a**2 * sp.cos(th) ** 2 + b**2 * sp.sin(th) ** 2),
    ),
    ("1/2*m", m / 2),
    ("x**-2", x**-2),
    ("-x", -x),
    ("- -x", x),
    ("- - -x", -x),
    ("-(-(-(x)))", -x),
    ("+x", x),
    ("-+-+x", x),
    ("-x**2", -(x**2)),
    ("(-x)**2", x**2),
    ("2**-1", sp.Rational(1, 2)),
    ("x**2**3", x**8),
    ("x/y/z", x / y / z),
    ("x - y - z", x - y - z),
    ("x - (y - z)", x - (y - z)),
    ("2*(x + 1)*y", 2 * (x + 1) * y),
    ("x*(y + z)/(x - y)", x * (y + z) / (x - y)),
    (
        "atan2(y, x) + atan(x) + asin(x) + acos(y)",
        sp.atan2(y, x) + sp.atan(x) + sp.asin(x) + sp.acos(y),
    ),
    ("sinh(x)*cosh(y)*tanh(z)*tan(x)", sp.sinh(x) * sp.cosh(y) * sp.tanh(z) * sp.tan(x)),
    ("exp(log(x))", x),
    ("exp(x) - log(y)", sp.exp(x) - sp.log(y)),
    ("0.5*m*xdot**2", 0.5 * m * xdot**2),
    ("1e3*x", sp.Float(1000.0) * x),
    ("pi*E*x", sp.pi * sp.E * x),
    ("sin(pi/6)", sp.Rational(1, 2)),
    ("12", sp.Integer(12)),
    ("0x10 + 1_000", sp.Integer(1016)),
    ("(x +\n y)", x + y),
    ("   x + y  ", x + y),
    ("\n  x*y\n", x * y),
    ("x**64 + x**-64", x**64 + x**-64),
    ("10**40", sp.Integer(10) ** 40),
    ("1" * MAX_DIGITS, sp.Integer("1" * MAX_DIGITS)),
    # a line break is whitespace, also outside brackets (a TOML multi-line string)
    ("m*g*y\n + 1000*x", m * g * y + 1000 * x),
    ("\n  m*g*y\r\n  - x\n\n  + 2\n", m * g * y - x + 2),
    ("sin(\nx)\n*\ny", sp.sin(x) * y),
]


@pytest.mark.parametrize(("text", "expected"), VALID, ids=[t for t, _ in VALID])
def test_parses_like_sympy(text, expected):
    got = parse(text)
    assert isinstance(got, sp.Expr)
    assert got == expected
    assert sp.srepr(got) == sp.srepr(expected)


def test_integer_and_float_literals():
    assert parse("3").is_Integer
    f = parse("0.1")
    assert isinstance(f, sp.Float)
    assert f == sp.Float(0.1)
    assert parse("1/10") == sp.Rational(1, 10)


def test_symbol_table_values_and_shadowing():
    c, s = sp.Symbol("c"), sp.Symbol("s")
    table = {"x": x, "k": sp.Integer(3), "w": 2, "h": 0.5, "E": c, "sin": s, "half": sp.S.Half}
    assert parse_expression("k*x + w + h", table) == 3 * x + 2 + sp.Float(0.5)
    assert parse_expression("E", table) == c  # a symbol shadows the constant
    assert parse_expression("pi", table) == sp.pi
    # in call position a name is the function, elsewhere the symbol
    assert parse_expression("sin(x) + sin", table) == sp.sin(x) + s
    assert parse_expression("half*x", table) == x / 2


def test_unicode_names():
    theta_u = sp.Symbol("θ", real=True)
    assert parse_expression("cos(θ)**2", {"θ": theta_u}) == sp.cos(theta_u) ** 2
    assert parse_expression("θ + 1", None) == sp.Symbol("θ", real=True) + 1
    # a name declared with characters that NFKC changes means that symbol when typed so
    bold = sp.Symbol("\U0001d431", real=True)
    assert parse_expression("\U0001d431**2", {"\U0001d431": bold, "x": x}) == bold**2


def test_a_hash_never_shortens_an_expression():
    """Python would read "m*g*y # +1000*x" as m*g*y: refused, with field, line and column."""
    with pytest.raises(ExpressionError) as info:
        parse_expression("m*g*y # +1000*x", SYMBOLS, field="potential", line=3)
    assert str(info.value).startswith("potential (line 3, col 7): character '#'")
    assert (info.value.line, info.value.column, info.value.token) == (3, 7, "#")
    with pytest.raises(ExpressionError) as info:
        parse_expression("(x +\n  y) # z", SYMBOLS, field="potential", line=3)
    assert (info.value.line, info.value.column) == (4, 6)


def test_homoglyph_names_are_refused_with_their_position():
    with pytest.raises(ExpressionError) as info:
        parse_expression("y + \U0001d431**2", SYMBOLS, field="potential")
    assert str(info.value).startswith("potential (col 5): name '\U0001d431'")
    assert info.value.column == 5 and info.value.token == "\U0001d431"
    for table in (SYMBOLS, None):
        with pytest.raises(ExpressionError, match="reads as 'x'"):
            parse_expression("\uff58", table)


def test_multiline_text_positions_are_those_of_the_physical_lines():
    text = "\n  m*g*y\n  + x.real\n"
    with pytest.raises(ExpressionError) as info:
        parse(text, field="potential", line=10)
    assert str(info.value).startswith("potential (line 12, col 5): attribute access 'x.real'")
    # a line break between two operands is not a product
    with pytest.raises(ExpressionError) as info:
        parse("x\ny", field="potential")
    assert (info.value.line, info.value.column, info.value.token) == (2, 1, "y")
    assert "syntax error" in str(info.value)


def test_symbols_none_accepts_any_identifier_as_real_symbol():
    got = parse_expression("alpha*cos(beta) + pi", None)
    alpha, beta = sp.symbols("alpha beta", real=True)
    assert got == alpha * sp.cos(beta) + sp.pi
    with pytest.raises(ExpressionError, match="__import__"):
        parse_expression("__import__", None, field=FIELD)
    with pytest.raises(ExpressionError, match="'open'"):
        parse_expression("open('f')", None, field=FIELD)


def test_long_chains_are_linear_and_correct():
    syms = sp.symbols("s0:900")
    table = {s.name: s for s in syms}
    start = time.perf_counter()
    assert parse_expression("+".join(table), table) == sp.Add(*syms)
    assert parse_expression("*".join(table), table) == sp.Mul(*syms)
    assert parse_expression("-".join(table), table) == syms[0] - sp.Add(*syms[1:])
    assert time.perf_counter() - start < 5


# -- hostile and malformed strings ----------------------------------------------------------

HOSTILE = [
    # (text, substrings the message must contain besides the field)
    ("__import__('os').system('echo pwned > /tmp/x')", ["__import__"]),
    ("().__class__.__bases__", ["attribute access", "().__class__"]),
    ("x.__class__", ["attribute access", "x.__class__"]),
    ("[x for x in ()]", ["comprehension", "[x for x in ()]"]),
    ("lambda: 1", ["lambda", "lambda: 1"]),
    ("open('f')", ["'open'"]),
    ("eval('1')", ["'eval'"]),
    ("exec('x=1')", ["'exec'"]),
    ("9**9**9", ["9**9**9", "max_exponent"]),
    ("x**100000", ["100000", "max_exponent"]),
    ("x" * 20_000, ["20000", "max_length"]),
    ("(" * 1000 + "x" + ")" * 1000, ["nested", "'('", "max_depth"]),
    ("-" * 5000 + "x", ["max_depth"]),
    ("x if y else z", ["conditional", "x if y else z"]),
    ("x < y", ["comparison", "x < y"]),
    ("x and y", ["boolean", "x and y"]),
    ("'abc'", ["string", "'abc'"]),
    ("b'abc'", ["bytes", "b'abc'"]),
    ("f'{x}'", ["f-string", "f'{x}'"]),
    ("1j", ["complex", "1j"]),
    ("True", ["'True'"]),
    ("None", ["'None'"]),
    ("...", ["'...'"]),
    ("x[0]", ["subscript", "x[0]"]),
    ("{}", ["dict", "{}"]),
    ("[x, y]", ["list", "[x, y]"]),
    ("(x, y)", ["tuple", "x, y"]),
    ("{x}", ["set", "{x}"]),
    ("f(x)", ["'f'", "f(x)"]),
    ("sin(x, y)", ["'sin' takes 1 argument", "sin(x, y)"]),
    ("atan2(x)", ["'atan2' takes 2 arguments", "atan2(x)"]),
    ("sin(x=1)", ["keyword", "x="]),
    ("sin(**{})", ["keyword", "**"]),
    ("sin(*x)", ["starred", "*x"]),
    ("(x:=1)", [":=", "x:=1"]),
    ("x; y", ["syntax error", "; y"]),
    ("import os", ["syntax error"]),
    ("sin(x", ["syntax error", "never closed"]),
    ("Abs(x)", ["'Abs'"]),
    ("sign(x)", ["'sign'"]),
    ("q1", ["unknown name 'q1'", "did you mean", "'q'", "'q_1'"]),
    ("x^2", ["'^'", "use '**'"]),
    ("x // 2", ["'//'"]),
    ("x % 2", ["'%'"]),
    ("x @ y", ["'@'"]),
    ("not x", ["'not'"]),
    ("~x", ["'~'"]),
    ("1/0", ["division by zero", "'0'"]),
    ("1/(x - x)", ["division by zero", "x - x"]),
    ("0**-1", ["undefined", "0**-1"]),
    ("log(0)", ["undefined", "log(0)"]),
    ("sqrt(-1)", ["not real", "sqrt(-1)"]),
    ("(9**64)**64", ["(9**64)**64", "digits"]),
    ("*".join(["(9**60)"] * 10), ["(9**60)*(9**60)", "digits"]),
    ("1" * 41, ["1" * 41, "max_digits"]),
    ("1e999", ["1e999", "out of range"]),
    # limits that sympy's own merging would otherwise slip past, and constants that
    # float64 cannot hold (evaluating them exactly takes minutes and gigabytes)
    ("(y**64)**64", ["(y**64)**64", "degree 4096", "limit 256"]),
    ("(((y + 1)**64)**64)**64", ["((y + 1)**64)**64", "degree 4096"]),
    ("y**60*y**60", ["y**60*y**60", "y**120", "max_exponent"]),
    ("((x + y)**60 + 1)**60", ["degree 3600"]),
    ("m*y*exp(exp(exp(100)))", ["'exp(exp(100))'", "outside the range of float64"]),
    ("1e308*1e308", ["'1e308*1e308'", "outside the range of float64"]),
    ("y*1e-400", ["'1e-400'", "underflows to 0"]),
    ("y*exp(-800)", ["'exp(-800)' is a constant nonzero but below", "underflows to 0"]),
    ("sin", ["'sin'", "must be called"]),
    ("", ["empty"]),
    ("   ", ["empty"]),
    ("x\x00y", ["null"]),
    ("getattr(x, '__class__')", ["'getattr'"]),
    ("globals()", ["'globals'"]),
    ("(lambda: 0)()", ["lambda: 0"]),
    ("__builtins__", ["'__builtins__'"]),
    ("sin.__globals__", ["attribute access", "sin.__globals__"]),
    ("x if x else __import__('os')", ["conditional"]),
    ("await x", ["await", "await x"]),
    ("x.real", ["attribute access", "x.real"]),
    ("+".join(["x"] * 1100), ["max_nodes"]),
    # characters Python would drop or reinterpret, and characters of no expression
    ("m*g*y # +1000*x", ["character '#'", "comment"]),
    ("x #", ["character '#'"]),
    ("x + \\\n y", ["character '\\'"]),
    ("x $ y", ["character '$'"]),
    ("x ? y", ["character '?'"]),
    ("x ! y", ["character '!'"]),
    ("`x`", ["character '`'"]),
    ("x +\x0by", ["U+000B"]),
    ("x +\x0cy", ["U+000C"]),
    ("x\u00a0+ y", ["U+00A0", "NO-BREAK SPACE"]),
    ("x\u200b+ y", ["U+200B", "ZERO WIDTH SPACE"]),
    ("x + y\u202e", ["U+202E", "RIGHT-TO-LEFT OVERRIDE"]),
    ("x \uff0b y", ["U+FF0B", "FULLWIDTH PLUS SIGN"]),
    ("x\u2028+ y", ["U+2028"]),
    # names that Python's NFKC normalisation would silently turn into declared names
    ("\U0001d431**2", ["name '\U0001d431'", "U+1D431", "reads as 'x'"]),
    ("\uff58 + 1", ["name '\uff58'", "U+FF58", "reads as 'x'"]),
    ("x\u00b2", ["U+00B2"]),
    ("\uff53\uff49\uff4e(x)", ["U+FF53", "reads as 'sin'"]),
    ("\u212bx", ["U+212B"]),
]


@pytest.mark.parametrize(("text", "needles"), HOSTILE, ids=[repr(t[:30]) for t, _ in HOSTILE])
def test_hostile_strings_are_refused(text, needles):
    with pytest.raises(ExpressionError) as info:
        parse(text, field=FIELD, line=12)
    message = str(info.value)
    assert message.startswith(f"{FIELD} (line 12"), message
    for needle in needles:
        assert needle in message, (needle, message)
    assert info.value.field == FIELD
    assert isinstance(info.value, ValueError)


def test_hostile_strings_refused_quickly():
    start = time.perf_counter()
    for text, _ in HOSTILE:
        with pytest.raises(ExpressionError):
            parse(text)
    assert time.perf_counter() - start < 5


def test_hostile_strings_run_nothing(monkeypatch, tmp_path):
    sentinel = tmp_path / "pwned"
    payloads = [
        f"__import__('os').system('touch {sentinel}')",
        f"open('{sentinel}', 'w')",
        f"open('{sentinel}', 'w').write('x')",
        f"exec(\"open('{sentinel}', 'w')\")",
        f"eval(\"open('{sentinel}', 'w')\")",
        f"[open('{sentinel}', 'w') for _ in (1,)]",
        f"(lambda: open('{sentinel}', 'w'))()",
        f"sin.__globals__['__builtins__'].open('{sentinel}', 'w')",
        f"().__class__.__bases__[0].__subclasses__()[0]('{sentinel}')",
        f"x if open('{sentinel}', 'w') else y",
        f"(f := open('{sentinel}', 'w'))",
        f"sin(open('{sentinel}', 'w'))",
        f"sin(*open('{sentinel}', 'w'))",
        f"x + f\"{{open('{sentinel}', 'w')}}\"",
    ]
    imports: list[str] = []
    compile_flags: list[int] = []
    real_import, real_compile = builtins.__import__, builtins.compile

    def spy_import(name, *args, **kwargs):
        imports.append(name)
        return real_import(name, *args, **kwargs)

    def spy_compile(source, filename, mode, flags=0, *args, **kwargs):
        compile_flags.append(flags)
        return real_compile(source, filename, mode, flags, *args, **kwargs)

    def forbidden(*args, **kwargs):
        raise AssertionError("the parser must not evaluate anything")

    monkeypatch.setattr(builtins, "__import__", spy_import)
    monkeypatch.setattr(builtins, "compile", spy_compile)
    monkeypatch.setattr(builtins, "eval", forbidden)
    monkeypatch.setattr(builtins, "exec", forbidden)
    monkeypatch.setattr(sympy_parser, "parse_expr", forbidden)
    monkeypatch.setattr(sympy_parser, "eval_expr", forbidden)
    for payload in payloads:
        for table in (SYMBOLS, None):
            with pytest.raises(ExpressionError):
                parse_expression(payload, table, field=FIELD)
    assert not sentinel.exists()
    assert not {"os", "subprocess", "posix", "shutil", "socket", "pty"} & set(imports)
    # compile is only ever used to build an AST, never code
    assert compile_flags
    assert all(flags & ast.PyCF_ONLY_AST for flags in compile_flags)


def test_module_never_calls_an_evaluator():
    source = inspect.getsource(expressions)
    banned = {"eval", "exec", "sympify", "parse_expr", "S", "__import__", "lambdify"}
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Call):
            func = node.func
            if isinstance(func, ast.Name):
                assert func.id not in banned | {"compile"}, f"line {node.lineno}: {func.id}"
            elif isinstance(func, ast.Attribute):
                assert func.attr not in banned, f"line {node.lineno}: {func.attr}"


# -- positions in messages ------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "line", "where", "token"),
    [
        ("x + y.z", None, "(col 5)", "y.z"),
        ("θ + y.z", None, "(col 5)", "y.z"),  # columns count characters, not bytes
        ("x + y.z", 12, "(line 12, col 5)", "y.z"),
        ("   y.z", None, "(col 4)", "y.z"),
        ("(x +\n  y.z)", None, "(line 2, col 3)", "y.z"),
        ("(x +\n  y.z)", 12, "(line 13, col 3)", "y.z"),
        ("\n  y.z", 7, "(line 8, col 3)", "y.z"),
        ("x + ;", None, "(col 5)", ";"),
        ("sin(x) + q1", None, "(col 10)", "q1"),
    ],
)
def test_error_positions(text, line, where, token):
    with pytest.raises(ExpressionError) as info:
        parse(text, field="potential", line=line)
    message = str(info.value)
    assert message.startswith(f"potential {where}: "), message
    assert token in message
    col = int(where.rstrip(")").rsplit("col ", 1)[1])
    assert info.value.column == col
    assert info.value.token == token


def test_unknown_name_lists_suggestions():
    with pytest.raises(ExpressionError) as info:
        parse_expression("q1 + 1", {"q": q}, field="metric[0,0]")
    assert "unknown name 'q1'" in str(info.value)
    assert "did you mean 'q'" in str(info.value)
    with pytest.raises(ExpressionError) as info:
        parse_expression("sine(x)", SYMBOLS, field="V")
    assert "did you mean 'sin'" in str(info.value)
    with pytest.raises(ExpressionError, match="no symbols are declared"):
        parse_expression("x", {})
    with pytest.raises(ExpressionError, match="'x' is a symbol, not a function"):
        parse_expression("x(y)", SYMBOLS)


def test_bad_symbol_table_value():
    with pytest.raises(ExpressionError, match="maps 'k' to a str"):
        parse_expression("k + 1", {"k": "__import__('os')"}, field=FIELD)
    with pytest.raises(ExpressionError, match="maps 'M' to a"):
        parse_expression("M", {"M": sp.eye(2)}, field=FIELD)


def test_non_string_text():
    with pytest.raises(ExpressionError, match=r"walls\[0\]\.psi: expected an expression string"):
        parse_expression(3, SYMBOLS, field=FIELD)  # type: ignore[arg-type]


# -- limits -------------------------------------------------------------------------------


def test_default_limits():
    assert (MAX_LENGTH, MAX_NODES, MAX_DEPTH, MAX_EXPONENT, MAX_DIGITS) == (
        10_000,
        2_000,
        50,
        64,
        40,
    )


def test_limits_boundaries_and_keywords():
    assert parse("x**64") == x**64
    assert parse("x**-64") == x**-64
    with pytest.raises(ExpressionError, match="max_exponent=64"):
        parse("x**65")
    with pytest.raises(ExpressionError, match="max_exponent=64"):
        parse("x**(-65)")
    with pytest.raises(ExpressionError, match="max_exponent=64"):
        parse("x**(8*9)")  # computed exponents count too
    assert parse("x**3", max_exponent=3) == x**3
    with pytest.raises(ExpressionError, match="max_exponent=3"):
        parse("x**4", max_exponent=3)

    assert parse("(" * 50 + "x" + ")" * 50) == x
    with pytest.raises(ExpressionError, match="max_depth=50"):
        parse("(" * 51 + "x" + ")" * 51)
    assert parse("-" * 50 + "x") == x
    with pytest.raises(ExpressionError, match="max_depth=50"):
        parse("-" * 51 + "x")
    assert parse("sin(" * 50 + "x" + ")" * 50).has(sp.sin)
    with pytest.raises(ExpressionError, match="max_depth=3"):
        parse("sin(cos(sin(cos(x))))", max_depth=3)

    with pytest.raises(ExpressionError, match="max_length=5"):
        parse("x + y + z", max_length=5)
    with pytest.raises(ExpressionError, match="max_nodes=4"):
        parse("x + y + z", max_nodes=4)
    assert parse("x + y + z", max_nodes=5) == x + y + z
    with pytest.raises(ExpressionError, match="max_digits=3"):
        parse("1234", max_digits=3)


def test_big_numbers_are_refused_before_they_are_computed():
    start = time.perf_counter()
    # sympy merges the radicals of a product (sqrt(a)*sqrt(b) -> sqrt(a*b)) and factors
    # the merged number: without limits these take minutes
    lits = [str(10**39 + 7919 * k + 13) for k in range(200)]
    merged_roots = ["*".join(f"sqrt({v})" for v in lits[:n]) for n in (30, 60, 200)]
    for text in [
        "(9**64)**64",
        "((9**64)**64)**64",
        "sqrt((7**60)**60 + 1)",
        "9**9**9**9",
        "(1000*x*y)**64",
        *merged_roots,
    ]:
        with pytest.raises(ExpressionError):
            parse(text)
    assert time.perf_counter() - start < 2


# -- to_expression -------------------------------------------------------------------------


def test_to_expression_passes_sympy_through():
    e = sp.sin(x) + 1
    assert to_expression(e, SYMBOLS, field=FIELD) is e
    assert to_expression(x, None) is x


@pytest.mark.parametrize(
    ("value", "expected"),
    [
        (2, sp.Integer(2)),
        (-7, sp.Integer(-7)),
        (0.25, sp.Float(0.25)),
        (fractions.Fraction(1, 3), sp.Rational(1, 3)),
        (np.int64(5), sp.Integer(5)),
        (np.float64(1.5), sp.Float(1.5)),
    ],
)
def test_to_expression_numbers(value, expected):
    got = to_expression(value, SYMBOLS, field=FIELD)
    assert got == expected
    assert type(got) is type(expected)


def test_to_expression_strings():
    assert to_expression("x*cos(th)", SYMBOLS, field=FIELD) == x * sp.cos(th)
    with pytest.raises(ExpressionError, match=r"walls\[0\]\.psi \(line 3, col 1\): attribute"):
        to_expression("x.y", SYMBOLS, field=FIELD, line=3)


@pytest.mark.parametrize(
    ("value", "needle"),
    [
        (None, "NoneType"),
        (True, "boolean"),
        ([1, 2], "list"),
        ({"a": 1}, "dict"),
        (1 + 2j, "complex"),
        (float("nan"), "finite"),
        (float("inf"), "finite"),
        (b"x", "bytes"),
        (sp.Matrix([1, 2]), "matrix"),
        (sp.ImmutableMatrix([1, 2]), "matrix"),
        (sp.Eq(x, 1), "Equality"),
        (sp.true, "BooleanTrue"),
        (object(), "object"),
    ],
)
def test_to_expression_refuses(value, needle):
    with pytest.raises(ExpressionError) as info:
        to_expression(value, SYMBOLS, field=FIELD)
    assert str(info.value).startswith(FIELD)
    assert needle in str(info.value)


def test_exports():
    """One list of elementary functions: what a string may call is what a scene's field
    may hold (declaration.admissible), and sqrt."""
    from symmech.declaration.admissible import ELEMENTARY_FUNCTIONS

    assert set(ALLOWED_FUNCTIONS) == {f.__name__ for f in ELEMENTARY_FUNCTIONS} | {"sqrt"}
    assert {"sin", "cos", "tan", "atan2", "exp", "log", "sec", "acosh"} <= set(ALLOWED_FUNCTIONS)
    assert ALLOWED_FUNCTIONS["atan2"] is sp.atan2
    assert dict(ALLOWED_CONSTANTS) == {"pi": sp.pi, "E": sp.E}
    with pytest.raises(TypeError):
        ALLOWED_FUNCTIONS["Abs"] = sp.Abs  # type: ignore[index]


# -- property tests -----------------------------------------------------------------------

_LEAVES = st.one_of(
    st.sampled_from([("x", x, False), ("y", y, False), ("z", z, False)]),
    st.integers(0, 9).map(lambda n: (str(n), sp.Integer(n), False)),
)
_BINOPS = {
    "+": lambda u, v: u + v,
    "-": lambda u, v: u - v,
    "*": lambda u, v: u * v,
    "/": lambda u, v: u / v,
}


def _combine(op, left, right):
    (lt, lv, lbad), (rt, rv, rbad) = left, right
    bad = lbad or rbad or (op == "/" and rv.is_Number and rv.is_zero)
    value = _BINOPS[op](lv, rv)
    return f"({lt}){op}({rt})", value, bad or value.has(sp.zoo, sp.nan)


def _power(base, k):
    bt, bv, bbad = base
    value = bv**k
    return f"({bt})**({k})", value, bbad or value.has(sp.zoo, sp.nan)


def _trees(depth: int) -> st.SearchStrategy:
    """(text, sympy value built directly, whether the parser must refuse it)."""
    if depth == 0:
        return _LEAVES
    sub = _trees(depth - 1)
    return st.one_of(
        _LEAVES,
        st.builds(_combine, st.sampled_from(sorted(_BINOPS)), sub, sub),
        sub.map(lambda t: (f"-({t[0]})", -t[1], t[2])),
        st.builds(
            lambda f, t: (f"{f}({t[0]})", ALLOWED_FUNCTIONS[f](t[1]), t[2]),
            st.sampled_from(["sin", "cos"]),
            sub,
        ),
        st.builds(_power, sub, st.integers(-2, 2)),
    )


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_trees(4))
def test_random_expressions_round_trip(tree):
    text, expected, refused = tree
    if refused:
        with pytest.raises(ExpressionError):
            parse_expression(text, SYMBOLS)
    else:
        got = parse_expression(text, SYMBOLS)
        assert got == expected, (text, got, expected)


_TOKENS = st.sampled_from(
    [
        "x", "y", "q1", "1", "0", "2.5", "1e9", "9", "+", "-", "*", "/", "**", "(", ")", ",",
        "sin", "atan2", "sqrt", "log", ".", "[", "]", "{", "}", "'", '"', ":", "=", "<", "and",
        "if", "else", "lambda", "for", "in", "__class__", "__import__", " ", "\n", "#", "@",
        "^", "%", "~", "not", "j", "_", "pi", "E",
    ]
)  # fmt: skip


@settings(max_examples=300, deadline=None)
@given(st.lists(_TOKENS, max_size=25).map("".join))
def test_arbitrary_strings_give_an_expression_or_expression_error(text):
    try:
        result = parse_expression(text, SYMBOLS, field=FIELD)
    except ExpressionError as exc:
        assert str(exc).startswith(FIELD)
    else:
        assert isinstance(result, sp.Expr)
        assert not result.has(sp.zoo, sp.nan, sp.I)
