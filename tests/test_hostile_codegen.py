"""Hostile names in generated code (issue 10, class 1): every string of a scene that reaches
generated text is escaped for the language it lands in, so nothing in a name can end a
comment or a docstring, splice or add a line, or make a file uncompilable or unimportable.

The strings are put in every place a scene carries text (scene, wall, coordinate,
parameter and function names, printed expressions); the checks are on the effect (the C
compiles with -Werror, the extension and the NumPy module load, no planted file is
created, the payload never appears outside a comment) and on the escape functions' rules.
"""

from __future__ import annotations

import ast
import io
import os
import re
import subprocess
import tokenize

import jinja2
import jinja2.nodes as jn
import numpy as np
import pytest
import sympy as sp
from codegen_support import require_c_compiler

import symmech as sm
from symmech import codegen
from symmech.codegen.backends import BACKENDS, ESCAPE_FILTERS, environment, templates_used
from symmech.codegen.escape import (
    MAX_STEM,
    c_comment,
    c_string,
    file_name,
    python_comment,
    python_docstring,
)
from symmech.codegen.generate import EXTENSION_TEMPLATE
from symmech.codegen.module import extension_source

STRICT = ["-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-pedantic"]

#: The issue's attack: a scene name closing the comment of the extension source.
CONSTRUCTOR = 'a */ __attribute__((constructor)) static void f(void){system("touch pwned");} /*'

#: One of each kind of hostile text (what each would do unescaped).
HOSTILE = [
    CONSTRUCTOR,  # ends a C block comment
    "n\nimport os; os.system('touch pwned')\n",  # a new line of Python / C
    '"""; import os; os.system("touch pwned"); """',  # ends a docstring
    'q"',  # a quote just before the closing triple quote
    "z\\",  # a backslash before a newline: splices the next line (C), escapes (Python)
    "w ??/",  # the trigraph of a backslash (C99)
    "c // x \\",  # a line comment continued onto the next line
    "x\x00y",  # NUL: a Python source cannot contain it
    "u\u2028import os",  # a Unicode line separator
    "p\x0c\x1c\x85v\rr",  # form feed, file separator, NEL, carriage return
    "b\u202ec\u2066d",  # bidirectional overrides ("Trojan source")
    "\\N{bad} \\x1 {{ stamp }} {% raw %}",  # Python escapes and Jinja syntax
]


#: What would reach code if a name escaped its comment (identifiers made from the names,
#: such as p_import_os_os_system_touch_pwned, are fine).
PAYLOADS = ("__attribute__", "system(", "import os", '"touch', "int pwn", "{{", "{%")


def _scene(seed: list[str]) -> sm.Scene:
    """A scene with hostile text in the scene, wall, coordinate, parameter and function
    names (coordinates 'a*' and '/b ...' printed next to each other in a list)."""
    a, b = sp.Symbol("a*", real=True), sp.Symbol(seed[0], real=True)
    c = sp.Symbol("/b " + seed[1 % len(seed)], real=True)
    m = sp.Symbol(seed[2 % len(seed)], positive=True)
    f = sp.Function(seed[3 % len(seed)].replace("\0", "0"))  # sympy refuses NUL here
    return sm.Scene(
        (a, b, c),
        metric=sp.diag(m, m, 1),
        potential=m * b,
        walls=[
            sm.Wall(c + 2 - f(sm.t), restitution=1, name=seed[4 % len(seed)]),
            sm.Wall(b + 3 + a**2 / 8, restitution=sp.Rational(1, 2), name=seed[5 % len(seed)]),
        ],
        name=seed[6 % len(seed)],
    )


def _seeds() -> list[list[str]]:
    n = len(HOSTILE)
    return [[HOSTILE[(i + k) % n] for k in range(7)] for i in range(n)]


def _comments_and_strings_c(text: str) -> str:
    """``text`` with its C comments blanked (phases of translation 2 and 3: line splices
    first, then comments; string literals kept), to check what remains is only code."""
    text = text.replace("??/", "\\")  # trigraph phase
    text = re.sub(r"\\\n", "", text)
    return re.sub(r"/\*.*?\*/|//[^\n]*", " ", text, flags=re.S)


