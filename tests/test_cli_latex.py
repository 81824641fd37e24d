"""LaTeX rendering (issue 5: "derived objects render as LaTeX in Jupyter").

Every object with a ``_repr_latex_`` (the impact map, the Carnot balance, the Frobenius and
bracket-rank results, the ``symmech show`` report) is rendered for the texts' examples and
checked two ways: the text is well-formed LaTeX (:func:`latex_problems`: paired math
delimiters, balanced braces, matched environments and ``\\left``/``\\right``, no special
character left unescaped in text mode, where ``rough_wall`` would print a subscript or stop
the compiler), and it shows the right quantity: the LaTeX of a value that is itself checked
against the formula of the text, typed in here.
"""

from __future__ import annotations

import re

import pytest
import sympy as sp

from symmech.cli import derivation
from symmech.geometry.distributions import bracket_rank, is_involutive
from symmech.scenefile import load_scene, reads_scene

# ---------------------------------------------------------------------------------------
# a structural LaTeX checker

_TEXT_COMMANDS = {"text", "textrm", "textit", "textbf", "mathrm", "operatorname", "paragraph"}
# characters that LaTeX does not print as themselves in text mode
_TEXT_SPECIALS = set("_^&~<>")


def latex_problems(text: str) -> list[str]:
    """What is wrong with ``text`` as LaTeX (document body or a Jupyter ``$...$``): [] if
    nothing.

    Checks that math delimiters (``$``, ``$$``, ``\\[ \\]``) pair up; braces balance;
    ``\\begin``/``\\end`` and ``\\left``/``\\right`` match; ``%`` and ``#`` are escaped
    everywhere; and in text mode (outside math, or in the argument of ``\\text``,
    ``\\paragraph``, ...) no ``_ ^ & ~ < >`` or ``$`` is left unescaped.
    """
    problems: list[str] = []
    math: str | None = None  # the delimiter that opened the current math, or None
    stack: list[tuple[str, bool, str | None]] = []  # ({ or env name, text mode before, math)
    lefts = 0
    text_mode = True
    i, n = 0, len(text)

    def at() -> str:
        return f"at {i}: {text[max(0, i - 15) : i + 15]!r}"

    while i < n:
        c = text[i]
        if c == "\\":
            m = re.match(r"\\([A-Za-z]+)|\\(.)", text[i:], re.S)
            assert m is not None
            name = m.group(1)
            if name is None:  # \\ \{ \} \_ \$ \[ \] \, ...
                symbol = m.group(2)
                if symbol == "[" and math is None:
                    math, text_mode = "\\[", False
                elif symbol == "]" and math == "\\[":
                    math, text_mode = None, True
                elif symbol in "[]" and not text_mode:
                    pass
                i += 2
                continue
            i += len(m.group(0))
            if name in ("begin", "end"):
                env = re.match(r"\{([A-Za-z*]+)\}", text[i:])
                if env is None:
                    problems.append(f"\\{name} without an environment name {at()}")
                    continue
                i += len(env.group(0))
                if name == "begin":
                    stack.append((env.group(1), text_mode, math))
                elif not stack or stack[-1][0] != env.group(1):
                    problems.append(f"\\end{{{env.group(1)}}} does not close {stack[-1:]} {at()}")
                else:
                    stack.pop()
            elif name in ("left", "right"):
                if text_mode:
                    problems.append(f"\\{name} outside math {at()}")
                lefts += 1 if name == "left" else -1
                if lefts < 0:
                    problems.append(f"\\right without \\left {at()}")
                    lefts = 0
                i += 1  # the delimiter
            elif name in _TEXT_COMMANDS and text[i : i + 1] == "{":
                stack.append(("{", text_mode, math))
                text_mode = True
                i += 1
            continue
        if c == "{":
            stack.append(("{", text_mode, math))
        elif c == "}":
            if not stack or stack[-1][0] != "{":
                problems.append(f"unbalanced '}}' {at()}")
            else:
                text_mode = stack.pop()[1]
        elif c in "%#":
            problems.append(f"unescaped '{c}' {at()}")
        elif c == "$":
            delimiter = "$$" if text.startswith("$$", i) else "$"
            if math is None and text_mode and not stack:
                math, text_mode = delimiter, False
            elif math == delimiter and not text_mode:
                math, text_mode = None, True
            else:
                problems.append(f"'{delimiter}' inside text inside math, or unpaired {at()}")
            i += len(delimiter)
            continue
        elif text_mode and c in _TEXT_SPECIALS:
            problems.append(f"unescaped '{c}' in text mode {at()}")
        i += 1
    if math is not None:
        problems.append(f"math opened with {math!r} is not closed")
    if stack:
        problems.append(f"not closed: {[s[0] for s in stack]}")
    if lefts:
        problems.append(f"{lefts} \\left without \\right")
    return problems


