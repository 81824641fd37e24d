"""Built-in scenes from the texts: a model zoo shared by the CLI, tests, docs and benchmarks.

The scene files ``symmech/scenes/*.toml`` are the single source of the named scenes: each
function here loads its file (a fresh :class:`~symmech.Scene` per call; the file also holds
the parameters' default values, see :func:`symmech.read_scene`).  Only the parametrised
families (:func:`pendulum_on_cart`, :func:`newtons_cradle`) and two stress scenes are built
in Python.  :data:`EXAMPLES` maps the names the command line uses to these functions and a
one-line description.
"""

from __future__ import annotations

import itertools
import numbers
from collections.abc import Callable

import sympy as sp

from symmech.declaration.drawing import Disc, Drawing, Point, Segment
from symmech.declaration.symbols import coordinates, t, velocities
from symmech.declaration.wall import Wall
from symmech.errors import SceneError
from symmech.scene import Scene
from symmech.scenefile import builtin_scene_path, load_scene

__all__ = [
    "EXAMPLES",
    "ball_in_corner",
    "body_pendulum_rotor",
    "bouncing_ball",
    "bouncing_ellipse",
    "car",
    "carnot_3_7",
    "carnot_3_13",
    "carnot_4_4",
    "disk_3_7_gravity",
    "ellipse_gravity",
    "example",
    "falling_rod",
    "ladder",
    "newtons_cradle",
    "pendulum_on_cart",
    "pendulum_wall",
    "rolling_ball",
    "spinning_disk",
    "stiff_dumbbell",
    "trig_wall",
]


def _builtin(name: str) -> Scene:
    """The shipped scene file ``symmech/scenes/<name>.toml`` (whatever the current folder
    holds)."""
    return load_scene(builtin_scene_path(name))


def _with_wall(scene: Scene, **changes: object) -> Scene:
    """``scene`` with its (single) wall rebuilt with ``changes`` (restitution, law); a new
    restitution symbol joins the parameters (ordered by name, as the files order them)."""
    (w,) = scene.walls
    return scene.replace(walls=[w.as_wall(**changes)], parameters=None)


def bouncing_ellipse(restitution: object = 1) -> Scene:
    """Text 001, section 3.1: a planar ellipse (mass m, inertia I, semi-axes a, b) hits the
    wall x = 0 from the side x < 0.  ``psi = -x - sqrt(a^2 cos^2 theta + b^2 sin^2 theta)``
    (support function; exact for every orientation)."""
    scene = _builtin("bouncing_ellipse")
    return scene if restitution == 1 else _with_wall(scene, restitution=restitution)


def spinning_disk(law: str = "energy") -> Scene:
    """Text 001, section 3.2: a spinning disk (mass m, inertia I, radius R) hits the rough
    wall x = 0 from the side x < 0, as in the text; at impact it rolls on the wall.  The
    contact point (x + R, y) moves with ``(x_dot, y_dot + R theta_dot)`` (theta
    counter-clockwise), so rolling is the text's ``y_dot + R theta_dot = 0``, and the
    rebound x_dot+ is the text's negative root."""
    scene = _builtin("spinning_disk")
    return scene if law == "energy" else _with_wall(scene, law=law)


def carnot_3_7() -> Scene:
    """Carnot paper, example 3.7: a disc (radius R, mass m, inertia m k^2) moving in a
    vertical plane hits the rough wall y = R; at impact ``x_dot - R theta_dot = 0``."""
    return _builtin("carnot_3_7")


def carnot_3_13() -> Scene:
    """Carnot paper, example 3.13: a sphere (radius r, mass 1, inertia k^2) rolling on a
    horizontal plane hits the rough wall x = 0; written in the angular velocities
    (quasi-velocities) with Euler angles (phi, theta, psi) as coordinates."""
    return _builtin("carnot_3_13")


def carnot_4_4() -> Scene:
    """Carnot paper, example 4.4: the rolling sphere of example 3.13 hits the moving wall
    x = f(t)."""
    return _builtin("carnot_4_4")


