"""Reference values typed in from the texts, by hand: what ``symmech verify`` and the tests
compare symmech's derivations with.

None of these is produced by symmech: each function writes a formula as printed in (or
re-derived by hand from) one text, named after the example and the quantity, in the symbols
the example uses.  Where a text has a typo the docstring says what was corrected.
"""

from __future__ import annotations

import sympy as sp

__all__ = [
    "bracket_example",
    "carnot_3_7_post_velocity",
    "carnot_3_12_t_c",
    "carnot_3_13_post_velocity",
    "carnot_3_13_t_c",
    "carnot_4_4_matrix",
    "carnot_4_4_wall_velocity",
    "disk_beta",
    "disk_energy_law_rebound_squared",
    "disk_newton_loss",
    "disk_newton_post_velocity",
    "ellipse_post_velocity",
    "polar_christoffel",
]


def polar_christoffel(r: sp.Expr) -> tuple[sp.Expr, sp.Expr]:
    """Slides 000, polar coordinates ``g = diag(1, r^2)``: ``(Gamma^r_thth, Gamma^th_rth)
    = (-r, 1/r)``."""
    return -r, 1 / r


def bracket_example(x: sp.Expr, y: sp.Expr) -> sp.Matrix:
    """Slides 000: ``X = (y, 0, 0)``, ``Y = (0, x, 0)`` give ``[X, Y] = (-x, y, 0)``."""
    return sp.Matrix([-x, y, 0])


def ellipse_post_velocity(
    x: sp.Expr,
    th: sp.Expr,
    xd: sp.Expr,
    yd: sp.Expr,
    thd: sp.Expr,
    m: sp.Expr,
    I: sp.Expr,
    a: sp.Expr,
    b: sp.Expr,
) -> sp.Matrix:
    """Text 001 §3.1, the ellipse (semi-axes a, b) against the wall at x = 0 with the
    support-function gap ``h = x + sqrt(a^2 cos^2 th + b^2 sin^2 th)``, ``Phi = dh/dth``:
    ``v+ = v- - 2 C (1/m, 0, Phi/I)`` with ``C = (xdot + Phi thdot) / (1/m + Phi^2/I)``."""
    h = x + sp.sqrt(a**2 * sp.cos(th) ** 2 + b**2 * sp.sin(th) ** 2)
    Phi = sp.diff(h, th)
    C = (xd + Phi * thd) / (1 / m + Phi**2 / I)
    return sp.Matrix([xd - 2 * C / m, yd, thd - 2 * C / I * Phi])


def disk_beta(
    yd: sp.Expr,
    thd: sp.Expr,
    m: sp.Expr,
    I: sp.Expr,
    R: sp.Expr,
) -> sp.Expr:
    """Text 001 §3.2, the spinning disk: the rolling component after impact,
    ``beta = (I thetadot - m R ydot) / (I + m R^2)`` (the text calls it alpha)."""
    return (I * thd - m * R * yd) / (I + m * R**2)


def disk_energy_law_rebound_squared(
    xd: sp.Expr,
    yd: sp.Expr,
    thd: sp.Expr,
    m: sp.Expr,
    I: sp.Expr,
    R: sp.Expr,
) -> sp.Expr:
    """Text 001 §3.2: ``xdot_1^2 = xdot_0^2 + ydot_0^2 + (I/m) thetadot_0^2 - beta^2 R^2 -
    (I/m) beta^2`` (energy conservation); the rebound is its negative root."""
    beta = disk_beta(yd, thd, m, I, R)
    return xd**2 + yd**2 + I / m * thd**2 - beta**2 * R**2 - I / m * beta**2


def disk_newton_post_velocity(
    xd: sp.Expr,
    yd: sp.Expr,
    thd: sp.Expr,
    m: sp.Expr,
    I: sp.Expr,
    R: sp.Expr,
) -> sp.Matrix:
    """The spinning disk under Newton's law with alpha = 1 (Carnot paper, Prop. 3.4):
    ``v+ = (-xdot, -R beta, beta)``."""
    beta = disk_beta(yd, thd, m, I, R)
    return sp.Matrix([-xd, -R * beta, beta])


