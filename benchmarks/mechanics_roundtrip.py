"""The round trip of ``Scene.from_mechanics`` over the table of models of
``tests/mechanics_table.py`` (sympy's tests, docstrings and models module, PyDy's
examples, the cases of issue 25), each built as a user builds it.

For each model it prints how the import did: ``imported`` (its accelerations agree with
the model's own ``mass_matrix_full \\ forcing_full`` at random states to 1e-9),
``refused`` (a SceneError with the reason the table lists) or ``wrong`` (anything else),
with the seconds it took (building the model with its equations included); then the count
of each kind.  The target is zero wrong.

Usage: python3 benchmarks/mechanics_roundtrip.py [--quick] [--harvest]

``--quick`` leaves out the entries marked slow; ``--harvest`` also runs every model that
sympy's own mechanics test functions and doctests form, unchanged
(``tests/mechanics_harvest.py``, about a minute), and counts them the same way.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from mechanics_entry import Outcome, judge
from mechanics_table import TABLE


def _counts(outcomes: list[Outcome]) -> str:
    kinds = [o.kind for o in outcomes]
    return (
        f"{len(kinds)} models: imported and agreeing {kinds.count('imported')},"
        f" refused with the listed reason {kinds.count('refused')},"
        f" wrong {kinds.count('wrong')}"
    )


def table(quick: bool) -> list[Outcome]:
    """Judge every entry of the table (the slow ones left out with ``quick``), printing
    one line each."""
    outcomes = []
    for entry in TABLE:
        if quick and entry.slow:
            continue
        outcome = judge(entry, c=entry.c and not quick)
        outcomes.append(outcome)
        print(
            f"{outcome.kind:9s} {outcome.seconds:6.2f} s  {entry.name}  [{entry.source}]:"
            f" {outcome.what[:110]}",
            flush=True,
        )
    return outcomes


def harvest() -> str:
    """The counts of the harvest of sympy's own tests (the same judgement as
    ``tests/test_mechanics_roundtrip.py``)."""
    import re

    from mechanics_harvest import harvest as run
    from mechanics_support import round_trip
    from test_mechanics_roundtrip import REFUSED, SKIP, TOLERANCE

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        found, _ = run(skip=SKIP)
        outcomes = {h.source: round_trip(h.model, name="model") for h in found}
    kinds = []
    for source, (kind, what) in outcomes.items():
        if kind == "imported" and source not in REFUSED and what < TOLERANCE:
            kinds.append("imported")
        elif kind == "refused" and source in REFUSED and re.search(REFUSED[source], what):
            kinds.append("refused")
        else:
            kinds.append("wrong")
            print(f"wrong     {source}: {what}")
    return (
        f"{len(kinds)} models: imported and agreeing {kinds.count('imported')},"
        f" refused with the listed reason {kinds.count('refused')},"
        f" wrong {kinds.count('wrong')}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="leave out the slow entries")
    parser.add_argument("--harvest", action="store_true", help="also sympy's tests, unchanged")
    args = parser.parse_args()
    t0 = time.perf_counter()
    outcomes = table(args.quick)
    print(f"table{' (quick)' if args.quick else ''}: {_counts(outcomes)}")
    if args.harvest:
        print(f"harvest of sympy's tests and doctests: {harvest()}")
    print(f"total run time: {time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    main()
