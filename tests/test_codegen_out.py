"""``out=`` of the generated functions: the output written into a preallocated array and
returned, the same doubles as the allocating call; a wrong shape, dtype, layout or a
read-only array refused with an error naming the function and what it expects; an
``out`` that is an argument's own memory gives the correct answer."""

from __future__ import annotations

import numpy as np
import pytest
from codegen_support import require_c_compiler

import symmech as sm
from symmech.codegen import CodegenError, NumericalError
from symmech.examples import carnot_3_7, pendulum_on_cart

N = 7


@pytest.fixture(scope="module", params=["c", "numpy"])
def mod(request):
    if request.param == "c":
        require_c_compiler()
    return sm.codegen.generate(pendulum_on_cart(2), request.param, strategy="linear_solve").load()


def _batch(mod, seed=0):
    rng = np.random.default_rng(seed)
    Y = 0.3 * rng.normal(size=(N, 2 * mod.n))
    return Y, 1 + rng.random(len(mod.parameters))


def test_out_receives_the_batch(mod):
    Y, p = _batch(mod)
    expected = mod.rhs(Y, p)
    out = np.full((N, 2 * mod.n), np.nan)
    got = mod.rhs(Y, p, out=out)
    assert got is out
    assert np.array_equal(out, expected)
    M = np.empty((N, mod.n, mod.n))
    assert mod.mass_matrix(Y[:, : mod.n], p, out=M) is M
    assert np.array_equal(M, mod.mass_matrix(Y[:, : mod.n], p))


def test_out_receives_one_state(mod):
    Y, p = _batch(mod)
    out = np.empty(2 * mod.n)
    assert mod.rhs(Y[0], p, out=out) is out
    assert np.array_equal(out, mod.rhs(Y[0], p))
    e = np.empty(())
    assert mod.energy(Y[0, : mod.n], Y[0, mod.n :], p, out=e) is e
    assert e == mod.energy(Y[0, : mod.n], Y[0, mod.n :], p)


def test_out_through_a_bound_module(mod):
    Y, p = _batch(mod)
    bound = mod.bind(p)
    out = np.empty((N, 2 * mod.n))
    assert bound.rhs(Y, out=out) is out
    assert np.array_equal(out, mod.rhs(Y, p))
    one = np.empty(2 * mod.n)
    assert bound.call("rhs", Y[1], out=one) is one
    assert np.array_equal(one, mod.rhs(Y[1], p))


@pytest.mark.parametrize(
    ("make", "what"),
    [
        (lambda k: np.empty((N, k + 1)), "got shape"),
        (lambda k: np.empty((N + 1, k)), "got shape"),
        (lambda k: np.empty(k), "got shape"),
        (lambda k: np.empty((N, k), dtype=np.float32), "got dtype"),
        (lambda k: np.empty((N, k), dtype=">f8"), "got dtype"),
        (lambda k: np.empty((N, k), order="F"), "non-contiguous"),
        (lambda k: np.empty((N, 2 * k))[:, ::2], "non-contiguous"),
        (lambda k: np.empty((N, k)).tolist(), "got list"),
    ],
)
def test_a_wrong_out_is_refused_by_name(mod, make, what):
    Y, p = _batch(mod)
    with pytest.raises(CodegenError) as info:
        mod.rhs(Y, p, out=make(2 * mod.n))
    message = str(info.value)
    assert message.startswith("rhs: out= must be a C-contiguous, writeable float64 array")
    assert f"of shape ({N}, {2 * mod.n})" in message
    assert what in message


def test_a_read_only_out_is_refused(mod):
    Y, p = _batch(mod)
    out = np.empty((N, 2 * mod.n))
    out.setflags(write=False)
    with pytest.raises(CodegenError, match=r"rhs: out= .* got a read-only array"):
        mod.rhs(Y, p, out=out)


def test_out_aliasing_the_input_gives_the_answer(mod):
    Y, p = _batch(mod)
    expected = mod.rhs(Y, p)
    Z = Y.copy()
    assert mod.rhs(Z, p, out=Z) is Z
    assert np.array_equal(Z, expected)
    # a view overlapping the argument, shifted by one state
    big = np.zeros((N + 1) * 2 * mod.n)
    big[: N * 2 * mod.n] = Y.ravel()
    src = big[: N * 2 * mod.n].reshape(N, 2 * mod.n)
    dst = big[2 * mod.n :].reshape(N, 2 * mod.n)
    assert mod.rhs(src, p, out=dst) is dst
    assert np.array_equal(dst, expected)


def test_impact_in_place_of_the_velocities():
    mod = sm.codegen.generate(carnot_3_7(), "numpy").load()
    p = {"R": 1, "alpha": 0.5, "k": 1, "m": 2}
    Q = np.array([[0.0, 1.0, 0.0], [0.1, 1.0, 0.2]])
    V = np.array([[1.0, -2.0, 0.0], [0.5, -1.0, 0.3]])
    expected = mod.impact(Q, V, p)
    assert mod.impact(Q, V, p, out=V) is V
    assert np.array_equal(V, expected)


def test_static_psi_t_fills_out_with_zeros():
    mod = sm.codegen.generate(carnot_3_7(), "numpy").load()
    out = np.ones(3)
    p = {"R": 1, "alpha": 0.5, "k": 1, "m": 2}
    assert mod.psi_t(np.zeros((3, 3)), p, out=out) is out
    assert np.array_equal(out, np.zeros(3))
    with pytest.raises(CodegenError, match=r"out= must be .* of shape \(3,\); got shape \(4,\)"):
        mod.psi_t(np.zeros((3, 3)), p, out=np.ones(4))


def test_a_failing_state_still_raises_with_out(mod):
    Y, p = _batch(mod)
    Y[3, :] = np.inf
    with pytest.raises(NumericalError, match=r"^rhs"):
        mod.rhs(Y, p, out=np.empty((N, 2 * mod.n)))
