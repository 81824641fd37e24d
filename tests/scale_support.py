"""Scenes of the scale and budget tests (and of the derive / codegen / impacts benchmarks).

Large or adversarial inputs, built by hand, each small to declare:

* :func:`cart_with_tip_wall` - the n-link pendulum on a cart (PyDy benchmark) whose tip
  must stay left of the vertical wall ``x_tip = d``;
* :func:`chaplygin_ball_wall` - a Chaplygin ball (centre of mass at the centre, principal
  moments I1, I2, I3) rolling on a plane, in the quasi-velocities (v_x, v_y, omega) with
  Euler angles, hitting the wall x = 0 and rolling on it at impact;
* scene-file texts: :data:`DIAGONAL_200` (200 coordinates, identity metric, one wall
  ``q0 + 1``), :data:`WALLS_100` (100 coordinates, a wall on each), :data:`WALL_POWER_64`
  (the gap ``(x + y + z + 1)**64 - 2``), :data:`POWER_64` (the potential
  ``(sin(x) + cos(y) + x*y*z + 1)**64``), :data:`DENSE_TRIG_3` (a dense trigonometric
  3 x 3 metric, the inertia tensor ``R diag(1, 2, 3) R^T`` of a rotated body plus
  ``u u^T``, u trigonometric, with a curved wall), :data:`DENSE_POLYNOMIAL_6`,
  :data:`NESTED_EXP`.
"""

from __future__ import annotations

import sympy as sp

import symmech as sm
from symmech.examples import pendulum_on_cart


def cart_with_tip_wall(n: int) -> sm.Scene:
    """The n-link pendulum on a cart with the wall ``psi = d - x_tip >= 0``,
    ``x_tip = x + sum_i l_i sin q_i`` (restitution alpha)."""
    base = pendulum_on_cart(n)
    x, *angles = base.coordinates
    lengths = sp.symbols(f"l0:{n}", positive=True)
    d = sp.Symbol("d", positive=True)
    alpha = sp.Symbol("alpha", nonnegative=True)
    tip = x + sum(li * sp.sin(qi) for li, qi in zip(lengths, angles, strict=True))
    return sm.Scene(
        base.coordinates,
        metric=base.mass_matrix(),
        potential=base.potential,
        walls=[sm.Wall(d - tip, restitution=alpha, name="tip")],
        name=f"cart_{n}_tip_wall",
    )


def _rotation(phi: sp.Expr, theta: sp.Expr, psi: sp.Expr) -> sp.Matrix:
    """Z-X-Z Euler rotation R = Rz(phi) Rx(theta) Rz(psi) (body to space)."""

    def rz(a: sp.Expr) -> sp.Matrix:
        return sp.Matrix([[sp.cos(a), -sp.sin(a), 0], [sp.sin(a), sp.cos(a), 0], [0, 0, 1]])

    rx = sp.Matrix(
        [[1, 0, 0], [0, sp.cos(theta), -sp.sin(theta)], [0, sp.sin(theta), sp.cos(theta)]]
    )
    return rz(phi) * rx * rz(psi)


def chaplygin_ball_wall() -> sm.Scene:
    """Chaplygin ball: coordinates (x, y, phi, theta, psi), quasi-velocities
    (v_x, v_y, omega_x, omega_y, omega_z) (centre velocity and space angular velocity),
    metric ``diag(m, m, R diag(I1, I2, I3) R^T)`` (dense and trigonometric), rolling
    constraints ``v_x - r omega_y = 0``, ``v_y + r omega_x = 0``, and the wall x = 0
    (psi = -x, the ball stays at x <= 0) on which it rolls at impact
    (``v_y - r omega_z = 0``, the contact point's tangential velocity on the wall)."""
    x, y, phi, theta, psi = sm.coordinates("x y phi theta psi")
    vx, vy, wx, wy, wz = sp.symbols("v_x v_y omega_x omega_y omega_z", real=True)
    m, r, I1, I2, I3 = sp.symbols("m r I1 I2 I3", positive=True)
    alpha = sp.Symbol("alpha", nonnegative=True)
    Rm = _rotation(phi, theta, psi)
    inertia = Rm * sp.diag(I1, I2, I3) * Rm.T
    metric = sp.diag(m, m, sp.zeros(3, 3))
    metric[2:, 2:] = inertia
    # space angular velocity = B (phi_dot, theta_dot, psi_dot) for Z-X-Z angles
    B = sp.Matrix(
        [
            [0, sp.cos(phi), sp.sin(theta) * sp.sin(phi)],
            [0, sp.sin(phi), -sp.sin(theta) * sp.cos(phi)],
            [1, 0, sp.cos(theta)],
        ]
    )
    S = sp.diag(sp.eye(2), sp.simplify(B.inv()))
    wall = sm.Wall(-x, restitution=alpha, impulsive_constraints=[vy - r * wz], name="rolling")
    return sm.Scene(
        (x, y, phi, theta, psi),
        metric=metric,
        constraints=[vx - r * wy, vy + r * wx],
        frame=S,
        quasi_velocities=(vx, vy, wx, wy, wz),
        walls=[wall],
        name="chaplygin_ball_wall",
    )


