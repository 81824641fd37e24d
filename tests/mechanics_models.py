"""sympy.physics.mechanics models for the import tests and benchmarks/mechanics.py."""

from __future__ import annotations

from pathlib import Path


def sympy_bicycle(timings: dict | None = None) -> tuple[object, dict]:
    """Run sympy's test_bicycle (the Whipple bicycle of Meijaard et al. 2007, from the
    installed sympy, unchanged) up to its equations; return (KanesMethod, values).
    ``timings["kane"]`` receives the seconds KanesMethod took to form the equations (its
    construction and ``kanes_equations``), the kinematics excluded."""
    import time

    import sympy.physics.mechanics.tests.test_kane3 as source

    text = Path(source.__file__).read_text()
    body = text.split("def test_bicycle():", 1)[1]
    model_part, rest = body.split("(fr, frstar) = KM.kanes_equations(BL, FL)", 1)
    kinematics, kane = model_part.split("KM = KanesMethod(", 1)
    values_part = rest.split("v = symbols('v')", 1)[1].split("A, B, _ = KM.linearize(", 1)[0]

    def dedent(part: str) -> str:
        return "\n".join(line[4:] for line in part.splitlines())

    namespace: dict = {}
    # the installed sympy's own test code, not user input
    exec(
        "from sympy import *\nfrom sympy.physics.mechanics import *\n" + dedent(kinematics),
        namespace,
    )
    t0 = time.perf_counter()
    first, _, more = kane.partition("\n")
    exec(
        "KM = KanesMethod(" + first + "\n" + dedent(more) + "\nKM.kanes_equations(BL, FL)\n",
        namespace,
    )
    if timings is not None:
        timings["kane"] = time.perf_counter() - t0
    exec(dedent(rest.split("v = symbols('v')", 1)[0]), namespace)
    exec("v = symbols('v')\n" + dedent(values_part), namespace)
    return namespace["KM"], namespace["val_dict"]
