"""The textbook checks of ``symmech verify`` can fail: each spinning-disk check is run on an
impact map that breaks one of the text's formulas (the ones ``symmech verify`` must not
take from symmech itself) and has to report it.

Text 001 §3.2, by hand: beta = (I thetadot - m R ydot) / I_1 with I_1 = I + m R^2; the
energy law gives v+ = (-sqrt(xdot^2 + ydot^2 + (I/m) thetadot^2 - (R^2 + I/m) beta^2),
-R beta, beta); Newton's law (alpha = 1) gives (-xdot, -R beta, beta) and changes the
energy by -m I (ydot + R thetadot)^2 / (2 I_1).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import pytest
import sympy as sp

from symmech import references
from symmech import verify as cli

M, I, R = (sp.Symbol(s, positive=True) for s in ("m", "I", "R"))
XD, YD, THD = (sp.Symbol(s, real=True) for s in ("xdot", "ydot", "thetadot"))
# the text's formulas, from the one module that holds them (symmech.references)
BETA = references.disk_beta(YD, THD, M, I, R)
X1 = sp.sqrt(references.disk_energy_law_rebound_squared(XD, YD, THD, M, I, R))
LOSS = references.disk_newton_loss(YD, THD, M, I, R)


@dataclass
class _Carnot:
    theorem: str = "Theorem 3.11"
    residual: sp.Expr = sp.S.Zero
    terms: dict = field(default_factory=dict)


@dataclass
class _Map:
    post_velocity: sp.Matrix
    change: sp.Expr
    t_c: sp.Expr = sp.S.Zero

    def energy_change(self) -> sp.Expr:
        return self.change

    def carnot(self) -> _Carnot:
        return _Carnot(terms={"T_C": self.t_c})


@dataclass
class _Scene:
    energy: _Map
    newton: _Map
    velocities: tuple = (XD, YD, THD)

    def impact_map(self, wall: str, law: str | None = None) -> _Map:
        return self.newton if law == "newton" else self.energy


RIGHT_ENERGY = _Map(sp.Matrix([-X1, -R * BETA, BETA]), sp.Integer(0))
RIGHT_NEWTON = _Map(sp.Matrix([-XD, -R * BETA, BETA]), -LOSS, LOSS)


def _run(monkeypatch: pytest.MonkeyPatch, check, energy: _Map, newton: _Map) -> bool:
    monkeypatch.setattr(cli, "_scene", lambda name: _Scene(energy, newton))
    ok, _ = check()
    return ok


def test_the_stand_ins_pass():
    """Control: the formulas of the text pass both checks."""
    with pytest.MonkeyPatch.context() as mp:
        assert _run(mp, cli._check_disk_energy_law, RIGHT_ENERGY, RIGHT_NEWTON)
        assert _run(mp, cli._check_disk_newton, RIGHT_ENERGY, RIGHT_NEWTON)


@pytest.mark.parametrize(
    "wrong",
    [
        _Map(sp.Matrix([X1, -R * BETA, BETA]), sp.Integer(0)),  # the positive root
        _Map(sp.Matrix([-XD, -R * BETA, BETA]), sp.Integer(0)),  # xdot reversed only
        _Map(sp.Matrix([-X1, R * BETA, BETA]), sp.Integer(0)),
        _Map(sp.Matrix([-X1, -R * BETA, BETA]), -LOSS),
    ],
    ids=["positive root", "Newton's xdot", "ydot sign", "energy lost"],
)
def test_energy_law_check_sees_a_wrong_map(monkeypatch: pytest.MonkeyPatch, wrong: _Map):
    assert not _run(monkeypatch, cli._check_disk_energy_law, wrong, RIGHT_NEWTON)


@pytest.mark.parametrize(
    "wrong",
    [
        # energy change and T_C wrong the same way: the old check compared them, and passed
        _Map(sp.Matrix([-XD, -R * BETA, BETA]), -2 * LOSS, 2 * LOSS),
        _Map(sp.Matrix([-XD, -R * BETA, BETA]), -LOSS, 2 * LOSS),
        _Map(sp.Matrix([XD, -R * BETA, BETA]), -LOSS, LOSS),
    ],
    ids=["loss doubled", "T_C doubled", "xdot kept"],
)
def test_newton_check_sees_a_wrong_map(monkeypatch: pytest.MonkeyPatch, wrong: _Map):
    assert not _run(monkeypatch, cli._check_disk_newton, RIGHT_ENERGY, wrong)


def test_the_real_checks_pass():
    cli._scene.cache_clear()
    assert cli._check_disk_energy_law()[0]
    assert cli._check_disk_newton()[0]
