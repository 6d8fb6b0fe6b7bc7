#!/usr/bin/env bash
# reference_file.sh NAME — tests/NAME.txt holds what tests/NAME.py (an independent numpy transcription of a model's
# specification or source) writes, and test_brdf compares the model with the file to 1e-6. This checks the file is
# still what the script writes (identical to 1e-12 relative), so neither drifts. Debian's python3-numpy is a
# dependency (scripts/install-deps.sh): without it the check fails, saying so. Ends with "N passed, N failed".
set -u
name=$1
root=$(cd "$(dirname "$0")/../.." && pwd)
python=/usr/bin/python3 # Debian's, with numpy; a python3 earlier on PATH (pyenv, a virtualenv) may lack it
[ -x "$python" ] || python=python3
fail() {
    echo "FAIL  $1"
    echo "0 passed, 1 failed"
    exit 1
}
"$python" -c 'import numpy' 2>/dev/null || fail "$name: no numpy for $python (Debian: python3-numpy)"
out=$(mktemp)
trap 'rm -f "$out"' EXIT
MR_ROOT="$root" "$python" "$root/tests/$name.py" >"$out" || fail "tests/$name.py failed"
"$python" - "$out" "$root/tests/$name.txt" <<'PY' || fail "tests/$name.txt differs from tests/$name.py's output: regenerate it"
import sys
a = [[float(x) for x in l.split()] for l in open(sys.argv[1])]
b = [[float(x) for x in l.split()] for l in open(sys.argv[2])]
ok = len(a) == len(b) and all(len(r) == len(s) and all(abs(x - y) <= 1e-12 * max(abs(x), abs(y), 1e-300)
                                                     for x, y in zip(r, s)) for r, s in zip(a, b))
sys.exit(0 if ok else 1)
PY
echo "ok    tests/$name.txt is what tests/$name.py writes"
echo "1 passed, 0 failed"