@pytest.mark.parametrize("seed", _seeds(), ids=lambda s: repr(s[0])[:24])
def test_hostile_names_stay_in_comments_and_docstrings(seed):
    scene = _scene(seed)
    for target in ("c", "numpy"):
        code = codegen.generate(scene, target, strategy="linear_solve")
        files = dict(code.files)
        if target == "c":
            files["extension.c"] = extension_source(code, "_symmech_ext_test")
        for name, text in files.items():
            assert not re.search(r"[\x00-\x08\x0b-\x1f\x7f-\x9f\u2028\u2029\u202e]", text)
            if target == "c":
                code_part = _comments_and_strings_c(text)
                for payload in PAYLOADS:
                    assert payload not in code_part, (name, payload)
                continue
            tree = ast.parse(text)  # an importable source
            imports = [n for n in ast.walk(tree) if isinstance(n, ast.Import | ast.ImportFrom)]
            # numpy, and math where a linear solve checks the inputs of one state
            assert [a.name for n in imports for a in n.names] in (["numpy"], ["math", "numpy"])
            for tok in tokenize.generate_tokens(io.StringIO(text).readline):
                if tok.type not in (tokenize.COMMENT, tokenize.STRING):
                    assert tok.string not in ("os", "system", "pwn"), tok
            functions = [n for n in tree.body if isinstance(n, ast.FunctionDef)]
            assert all(ast.get_docstring(n) for n in [tree, *functions])


def test_the_constructor_attack_compiles_and_loads_without_running(tmp_path, monkeypatch):
    """The issue's example: the name reaches the C header, source and extension source as
    comment text only; -Wall -Wextra -Werror -pedantic accepts every file; loading (which
    compiles and imports the extension) creates no file."""
    require_c_compiler()
    monkeypatch.chdir(tmp_path)
    x, y = sm.coordinates("x y")
    scene = sm.Scene((x, y), metric=sp.eye(2), walls=[sm.Wall(y)], name=CONSTRUCTOR)
    code = codegen.generate(scene, "c")
    code.write(tmp_path)
    (tmp_path / "ext.c").write_text(extension_source(code, "ext"))
    for source in (f"{code.stem}.c", "ext.c"):
        flags = STRICT if source != "ext.c" else ["-std=c99", "-Wall", "-Werror", "-E"]
        proc = subprocess.run(
            [require_c_compiler(), *flags, "-c", source, "-o", os.devnull],
            cwd=tmp_path,
            capture_output=True,
            text=True,
        )
        assert proc.returncode == 0 or "Python.h" in proc.stderr, proc.stderr
    mod = code.load(cache=tmp_path / "cache")
    assert "CPython extension" in mod.fast_path, mod.fast_path
    np.testing.assert_array_equal(mod.impact([0.0, 0.0], [1.0, -2.0]), [1.0, 2.0])
    assert not (tmp_path / "pwned").exists()


