#!/usr/bin/env bash
# Runs every test binary in BUILD/tests and every tests/*.sh script, then prints the totals as the last line:
# "N passed, N failed". Exit status is non-zero if anything failed. Usage: scripts/run-tests.sh BUILD [NAME]
set -u
build=${1:-build}
only=${2:-}
root=$(cd "$(dirname "$0")/.." && pwd)
export MR_BUILD="$root/$build" MR_ROOT="$root" MR_SHARED="${MR_SHARED:-$root/../shared}"
passed=0
failed=0
log=$(mktemp)
trap 'rm -f "$log"' EXIT
run_one() {
    local name=$1; shift
    echo "== $name"
    "$@" 2>&1 | tee "$log"
    local rc=${PIPESTATUS[0]}
    local line
    line=$(grep -E '^[0-9]+ passed, [0-9]+ failed$' "$log" | tail -n 1)
    if [ -n "$line" ]; then
        passed=$((passed + $(echo "$line" | cut -d' ' -f1)))
        failed=$((failed + $(echo "$line" | cut -d' ' -f3)))
    fi
    if [ "$rc" -ne 0 ] && [ -z "$line" -o "$(echo "$line" | cut -d' ' -f3)" = 0 ]; then
        echo "   $name exited with status $rc"
        failed=$((failed + 1))
    fi
}
for t in "$root/$build"/tests/test_*; do
    [ -x "$t" ] || continue
    name=$(basename "$t")
    [ -n "$only" ] && [ "$only" != "$name" ] && continue
    run_one "$name" "$t"
done
for s in "$root"/tests/*.sh; do
    [ -f "$s" ] || continue
    name=$(basename "$s" .sh)
    [ -n "$only" ] && [ "$only" != "$name" ] && continue
    run_one "$name" bash "$s"
done
echo
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
