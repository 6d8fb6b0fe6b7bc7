#!/usr/bin/env bash
# python.sh — the Python package's suite (tests/python/test_*.py, Debian's python3-pytest) against the build tree's
# libmatremap.so (MR_BUILD, set by scripts/run-tests.sh), ending in run-tests.sh's "N passed, N failed" line.
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
export MR_BUILD="${MR_BUILD:-$root/build}"
if ! /usr/bin/python3 -c 'import pytest, numpy' 2>/dev/null; then
    echo "FAIL  python: /usr/bin/python3 lacks pytest or numpy (scripts/install-deps.sh installs python3-pytest)"
    echo "0 passed, 1 failed"
    exit 1
fi
# A sanitizer build's library (make asan) cannot load into an uninstrumented Python: its suite is the plain build's.
if nm -D "$MR_BUILD/lib/libmatremap.so.0" 2>/dev/null | grep -q ' U __asan_init'; then
    echo "skip  python: $MR_BUILD/lib/libmatremap.so.0 is built with AddressSanitizer (make check runs the suite)"
    echo "0 passed, 0 failed"
    exit 0
fi
out=$(mktemp)
trap 'rm -f "$out"' EXIT
cd "$root" && /usr/bin/python3 -m pytest -q -p no:cacheprovider tests/python 2>&1 | tee "$out"
rc=${PIPESTATUS[0]}
summary=$(tail -n 1 "$out")
passed=$(echo "$summary" | grep -oE '[0-9]+ passed' | cut -d' ' -f1)
failed=$(echo "$summary" | grep -oE '[0-9]+ (failed|errors?)' | awk '{n += $1} END {print n + 0}')
passed=${passed:-0}
failed=${failed:-0}
[ "$rc" -ne 0 ] && [ "$failed" -eq 0 ] && failed=1
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
