r"""Scene files: a mechanical system written in TOML, loaded without executing anything.

A scene file holds exactly what :class:`symmech.Scene` takes (coordinates, a metric or a
kinetic energy, a potential, constraints, a frame of quasi-velocities, walls), plus default
values for the parameters and functions of time.  :func:`load_scene` (a path) and
:func:`loads_scene` (text) return the :class:`~symmech.Scene`; :func:`read_scene` and
:func:`reads_scene` return a :class:`SceneFile` that also carries the defaults, the
functions and the description; :func:`save_scene` and :func:`dump_scene` write a Scene
back.

Format (version 1)
------------------
::

    format = 1                                   # optional; 1 is the only version
    name = "carnot_3_7"                          # optional; default: the file's stem
    description = "Carnot paper, example 3.7"    # optional
    coordinates = ["x", "y", "theta"]            # required; their velocities are xdot, ...
    metric = ["m", "m", "m*k**2"]                # n entries: the diagonal; or n rows of n
    # kinetic_energy = "m*(xdot**2 + ydot**2)/2 + m*k**2*thetadot**2/2"   (instead of metric)
    potential = "m*g*y"                          # optional, default 0; may use t
    forces = ["-c*xdot + u", "0", "0"]           # optional: applied generalized forces, one
                                                 # per velocity (in the quasi-velocities'
                                                 # basis with a [frame]); may use t and the
                                                 # velocities; u = {} in [functions] is a
                                                 # run-time input u(t)
    constraints = ["xdot - R*thetadot"]          # optional; linear in the velocities,
                                                 # or coefficient rows [[1, 0, "-R"]]

    [parameters]                 # every parameter, in order, with its default value
    m = 1                        # a number, or a string of numbers: "sqrt(2)/4", "2*pi"
    R = { value = 0.5 }          # the same, as a table
    alpha = { value = 0.8, sign = "nonnegative" }
    g = { sign = "real" }        # no default value

    [functions]                  # functions, used by their name alone
    f = "A*sin(omega*t)"         # defined: "x - f" in an expression means x - A sin(omega t)
    h = {}                       # arbitrary: "x - h" means x - h(t), kept symbolic
    V = { arguments = ["x", "y"] }   # arbitrary, of coordinates (and t): "V" means V(x, y)

    [inputs]                     # run-time inputs: arbitrary real functions of t, given
    tau = { description = "motor torque" }   # to generated code by name (inputs={"tau": ..})

    [frame]                      # quasi-velocities v with q_dot = S(q) v (optional)
    quasi_velocities = ["v_x", "v_y", "omega"]
    matrix = [[...], [...], [...]]     # S; or `inverse = [...]`, S^-1 (v = S^-1 q_dot),
                                       # inverted symbolically by the loader

    [[walls]]                    # one table per wall (optional)
    name = "rough_wall"          # optional identifier, default wall0, wall1, ...
    psi = "y - R"                # gap psi(t, q) >= 0 on the admissible side
    restitution = "alpha"        # a number in [0, 1], a string of numbers, or a parameter
    impulsive_constraints = ["xdot - R*thetadot"]   # optional, kept after the impact
    law = "newton"               # or "energy" (text 001, section 3.2)
    velocity = ["0", "A*omega*cos(omega*t)", "0"]   # optional: the wall's velocity field
                                 # W(t, q), one component per velocity (default: the
                                 # metric normal; see symmech.declaration.wallvelocity)

Rules:

* Every expression is a string (or a number) parsed by
  :func:`symmech.declaration.expressions.parse_expression`, a whitelist over Python's
  ``ast``; nothing is passed to ``eval``, ``sympify`` or ``parse_expr``.  The names an
  expression may use are the coordinates, their velocities (``<name>dot``), the
  quasi-velocities, ``t``, the parameters, the functions, ``pi`` and ``E``.  A ``#`` in an
  expression is refused (Python would drop the rest as a comment), and so is a name
  written with look-alike Unicode characters (``𝐱`` for ``x``); a line break is
  whitespace, so an expression may span the lines of a multi-line string.  Where a name
  may appear (only the potential, forces and walls may use ``t``, ...) is checked by
  :class:`~symmech.Scene`.  With a ``[frame]``, velocities are written in the
  quasi-velocities only (the kinetic energy and the constraints are in that basis).
* Parameters are positive unless ``sign`` says otherwise: ``"positive"``,
  ``"nonnegative"``, ``"negative"``, ``"nonpositive"``, ``"nonzero"``, ``"real"`` or
  ``"any"`` (a sympy symbol with no assumptions).  A default value must be a real number
  of that sign.  Every declared parameter must be used, and every name used must be
  declared.  The scene's parameters are in the order of the file.  A parameter used as a
  restitution must be ``"nonnegative"`` or ``"positive"``, with a default value in [0, 1].
* Functions are written by name alone (``"x - f"``; the parser refuses ``f(t)``: only its
  whitelisted functions may be called).  A defined function is an expression in t and the
  parameters, substituted where its name appears.  An arbitrary (undefined) function
  stays symbolic in the derived quantities: ``{}`` is ``f(t)``; ``{ arguments = ["x",
  "y"] }`` declares ``V(x, y)``, its arguments distinct names among t and the coordinates
  (a generic potential; its derivatives appear in the forcing); ``real = false`` makes a
  complex-valued sympy function.  Where such a function may appear is checked by
  :class:`~symmech.Scene` as for any expression.  A function of anything else (of an
  expression ``V(x + y)``, of a velocity, of a parameter) cannot be written in a file:
  :func:`dump_scene` refuses it, saying why.
* Names (coordinates, parameters, quasi-velocities, functions) are Python identifiers,
  distinct, not ``t``, not starting with ``__``, and not the names of the parser's
  functions or constants; the scene and wall names are identifiers too (they become names
  in generated code and files).
* Unknown keys are refused (with a suggestion), so a misspelt key is not silently ignored.

Limits, by what reading costs: :data:`MAX_FILE_BYTES` bytes of file, :data:`MAX_NAMES`
coordinates or parameters, :data:`MAX_WALLS` walls, :data:`MAX_FILE_NODES` operands and
operations and :data:`MAX_FILE_CALLS` distinct function applications in all the
expressions together (an entry may be as long as the file allows: an imported model's
forcing is; each is charged the nodes it parses or builds, whichever is more, and a text
with more names, numbers and operators than are left is refused before it is parsed),
integers of at most :data:`~symmech.declaration.expressions.MAX_DIGITS`
digits; each expression has the parser's limits on depth and exponent size.

Errors raise :class:`SceneFileError` (a :class:`~symmech.SceneError`) listing every problem,
each naming the file, the field (``walls[0].psi``), the line and the offending token.  When
a declaration is refused (a coordinate, parameter, function or quasi-velocity name), the
expressions are not read: every use of that name would be reported again.
TOML parsers do not report where a key is, so the line is found by one linear-time scan
of the file text (:class:`_Scanner`, no regular expression): the table header
(``[parameters]``, the k-th ``[[walls]]``) is found first, then the first statement
``key =`` below it before the next header (a dotted key ``parameters.m =`` too); the
element of an array is found as its string on or after that line.  An expression in a
multi-line string (triple quotes) is located on the line where its text starts, and its errors
on the line within it.  A key written in an unusual way (inside an inline table, a string
with line-ending backslashes) may get the line of its table or no line at all: the field
name is always given.  Keys and tokens echoed in messages are cut to 60 characters.

>>> sf = reads_scene('''
... coordinates = ["x"]
... metric = ["m"]
... potential = "k*x**2/2"
... [parameters]
... m = 2
... k = { value = "1/2" }
... ''', name="oscillator")
>>> sf.scene
Scene('oscillator': q=[x])
>>> sf.defaults
{m: 2, k: 1/2}

Nothing in a file is run; what is not a plain expression is refused, with its place:

>>> reads_scene('coordinates = ["x"]\nmetric = ["().__class__"]', source="evil.toml")
Traceback (most recent call last):
...
symmech.scenefile.SceneFileError: evil.toml: metric[0,0] (line 2, col 1): attribute access '().__class__' is not allowed
"""  # noqa: E501

from symmech.scenefile.builtin import builtin_scene_names, builtin_scene_path
from symmech.scenefile.format import (
    FORMAT_VERSION,
    MAX_FILE_BYTES,
    MAX_FILE_CALLS,
    MAX_FILE_NODES,
    MAX_NAMES,
    MAX_WALLS,
    SIGNS,
    SceneFileError,
)
from symmech.scenefile.loaded import SceneFile
from symmech.scenefile.reader import load_scene, loads_scene, read_scene, reads_scene
from symmech.scenefile.writer import dump_scene, save_scene

__all__ = [
    "FORMAT_VERSION",
    "MAX_FILE_BYTES",
    "MAX_FILE_CALLS",
    "MAX_FILE_NODES",
    "MAX_NAMES",
    "MAX_WALLS",
    "SIGNS",
    "SceneFile",
    "SceneFileError",
    "builtin_scene_names",
    "builtin_scene_path",
    "dump_scene",
    "load_scene",
    "loads_scene",
    "read_scene",
    "reads_scene",
    "save_scene",
]
