# cli_harness.sh — what the CLI test scripts share (sourced, not run: tests/lib/ is outside run-tests.sh's glob).
# Gives a scratch directory $tmp (removed on exit), the counters, and:
#   expect NAME EXPECTED_EXIT PATTERN -- command...   runs the command (stdout in $tmp/out, stderr in $tmp/err) and
#          passes if it exits with EXPECTED_EXIT and, when PATTERN is not empty, stdout+stderr match it (grep -E);
#   check NAME CONDITION-COMMAND...                   passes if the condition command succeeds;
#   refuses NAME PATTERN FOLDER -- command...         an output over an input: passes if the command exits 2 with
#          PATTERN in its output (as expect) and leaves FOLDER as it was: the same entries, every file with the same
#          checksum (no input overwritten, nothing written); in $tmp itself, expect's own out and err are left out;
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

# Every entry of folder $1 (sorted) with the checksum of each file (symbolic links followed).
snapshot() {
    local skip=""
    [ "$1" = "$tmp" ] && skip="^\./(out|err)$"
    (cd "$1" && find . -print | grep -vE "${skip:-^$}" | LC_ALL=C sort | while IFS= read -r f; do
        if [ -f "$f" ]; then printf '%s %s\n' "$(md5sum <"$f" | cut -d' ' -f1)" "$f"; else printf 'dir %s\n' "$f"; fi
    done)
}

refuses() {
    local name=$1 pattern=$2 folder=$3 before
    shift 4
    before=$(snapshot "$folder")
    expect "$name" 2 "$pattern" -- "$@"
    if [ "$(snapshot "$folder")" = "$before" ]; then
        echo "ok    $name: every input unchanged, nothing written"; passed=$((passed + 1))
    else
        echo "FAIL  $name: the folder changed"; diff <(echo "$before") <(snapshot "$folder") | sed 's/^/      /' | head -5
        failed=$((failed + 1))
    fi
}

finish() {
    echo "$passed passed, $failed failed"
    [ "$failed" -eq 0 ]
    exit
}
