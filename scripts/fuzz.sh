#!/usr/bin/env bash
# fuzz.sh — runs every libFuzzer target of tests/fuzz/ (made by `make fuzz`) for a time or a number of runs, one
# after another on one core, and records what each did. Usage:
#   scripts/fuzz.sh BUILD FUZZ_BUILD SECONDS [RUNS] [TARGET...]
# SECONDS: each target's time (0 = no limit); RUNS: each target's executions (0 or empty = no limit; the first
# limit reached stops it). The corpus is made once from BUILD's tools (tests/fuzz/make-corpus.sh), into
# FUZZ_BUILD/corpus; what the fuzzer finds new goes to FUZZ_BUILD/work/NAME, kept between runs, so that a
# second run goes on from the first. A finding (crash, leak, sanitizer report, timeout, out of memory) is written
# to FUZZ_BUILD/findings/NAME-*; the script then exits 1 after the others have run. Every run appends a line to
# FUZZ_BUILD/runs.tsv: date, commit, target, seconds, executions, executions/s, findings.
set -uo pipefail
build=$1
fuzz_build=$2
seconds=${3:-60}
runs=${4:-0}
shift 4 2>/dev/null || shift $#
root=$(cd "$(dirname "$0")/.." && pwd)
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(gltf png jpeg exr hdr mlp mrt sweep cli_value obj mtlx)

"$root/tests/fuzz/make-corpus.sh" "$build" "$fuzz_build/corpus" || { echo "fuzz: cannot make the corpus" >&2; exit 2; }
mkdir -p "$fuzz_build/findings" "$fuzz_build/logs"
commit=$(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)
[ -f "$fuzz_build/runs.tsv" ] || printf 'date\tcommit\ttarget\tseconds\texecutions\texec_per_s\tfindings\n' \
    > "$fuzz_build/runs.tsv"
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
# One thread per execution: libFuzzer measures and mutates one input at a time, and the readers' OpenMP teams
# would only add noise (and other copies of the tool may be running).
export OMP_NUM_THREADS=1
failed=0
printf '%-10s %8s %14s %10s  %s\n' target seconds executions "exec/s" result
for t in "${targets[@]}"; do
    binary=$fuzz_build/bin/fuzz_$t
    [ -x "$binary" ] || { echo "fuzz: $binary is missing (make fuzz builds it)" >&2; failed=1; continue; }
    mkdir -p "$fuzz_build/work/$t"
    before=$(ls "$fuzz_build/findings" | grep -c "^$t-" || true)
    log=$fuzz_build/logs/$t.log
    start=$(date +%s)
    dict=()
    [ -f "$root/tests/fuzz/$t.dict" ] && dict=(-dict="$root/tests/fuzz/$t.dict")
    # Inputs grow up to max_len: 64 kB for text and glTF (a seed is at most 32 kB), 256 kB for images.
    max_len=262144
    case $t in gltf|mlp|mrt|sweep|cli_value|obj|mtlx) max_len=65536 ;; esac
    run_target() {
        "$binary" -max_total_time="$seconds" -runs="$([ "$runs" -gt 0 ] && echo "$runs" || echo -1)" \
            -print_final_stats=1 -close_fd_mask=3 -timeout=20 -rss_limit_mb=3072 -malloc_limit_mb=3072 \
            -max_len=$max_len -artifact_prefix="$fuzz_build/findings/$t-" "${dict[@]}" \
            "$fuzz_build/work/$t" "$fuzz_build/corpus/$t" > "$log" 2>&1
    }
    run_target
    rc=$?
    # LeakSanitizer's own tracer (the ptrace helper of its leak check at exit) sometimes dies of SIGSEGV on a loaded
    # machine, after every input has run and passed: libFuzzer then saves the empty input as a "crash". That is the
    # tool failing, not a reader: the log is kept beside, the empty artifact removed, and the target run once more;
    # a second failure of any kind is a finding.
    empty=$fuzz_build/findings/$t-crash-da39a3ee5e6b4b0d3255bfef95601890afd80709
    note=""
    if [ "$rc" -ne 0 ] && [ -f "$empty" ] && grep -q '^Done [0-9]* runs' "$log" &&
        grep -q 'LeakSanitizer has encountered a fatal error' "$log" &&
        [ "$(ls "$fuzz_build/findings" | grep -c "^$t-")" -eq $((before + 1)) ]; then
        mv "$log" "$log.lsan-tracer"
        rm -f "$empty"
        run_target
        rc=$?
        note=" (run twice: LeakSanitizer's tracer died at exit the first time, $log.lsan-tracer)"
    fi
    elapsed=$(( $(date +%s) - start ))
    execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
    rate=$(grep -o 'stat::average_exec_per_sec: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
    after=$(ls "$fuzz_build/findings" | grep -c "^$t-" || true)
    found=$((after - before))
    result=ok$note
    if [ "$rc" -ne 0 ] || [ "$found" -gt 0 ]; then
        result="FINDING (exit $rc; $log, $fuzz_build/findings/$t-*)"
        failed=1
    fi
    printf '%-10s %8s %14s %10s  %s\n' "$t" "$elapsed" "${execs:-?}" "${rate:-?}" "$result"
    printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$(date -u +%FT%TZ)" "$commit" "$t" "$elapsed" "${execs:-0}" "${rate:-0}" \
        "$found" >> "$fuzz_build/runs.tsv"
done
exit $failed
