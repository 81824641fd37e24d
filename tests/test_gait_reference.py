"""Issue 29's acceptance figures against the mpmath reference (slow: about a minute each).

The variational-saltation route in generated C against central differences of the stride
map at 38 digits (an independent route: no variational equations, no saltation matrix),
and the mpmath route against the rimless wheel's closed form.
"""

from __future__ import annotations

import warnings

import mpmath
import pytest

from symmech.gait.models import GAITS
from symmech.gait.report import solve_routes

pytestmark = pytest.mark.slow


@pytest.mark.parametrize("name", ["simplest_walker", "compass_gait", "hopper"])
def test_c_multipliers_equal_central_differences_at_mpmath_precision(name):
    case = GAITS[name]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        gait = case.build()
    c, ref = solve_routes(
        gait, case.parameters, case.guess, ("c", "mp-cd"), digits=30, section=case.section
    )
    assert ref.error is not None and c.error is not None
    assert c.error <= 1e-10
    assert max(abs(a - b) for a, b in zip(c.x, ref.x, strict=True)) <= 1e-10
    if name == "simplest_walker":
        assert abs(c.x[0] - 0.20031090049483) <= 1e-10
        assert abs(c.x[2] - -0.19983247291764) <= 1e-10


def test_mpmath_route_meets_the_rimless_wheel_closed_form_to_25_digits():
    case = GAITS["rimless_wheel"]
    p = case.parameters
    (mp,) = solve_routes(case.build(), p, case.guess, ("mp",), digits=30)
    with mpmath.workdps(40):
        a, gm, r, l, g = (mpmath.mpf(p[k]) for k in ("alpha", "gamma", "r", "l", "g"))
        eta = (r * r + l * l * mpmath.cos(2 * a)) / (r * r + l * l)
        K = 4 * g * l * mpmath.sin(a) * mpmath.sin(gm) / (r * r + l * l)
        w = -mpmath.sqrt(eta**2 * K / (1 - eta**2))
        assert abs(mpmath.mpc(mp.exact[0]) - eta**2) <= mpmath.mpf(10) ** -25
    assert abs(mp.x[1] - float(w)) <= 1e-15
