#!/usr/bin/env bash
# `mpirun -np 2 matremap sweep` against a single process (docs/sweep.md, "Several processes"): the same rows in
# the same order (the seconds column and the command line aside; typed alike, the same bytes but the seconds), on 3
# ranks too; a rank killed with SIGKILL at random moments
# (mpirun then ends the other) and the run resumed, on 2 ranks or on one process, ends as the same file; a single
# process's interrupted file resumed on 2 ranks too; --help and usage errors printed once, not once per rank; an
# existing file refused (exit 2, untouched); a missing MPI module refused (exit 2, naming it, no file).
# Runs only where mpirun is on PATH (and, past the module check, where build/lib/matremap/libmatremap-mpi.so was
# built); otherwise it says why and counts nothing. Set MR_TEST_SEED to replay the same kills.
# Ends with "N passed, N failed".
set -u
. "$(dirname "$0")/lib/cli_harness.sh"
bin="${MR_BUILD:-build}/bin/matremap"
module="$(dirname "$bin")/../lib/matremap/libmatremap-mpi.so"

if ! command -v mpirun >/dev/null 2>&1; then
    echo "   skipped: mpirun is not on PATH (scripts/install-deps.sh installs openmpi-bin and libopenmpi-dev)"
    finish
fi
# As root Open MPI wants to be told; --oversubscribe lets 2 ranks run on a 1-core machine.
launcher=(mpirun --oversubscribe)
# Under AddressSanitizer (make asan), Open MPI's own allocations outlive MPI_Finalize (thousands of them, from
# MPI_Init): LeakSanitizer is told to leave what Open MPI's libraries and components allocated, and unwinds fully
# so that it can tell (its fast unwinder stops inside those libraries, which keep no frame pointers). Our own
# allocations are checked as in every other test; ignored by an ordinary build.
printf 'leak:%s\n' libopen-pal.so libopen-rte.so libmpi.so libpmix.so libhwloc.so libevent mca_ ld-linux >"$tmp/lsan.supp"
export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}fast_unwind_on_malloc=0"
export LSAN_OPTIONS="${LSAN_OPTIONS:+$LSAN_OPTIONS:}suppressions=$tmp/lsan.supp:print_suppressions=0"
[ "$(id -u)" -eq 0 ] && launcher+=(--allow-run-as-root)
mpi=("${launcher[@]}" -np 2)
echo "   $(mpirun --version 2>/dev/null | head -n 1)"

args=(--from ggx --to ward-balanced --random 60 --seed 7 --size 192)
total=60
rows() { grep -v '^#' "$1" | tail -n +2; }
# Complete lines but the command line, without the seconds column.
values() { head -n "$(wc -l <"$1")" "$1" | grep -v '^# command:' | sed '/^#/!s/,[^,]*$//'; }
same_as_ref() { diff <(values "$tmp/ref.csv") <(values "$1") >"$tmp/diff"; }
# None of the PIDs runs (zombies awaiting their reaper aside) within 5 s.
none_running() {
    local p state tries
    for tries in $(seq 50); do
        state=""
        for p in "$@"; do
            [ -r "/proc/$p/stat" ] && state+=$(awk '{print $3}' "/proc/$p/stat" 2>/dev/null | grep -v Z)
        done
        [ -z "$state" ] && return 0
        sleep 0.1
    done
    return 1
}

# A missing module is refused on every rank: exit 2, naming the module, nothing written.
expect "a missing MPI module: exit 2" 2 "has no MPI module: libmatremap-mpi.so" -- \
    env MR_MPI_MODULE="$tmp/none.so" "${mpi[@]}" "$bin" sweep "${args[@]}" -o "$tmp/none.csv"
check "... and no file" [ ! -e "$tmp/none.csv" ]

if [ ! -f "$module" ]; then
    echo "   skipped the 2-rank runs: $module was not built (make found no Open MPI development files,"
    echo "   libopenmpi-dev, or ran with MPI=0)"
    finish
fi

