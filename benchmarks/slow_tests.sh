#!/usr/bin/env bash
# The tests marked slow (deselected by default, so not run in CI): run them here.
# Usage: benchmarks/slow_tests.sh [pytest options]
set -uo pipefail
cd "$(dirname "$0")/.."
python3 -m pytest -m slow "$@"
status=$?
if [ "$status" -eq 5 ]; then
    echo "no test is marked slow at present"
    exit 0
fi
exit "$status"
