# cli_harness.sh — what the CLI test scripts share (sourced, not run: tests/lib/ is outside run-tests.sh's glob).
# Gives a scratch directory $tmp (removed on exit), the counters, and:
#   expect NAME EXPECTED_EXIT PATTERN -- command...   runs the command (stdout in $tmp/out, stderr in $tmp/err) and
#          passes if it exits with EXPECTED_EXIT and, when PATTERN is not empty, stdout+stderr match it (grep -E);
#   check NAME CONDITION-COMMAND...                   passes if the condition command succeeds;
#   finish                                            prints "N passed, N failed" and exits non-zero on a failure.
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
passed=0
failed=0

expect() {
    local name=$1 code=$2 pattern=$3
    shift 4
    "$@" >"$tmp/out" 2>"$tmp/err"
    local rc=$?
    if [ "$rc" -ne "$code" ]; then
        echo "FAIL  $name: exit $rc, expected $code"; sed 's/^/      /' "$tmp/err" | head -5
        failed=$((failed + 1)); return
    fi
    if [ -n "$pattern" ] && ! cat "$tmp/out" "$tmp/err" | grep -qE -- "$pattern"; then
        echo "FAIL  $name: output does not match /$pattern/"; cat "$tmp/out" "$tmp/err" | sed 's/^/      /' | head -5
        failed=$((failed + 1)); return
    fi
    echo "ok    $name"
    passed=$((passed + 1))
}

check() {
    local name=$1; shift
    if "$@"; then echo "ok    $name"; passed=$((passed + 1)); else echo "FAIL  $name"; failed=$((failed + 1)); fi
}

finish() {
    echo "$passed passed, $failed failed"
    [ "$failed" -eq 0 ]
    exit
}