def disk_newton_loss(
    yd: sp.Expr,
    thd: sp.Expr,
    m: sp.Expr,
    I: sp.Expr,
    R: sp.Expr,
) -> sp.Expr:
    """By hand: ``(m ydot^2 + I thetadot^2)/2 - I_1 beta^2/2 = m I (ydot + R thetadot)^2 /
    (2 I_1)``, ``I_1 = I + m R^2``: the kinetic energy Newton's law removes, T_C of Theorem
    3.11 (its alpha-term vanishes at alpha = 1)."""
    return m * I * (yd + R * thd) ** 2 / (2 * (I + m * R**2))


def carnot_3_7_post_velocity(
    xd: sp.Expr, yd: sp.Expr, thd: sp.Expr, k: sp.Expr, R: sp.Expr, alpha: sp.Expr
) -> sp.Matrix:
    """Carnot paper, example 3.7 (a disc rolling on a line hits the wall y = R)."""
    return sp.Matrix(
        [
            (R**2 * xd + R * k**2 * thd) / (R**2 + k**2),
            -alpha * yd,
            (R * xd + k**2 * thd) / (R**2 + k**2),
        ]
    )


def carnot_3_12_t_c(xd: sp.Expr, thd: sp.Expr, m: sp.Expr, k: sp.Expr, R: sp.Expr) -> sp.Expr:
    """Carnot paper, example 3.12: ``T_C = m k^2 (xdot - R thetadot)^2 / (2 (k^2 + R^2))``."""
    return m * k**2 / (2 * (k**2 + R**2)) * (xd - R * thd) ** 2


def carnot_3_13_post_velocity(
    x0: sp.Expr, y0: sp.Expr, w0: sp.Expr, k: sp.Expr, r: sp.Expr, alpha: sp.Expr
) -> sp.Matrix:
    """Carnot paper, example 3.13 (a rolling sphere hits a rough wall), for
    ``v- = (x0, y0, 0, -y0/r, x0/r, wz0)``: ``v+ = (-alpha x0, y1, 0, -y1/r, -alpha x0/r,
    y1/r)`` with ``y1 = ((k^2 + r^2) y0 + r k^2 wz0) / (2 k^2 + r^2)``."""
    y1 = ((k**2 + r**2) * y0 + r * k**2 * w0) / (2 * k**2 + r**2)
    return sp.Matrix([-alpha * x0, y1, 0, -y1 / r, -alpha * x0 / r, y1 / r])


def carnot_3_13_t_c(y0: sp.Expr, w0: sp.Expr, k: sp.Expr, r: sp.Expr) -> sp.Expr:
    """Carnot paper, example 3.13: ``T_C = k^2 (k^2 + r^2) (y0 - r wz0)^2 / (2 r^2 (2 k^2 +
    r^2))`` (per unit mass)."""
    return k**2 * (k**2 + r**2) / (2 * r**2 * (2 * k**2 + r**2)) * (y0 - r * w0) ** 2


def carnot_4_4_matrix(k: sp.Expr, r: sp.Expr, a: sp.Expr) -> sp.Matrix:
    """Carnot paper, example 4.4 (a sphere hits a moving wall): the 6 x 6 matrix M of
    ``v+ = M v- + ...``, acting on columns, ``D1 = k^2 + r^2``, ``D2 = 2 k^2 + r^2``."""
    D1, D2 = k**2 + r**2, 2 * k**2 + r**2
    return sp.Matrix(
        [
            [1 - (r**2 + a * r**2) / D1, 0, 0, 0, -(k**2) * r * (1 + a) / D1, 0],
            [0, 1 - k**2 * r**2 / (D1 * D2), 0, k**4 * r / (D1 * D2), 0, k**2 * r / D2],
            [0, 0, 1, 0, 0, 0],
            [0, k**2 * r / (D1 * D2), 0, 1 - k**4 / (D1 * D2), 0, -(k**2) / D2],
            [-r * (a + 1) / D1, 0, 0, 0, 1 - k**2 * (a + 1) / D1, 0],
            [0, r / D2, 0, -(k**2) / D2, 0, 1 - D1 / D2],
        ]
    )


def carnot_4_4_wall_velocity(f_dot: sp.Expr, r: sp.Expr) -> sp.Matrix:
    """Carnot paper, example 4.4: the wall x = f(t) moves with ``W = (f', 0, 0, 0, f'/r,
    0)``."""
    return sp.Matrix([f_dot, 0, 0, 0, f_dot / r, 0])
