#!/usr/bin/env bash
# standard_surface_reference.sh — the `standard-surface` model (src/brdf/standard_surface.c) against an independent
# evaluation of the Autodesk Standard Surface formulas in Python (tests/standard_surface_reference.py): six
# parameter sets x six direction pairs, diffuse and specular parts, 1e-6 relative. (The albedo table it shares with
# the model, src/brdf/ggx_albedo_tables.h, is checked against its generator by tests/ggx_albedo_table.sh.)
# The library's side is tests/lib/brdf_eval.c, built here against $MR_BUILD/libmatremap.a (it links only the
# brdf module, so libm is all it needs). Needs a C compiler and Python 3 with numpy (Debian: python3-numpy,
# installed by scripts/install-deps.sh); a missing one is a failure, not a skip.
# Ends with "N passed, N failed" for scripts/run-tests.sh.
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
build=${MR_BUILD:-$root/build}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() {
    echo "FAIL  $1"
    echo "0 passed, 1 failed"
    exit 1
}
[ -f "$build/libmatremap.a" ] || fail "no $build/libmatremap.a: run make first"
# Under `make asan` the library's objects carry the sanitizers (the parent make's SAN reaches us in MAKEFLAGS).
san=""
case "${MAKEFLAGS:-}" in *fsanitize=*) san="-fsanitize=address,undefined" ;; esac
${CC:-cc} -std=c11 -D_POSIX_C_SOURCE=200809L -I"$root/src" -O2 $san "$root/tests/lib/brdf_eval.c" \
    "$build/libmatremap.a" -lm -o "$tmp/brdf_eval" || fail "tests/lib/brdf_eval.c does not build"
# Debian's python3 carries python3-numpy; a python3 earlier on PATH (a virtualenv, pyenv) may not.
python=""
for p in python3 /usr/bin/python3; do
    if command -v "$p" >/dev/null 2>&1 && "$p" -c 'import numpy' >/dev/null 2>&1; then
        python=$p
        break
    fi
done
[ -n "$python" ] || fail "no python3 with numpy (Debian: apt-get install python3-numpy)"
"$python" "$root/tests/standard_surface_reference.py" "$root" "$tmp/brdf_eval" > "$tmp/out"
status=$?
sed '$d' "$tmp/out"
read -r passed _ failed _ < <(tail -n 1 "$tmp/out")
[ -n "${passed:-}" ] || { passed=0; failed=1; }
echo "$passed passed, $failed failed"
[ "$status" -eq 0 ]