def rolling_ball() -> Scene:
    """Slides 000, "Example: rolling ball": the orientation of a ball (radius r, mass 1,
    inertia k^2 about every axis) rolling on a horizontal plane without spinning about the
    vertical.  Its admissible angular velocities are the slides' distribution
    ``A_R = span{[e1 x] R, [e2 x] R}``: omega_z = 0.  Coordinates are the Euler angles
    (phi, theta, psi) and the quasi-velocities the angular velocities (omega_x, omega_y,
    omega_z) of Carnot paper ex. 3.13.  Rolling fixes the centre's velocity to
    ``r (omega_y, -omega_x, 0)``, so the kinetic energy reduced to SO(3) is
    ``T = 1/2 (k^2 + r^2) (omega_x^2 + omega_y^2) + 1/2 k^2 omega_z^2``."""
    return _builtin("rolling_ball")


def car() -> Scene:
    """Slides 000, "Driving a car": (x, y, theta, kappa) with the admissible directions
    span{(cos theta, sin theta, kappa, 0), (0, 0, 0, 1)}, written as two constraints
    (no side slip; heading rate = curvature times speed)."""
    return _builtin("car")


def bouncing_ball() -> Scene:
    """A ball (mass m) falling under gravity g onto the floor y = 0 with restitution alpha:
    ``T = m y_dot^2 / 2``, ``V = m g y``, ``psi = y``.  Dropped from rest at height h it
    comes to rest at ``t* = sqrt(2h/g) (1 + alpha)/(1 - alpha)`` (alpha < 1)."""
    return _builtin("bouncing_ball")


def ellipse_gravity() -> Scene:
    """Text 001, section 3.1, under gravity: the ellipse (mass m, inertia I, semi-axes a, b)
    falls onto the floor y = 0 with restitution alpha;
    ``psi = y - sqrt(a^2 sin^2 theta + b^2 cos^2 theta)`` (support function)."""
    return _builtin("ellipse_gravity")


def disk_3_7_gravity() -> Scene:
    """Carnot paper, example 3.7, under gravity: the disc (radius R, mass m, inertia m k^2)
    falls onto the rough floor y = R, rolls at each impact (``x_dot - R theta_dot = 0``)
    and restitutes the normal velocity with alpha."""
    return _builtin("disk_3_7_gravity")


def pendulum_wall() -> Scene:
    """A pendulum (point mass m on a massless rod of length l, angle theta from the downward
    vertical, gravity g) swinging into the vertical wall x = d (d < l):
    ``psi = d - l sin theta``, restitution alpha."""
    return _builtin("pendulum_wall")


def stiff_dumbbell() -> Scene:
    """A stiff scene: two masses m at heights y1 <= y2 joined by a spring of stiffness k and
    rest length L (k up to 1e8), falling under gravity g; the lower one bounces on the floor
    y1 = 0 with restitution alpha.  ``V = m g (y1 + y2) + k (y2 - y1 - L)^2 / 2``."""
    return _builtin("stiff_dumbbell")


def falling_rod() -> Scene:
    """A uniform rod falling on the floor, each end a wall (several contacts at once)."""
    return _builtin("falling_rod")


def ladder() -> Scene:
    """A ladder sliding on a frictionless floor and wall; it leaves the wall at
    sin(theta) = (2/3) sin(theta0)."""
    return _builtin("ladder")


def ball_in_corner() -> Scene:
    """A ball dropped into a V corner of two frictionless planes."""
    return _builtin("ball_in_corner")


