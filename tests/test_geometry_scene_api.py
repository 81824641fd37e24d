"""The Scene's derived-quantity API: simplification levels are validated, results are
cached once and the cache cannot be overwritten from outside, nothing is derived at
construction, and the scene renders as LaTeX in Jupyter."""

from __future__ import annotations

import pytest
import sympy as sp

import symmech as sm
from symmech.algebra.simplification import LEVELS, tidy
from symmech.geometry.lie import commutation_coefficients, lie_bracket

x, y, th = sm.coordinates("x y theta")
xd, yd, thd = sm.velocities((x, y, th))
m, k, R = sp.symbols("m k R", positive=True)
alpha = sp.Symbol("alpha", nonnegative=True)


def rolling_disk() -> sm.Scene:
    """A disk rolling on the line y = R (x_dot = R theta_dot), hitting the wall x = 0."""
    return sm.Scene(
        (x, y, th),
        metric=sp.diag(m, m, m * k**2),
        potential=m * y,
        constraints=[xd - R * thd],
        walls=[sm.Wall(-x, restitution=alpha, name="wall")],
        name="rolling_disk",
    )


def assert_level_error(exc: pytest.ExceptionInfo, argument: str = "simplify") -> None:
    message = str(exc.value)
    assert argument in message and "'bogus'" in message
    for level in LEVELS:
        assert repr(level) in message
    assert isinstance(exc.value, ValueError)


# --------------------------------------------------------------------- levels


@pytest.mark.parametrize(
    "call",
    [
        lambda s: s.christoffel(simplify="bogus"),
        lambda s: s.christoffel(kind=1, simplify="bogus"),
        lambda s: s.acceleration(simplify="bogus"),
        lambda s: s.multipliers(simplify="bogus"),
        lambda s: s.connection_coefficients(simplify="bogus"),
    ],
)
def test_scene_rejects_unknown_levels(call):
    scene = rolling_disk()
    with pytest.raises(sm.SceneError) as exc:
        call(scene)
    assert_level_error(exc)
    assert len(scene._cache) == 0  # nothing was derived or cached under the bad key


def test_geometry_functions_reject_unknown_levels():
    # polynomial fields take the sparse-polynomial route, which used to ignore the level
    with pytest.raises(sm.SceneError) as exc:
        lie_bracket([y, 0, 0], [0, x, 0], (x, y, th), simplify="bogus")
    assert_level_error(exc)
    with pytest.raises(sm.SceneError) as exc:
        lie_bracket([sp.cos(th), sp.sin(th), 0], [0, 0, 1], (x, y, th), simplify="bogus")
    assert_level_error(exc)
    with pytest.raises(sm.SceneError) as exc:
        commutation_coefficients(sp.eye(3), (x, y, th), simplify="bogus")
    assert_level_error(exc)
    with pytest.raises(sm.SceneError) as exc:
        tidy(x, "bogus")
    assert_level_error(exc, "level")
    with pytest.raises(sm.SceneError):
        rolling_disk().christoffel(kind=True)


def test_every_level_gives_the_same_symbols():
    # the levels differ in form only: the polar Christoffel symbols Gamma^r_thth = -r,
    # Gamma^th_rth = 1/r (slides 000) at every level
    r, phi = sm.coordinates("r phi")
    scene = sm.Scene((r, phi), metric=sp.diag(1, r**2))
    for level in LEVELS:
        G = scene.christoffel(simplify=level)
        assert sp.cancel(G[0, 1, 1] + r) == 0
        assert sp.cancel(G[1, 0, 1] - 1 / r) == 0 and sp.cancel(G[1, 1, 0] - 1 / r) == 0


# ---------------------------------------------------------------------- caching

DERIVED = {
    "christoffel": lambda s: s.christoffel(),
    "christoffel kind 1": lambda s: s.christoffel(kind=1),
    "forcing": lambda s: s.forcing(),
    "acceleration": lambda s: s.acceleration(),
    "projectors": lambda s: s.projectors(),
    "multipliers": lambda s: s.multipliers(),
    "gradients": lambda s: s.gradients(),
    "gram": lambda s: s.gram(),
    "connection_coefficients": lambda s: s.connection_coefficients(),
    "commutation_coefficients": lambda s: s.commutation_coefficients(),
    "kinetic_energy": lambda s: s.kinetic_energy(),
    "constraint_rate": lambda s: s.constraint_rate(),
    "impact_map": lambda s: s.impact_map(0),
}


def test_nothing_is_derived_at_construction():
    scene = rolling_disk()
    assert len(scene._cache) == 0


@pytest.mark.parametrize("name", sorted(DERIVED))
def test_derived_quantities_are_computed_once(name):
    scene = rolling_disk()
    first = DERIVED[name](scene)
    assert DERIVED[name](scene) is first
    assert len(scene._cache) >= 1


def test_cache_is_read_only():
    scene = rolling_disk()
    f = scene.forcing()
    with pytest.raises(TypeError):
        scene._cache[("forcing",)] = sp.Matrix([1, 2, 3])  # type: ignore[index]
    with pytest.raises(AttributeError):
        scene._cache = {}
    assert scene.forcing() is f
    # the forcing is -dV = (0, -m, 0) (no velocity terms for this constant metric)
    assert sp.Matrix(f) == sp.Matrix([0, -m, 0])


# ------------------------------------------------------------------------ LaTeX


def test_repr_latex_summary():
    scene = rolling_disk()
    text = scene._repr_latex_()
    assert text.startswith("$") and text.endswith("$")
    assert sp.latex(scene.mass_matrix()) in text
    assert sp.latex(scene.potential) in text
    assert sp.latex(scene.constraint_matrix) in text
    assert sp.latex(-x) in text and r"rolling\_disk" in text
    assert len(scene._cache) == 0  # rendering derives nothing


def test_repr_latex_of_a_frame_scene_and_a_large_one():
    from symmech.examples import carnot_3_13, pendulum_on_cart

    frame_scene = carnot_3_13()
    text = frame_scene._repr_latex_()
    assert text.startswith("$") and text.endswith("$")
    assert sp.latex(frame_scene.mass_matrix()) in text
    assert sp.latex(frame_scene.frame) in text
    big = pendulum_on_cart(8)  # 9 x 9: summarised by its shape
    assert "9 x 9 matrix" in big._repr_latex_()