def _diagonal_text(n: int) -> str:
    names = ", ".join(f'"q{i}"' for i in range(n))
    ones = ", ".join('"1"' for _ in range(n))
    return f'coordinates = [{names}]\nmetric = [{ones}]\n[[walls]]\npsi = "q0 + 1"\n'


#: 200 coordinates, identity metric, one wall q0 + 1 >= 0 (a 2.5 KB scene file).
DIAGONAL_200 = _diagonal_text(200)


def _walls_text(n: int) -> str:
    names = ", ".join(f'"q{i}"' for i in range(n))
    ones = ", ".join('"1"' for _ in range(n))
    walls = "".join(f'[[walls]]\npsi = "q{i} + 1"\n' for i in range(n))
    return f"coordinates = [{names}]\nmetric = [{ones}]\n{walls}"


#: 100 coordinates, identity metric, a wall q_i + 1 >= 0 on every coordinate (3.8 KB).
WALLS_100 = _walls_text(100)

#: A wall whose gap is a 64th power (its closed-form impact map is refused at once).
WALL_POWER_64 = (
    'coordinates = ["x", "y", "z"]\n'
    'metric = ["1", "1", "1"]\n'
    "[[walls]]\n"
    'psi = "(x + y + z + 1)**64 - 2"\n'
)


def _dense_polynomial_text(n: int) -> str:
    rows = ",\n  ".join(
        "[" + ", ".join(f'"x{i}*x{j}{" + 1" if i == j else ""}"' for j in range(n)) + "]"
        for i in range(n)
    )
    names = ", ".join(f'"x{i}"' for i in range(n))
    return f'coordinates = [{names}]\nmetric = [\n  {rows}\n]\n[[walls]]\npsi = "x0 + x1*x2 + 3"\n'


#: A dense polynomial 6 x 6 metric ``I + x x^T`` with a curved wall.
DENSE_POLYNOMIAL_6 = _dense_polynomial_text(6)

#: Nested exponentials in the potential, with a wall.
NESTED_EXP = (
    'coordinates = ["x", "y"]\n'
    'metric = ["1", "1"]\n'
    'potential = "exp(exp(exp(x*y)))*sin(x)**9"\n'
    "[[walls]]\n"
    'psi = "x + 2"\n'
)

#: A 3-coordinate scene whose potential is a 64th power of a trigonometric polynomial.
POWER_64 = (
    'coordinates = ["x", "y", "z"]\n'
    'metric = ["1", "1", "1"]\n'
    'potential = "(sin(x) + cos(y) + x*y*z + 1)**64"\n'
)


def _dense_trig_text() -> str:
    a, b, c = sp.symbols("a b c", real=True)
    Rm = _rotation(a, b, c)
    u = sp.Matrix([sp.cos(b), sp.sin(c), sp.cos(a) * sp.sin(b)])
    g = Rm * sp.diag(1, 2, 3) * Rm.T + u * u.T
    rows = ",\n  ".join(
        "[" + ", ".join(f'"{sp.sstr(sp.expand(g[i, j]))}"' for j in range(3)) + "]"
        for i in range(3)
    )
    return (
        'coordinates = ["a", "b", "c"]\n'
        f"metric = [\n  {rows}\n]\n"
        'potential = "cos(a) + sin(b)*cos(c)"\n'
        "[[walls]]\n"
        'psi = "a + sin(b) + 2"\n'
    )


#: A dense trigonometric 3 x 3 metric (the rotated inertia tensor) with a curved wall.
DENSE_TRIG_3 = _dense_trig_text()
