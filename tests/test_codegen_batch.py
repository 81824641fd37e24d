"""The C batch loop (symmech.codegen.batch_split): the lines that read only the parameters
run once per batch, the rest once per state, with the same doubles and the same failures
as the one-state function."""

from __future__ import annotations

import ctypes
import math
import re

import numpy as np
import pytest
from codegen_support import require_c_compiler

import symmech as sm
from symmech.codegen import NumericalError
from symmech.codegen.batch_split import _split
from symmech.examples import carnot_3_13, pendulum_on_cart


def test_the_split_hoists_what_reads_only_p_and_keeps_the_order():
    lines = [
        "const double p_k = p[1];",
        "const double v_x = v[0];",
        "const double a = 1.0/sqrt(p_k*p_k + 1.0e-3);",
        "const double b = a*v_x;",
        "if (!(isfinite(a) && isfinite(v[1]))) return SYMMECH_NONFINITE;",
        "if (!(a > 0.0)) return SYMMECH_NOT_SPD;",
        "const double c = M_PI*a;",  # a name it does not know: per state
        "out[0] = b + c;",
    ]
    split = _split(lines, {"p"})
    assert split.once == (lines[0], lines[2])
    assert split.checks == ("isfinite(a)", "a > 0.0")
    assert split.fields == ("a",)
    assert split.state == (
        lines[1],
        lines[3],
        "if (!(isfinite(v[1]))) return SYMMECH_NONFINITE;",
        lines[6],
        lines[7],
    )


@pytest.fixture(scope="module", params=["closed_form", "linear_solve"])
def impact(request):
    require_c_compiler()
    code = sm.codegen.generate(carnot_3_13(), "c", strategy=request.param, functions=["impact"])
    return request.param, code, code.load()


def test_the_batch_gives_the_one_state_doubles(impact):
    strategy, code, mod = impact
    rng = np.random.default_rng(1)
    # 150 states: two full blocks of 64 scalings and a part (FUNCTION.c.jinja)
    Q, V = rng.uniform(-1, 1, (150, 6)), rng.uniform(-1, 1, (150, 6))
    V[-8:] *= np.array([[1e-300], [1e300], [1e-310], [0.0], [1e-3], [1e3], [-1e200], [1]])
    p = np.array([0.5, 0.8, 1.2])
    batch = mod.impact(Q, V, p)
    single = np.array([mod.impact(q, v, p) for q, v in zip(Q, V, strict=True)])
    assert np.array_equal(batch, single)
    if strategy == "linear_solve":
        (text,) = [t for f, t in code.files.items() if f.endswith(".c")]
        each = text[text.index("static int sm_each_") : text.index("_batch(long count")]
        # the Cholesky factor of A M^-1 A^T reads only the parameters: once per batch
        assert "sqrt(" in text[text.index("static int sm_once_") :] and "sqrt(" not in each


def test_a_failing_state_is_found_by_the_batch(impact):
    _, _, mod = impact
    Q, V = np.zeros((150, 6)), np.ones((150, 6))
    V[100, 0], V[120, 1] = math.nan, math.inf
    with pytest.raises(NumericalError, match="at state 100"):
        mod.impact(Q, V, np.array([0.5, 0.8, 1.2]))


def test_the_rhs_batch_of_the_pendulum_on_a_cart():
    require_c_compiler()
    mod = sm.codegen.generate(pendulum_on_cart(2), "c", strategy="linear_solve").load()
    rng = np.random.default_rng(2)
    Y, p = 0.3 * rng.normal(size=(9, 6)), 1 + rng.random(len(mod.parameters))
    assert np.array_equal(mod.rhs(Y, p), np.array([mod.rhs(y, p) for y in Y]))


def test_a_failing_parameter_check_fails_the_first_state(impact):
    """A check that reads only p runs once per batch: when it fails, every state would
    fail, and the batch returns 1 (0 for no state), as the loop over states would."""
    code, mod = impact[1], impact[2]
    lib = ctypes.CDLL(str(mod.path))
    (header,) = [t for f, t in code.files.items() if f.endswith(".h")]
    name = re.search(r"^long (\w+_batch)\(", header, re.M).group(1)
    batch, one = getattr(lib, name), getattr(lib, name[: -len("_batch")])
    batch.restype, one.restype = ctypes.c_long, ctypes.c_int
    Q, V, out = np.zeros((3, 6)), np.ones((3, 6)), np.empty((3, 6))
    p = np.array([0.5, math.nan, 1.2])  # k: past mod.impact's parameter check
    ptr = [ctypes.c_void_p(a.ctypes.data) for a in (Q, V, p, out)]
    assert one(*ptr) == 2  # SYMMECH_NONFINITE
    assert batch(ctypes.c_long(3), *ptr) == 1
    assert batch(ctypes.c_long(0), *ptr) == 0


def test_a_body_too_long_to_print_twice_is_not_split(monkeypatch):
    """Above MAX_SPLIT_CHARACTERS the batch loop calls the exported function per state
    (the body printed once: the compile time of an imported bicycle is not doubled)."""
    require_c_compiler()
    import symmech.codegen.batch_split as batch_split

    scene = pendulum_on_cart(2)
    split = sm.codegen.generate(scene, "c", functions=["acceleration"])
    monkeypatch.setattr(batch_split, "MAX_SPLIT_CHARACTERS", 10)
    plain = sm.codegen.generate(scene, "c", functions=["acceleration"])
    source = next(v for k, v in plain.files.items() if k.endswith(".c"))
    assert "sm_each_" not in source and "sm_once_" not in source
    assert "sm_each_acceleration" in next(v for k, v in split.files.items() if k.endswith(".c"))
    rng = np.random.default_rng(3)
    Q, V = rng.uniform(-1, 1, (20, 3)), rng.uniform(-1, 1, (20, 3))
    p = rng.uniform(0.5, 1.5, len(plain.plan.parameters))
    a, b = split.load(), plain.load()
    np.testing.assert_array_equal(a.acceleration(Q, V, p), b.acceleration(Q, V, p))
    single = np.array([b.acceleration(q, v, p) for q, v in zip(Q, V, strict=True)])
    np.testing.assert_array_equal(b.acceleration(Q, V, p), single)
