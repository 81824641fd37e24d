"""The Whipple bicycle of the benchmark by Meijaard, Papadopoulos, Ruina and Schwab (2007),
imported from the KanesMethod model of sympy's own test suite, unchanged.

The model is the one ``sympy/physics/mechanics/tests/test_kane3.py::test_bicycle`` builds
(read from the installed sympy and run up to its ``kanes_equations`` call).  symmech's
generated C rhs is linearized about upright straight running (central differences with
Richardson extrapolation, on the states that satisfy the rolling constraints), reduced to
lean, steer and their rates, and its eigenvalues are compared with those of the published
benchmark matrices M, C1, K0, K2 (Meijaard et al. 2007, eq. (A 20)-(A 23), 14 digits) over
the published speed range 0 to 10 m/s.  The weave and capsize speeds of the benchmark
(4.292382799 and 6.024262734 m/s) must bound the speed range where the weave mode is
stable and the capsize mode is not yet unstable.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
import sympy as sp
from mechanics_models import sympy_bicycle

import symmech as sm

pytestmark = pytest.mark.slow

# Meijaard et al. (2007), benchmark matrices (A 20)-(A 23)
M_B = np.array([[80.81722, 2.31941332208709], [2.31941332208709, 0.29784188199686]])
K0_B = np.array([[-80.95, -2.59951685249872], [-2.59951685249872, -0.80329488458618]])
K2_B = np.array([[0.0, 76.59734589573222], [0.0, 2.65431523794604]])
C1_B = np.array([[0.0, 33.86641391492494], [-0.85035641456978, 1.68540397397560]])
G = 9.81
WEAVE, CAPSIZE = 4.292382799, 6.024262734


def _benchmark_eigenvalues(speed: float) -> np.ndarray:
    Mi = np.linalg.inv(M_B)
    A = np.block(
        [[np.zeros((2, 2)), np.eye(2)], [-Mi @ (G * K0_B + speed**2 * K2_B), -Mi @ (speed * C1_B)]]
    )
    return np.sort_complex(np.linalg.eigvals(A))


def test_whipple_bicycle_eigenvalues_match_the_benchmark():
    KM, val_dict = sympy_bicycle()
    scene = sm.Scene.from_mechanics(KM, name="bicycle")
    mod = sm.codegen.generate(scene, target="c").load()
    params = {}
    for k, v in val_dict.items():
        if isinstance(k, sp.Symbol):
            params[k.name] = float(v)
    params = {p: params[p] for p in mod.parameters}
    qn = [str(c) for c in scene.coordinates]
    vn = [str(c) for c in scene.velocities]
    n = scene.n
    rear = params["WRrad"]
    ind = [vn.index(u) for u in ("u2", "u3", "u5")]
    dep = [vn.index(u) for u in ("u1", "u4", "u6")]

    def state(x: np.ndarray, speed: float) -> np.ndarray:
        q = np.zeros(n)
        q[qn.index("q2")], q[qn.index("q5")] = x[0], x[1]
        v = np.zeros(n)
        v[vn.index("u2")], v[vn.index("u5")] = x[2], x[3]
        v[vn.index("u3")] = speed / rear
        mu = np.array([mod.constraint_residual(q, e, params) for e in np.eye(n)]).T
        v[dep] = -np.linalg.solve(mu[:, dep], mu[:, ind] @ v[ind])
        return np.concatenate([q, v])

    def xdot(x: np.ndarray, speed: float) -> np.ndarray:
        d = mod.rhs(state(x, speed), params)
        return d[[qn.index("q2"), qn.index("q5"), n + vn.index("u2"), n + vn.index("u5")]]

    def linearized(speed: float, h: float = 1e-5) -> np.ndarray:
        A = np.zeros((4, 4))
        for j in range(4):
            e = np.zeros(4)
            e[j] = h
            d1 = (xdot(e, speed) - xdot(-e, speed)) / (2 * h)
            d2 = (xdot(2 * e, speed) - xdot(-2 * e, speed)) / (4 * h)
            A[:, j] = (4 * d1 - d2) / 3
        return A

    for speed in [*range(11), WEAVE, CAPSIZE]:
        ours = np.sort_complex(np.linalg.eigvals(linearized(float(speed))))
        np.testing.assert_allclose(ours, _benchmark_eigenvalues(speed), rtol=0, atol=1e-9)

    # the weave mode turns stable, and the capsize mode unstable, across the published speeds
    def weave_real(speed: float) -> float:
        return max(e.real for e in np.linalg.eigvals(linearized(speed)) if abs(e.imag) > 1)

    def capsize_real(speed: float) -> float:
        return max(e.real for e in np.linalg.eigvals(linearized(speed)) if abs(e.imag) < 1e-9)

    assert weave_real(WEAVE - 1e-3) > 0 > weave_real(WEAVE + 1e-3)
    assert capsize_real(CAPSIZE - 1e-3) < 0 < capsize_real(CAPSIZE + 1e-3)
    assert math.isclose(params["g"], G)
    assert re.match(r"Scene\('bicycle'", repr(scene))