@pytest.mark.parametrize("seed", _seeds()[:4], ids=lambda s: repr(s[0])[:24])
def test_hostile_scene_compiles_strict_imports_and_agrees(tmp_path, monkeypatch, seed):
    """Both backends of a scene full of hostile names: the C compiles with -Werror
    -pedantic, the NumPy module imports, and both give the same numbers."""
    monkeypatch.chdir(tmp_path)
    scene = _scene(seed)
    c = codegen.generate(scene, "c", strategy="linear_solve")
    py = codegen.generate(scene, "numpy", strategy="linear_solve")
    folder = tmp_path / "src"
    c.write(folder)
    proc = subprocess.run(
        [require_c_compiler(), *STRICT, "-c", f"{c.stem}.c", "-o", "out.o"],
        cwd=folder,
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stderr
    cm, pm = c.load(cache=tmp_path / "cache"), py.load(cache=tmp_path / "cache")
    q, v = np.array([0.3, -0.2, 0.1]), np.array([0.5, -1.0, 2.0])
    p, u = [2.0], [0.25, -0.5]
    for wall in (0, 1):
        np.testing.assert_allclose(
            cm.impact(q, v, p, wall, t=0.5, inputs=u),
            pm.impact(q, v, p, wall, t=0.5, inputs=u),
            rtol=1e-14,
            atol=1e-15,
        )
    np.testing.assert_allclose(cm.energy(q, v, p), pm.energy(q, v, p), rtol=1e-15)
    assert not (tmp_path / "pwned").exists()


# ------------------------------------------------------------------- the escape rules


@pytest.mark.parametrize("text", [*HOSTILE, "*", "/", "a*", "/b", "\\", "?", "??"])
def test_c_comment_rules(text):
    out = c_comment(text)
    assert "*/" not in out and "/*" not in out and "??" not in out
    assert "\n" not in out and not out.endswith(("*", "\\")) and not out.startswith("/")
    assert out.isprintable()
    # put between the template's neighbours, the comment still ends where it should
    for left, right in (("/* ", " */"), ("/*", "*/"), ("/* x", "\n */")):
        blanked = _comments_and_strings_c(f"{left}{out}{right} int ok;")
        assert blanked.strip() == "int ok;", (text, out)


@pytest.mark.parametrize("text", [*HOSTILE, 'é"\\?', "??=", "\x7f"])
def test_c_string_round_trips_through_the_compiler(tmp_path, text):
    """The literal compiles and its bytes are the UTF-8 of the text."""
    cc = require_c_compiler()
    src = tmp_path / "s.c"
    src.write_text(
        '#include <stdio.h>\nint main(void) { static const char s[] = "'
        + c_string(text)
        + '"; fwrite(s, 1, sizeof s - 1, stdout); return 0; }\n'
    )
    exe = tmp_path / "s"
    proc = subprocess.run([cc, *STRICT, str(src), "-o", str(exe)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    out = subprocess.run([str(exe)], capture_output=True, check=True).stdout
    assert out == text.encode("utf-8")


@pytest.mark.parametrize("text", [*HOSTILE, '"', '""', "\\", 'a"', "'''", "\\N{DIGIT ONE}"])
def test_python_docstring_rules(text):
    """Between triple quotes (also right next to them) the escaped text is one string whose
    value is the visible form of the text."""
    body = python_docstring(text)
    for source in (f'"""{body}"""', f'"""{body}\n"""', f'"""x {body}"""'):
        tree = ast.parse(source)
        assert len(tree.body) == 1
        value = tree.body[0].value.value
        assert value.strip().removeprefix("x ") == python_comment(text)


@pytest.mark.parametrize("text", HOSTILE)
def test_python_comment_is_one_line(text):
    source = f"x = 1  # {python_comment(text)}\ny = 2\n"
    tree = ast.parse(source)
    assert [type(n) for n in tree.body] == [ast.Assign, ast.Assign]
    assert source.count("\n") == 2 and python_comment(text).isprintable()


def test_file_names_are_safe_short_and_distinct():
    long_a, long_b = "a" * 300 + "x", "a" * 300 + "y"
    assert file_name(long_a) != file_name(long_b)
    for name in [*HOSTILE, long_a, "..", ".", "", "3d", "../../etc/passwd", "é"]:
        stem = file_name(name)
        assert re.fullmatch(r"[A-Za-z_][0-9A-Za-z_]*", stem), stem
        assert len(stem) <= MAX_STEM
    assert file_name("bouncing_ellipse") == "bouncing_ellipse"  # ordinary names unchanged


def test_a_300_character_scene_name_gives_short_file_names(tmp_path):
    x = sm.coordinates("x")[0]
    scene = sm.Scene((x,), metric=sp.eye(1), walls=[sm.Wall(x)], name="s" * 300)
    for target in ("c", "numpy"):
        code = codegen.generate(scene, target)
        assert all(len(name) < 100 for name in code.files)
        code.write(tmp_path / target)
        mod = code.load(cache=tmp_path / "cache")
        np.testing.assert_array_equal(mod.impact([0.0], [-1.0]), [1.0])


# --------------------------------------------------- every template output is escaped

#: Template expressions that are code built by symmech (identifiers, integers, printed
#: expressions), never text of the scene: anything else must go through an escape filter.
CODE = {
    "n",
    "m",
    "n_inputs",
    "n_parameters",
    "stride",
    "rules",  # only its length is printed raw; rule.text goes through a filter
    "rule.index",
    "rule.c_condition",
    "rule.numpy_condition",
    "fn",  # passed whole to a macro, whose own outputs are checked here too
    "strategy",
    "prefix",
    "guard",
    "macro",
    "header",
    "module",
    "size",
    "loop",
    "fn.name",
    "fn.scaled",
    "velocity",  # a macro argument: "v" or "w"
    "arguments",  # a macro argument: a C argument list from c_signatures
    "split",  # symmech.codegen.batch_split: lines of the one-state body, re-ordered
    "hoisted",
    "condition",
    "c_batch_split",
    "scale_down",  # a macro of the template, whose own outputs are checked here too
    "fn.takes_parameters",
    "fn.sizes",
    "fn.parameters",
    "fn.dims",
    "fn.out_size",
    "fn.out_shape",
    "fn.calls",
    "fn.call_stop",  # an int (or None)
    "fn.part_of",  # (a generated function's name, an offset)
    "whole",  # the generated function that fn is part of (as callees[...])
    "fn.arguments",
    "fn.unused",
    "arg",
    "array",
    "i",
    "name",
    "expr",
    "block",
    "flat",
    "idx",
    "bshape",
    "line",
    "s",
    "a",
    "mac",
    # C argument lists printed by symmech.codegen.c_signatures from a function's flags
    "c_parameters",
    "c_batch_parameters",
    "c_call_arguments",
    "c_scaled_arguments",
    "step_docs",
    "fn.step",
    "parameters",
    "inputs",
    "callee",
    "callees",
    "c",
}

#: Loop variables over scene text: an output of them unfiltered would be raw text.
TEXT_LOOPS = {"omitted": "line", "constants": "c"}


def _roots(node: jn.Node) -> set[str]:
    """The variables an expression reads: ``x`` or ``x.attr`` (the first attribute)."""
    if isinstance(node, jn.Getattr) and isinstance(node.node, jn.Name):
        return {f"{node.node.name}.{node.attr}"}
    if isinstance(node, jn.Name):
        return {node.name}
    out: set[str] = set()
    for child in node.iter_child_nodes():
        out |= _roots(child)
    return out


def _template_outputs():
    """The output nodes of the code generator's templates: those of every backend and of
    the CPython extension, with the templates they include or import."""
    env = environment()
    roots = [t for b in BACKENDS.values() for t, _ in b.templates]
    roots += [b.function_template for b in BACKENDS.values()] + [EXTENSION_TEMPLATE]
    names = sorted({t for root in roots for t in templates_used(root)})
    assert len(names) >= 8, names
    for name in names:
        tree = env.parse(env.loader.get_source(env, name)[0])  # type: ignore[union-attr]
        text_loops = {
            f.target.name
            for f in tree.find_all(jn.For)
            if isinstance(f.iter, jn.Name) and f.iter.name in TEXT_LOOPS
        }
        for out in tree.find_all(jn.Output):
            for node in out.nodes:
                if not isinstance(node, jn.TemplateData):
                    yield name, node, text_loops


def test_every_template_output_of_scene_text_goes_through_an_escape_filter():
    """A structural check: every ``{{ ... }}`` of every template either applies one of the
    escape filters last, or prints code built by symmech (CODE); a loop variable over
    scene text (omitted notes, constants) is never printed raw."""
    bad = []
    for name, node, text_loops in _template_outputs():
        if isinstance(node, jn.Filter) and node.name in ESCAPE_FILTERS:
            continue
        roots = _roots(node)
        raw_text = (roots & text_loops) or any(
            r not in CODE and r.split(".")[0] not in CODE - {"fn"} for r in roots
        )
        if raw_text:
            bad.append((name, node))
    assert not bad, bad


def test_escape_filters_are_registered_once_in_the_environment():
    env = environment()
    for name, func in ESCAPE_FILTERS.items():
        assert env.filters[name] is func
    with pytest.raises(jinja2.TemplateSyntaxError):
        env.from_string("{{ x | no_such_filter }}")
