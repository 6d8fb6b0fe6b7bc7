#!/usr/bin/env bash
# tests/blender_principled_reference.txt holds what tests/blender_principled_reference.py (a numpy
# implementation of Cycles' Principled BSDF, written from the Blender 4.2 sources and blender_principled.c's
# documented substitutions) writes; test_brdf's known_blender_principled_reference compares the model with it to
# 1e-6. This checks the file is still what the script writes (identical to 1e-12 relative), so neither drifts.
# Without Debian's python3-numpy it says so and counts nothing. Ends with "N passed, N failed".
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
python=/usr/bin/python3
[ -x "$python" ] || python=python3
if ! "$python" -c 'import numpy' 2>/dev/null; then
    echo "skip  blender_principled_reference: no numpy for $python"
    echo "0 passed, 0 failed"
    exit 0
fi
out=$(mktemp)
trap 'rm -f "$out"' EXIT
if ! MR_ROOT="$root" "$python" "$root/tests/blender_principled_reference.py" >"$out"; then
    echo "FAIL  tests/blender_principled_reference.py failed"
    echo "0 passed, 1 failed"
    exit 1
fi
if "$python" - "$out" "$root/tests/blender_principled_reference.txt" <<'PY'
import sys
a = [[float(x) for x in l.split()] for l in open(sys.argv[1])]
b = [[float(x) for x in l.split()] for l in open(sys.argv[2])]
ok = len(a) == len(b) and all(len(r) == len(s) and all(abs(x - y) <= 1e-12 * max(abs(x), abs(y), 1e-300)
                                                     for x, y in zip(r, s)) for r, s in zip(a, b))
sys.exit(0 if ok else 1)
PY
then
    echo "ok    tests/blender_principled_reference.txt is what tests/blender_principled_reference.py writes"
    echo "1 passed, 0 failed"
else
    echo "FAIL  tests/blender_principled_reference.txt differs from the script's output: regenerate it"
    echo "0 passed, 1 failed"
    exit 1
fi