# The reference: one process, uninterrupted, timed to scale the kill delays.
start_ms=$(date +%s%3N)
"$bin" sweep "${args[@]}" --threads 2 -o "$tmp/ref.csv" 2>"$tmp/ref.err"
rc=$?
ref_ms=$(($(date +%s%3N) - start_ms))
echo "   single process, 2 threads: $ref_ms ms"
check "the single-process sweep succeeds" [ "$rc" -eq 0 ]

expect "mpirun -np 2 matremap sweep succeeds" 0 "2 ranks, 2 threads in all" -- \
    "${mpi[@]}" "$bin" sweep "${args[@]}" -o "$tmp/mpi.csv"
check "... with $total rows" [ "$(rows "$tmp/mpi.csv" | wc -l)" -eq "$total" ]
if same_as_ref "$tmp/mpi.csv"; then
    ok_rows=1
else
    ok_rows=0
    head -5 "$tmp/diff" | sed 's/^/      /'
fi
check "... the single process's file: same header, rows, order (seconds, command line aside)" [ "$ok_rows" -eq 1 ]
check "... the summary printed once (rank 0 speaks)" [ "$(grep -c 'is complete' "$tmp/err")" -eq 1 ]

# Typed the same way (the same arguments, -o included, in another folder), the two files are the same bytes but
# for the seconds column: the command line recorded is the same too.
mkdir -p "$tmp/a" "$tmp/b"
abs_bin="$(cd "$(dirname "$bin")" && pwd)/$(basename "$bin")"
(cd "$tmp/a" && "$abs_bin" sweep "${args[@]}" -o same.csv 2>/dev/null)
(cd "$tmp/b" && "${mpi[@]}" "$abs_bin" sweep "${args[@]}" -o same.csv >/dev/null 2>&1)
strip_seconds() { sed '/^#/!s/,[^,]*$//' "$1"; }
check "the same command with and without mpirun: the same bytes but the seconds" \
    cmp -s <(strip_seconds "$tmp/a/same.csv") <(strip_seconds "$tmp/b/same.csv")
# Three ranks (more than the cores here: --oversubscribe): the same rows.
expect "mpirun -np 3 matremap sweep succeeds" 0 "3 ranks" -- \
    "${launcher[@]}" -np 3 "$bin" sweep "${args[@]}" -o "$tmp/np3.csv"
if same_as_ref "$tmp/np3.csv"; then ok_rows=1; else ok_rows=0; head -5 "$tmp/diff" | sed 's/^/      /'; fi
check "... the single process's rows" [ "$ok_rows" -eq 1 ]

# --help and usage errors: once, not once per rank.
expect "--help under mpirun" 0 "Several processes" -- "${mpi[@]}" "$bin" sweep --help
check "... printed once" [ "$(grep -c '^Usage: matremap sweep' "$tmp/out")" -eq 1 ]
expect "a usage error under mpirun: exit 1" 1 "missing --to MODEL" -- "${mpi[@]}" "$bin" sweep --from ggx -o x.csv
check "... printed once" [ "$(grep -c 'missing --to MODEL' "$tmp/err")" -eq 1 ]

# An existing file without --resume: refused by rank 0 for all, untouched.
sum=$(md5sum <"$tmp/mpi.csv")
expect "an existing file without --resume: exit 2" 2 "already exists; not overwriting it" -- \
    "${mpi[@]}" "$bin" sweep "${args[@]}" -o "$tmp/mpi.csv"
check "... the file untouched" [ "$(md5sum <"$tmp/mpi.csv")" = "$sum" ]

