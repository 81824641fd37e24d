"""Code generation: what is emitted, how it compiles, golden files, errors.

Numerical agreement with independent references is in ``test_codegen_numerics.py``.
Compile tests need a C compiler: without one they are skipped with the reason, except on
CI (CI=true), where that is a failure (``codegen_support.require_c_compiler``).
"""

from __future__ import annotations

import math
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from codegen_support import require_c_compiler

import symmech as sm
from symmech import codegen
from symmech.codegen.backends import environment
from symmech.examples import (
    EXAMPLES,
    bouncing_ellipse,
    carnot_3_7,
    carnot_3_13,
    carnot_4_4,
    example,
    pendulum_on_cart,
)

STRICT = ["-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-pedantic"]


def _gcc() -> str:
    return require_c_compiler()


# ------------------------------------------------------------------------ compilation


@pytest.mark.parametrize("name", sorted(EXAMPLES))
@pytest.mark.parametrize("strategy", ["auto", "linear_solve"])
def test_generated_c_compiles_with_strict_warnings(tmp_path, name, strategy):
    code = codegen.generate(example(name), "c", strategy=strategy, projectors=True)
    code.write(tmp_path)
    proc = subprocess.run(
        [_gcc(), *STRICT, "-c", f"{code.stem}.c", "-o", "out.o"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stderr


def test_a_missing_compiler_skips_with_its_reason_except_on_ci(monkeypatch):
    monkeypatch.setenv("PATH", "")
    monkeypatch.delenv("CC", raising=False)
    monkeypatch.delenv("CI", raising=False)
    with pytest.raises(pytest.skip.Exception, match="no C compiler"):
        require_c_compiler()
    monkeypatch.setenv("CI", "true")
    with pytest.raises(pytest.fail.Exception, match="CI=true: a compiler is required"):
        require_c_compiler()


@pytest.mark.parametrize("target", ["c", "numpy"])
def test_load_takes_the_cache_option_its_docstring_names(tmp_path, target):
    if target == "c":
        require_c_compiler()
    code = codegen.generate(carnot_3_7(), target)
    assert "``cache``" in type(code).load.__doc__ and "cache_dir``" not in type(code).load.__doc__
    mod = code.load(cache=tmp_path / "cache")
    assert mod.path.parent == tmp_path / "cache"
    np.testing.assert_allclose(
        mod.impact([0, 1.0, 0], [1.0, -2.0, 0.0], [1.0, 0.5, 1.0, 2.0]), [0.5, 1.0, 0.5]
    )


def _driver(code: codegen.GeneratedCode, count: int) -> str:
    """A C main() calling every batch function on `count` pseudo-random states."""
    plan = code.plan
    n, npar, nin = plan.n, len(plan.parameters), len(plan.inputs)
    lines = [
        "#include <stdio.h>",
        "#include <stdlib.h>",
        f'#include "{code.stem}.h"',
        "static double rnd(unsigned *s) { *s = *s * 1103515245u + 12345u;"
        " return 0.4 + 1.2 * (double)((*s >> 8) & 0xffff) / 65535.0; }",
        "int main(void) {",
        "    unsigned seed = 12345u;",
        f"    enum {{ N = {count} }};",
        f"    double *q = malloc(sizeof(double) * N * {n});",
        f"    double *v = malloc(sizeof(double) * N * {n});",
        f"    double *y = malloc(sizeof(double) * N * {2 * n});",
        "    double *t = malloc(sizeof(double) * N);",
        f"    double *u = malloc(sizeof(double) * N * {max(nin, 1)});",
        f"    double p[{max(npar, 1)}];",
        "    long failures = 0;",
        f"    for (int i = 0; i < N * {n}; ++i) {{ q[i] = rnd(&seed); v[i] = rnd(&seed) - 1.0; }}",
        f"    for (int i = 0; i < N; ++i) {{ t[i] = rnd(&seed);"
        f" for (int j = 0; j < {n}; ++j) {{ y[i*{2 * n} + j] = q[i*{n} + j];"
        f" y[i*{2 * n} + {n} + j] = v[i*{n} + j]; }} }}",
        f"    for (int i = 0; i < N * {max(nin, 1)}; ++i) u[i] = rnd(&seed) - 1.0;",
        f"    for (int i = 0; i < {max(npar, 1)}; ++i) p[i] = 0.5 + 0.1 * i;",
    ]
    for f in code.functions:
        args = ["N"]
        args += ["y"] if f.state == ("y",) else list(f.state)
        if f.takes_parameters:
            args.append("p")
        if f.takes_time:
            args.append("t")
        if f.takes_inputs:
            args.append("u")
        lines += [
            "    {",
            f"        double *out = malloc(sizeof(double) * N * {f.out_size});",
            f"        long r = {code.stem}_{f.name}_batch({', '.join(args)}, out);",
            f'        if (r) {{ failures++; fprintf(stderr, "{f.name} failed at %ld\\n", r); }}',
            "        free(out);",
            "    }",
        ]
    lines += [
        "    free(q); free(v); free(y); free(t); free(u);",
        '    printf("checked\\n");',
        "    return failures ? 3 : 0;",
        "}",
    ]
    return "\n".join(lines) + "\n"


def test_batch_calls_are_clean_under_address_and_undefined_sanitizers(tmp_path):
    """Every batch function of a constrained, moving-wall, linear-solve scene (carnot_4_4:
    Cholesky, constrained solve, KKT impact, inputs) runs clean under ASan + UBSan."""
    code = codegen.generate(carnot_4_4(), "c", strategy="linear_solve", projectors=True)
    code.write(tmp_path)
    (tmp_path / "driver.c").write_text(_driver(code, 257))
    exe = tmp_path / "driver"
    flags = ["-std=c99", "-O1", "-g", "-fsanitize=address,undefined", "-fno-sanitize-recover=all"]
    proc = subprocess.run(
        [_gcc(), *flags, "-o", str(exe), "driver.c", f"{code.stem}.c", "-lm"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stdout + run.stderr
    assert run.stdout.strip() == "checked"
    assert "runtime error" not in run.stderr and "AddressSanitizer" not in run.stderr


# ------------------------------------------------------------------ only what is needed


def test_unconstrained_static_scene_has_no_constraint_impact_solver_or_time_code():
    code = codegen.generate(bouncing_ellipse(), "c")
    src = code.files["symmech_bouncing_ellipse.c"]
    names = {f.name for f in code.functions}
    assert names == {
        "mass_matrix",
        "forcing",
        "acceleration",
        "rhs",
        "energy",
        "psi_wall",
        "dpsi_wall",
        "impact_wall",
    }
    # no linear solve and no inputs; the closed forms holding g^-1 check g (a diagonal
    # metric: its diagonal entries finite and positive), the other functions check nothing
    for absent in ("const double x0_0", "Li0", "const double *u"):
        assert absent not in src, absent
    # the impact's map is the static sm_unscaled_ function (its public one scales v)
    bodies = {
        f: src.split(
            f"int sm_unscaled_{f}(" if f == "impact_wall" else f"int symmech_bouncing_ellipse_{f}("
        )[1].split("\n}\n")[0]
        for f in names
    }
    for f, body in bodies.items():
        checked = f == "impact_wall"  # the acceleration of this free body is 0
        assert (body.count("return SYMMECH_NOT_SPD;") == 3) == checked, f
        assert ("if (!(isfinite(M0_0) && isfinite(M1_1) && isfinite(M2_2)))" in body) == checked
    assert not re.search(r"double t[,)]", src), "a time argument"
    omitted = " ".join(code.omitted)
    assert "no constraints" in omitted and "V = 0" in omitted and "nothing depends on t" in omitted
    header = code.files["symmech_bouncing_ellipse.h"]
    assert "Left out of this file" in header and "no constraints" in header
    # V = 0 and a constant metric: the forcing is identically zero, no operation emitted
    assert code.operation_counts()["forcing"] == 0


def test_scene_without_walls_has_no_impact_code():
    code = codegen.generate(pendulum_on_cart(2), "c")
    assert not any(f.kind in ("impact", "psi", "dpsi") for f in code.functions)
    assert "no walls" in " ".join(code.omitted)
    assert "sm_impact_kkt" not in code.files["symmech_pendulum_on_cart_2.c"]


def test_moving_wall_takes_inputs_not_time():
    """psi = x - f(t): f(t) and f'(t) are run-time inputs; nothing else needs t."""
    code = codegen.generate(carnot_4_4(), "c")
    assert [str(a) for _, a in code.plan.inputs] == ["f(t)", "Derivative(f(t), t)"]
    by = {f.name: f for f in code.functions}
    assert by["psi_rough_wall"].takes_inputs and not by["psi_rough_wall"].takes_time
    assert by["impact_rough_wall"].takes_inputs
    assert not by["mass_matrix"].takes_inputs and not by["acceleration"].takes_inputs
    assert not any(f.takes_time for f in code.functions)


def test_definitions_turn_inputs_into_time():
    f = sp.Function("f", real=True)
    code = codegen.generate(carnot_4_4(), "numpy", definitions={f: sp.sin(2 * sm.t)})
    by = {fn.name: fn for fn in code.functions}
    assert not code.plan.inputs
    assert by["psi_rough_wall"].takes_time and by["impact_rough_wall"].takes_time
    mod = code.load()
    q = np.array([0.3, 0, 0.1, 0.2, 1.0, 0.4])
    assert mod.psi(q, [0.4, 0.5, 0.7], t=0.25) == pytest.approx(0.3 - np.sin(0.5), rel=1e-15)


def test_constants_are_folded_and_leave_the_parameter_list():
    code = codegen.generate(carnot_3_7(), "c", constants={"m": 2, "alpha": sp.Rational(1, 2)})
    assert [str(p) for p in code.plan.parameters] == ["R", "k"]
    src = code.files["symmech_carnot_3_7.c"]
    assert "p_m" not in src and "p_alpha" not in src
    assert "-0.5*v_ydot" in src.replace(" ", "")  # y_dot+ = -alpha y_dot, alpha = 1/2 folded
    mod = code.load()
    np.testing.assert_allclose(
        mod.impact([0, 1.0, 0], [1.0, -2.0, 0.0], [1.0, 1.0]), [0.5, 1.0, 0.5], rtol=1e-15
    )


@pytest.mark.parametrize(
    ("constants", "fragment"),
    [
        ({"nope": 1}, "not a parameter"),
        ({"m": -1}, "declared positive"),
        ({"m": "2"}, "is not a real number"),
        ({"m": sp.oo}, "not a finite real number"),
        ({"m": True}, "not a real number"),
    ],
)
def test_bad_constants_are_refused(constants, fragment):
    with pytest.raises(codegen.CodegenError, match=fragment):
        codegen.generate(carnot_3_7(), "c", constants=constants)


def test_bad_options_are_refused():
    with pytest.raises(codegen.CodegenError, match="target must be one of"):
        codegen.generate(carnot_3_7(), "fortran")
    with pytest.raises(codegen.CodegenError, match="strategy must be one of"):
        codegen.generate(carnot_3_7(), "c", strategy="fast")
    with pytest.raises(codegen.CodegenError, match="unknown"):
        codegen.generate(carnot_3_7(), "c", functions=["acceleration", "jerk"])


def test_functions_option_restricts_what_is_emitted():
    code = codegen.generate(carnot_3_13(), "c", functions=["impact", "psi"])
    assert {f.kind for f in code.functions} == {"impact", "psi"}
    rhs_only = codegen.generate(carnot_3_7(), "c", functions=["rhs"])
    assert {f.name for f in rhs_only.functions} == {"acceleration", "rhs"}
    assert any("rhs calls it" in o for o in rhs_only.omitted)


# ------------------------------------------------------------------ printing conventions


def test_hostile_identifiers_compile_and_compute(tmp_path):
    """Symbol names that are C/Python keywords, libm names or LaTeX must all work."""
    x, y = sm.coordinates("x y")
    Ixx, lam, dbl, pw, same = sp.symbols("I_{xx} lambda double pow I_xx", positive=True)
    scene = sm.Scene(
        (x, y),
        metric=sp.diag(Ixx + same, lam),
        potential=dbl * x**2 / 2 + pw * y,
        walls=[sm.Wall(y, restitution=sp.Rational(1, 2), name="int")],
        name="for",
    )
    for target in ("c", "numpy"):
        code = codegen.generate(scene, target)
        if target == "c":
            code.write(tmp_path)
            proc = subprocess.run(
                [_gcc(), *STRICT, "-c", f"{code.stem}.c"],
                cwd=tmp_path,
                capture_output=True,
                text=True,
            )
            assert proc.returncode == 0, proc.stderr
        mod = code.load()
        values = dict(zip(mod.parameters, [1.5, 0.25, 2.0, 3.0, 0.5], strict=True))
        # parameters are sorted by name: I_xx, I_{xx}, double, lambda, pow
        assert mod.parameters == ("I_xx", "I_{xx}", "double", "lambda", "pow")
        acc = mod.acceleration([0.4, 1.0], [0.0, 0.0], values)
        np.testing.assert_allclose(acc, [-2.0 * 0.4 / 1.75, -0.5 / 3.0], rtol=1e-15)
        np.testing.assert_allclose(mod.impact([0.4, 0.0], [1.0, -2.0], values), [1.0, 1.0])


def test_printing_is_float64_safe():
    src = codegen.generate(bouncing_ellipse(), "c").files["symmech_bouncing_ellipse.c"]
    assert "hypot(" in src  # the support function sqrt(a^2 cos^2 + b^2 sin^2)
    assert "pow(" not in src  # squares are products
    assert "M_PI" not in src
    body = "\n".join(line for line in src.splitlines() if not line.lstrip().startswith("*"))
    assert not re.search(r"(?<![\w.])\d+/\d+(?![\w.])", body), "integer division"
    numpy_src = codegen.generate(pendulum_on_cart(2), "numpy").files[
        "symmech_pendulum_on_cart_2.py"
    ]
    assert "**2" not in numpy_src


def test_every_function_header_states_its_cost_and_files_are_stamped():
    for strategy in ("closed_form", "linear_solve"):
        for target, ext in (("c", "c"), ("numpy", "py")):
            code = codegen.generate(carnot_3_13(), target, strategy=strategy)
            src = code.files[f"symmech_carnot_3_13.{ext}"]
            for f in code.functions:
                assert (
                    f"Operations after CSE: {f.operations} (sympy.count_ops); temporaries:"
                    f" {f.n_temporaries}" in src
                )
                assert f.cost in src
                if f.step:
                    assert f"solve: {f.solve_flops} flops (n = 6," in f.cost
                if f.calls:  # rhs states the cost of its call of the acceleration
                    callee = next(g for g in code.functions if g.name == f.calls)
                    assert f"then the call of acceleration: {callee.operations} operations" in (
                        f.cost
                    )
    stamps = {}
    for target in ("c", "numpy"):
        for name, text in codegen.generate(carnot_3_13(), target).files.items():
            first = "\n".join(text.splitlines()[:3])
            assert "Generated by symmech" in first and "do not edit" in first
            stamps[name] = first
    # each file names the templates it was rendered from, and only those
    header = stamps["symmech_carnot_3_13.h"]
    assert "from template c/header.h.jinja;" in header
    assert "source.c.jinja" not in header and "FUNCTION" not in header
    source = stamps["symmech_carnot_3_13.c"]
    assert "header.h.jinja" not in source and "c/linalg.c.jinja" in source
    assert "numpy/function/FUNCTION.py.jinja" in stamps["symmech_carnot_3_13.py"]


def test_cse_reduces_the_operation_count():
    scene = pendulum_on_cart(2)
    with_cse = codegen.generate(scene, "c").operation_counts()
    without = codegen.generate(scene, "c", cse=False).operation_counts()
    assert with_cse["forcing"] < without["forcing"]
    assert with_cse["mass_matrix"] <= without["mass_matrix"]


def test_templates_are_strict():
    env = environment()
    with pytest.raises(Exception, match="undefined"):
        env.from_string("{{ missing }}").render()


# ------------------------------------------------------------------------ run-time errors


def test_loaded_module_checks_its_arguments():
    mod = codegen.generate(carnot_3_7(), "c").load()
    q, v, p = [0, 1.0, 0], [1.0, -2.0, 0.0], [1.0, 0.5, 1.0, 2.0]
    with pytest.raises(codegen.CodegenError, match="params required"):
        mod.impact(q, v)
    with pytest.raises(codegen.CodegenError, match="expected 4 values"):
        mod.impact(q, v, [1.0, 2.0])
    with pytest.raises(codegen.CodegenError, match=r"missing \['m'\]"):
        mod.impact(q, v, {"R": 1, "alpha": 0.5, "k": 1})
    with pytest.raises(codegen.CodegenError, match=r"expected shape \(\.\.\., 3\)"):
        mod.impact([0, 1.0], v, p)
    with pytest.raises(codegen.CodegenError, match="no wall named"):
        mod.impact(q, v, p, wall="floor")
    with pytest.raises(codegen.CodegenError, match="not generated"):
        mod.multipliers(q, v, p)
    moving = codegen.generate(carnot_4_4(), "numpy").load()
    with pytest.raises(codegen.CodegenError, match="inputs"):
        moving.psi(np.zeros(6), [0.4, 0.5, 0.7])


@pytest.mark.parametrize("target", ["c", "numpy"])
def test_non_positive_definite_metric_and_nan_raise_numerical_errors(target):
    """The generated code does not trust the parameters: a metric that a run-time value
    makes indefinite is caught by the Cholesky factorisation, not returned as garbage."""
    x, y = sm.coordinates("x y")
    a = sp.Symbol("a", positive=True)
    scene = sm.Scene(
        (x, y), metric=[[2, 1], [1, a + 1]], potential=x * y, name="spd_for_positive_a"
    )
    mod = codegen.generate(scene, target, strategy="linear_solve").load()
    assert np.isfinite(mod.acceleration([0, 0], [1, 1], [0.5])).all()
    # a < 0 breaks the declaration: the call is refused once, naming the parameter
    with pytest.raises(codegen.NumericalError, match=r"'a' = -0\.9 breaks 0 < a"):
        mod.acceleration([0, 0], [1, 1], [-0.9])
    # and the generated code itself (called without the wrapper's parameter check)
    with pytest.raises(codegen.NumericalError, match="positive definite"):
        mod._raw["acceleration"]((np.zeros(2), np.ones(2)), np.array([-0.9]), None, None)
    states = np.zeros((4, 2))
    with pytest.raises(codegen.NumericalError, match="not finite"):
        mod.energy(states, np.array([[1, 1], [1, 1], [np.nan, 1], [1, 1]]), [0.5])


# ---------------------------------------------------------------------------- golden


GOLDEN_SCENES = {
    "bouncing_ellipse": bouncing_ellipse,
    "carnot_3_7": carnot_3_7,
    "carnot_4_4": carnot_4_4,
}


@pytest.mark.parametrize("target", ["c", "numpy"])
@pytest.mark.parametrize("name", sorted(GOLDEN_SCENES))
def test_golden_files(golden, name, target):
    """The generated files equal tests/golden/<scene>/, the CPython extension of a C target
    (``<stem>_python.c``) included; update with --update-golden."""
    code = codegen.generate(GOLDEN_SCENES[name](), target)
    outputs = dict(code.files)
    if code.extension:
        outputs[f"{code.stem}_python.c"] = code.extension
    assert (target == "c") == bool(code.extension)
    for filename, text in outputs.items():
        golden(name, filename, text)


def test_numpy_solve_refuses_non_finite_inputs_for_one_state_and_a_batch():
    """The NumPy code checks the inputs of its linear solves as the C code does
    (SYMMECH_NONFINITE): a float64 scalar of one state as a number, a batch element-wise."""
    x, y = sm.coordinates("x y")
    a = sp.Symbol("a", positive=True)
    scene = sm.Scene((x, y), metric=[[2, 1], [1, a + 1]], potential=x * y, name="spd_nonfinite")
    mod = codegen.generate(scene, "numpy", strategy="linear_solve").load()
    raw = mod._raw["acceleration"]
    p = np.array([0.5])
    ok = raw((np.zeros(2), np.ones(2)), p, None, None)
    assert np.isfinite(ok).all()
    for bad in (np.inf, -np.inf, np.nan):
        with pytest.raises(codegen.NumericalError, match="not finite"):
            raw((np.array([1.0, bad]), np.ones(2)), p, None, None)  # f = -grad V
        batch = np.ones((3, 2))
        batch[1, 0] = bad
        with pytest.raises(codegen.NumericalError, match="not finite"):
            raw((batch, np.ones((3, 2))), p, None, None)
    np.testing.assert_array_equal(raw((np.zeros((1, 2)), np.ones((1, 2))), p, None, None)[0], ok)


def test_the_one_state_variant_checks_its_solve_inputs_without_overflow():
    """The one-state variant of a function with a linear solve refuses an inf or a NaN
    among the solve's inputs, as the vectorised function does, and accepts finite inputs
    however large (its single test sums ``x - x``, which cannot overflow)."""
    import importlib.util

    x, y = sm.coordinates("x y")
    a = sp.Symbol("a", positive=True)
    scene = sm.Scene((x, y), metric=[[2, 1], [1, a + 1]], potential=x * y, name="one_nonfinite")
    mod = codegen.generate(scene, "numpy", strategy="linear_solve").load()
    spec = importlib.util.spec_from_file_location("one_nonfinite_module", mod.path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    one = module._one_acceleration
    for bad in (math.inf, -math.inf, math.nan):
        with pytest.raises(FloatingPointError, match="not finite"):
            one([1.0, bad], [1.0, 1.0], [0.5])
    huge = one([1e308, 1e308], [0.0, 0.0], [0.5])  # forcing (-1e308, -1e308): finite
    want = mod.acceleration(np.array([[1e308, 1e308]]), np.zeros((1, 2)), [0.5])[0]
    assert huge == want.tolist()


@pytest.mark.parametrize("value", [sp.zoo, sp.oo, -sp.oo, sp.nan])
def test_an_entry_that_is_not_finite_is_refused_with_its_place(value):
    """An input defined as an infinity (or nan) would make the forcing's entry singular
    for every state: generation refuses the definition itself, by the admissibility rules
    of a scene's fields, naming it."""
    x = sp.Symbol("x", real=True)
    f = sp.Function("f")
    scene = sm.Scene((x,), metric=sp.eye(1), forces=[f(sm.t)], name="pushed")
    with pytest.raises(
        codegen.CodegenError, match=r"definitions\['f'\] = .*infinite or undefined value"
    ):
        codegen.generate(scene, "numpy", definitions={f: value})


def test_templates_come_from_the_tree_the_code_was_imported_from(tmp_path, monkeypatch):
    """An editable install's templates must not fill the code of another checkout: with
    the resource ``symmech.templates`` resolving to another tree's folder (as an editable
    install's finder does for a second checkout on PYTHONPATH), the template folder is
    still the package's own or the checkout's next to it."""
    import importlib.resources

    from symmech.codegen import backends

    other = tmp_path / "other_tree" / "templates"
    (other / "c").mkdir(parents=True)
    (other / "c" / "source.c.jinja").write_text("/* another tree */\n", encoding="utf-8")
    real_files = importlib.resources.files

    def files(name):
        return other if name == "symmech.templates" else real_files(name)

    monkeypatch.setattr(importlib.resources, "files", files)
    package = Path(backends.__file__).resolve().parents[1]
    assert backends.template_root() in (package / "templates", package.parent / "templates")


def test_functions_as_one_name_empty_or_unknown():
    scene = bouncing_ellipse()
    one = sm.codegen.generate(scene, "numpy", functions="rhs")
    assert one.files == sm.codegen.generate(scene, "numpy", functions=["rhs"]).files
    with pytest.raises(sm.codegen.CodegenError, match=r"functions: empty; choose from \["):
        sm.codegen.generate(scene, "numpy", functions=[])
    with pytest.raises(sm.codegen.CodegenError, match=r"functions: unknown \['zzz', 1\]"):
        sm.codegen.generate(scene, "numpy", functions=["rhs", "zzz", 1])
