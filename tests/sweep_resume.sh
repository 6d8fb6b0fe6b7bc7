#!/usr/bin/env bash
# The crash test of `matremap sweep` (docs/sweep.md): a sweep killed with SIGKILL at random moments, and
# resumed each time, ends as the same file as an uninterrupted run: no sample lost, none twice, the same values
# in every row (the seconds column aside), in the same order. Also: --resume of a finished file changes nothing;
# --resume with another seed, a run without --resume over an existing file, and a second writer on the same
# file are all refused (exit 2) with the file untouched. Set MR_TEST_SEED to replay the same kill delays.
# Ends with "N passed, N failed".
set -u
bin="${MR_BUILD:-build}/bin/matremap"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
passed=0
failed=0
ok() { echo "ok    $1"; passed=$((passed + 1)); }
fail() { echo "FAIL  $1"; failed=$((failed + 1)); }
check() { # NAME COMMAND...: passes if the command succeeds
    local name=$1; shift
    if "$@"; then ok "$name"; else fail "$name"; fi
}

seed=${MR_TEST_SEED:-$$}
RANDOM=$seed
echo "   kill delays drawn with MR_TEST_SEED=$seed"

# 40 samples at 96^2: ~0.1 s on 2 threads since issue 31's engine (~2 s before it; more under ASan); the kill delays
# below scale with the reference's time, so they land mid-run at any speed.
args=(--from ggx --to ward-balanced --random 40 --seed 7 --size 96 --threads 2)
total=40

rows() { grep -v '^#' "$1" | tail -n +2; }                 # data rows only
# Complete lines (wc -l counts the newlines) but the command line, without the seconds column.
values() { head -n "$(wc -l <"$1")" "$1" | grep -v '^# command:' | sed '/^#/!s/,[^,]*$//'; }
# Complete lines whose column count is not the column-name line's.
bad_rows() {
    head -n "$(wc -l <"$1")" "$1" | grep -v '^#' |
        awk -F, 'NR == 1 { n = NF; next } NF != n { print "row " NR - 1 ": " NF " columns" }'
}
torn_tail() { [ -s "$1" ] && [ -n "$(tail -c 1 "$1")" ]; }

# The reference: one uninterrupted run, timed to scale the kill delays.
start_ms=$(date +%s%3N)
"$bin" sweep "${args[@]}" -o "$tmp/ref.csv" 2>"$tmp/ref.err"
rc=$?
ref_ms=$(($(date +%s%3N) - start_ms))
echo "   reference run: $ref_ms ms"
check "uninterrupted sweep succeeds" [ "$rc" -eq 0 ]
check "reference has $total rows" [ "$(rows "$tmp/ref.csv" | wc -l)" -eq "$total" ]

# The same sweep, killed with SIGKILL after a random delay, then resumed and killed again, four times. The
# delays are 2.5-25 % of the reference's wall time (a few ms for the optimised build), so the kills land
# at random points of the run whatever the build's speed, and the four together rarely finish the sweep.
crash="$tmp/crash.csv"
landed=0
partial=0
for round in 1 2 3 4; do
    resume=()
    [ "$round" -gt 1 ] && resume=(--resume)
    "$bin" sweep "${args[@]}" -o "$crash" "${resume[@]}" 2>>"$tmp/crash.err" &
    pid=$!
    delay_ms=$((ref_ms * (25 + RANDOM % 226) / 1000))
    delay=$(printf '%d.%03d' $((delay_ms / 1000)) $((delay_ms % 1000)))
    sleep "$delay"
    if kill -0 "$pid" 2>/dev/null; then
        kill -9 "$pid"
        { wait "$pid"; } 2>/dev/null
        landed=$((landed + 1))
        n=$(rows "$crash" 2>/dev/null | wc -l)
        echo "   round $round: killed after ${delay} s with $n of $total rows in the file"
        [ "$n" -gt 0 ] && [ "$n" -lt "$total" ] && partial=$((partial + 1))
        # Whole rows plus at most one torn final line (one write per row makes a torn one all but impossible:
        # Linux could only stop a write between two pages on SIGKILL).
        torn_tail "$crash" && echo "   round $round: the file ends in a torn line (resume will cut it)"
        bad=$(bad_rows "$crash")
        [ -z "$bad" ] || fail "round $round: a complete row is malformed: $bad"
        # Every row written so far is a row of the reference (seconds aside).
        extra=$(comm -13 <(values "$tmp/ref.csv" | sort) <(values "$crash" | sort))
        [ -z "$extra" ] || fail "round $round: a line differs from the reference: ${extra:0:100}"
    else
        wait "$pid"
        rc=$?
        echo "   round $round: the run finished within ${delay} s"
        [ "$rc" -eq 0 ] || { fail "round $round: the run exited with $rc:"; tail -3 "$tmp/crash.err"; }
        break
    fi
