"""Write the gallery of the scene zoo: one animation (GIF) per built-in scene, and the
gallery page that shows them.

    python3 docs/make_gallery.py            # every scene
    python3 docs/make_gallery.py ladder     # one

Each built-in scene with a simulation case (:data:`symmech.bench.cases.CASES`) runs its
case; the others run the state given in :data:`EXTRA` below.  The GIFs go to
``docs/_static/gallery/NAME.gif`` (20 frames a second, 60 dpi: small files), the page to
``docs/gallery.md``, the plots of :data:`PLOTS` to ``docs/_static/NAME_plot.png``.  All are
committed: the documentation build shows them without simulating (rerun this script when a
scene or the drawing code changes).
"""

from __future__ import annotations

import sys
import time
import warnings
from pathlib import Path

import symmech as sm
from symmech.bench.cases import CASES
from symmech.scenefile import builtin_scene_names
from symmech.simulate.animation import save_animation

HERE = Path(__file__).resolve().parent
OUT = HERE / "_static" / "gallery"
PAGE = HERE / "gallery.md"
FPS, DPI = 20.0, 60.0
#: Scenes whose plot (``res.plot()``) is also written, as ``docs/_static/NAME_plot.png``.
PLOTS = ("ellipse_gravity",)

#: Scenes without a simulation case: (q0, v0, t_end, what the animation shows).
EXTRA: dict[str, tuple[list[float], list[float], float, str]] = {
    "bouncing_ellipse": ([-2.0, 0.0, 0.3], [1.5, 0.0, 1.0], 3.0, "spinning into the wall"),
    "spinning_disk": ([-1.0, 0.0, 0.0], [1.0, 0.0, 5.0], 2.0, "a spinning disc meets the wall"),
    "carnot_3_7": ([0.0, 1.0, 0.0], [1.0, -1.0, 4.0], 2.0, "a disc strikes the rough floor"),
    "ball_in_corner": ([0.3, 1.5], [0.0, 0.0], 3.0, "a ball dropped into a V corner"),
    "car": ([0.0, 0.0, 0.0, 0.5], [1.0, 0.0, 0.5, 0.0], 8.0, "the car drives a circle"),
    "pendulum_on_cart_3": ([0.0, 1.0, 0.5, -0.5], [0.0] * 4, 4.0, "released at rest"),
    "rolling_ball": ([0.3, 1.0, 0.2], [1.0, 0.5, 0.0], 3.0, "no drawing: its coordinates"),
}
#: Scenes left out, and why.
LEFT_OUT = {"carnot_4_4": "its wall moves as an arbitrary f(t): give it with definitions="}


def state(name: str) -> tuple[list[float], list[float], float, str]:
    """``(q0, v0, t_end, what it shows)`` of a scene's gallery run."""
    case = CASES.get(name)
    if case is None:
        return EXTRA[name]
    return list(case.q0), list(case.v0), case.t_end, case.description


def run(name: str) -> sm.simulate.SimulationResult:
    sf = sm.read_scene(name)
    params = sf.numeric_defaults()
    if name in CASES:
        params.update(CASES[name].overrides)
    q0, v0, t_end, _ = state(name)
    return sm.simulate(sf.scene, q0, v0, t_end, params=params)


def main(names: list[str]) -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    rows = []
    for name in builtin_scene_names():
        if name in LEFT_OUT:
            continue
        description = sm.read_scene(name).description
        rows.append((name, description, state(name)[3]))
        if names and name not in names:
            continue
        clock = time.perf_counter()
        res = run(name)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", sm.SymmechWarning)  # rolling_ball: no drawing
            anim = res.animate(fps=FPS)
        path = save_animation(anim, OUT / f"{name}.gif", fps=FPS, dpi=DPI)
        if name in PLOTS:
            res.plot(path=HERE / "_static" / f"{name}_plot.png")
        print(
            f"{path.relative_to(HERE)}: {len(anim.times)} frames, {res.status},"
            f" {len(res.events)} events, {time.perf_counter() - clock:.1f} s"
        )
    _page(rows)


def _page(rows: list[tuple[str, str, str]]) -> None:
    lines = [
        "# Gallery",
        "",
        "The scene zoo: every built-in scene (`symmech examples`) run from its simulation"
        " case and drawn as its scene file's `[[drawing]]` says, at real time with every"
        " event instant a frame.  Made by `python3 docs/make_gallery.py`; each one is also"
        " `symmech simulate NAME --animate NAME.gif` away.",
        "",
    ]
    for name, description, what in sorted(rows):
        lines += [f"## {name}", "", f"{description}: {what}.", ""]
        lines += [f"![{name}](_static/gallery/{name}.gif)", ""]
    for name, why in LEFT_OUT.items():
        lines += [f"## {name}", "", f"Not animated here: {why}.", ""]
    PAGE.write_text("\n".join(lines), encoding="utf-8")


if __name__ == "__main__":
    main(sys.argv[1:])