def pendulum_on_cart(n: int) -> Scene:
    """The n-link planar pendulum on a cart (the PyDy benchmark), declared by its kinetic and
    potential energy: cart mass m0 at x, links of length l_i with point masses m_{i+1},
    angles q_i from the downward vertical, gravity g."""
    if isinstance(n, bool) or not isinstance(n, numbers.Integral) or n < 1:
        raise SceneError(
            f"pendulum_on_cart: n (the number of links) must be an integer >= 1, got {n!r}"
        )
    n = int(n)
    q = coordinates(["x"] + [f"q{i}" for i in range(n)])
    qd = velocities(q)
    m = sp.symbols(f"m0:{n + 1}", positive=True)
    l = sp.symbols(f"l0:{n}", positive=True)
    g = sp.Symbol("g", positive=True)
    half = sp.Rational(1, 2)
    # the terms of each sum collected, the sum built once (not grown term by term)
    kinetic, potential = [sp.Mul(half, m[0], qd[0] ** 2)], []
    vx, vy, height = [qd[0]], [], []  # velocity and height of the current link's mass
    for i in range(n):
        c, s = sp.cos(q[i + 1]), sp.sin(q[i + 1])
        vx.append(sp.Mul(l[i], c, qd[i + 1]))
        vy.append(sp.Mul(l[i], s, qd[i + 1]))
        height.append(sp.Mul(-1, l[i], c))
        kinetic.append(sp.Mul(half, m[i + 1], sp.Add(sp.Add(*vx) ** 2, sp.Add(*vy) ** 2)))
        potential.append(sp.Mul(m[i + 1], g, sp.Add(*height)))
    T, V = sp.Add(*kinetic), sp.Add(*potential)
    joints = [(q[0], sp.S.Zero)]  # the cart, then each link's mass
    for i in range(n):
        x0, y0 = joints[-1]
        joints.append((x0 + l[i] * sp.sin(q[i + 1]), y0 - l[i] * sp.cos(q[i + 1])))
    drawing = Drawing(
        [Disc(joints[0], sp.Rational(1, 5))]
        + [Segment(a, b) for a, b in itertools.pairwise(joints)]
        + [Point(p) for p in joints[1:]]
    )
    return Scene(q, kinetic_energy=T, potential=V, name=f"pendulum_on_cart_{n}", drawing=drawing)


# ------------------------------------------------------------------ stress scenes
#
# Not from the texts and not listed in EXAMPLES: two systems whose impact maps once took
# minutes to derive (the audit of the impact-map issue); tests hold their derivation and
# Carnot check to time guards and benchmarks/impacts.py times them.


def trig_wall() -> Scene:
    """A free point (x, y) with a rotor theta (identity metric) hitting the wall
    ``y = sin(x) cos(theta)/4 + cos(x + theta)/6 + sin(2x) cos(2 theta)/5 + cos(2x + theta)/7``
    with the rotor stopped at impact (impulsive constraint theta_dot = 0), elastic."""
    x, y, th = coordinates("x y theta")
    _xd, _yd, thd = velocities((x, y, th))
    psi = (
        y
        - sp.sin(x) * sp.cos(th) / 4
        - sp.cos(x + th) / 6
        - sp.sin(2 * x) * sp.cos(2 * th) / 5
        - sp.cos(2 * x + th) / 7
    )
    return Scene(
        (x, y, th),
        metric=sp.eye(3),
        walls=[Wall(psi, impulsive_constraints=[thd])],
        name="trig_wall",
    )


def body_pendulum_rotor() -> Scene:
    """A body (mass M) at (x, y) carrying a pendulum (mass m, length l, inertia I, angle
    theta) and a rotor (inertia J, angle phi), with a knife edge (no velocity across
    theta); it hits the curved moving wall ``y = c cos(x) + f(t)`` with a symbolic
    restitution alpha and rolls on it at impact (``x_dot cos + y_dot sin = R phi_dot``)."""
    M, m, l, I, J, c, R = sp.symbols("M m l I J c R", positive=True)
    alpha = sp.Symbol("alpha", nonnegative=True)
    f = sp.Function("f")
    x, y, th, ph = coordinates("x y theta phi")
    xd, yd, _thd, phd = velocities((x, y, th, ph))
    g = sp.Matrix(
        [
            [M + m, 0, -m * l * sp.sin(th), 0],
            [0, M + m, m * l * sp.cos(th), 0],
            [-m * l * sp.sin(th), m * l * sp.cos(th), m * l**2 + I + J, J],
            [0, 0, J, J],
        ]
    )
    wall = Wall(
        y - c * sp.cos(x) - f(t),
        restitution=alpha,
        impulsive_constraints=[xd * sp.cos(th) + yd * sp.sin(th) - R * phd],
    )
    return Scene(
        (x, y, th, ph),
        metric=g,
        constraints=[-sp.sin(th) * xd + sp.cos(th) * yd],
        walls=[wall],
        name="body_pendulum_rotor",
    )