def assert_latex(text: str) -> None:
    problems = latex_problems(text)
    assert not problems, (problems, text)


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("$\\text{wall rough_wall}$", "unescaped '_' in text mode"),
        ("$x^{2$", "not closed"),
        ("$x}$", "unbalanced"),
        ("$x", "not closed"),
        ("\\[ x \\]\n50% done", "unescaped '%'"),
        ("\\paragraph{psi >= 0}", "unescaped '>'"),
        ("$\\begin{matrix}1\\end{bmatrix}$", "does not close"),
        ("$\\left[ x$", "\\left without \\right"),
        ("$\\text{a $b$}$", "inside text inside math"),
        ("a_b", "unescaped '_' in text mode"),
    ],
)
def test_the_checker_finds_broken_latex(text: str, fragment: str):
    problems = latex_problems(text)
    assert any(fragment in p for p in problems), problems


def test_the_checker_accepts_sympy_latex():
    x, y = sp.symbols("x y")
    for expr in (sp.Matrix([[x, y], [y / x, sp.sqrt(x)]]), sp.Derivative(sp.Function("f")(x), x)):
        assert_latex(f"${sp.latex(expr)}$")
        assert_latex(f"\\paragraph{{a\\_b}}\n\\[ {sp.latex(expr)} \\]\n")


# ---------------------------------------------------------------------------------------
# the texts' examples, typed in

M, K, R = sp.symbols("m k R", positive=True)
ALPHA = sp.Symbol("alpha", nonnegative=True)
X, Y, TH, KAP = sp.symbols("x y theta kappa", real=True)
XD, YD, THD = sp.symbols("xdot ydot thetadot", real=True)
# Carnot paper, example 3.7: the disc after hitting the rough wall y = R
PAPER_3_7 = sp.Matrix(
    [
        (R**2 * XD + R * K**2 * THD) / (R**2 + K**2),
        -ALPHA * YD,
        (R * XD + K**2 * THD) / (R**2 + K**2),
    ]
)
# slides 000, the car: X0 = (cos th, sin th, kappa, 0), X1 = (0, 0, 0, 1); by hand
# [X0, X1] = DX1 X0 - DX0 X1 = -dX0/dkappa = (0, 0, -1, 0)
CAR_FIELDS = [[sp.cos(TH), sp.sin(TH), KAP, 0], [0, 0, 0, 1]]
CAR_BRACKET = sp.Matrix([0, 0, -1, 0])


def _zero(m: sp.MatrixBase) -> bool:
    return all(sp.simplify(e) == 0 for e in m)


def test_impact_map_latex():
    """Fails until ImpactMap._repr_latex_ escapes the wall name (``rough\\_wall``)."""
    imp = load_scene("carnot_3_7").impact_map(0)
    assert _zero(imp.post_velocity - PAPER_3_7)
    tex = imp._repr_latex_()
    assert_latex(tex)
    assert sp.latex(imp.post_velocity) in tex
    assert "rough\\_wall" in tex and "newton law" in tex