done
check "kills landed mid-sweep (landed $landed, with a partial file $partial times)" \
    [ "$landed" -ge 2 -a "$partial" -ge 1 ]

# A full disk or a power cut can tear the last row (a kill practically cannot): simulate one, unless a kill did.
torn_tail "$crash" || printf '17,0.00123' >>"$crash"
"$bin" sweep "${args[@]}" -o "$crash" --resume 2>"$tmp/final.err"
rc=$?
check "final --resume completes" [ "$rc" -eq 0 ]
check "... after cutting the torn last line" grep -q "removed a torn last line" "$tmp/final.err"
check "no sample twice" [ -z "$(rows "$crash" | cut -d, -f1 | sort -n | uniq -d)" ]
check "no sample lost (indices 0..$((total - 1)))" \
    [ "$(rows "$crash" | cut -d, -f1 | sort -n | tr '\n' ' ')" = "$(seq 0 $((total - 1)) | tr '\n' ' ')" ]
check "rows in index order" [ "$(rows "$crash" | cut -d, -f1 | tr '\n' ' ')" = "$(seq 0 $((total - 1)) | tr '\n' ' ')" ]
if diff <(values "$tmp/ref.csv") <(values "$crash") >"$tmp/diff"; then
    ok "same file as the uninterrupted run (seconds and command line aside)"
else
    fail "resumed file differs from the reference:"; head -5 "$tmp/diff" | sed 's/^/      /'
fi

# --resume of a finished file: nothing to do, not a byte changed.
cp "$crash" "$tmp/before.csv"
"$bin" sweep "${args[@]}" -o "$crash" --resume 2>"$tmp/again.err"
rc=$?
check "--resume of a finished file exits 0" [ "$rc" -eq 0 ]
check "... saying there is nothing to do" grep -q "nothing to do" "$tmp/again.err"
check "... and leaves the file unchanged" cmp -s "$crash" "$tmp/before.csv"

# Another seed is another sweep: refused, file untouched.
other=(--from ggx --to ward-balanced --random 40 --seed 8 --size 96 --threads 2)
"$bin" sweep "${other[@]}" -o "$crash" --resume 2>"$tmp/seed.err"
rc=$?
check "--resume with another seed exits 2" [ "$rc" -eq 2 ]
check "... naming the mismatching line" grep -q "line 6 is '# sampling: random=40 seed=7" "$tmp/seed.err"
check "... and leaves the file unchanged" cmp -s "$crash" "$tmp/before.csv"

# Another local stage is another sweep (rows fitted by BOBYQA do not continue by gradient steps): refused, untouched.
"$bin" sweep "${args[@]}" --local bobyqa -o "$crash" --resume 2>"$tmp/local.err"
rc=$?
check "--resume with another local method exits 2" [ "$rc" -eq 2 ]
check "... naming the mismatching line" grep -q "local=auto', this run's is .* local=bobyqa'" "$tmp/local.err"
check "... and leaves the file unchanged" cmp -s "$crash" "$tmp/before.csv"

# Without --resume an existing file is refused.
"$bin" sweep "${args[@]}" -o "$crash" 2>"$tmp/exists.err"
rc=$?
check "an existing file without --resume exits 2" [ "$rc" -eq 2 ]
check "... suggesting --resume" grep -q "already exists: use --resume" "$tmp/exists.err"
check "... and leaves the file unchanged" cmp -s "$crash" "$tmp/before.csv"

# Two processes on one file: the second is refused while the first runs (an fcntl lock).
small=(--from ggx --to ward-balanced --random 12 --seed 7 --size 96 --threads 2)
"$bin" sweep "${small[@]}" -o "$tmp/locked.csv" 2>/dev/null &
pid=$!
sleep 0.2
"$bin" sweep "${small[@]}" -o "$tmp/locked.csv" --resume 2>"$tmp/lock.err"
rc=$?
if kill -0 "$pid" 2>/dev/null; then
    check "a second writer is refused (exit 2)" [ "$rc" -eq 2 ]
    check "... naming the other process" grep -q "being written by another process (pid $pid)" "$tmp/lock.err"
else
    echo "   (the first run ended before the second started: lock check skipped)"
fi
wait "$pid"
check "the first writer still finishes its file" [ "$(rows "$tmp/locked.csv" | wc -l)" -eq 12 ]

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
