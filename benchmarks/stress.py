"""Stiff and extreme cases of the simulator (see symmech.bench.stress): each case prints its
measured error against its reference, its tolerance and pass/fail.

    python3 benchmarks/stress.py [--backend c|numpy|scipy] [-k CASE ...]
"""

from __future__ import annotations

import argparse
import sys
import time

from symmech.bench import stress

#: the case ``--quick`` runs (a smoke test of the script)
QUICK_CASE = "grazing"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--backend", default="c", choices=("c", "numpy", "scipy"))
    ap.add_argument("-k", dest="cases", action="append", choices=sorted(stress.CASES))
    ap.add_argument("--quick", action="store_true", help=f"a smoke test: {QUICK_CASE} only")
    args = ap.parse_args(argv)
    if args.quick:
        args.cases = [QUICK_CASE]
    clock = time.perf_counter()
    results = stress.run_all(args.backend, args.cases)
    print(stress.format_table(results))
    failed = [r for r in results if not r.passed]
    print(
        f"\n{len(results) - len(failed)} passed, {len(failed)} failed"
        f" ({time.perf_counter() - clock:.1f} s, backend {args.backend})"
    )
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