def newtons_cradle(balls: int = 3) -> Scene:
    """Newton's cradle as a chain of ``balls`` equal balls (mass m, radius r) on a line,
    ``x_i`` their centres; the walls ``x_{i+1} - x_i - 2 r >= 0`` are elastic (alpha = 1)
    by default.  Equal masses exchange their velocities at each contact."""
    if isinstance(balls, bool) or not isinstance(balls, numbers.Integral) or balls < 2:
        raise SceneError(f"newtons_cradle: balls must be an integer >= 2, got {balls!r}")
    balls = int(balls)
    xs = coordinates([f"x{i}" for i in range(balls)])
    m, r = sp.symbols("m r", positive=True)
    walls = [
        Wall(xs[i + 1] - xs[i] - 2 * r, restitution=1, name=f"contact{i}") for i in range(balls - 1)
    ]
    drawing = Drawing([Disc((x, 0), r) for x in xs])
    return Scene(
        xs,
        metric=sp.eye(balls) * m,
        walls=walls,
        name=f"newtons_cradle_{balls}",
        drawing=drawing,
    )


EXAMPLES: dict[str, tuple[Callable[[], Scene], str]] = {
    "bouncing_ellipse": (bouncing_ellipse, "text 001 §3.1: ellipse bouncing on a wall (elastic)"),
    "spinning_disk": (spinning_disk, "text 001 §3.2: spinning disk, frictional impact"),
    "carnot_3_7": (carnot_3_7, "Carnot paper ex. 3.7: disc hits a rough wall"),
    "carnot_3_13": (carnot_3_13, "Carnot paper ex. 3.13: rolling sphere hits a rough wall"),
    "carnot_4_4": (carnot_4_4, "Carnot paper ex. 4.4: rolling sphere hits a moving wall"),
    "rolling_ball": (rolling_ball, "slides 000: ball rolling without spinning (SO(3))"),
    "car": (car, "slides 000: car with curvature state (non-holonomic)"),
    "pendulum_on_cart_3": (lambda: pendulum_on_cart(3), "3-link pendulum on a cart"),
    "bouncing_ball": (bouncing_ball, "bouncing ball under gravity, restitution alpha"),
    "ellipse_gravity": (ellipse_gravity, "text 001 §3.1 ellipse falling on the floor"),
    "disk_3_7_gravity": (disk_3_7_gravity, "Carnot ex. 3.7 disc falling on a rough floor"),
    "newtons_cradle_3": (lambda: newtons_cradle(3), "Newton's cradle of 3 balls on a line"),
    "pendulum_wall": (pendulum_wall, "pendulum swinging into a vertical wall"),
    "stiff_dumbbell": (stiff_dumbbell, "stiff spring dumbbell bouncing on the floor"),
    "falling_rod": (falling_rod, "uniform rod falling on the floor, both ends walls"),
    "ladder": (ladder, "ladder sliding on a frictionless floor and wall"),
    "ball_in_corner": (ball_in_corner, "ball dropped into a V corner"),
}


def example(name: str) -> Scene:
    """The built-in scene called ``name`` (see :data:`EXAMPLES`)."""
    try:
        build = EXAMPLES[name][0]
    except (KeyError, TypeError):  # TypeError: an unhashable name
        raise SceneError(
            f"no built-in scene named {name!r}; choose one of {sorted(EXAMPLES)}"
        ) from None
    return build()
