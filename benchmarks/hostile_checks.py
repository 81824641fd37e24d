"""Cost of the run-time checks of issue 10 (argument conversion, parameter ranges, metric
checks of the closed forms, scale-invariant impacts), as ratios against a baseline
revision of symmech measured in the same run.

    python3 benchmarks/hostile_checks.py [BASELINE_REVISION] [--quick]

``--quick`` (a smoke test): each tree once, fewer calls per timing.

The baseline (default ``e785862``, the tree before these checks) is exported with
``git archive`` into a temporary folder; each tree runs the same timing code in its own
subprocess, with its own compiled-library cache, three times, alternating with the other
tree (the best of the three is kept: the machine may be shared).  Printed: microseconds
per call (best of several repeats) of one-state calls (the CPython extension, ctypes,
NumPy) and of batches of 100 000 states (C, NumPy), for the impact map and the energy of
``carnot_3_7``, and the ratio current / baseline.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

TIMING = r"""
import json, sys, timeit
from symmech.codegen.backends import template_root
assert str(template_root()).startswith(sys.argv[1]), (template_root(), sys.argv[1])
import numpy as np
import symmech as sm
from symmech.examples import carnot_3_7

scene = carnot_3_7()
c = sm.codegen.generate(scene, "c")
ext, plain = c.load(), c.load(extension=False)
py = sm.codegen.generate(scene, "numpy").load()
q, v, p = [0.0, 1.0, 0.0], [1.0, -2.0, 0.0], [1.0, 0.5, 1.0, 2.0]
rng = np.random.default_rng(0)
Q, V = rng.normal(size=(100_000, 3)), rng.normal(size=(100_000, 3))
P = np.array(p)


QUICK = len(sys.argv) > 2 and sys.argv[2] == "--quick"


def best(fn, number):
    if QUICK:
        return timeit.timeit(fn, number=max(1, number // 100)) / max(1, number // 100) * 1e6
    return min(timeit.repeat(fn, number=number, repeat=7)) / number * 1e6


out = {}
for label, mod in (("extension", ext), ("ctypes", plain), ("numpy", py)):
    out[f"impact, one state, {label}"] = best(lambda: mod.impact(q, v, p), 2000)
    out[f"energy, one state, {label}"] = best(lambda: mod.energy(q, v, p), 2000)
for label, mod in (("C", ext), ("numpy", py)):
    out[f"impact, batch of 1e5, {label}"] = best(lambda: mod.impact(Q, V, P), 5)
    out[f"energy, batch of 1e5, {label}"] = best(lambda: mod.energy(Q, V, P), 5)
print(json.dumps(out))
"""


def _run(tree: Path, cache: Path, quick: bool) -> dict[str, float]:
    env = {**os.environ, "PYTHONPATH": str(tree), "SYMMECH_CACHE_DIR": str(cache)}
    proc = subprocess.run(
        [sys.executable, "-c", TIMING, str(tree), *(["--quick"] if quick else [])],
        cwd=tree,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    if proc.returncode != 0:
        raise SystemExit(f"timing in {tree} failed:\n{proc.stderr}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main(revision: str = "e785862", quick: bool = False) -> None:
    with tempfile.TemporaryDirectory(prefix="symmech_baseline_") as tmp:
        base = Path(tmp) / "tree"
        base.mkdir()
        archive = subprocess.run(
            ["git", "archive", revision], cwd=ROOT, capture_output=True, check=True
        ).stdout
        subprocess.run(["tar", "-x", "-C", str(base)], input=archive, check=True)
        # its own templates as the package data symmech.templates (else an editable
        # install of the current tree would lend it the current templates)
        shutil.copytree(base / "templates", base / "symmech" / "templates")
        # alternate the trees (the machine is shared): the best of three runs of each
        runs: dict[str, list[dict[str, float]]] = {"base": [], "now": []}
        for _ in range(1 if quick else 3):
            runs["base"].append(_run(base, Path(tmp) / "cache_base", quick))
            runs["now"].append(_run(ROOT, Path(tmp) / "cache_now", quick))
        before = {k: min(r[k] for r in runs["base"]) for k in runs["base"][0]}
        after = {k: min(r[k] for r in runs["now"]) for k in runs["now"][0]}
    width = max(len(k) for k in after)
    print(f"{'case':{width}}  {revision + ' us':>14}  {'now us':>10}  {'ratio':>6}")
    for key, now in after.items():
        then = before[key]
        print(f"{key:{width}}  {then:14.2f}  {now:10.2f}  {now / then:6.2f}")


if __name__ == "__main__":
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("revision", nargs="?", default="e785862", help="the baseline revision")
    ap.add_argument("--quick", action="store_true", help="a smoke test: each tree once")
    args = ap.parse_args()
    main(args.revision, args.quick)