# Kill one rank at random mid-run (SIGKILL; mpirun then ends the other), resume, and again: three rounds on 2
# ranks, each killed once a random number of new rows is in, then the rest on 1 process. After each kill the file holds rows of the reference only, whole, plus at
# most one torn last line.
seed=${MR_TEST_SEED:-$$}
RANDOM=$seed
echo "   kills drawn with MR_TEST_SEED=$seed"
crash="$tmp/crash.csv"
landed=0
for round in 1 2 3; do
    resume=()
    [ "$round" -gt 1 ] && resume=(--resume)
    "${mpi[@]}" "$bin" sweep "${args[@]}" -o "$crash" "${resume[@]}" >/dev/null 2>>"$tmp/crash.err" &
    launcher=$!
    # Kill when a random number (2 to 9) of new rows is in: at a random point of the run whatever its speed.
    have=$(rows "$crash" 2>/dev/null | wc -l)
    target=$((have + 2 + RANDOM % 8))
    while kill -0 "$launcher" 2>/dev/null && [ "$(rows "$crash" 2>/dev/null | wc -l)" -lt "$target" ]; do
        sleep 0.02
    done
    mapfile -t ranks < <(pgrep -P "$launcher")
    if [ "${#ranks[@]}" -eq 2 ] && kill -0 "$launcher" 2>/dev/null; then
        victim=${ranks[$((RANDOM % 2))]}
        kill -9 "$victim" 2>/dev/null
        wait "$launcher"
        rc=$?
        landed=$((landed + 1))
        n=$(rows "$crash" 2>/dev/null | wc -l)
        echo "   round $round: killed rank pid $victim at $target rows: mpirun exit $rc, $n of $total rows"
        check "round $round: mpirun reports the failure (exit $rc)" [ "$rc" -ne 0 ]
        check "round $round: no rank left running" none_running "${ranks[@]}"
        extra=$(comm -13 <(values "$tmp/ref.csv" | sort) <(values "$crash" | sort))
        check "round $round: every complete line is a line of the reference" [ -z "$extra" ]
    else
        wait "$launcher"
        echo "   round $round: the run ended before the kill (exit $?)"
        break
    fi
done
check "kills landed mid-run ($landed of 3)" [ "$landed" -ge 2 ]
expect "a single process resumes what the ranks left" 0 "is complete" -- "$bin" sweep "${args[@]}" -o "$crash" --resume
check "... no sample twice" [ -z "$(rows "$crash" | cut -d, -f1 | sort -n | uniq -d)" ]
check "... all $total samples, in order" [ "$(rows "$crash" | cut -d, -f1 | tr '\n' ' ')" = "$(seq 0 $((total - 1)) | tr '\n' ' ')" ]
if same_as_ref "$crash"; then ok_rows=1; else ok_rows=0; head -5 "$tmp/diff" | sed 's/^/      /'; fi
check "... the uninterrupted file (seconds, command line aside)" [ "$ok_rows" -eq 1 ]

# The other way round: a single process killed, 2 ranks resume (and cut its torn line, if any).
"$bin" sweep "${args[@]}" -o "$tmp/single_crash.csv" 2>/dev/null &
pid=$!
sleep "$(printf '%d.%03d' $((ref_ms * 3 / 10 / 1000)) $((ref_ms * 3 / 10 % 1000)))"
kill -9 "$pid" 2>/dev/null
wait "$pid" 2>/dev/null
printf '39,0.0012' >>"$tmp/single_crash.csv"
before=$(rows "$tmp/single_crash.csv" | wc -l)
expect "2 ranks resume a single process's file ($before lines there)" 0 "removed a torn last line" -- \
    "${mpi[@]}" "$bin" sweep "${args[@]}" -o "$tmp/single_crash.csv" --resume
if same_as_ref "$tmp/single_crash.csv"; then ok_rows=1; else ok_rows=0; head -5 "$tmp/diff" | sed 's/^/      /'; fi
check "... the uninterrupted file" [ "$ok_rows" -eq 1 ]
sum=$(md5sum <"$tmp/single_crash.csv")
expect "2 ranks resume a finished file: nothing to do" 0 "nothing to do" -- \
    "${mpi[@]}" "$bin" sweep "${args[@]}" -o "$tmp/single_crash.csv" --resume
check "... not a byte changed" [ "$(md5sum <"$tmp/single_crash.csv")" = "$sum" ]

finish