def test_impact_map_latex_energy_law():
    scene = load_scene("spinning_disk")
    tex = scene.impact_map("wall")._repr_latex_()
    assert_latex(tex)
    assert "energy law" in tex


@pytest.mark.parametrize(
    ("scene", "restrict", "theorem"),
    [
        ("carnot_3_7", True, "Theorem 3.6"),
        ("carnot_3_7", False, "Theorem 3.11"),
        ("carnot_3_13", False, "Theorem 3.11"),
        ("carnot_4_4", False, "Theorem 4.3"),
    ],
)
def test_carnot_result_latex(scene: str, restrict: bool, theorem: str):
    res = load_scene(scene).impact_map(0).carnot(restrict=restrict)
    tex = res._repr_latex_()
    assert_latex(tex)
    assert tex.startswith(f"$\\text{{{theorem}")
    assert "alpha" not in tex.replace("\\alpha", "")  # the statement's symbols are LaTeX
    assert sp.simplify(res.residual) == 0
    assert tex.endswith(f"\\text{{residual }} = {sp.latex(res.residual)}$")


def test_frobenius_and_bracket_rank_latex():
    car = is_involutive(CAR_FIELDS, (X, Y, TH, KAP))
    assert not car and car.pair == (0, 1) and sp.Matrix(car.bracket) == CAR_BRACKET
    tex = car._repr_latex_()
    assert_latex(tex)
    assert f"[X_{{0}}, X_{{1}}] = {sp.latex(CAR_BRACKET)}" in tex
    assert "\\notin \\operatorname{span}" in tex

    plane = is_involutive([[1, 0, 0], [0, 1, 0]], (X, Y, TH))
    assert plane
    assert plane._repr_latex_() == "$\\text{involutive (rank 2 of 3)}$"
    assert_latex(plane._repr_latex_())

    rank = bracket_rank(CAR_FIELDS, (X, Y, TH, KAP), depth=3)
    assert rank.rank == 4 and rank.bracket_generating
    tex = rank._repr_latex_()
    assert_latex(tex)
    assert "rank 4 of 4 at depth 3 (bracket-generating)" in tex
    assert tex.count("X_{0}") >= 1 and tex.count("X_{1}") >= 1


# ---------------------------------------------------------------------------------------
# the show report


@pytest.mark.parametrize("name", ["carnot_3_7", "spinning_disk", "rolling_ball"])
def test_derivation_latex_and_markdown(name: str):
    scene = load_scene(name)
    rep = derivation(scene)
    tex = rep._repr_latex_()
    assert tex == rep.latex()
    assert_latex(tex)
    md = rep._repr_markdown_()
    blocks = re.findall(r"\$\$(.*?)\$\$", md, re.S)
    values = [v for _, v in rep.sections]
    expected = sum(len(v) if isinstance(v, list) else not isinstance(v, str) for v in values)
    assert len(blocks) == expected
    for block in blocks:
        assert_latex(f"$${block}$$")
    assert f"$$ {sp.latex(scene.mass_matrix())} $$" in md
    if name == "carnot_3_7":
        assert sp.latex(sp.diag(M, M, M * K**2)) in tex
        assert (
            "\\paragraph{wall 'rough\\_wall': gap psi (psi \\textgreater{}= 0 admissible)}" in tex
        )


def test_derivation_notes_are_latex_text():
    seven = reads_scene(
        'coordinates = ["r", "th", "z1", "z2", "z3", "z4", "z5"]\n'
        'metric = [1, "r**2", 1, 1, 1, 1, 1]\n'
    ).scene
    rep = derivation(seven)
    tex = rep.latex()
    assert_latex(tex)
    assert "not derived for n = 7 \\textgreater{} 6 coordinates" in tex
    assert "'symmech show --full'" in rep._repr_markdown_()
