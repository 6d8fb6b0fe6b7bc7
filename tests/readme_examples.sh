#!/usr/bin/env bash
# The README's worked examples, run as a new user runs them: top to bottom, in one empty folder, each command as
# printed (its "$ " line and the lines its trailing backslashes continue). Every command must exit 0 and must not
# change a file that an earlier command wrote (no example overwrites another's output); the README's learned
# transforms must give its texel within 5 % of --direct. Two things differ from a reader's run, and are said here:
# the random sweeps draw 400 samples instead of 5000 (the README's text: any count from 300 on; 5000 takes
# minutes), and mpirun gets --allow-run-as-root --oversubscribe when the test runs as root on fewer cores than
# ranks (the flags 'matremap sweep --help' names for that case); without mpirun or the MPI module that line runs
# as one process, which writes the same file. Ends with "N passed, N failed".
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
build="${MR_BUILD:-$root/build}"
shared="${MR_SHARED:-$root/../shared}"
source "$(dirname "$0")/lib/cli_harness.sh"

# The console blocks of "Worked examples", as one command per line (continuations joined).
python3 - "$root/README.md" > "$tmp/commands.txt" <<'PY'
import sys
text = open(sys.argv[1]).read()
section = text[text.index("## Worked examples"):text.index("Every command has `--help`")]
commands, inside, pending = [], False, None
for line in section.split("\n"):
    if line.startswith("```"):
        inside = line.startswith("```console")
        continue
    if not inside:
        continue
    if pending is not None:
        pending += " " + line.strip()
    elif line.startswith("$ "):
        pending = line[2:]
    else:
        continue  # what a command prints
    if pending.endswith("\\"):
        pending = pending[:-1].rstrip()
        continue
    commands.append(pending)
    pending = None
print("\n".join(commands))
PY
check "the README has worked examples" test "$(wc -l < "$tmp/commands.txt")" -gt 30

have_mpi=0
if command -v mpirun >/dev/null 2>&1 && [ -e "$build/lib/matremap/libmatremap-mpi.so" ]; then have_mpi=1; fi
# Under AddressSanitizer (make asan) Open MPI's own allocations outlive MPI_Finalize: its libraries' leaks are
# left to it, as tests/sweep_mpi.sh does (ignored by an ordinary build).
printf 'leak:%s\n' libopen-pal.so libopen-rte.so libmpi.so libpmix.so libhwloc.so libevent mca_ ld-linux >"$tmp/lsan.supp"
mpi_env="ASAN_OPTIONS=${ASAN_OPTIONS:+$ASAN_OPTIONS:}fast_unwind_on_malloc=0"
mpi_env="$mpi_env LSAN_OPTIONS=${LSAN_OPTIONS:+$LSAN_OPTIONS:}suppressions=$tmp/lsan.supp:print_suppressions=0"
mpi_flags=""
[ "$(id -u)" = 0 ] && mpi_flags="--allow-run-as-root"
[ "$(nproc)" -lt 8 ] && mpi_flags="$mpi_flags --oversubscribe"

# One bash runs them all (the examples set variables and change folder); after each command, the folder's files
# are compared with those before it.
mkdir -p "$tmp/examples"
{
    echo "snapshot() { python3 '$root/tests/lib/tree_digest.py' \"\$1\"; }"
    n=0
    while IFS= read -r cmd; do
        n=$((n + 1))
        run="$cmd"
        case "$cmd" in
        export\ PATH=*)
            run="export PATH=\"$build/bin:\$PATH\" S=\"$shared/assets\" D=\"$root/data\"" ;;
        cd\ \"\$\(mktemp\ -d\)\")
            run="cd '$tmp/examples'" ;;
        mpirun\ *)
            # Without MPI, the same sweep in one process: the file is the same (docs/sweep.md).
            if [ "$have_mpi" = 1 ]; then run="env $mpi_env mpirun $mpi_flags ${cmd#mpirun }"; else run="${cmd#mpirun -np * }"; fi ;;
        esac
        run=${run//--random 5000/--random 400}
        printf 'before=$(snapshot .)\n'
        printf '{ %s\n} > %q 2>&1\n' "$run" "$tmp/cmd$n.log"
        printf 'echo "rc $? %d"\n' "$n"
        printf 'python3 %q "$before" "$(snapshot .)" %d\n' "$root/tests/lib/tree_digest.py" "$n"
    done < "$tmp/commands.txt"
} > "$tmp/run.sh"
(cd "$root" && bash "$tmp/run.sh") > "$tmp/results.txt" 2>&1

n=0
while IFS= read -r cmd; do
    n=$((n + 1))
    rc=$(grep -E "^rc [0-9]+ $n\$" "$tmp/results.txt" | cut -d' ' -f2)
    if [ "$rc" = 0 ]; then
        echo "ok    example $n runs: ${cmd:0:90}"; passed=$((passed + 1))
    else
        echo "FAIL  example $n exits ${rc:-?}: $cmd"; sed 's/^/      /' "$tmp/cmd$n.log" | tail -5
        failed=$((failed + 1))
    fi
    if grep -q "^changed $n " "$tmp/results.txt"; then
        echo "FAIL  example $n writes over an earlier example's file:"
        grep "^changed $n " "$tmp/results.txt" | sed 's/^/      /'
        failed=$((failed + 1))
    fi
done < "$tmp/commands.txt"
check "no example changed a file an earlier one wrote" bash -c "! grep -q '^changed ' '$tmp/results.txt'"
# Files the examples are said to write.
for f in plastic.exr cycles_mask.exr ssim_map.png avocado_basecolor.png out/floppy.gltf out/floppy.bin \
    out/ggx_alpha.exr out/ggx_flags.png ward_ggx.mrt ward_ggx_random.mrt ward_ggx_merged.csv my.mlp \
    out/report/index.html bottle.png; do
    check "the examples wrote $f" test -s "$tmp/examples/$f"
done

# The README's transforms against --direct on its texel (the learn example's grid, and the random sweep's).
texel="diffuse=0.5 specular=0.2 alpha=0.1"
# shellcheck disable=SC2086
"$build/bin/matremap" convert --from ward --to ggx $texel --direct --json > "$tmp/direct.json" 2>/dev/null
for t in ward_ggx.mrt ward_ggx_random.mrt; do
    # shellcheck disable=SC2086
    "$build/bin/matremap" convert --from ward --to ggx $texel --transform "$tmp/examples/$t" --json \
        > "$tmp/learned.json" 2>/dev/null
    check "$t gives the README's texel within 5 % of --direct" python3 -c "
import json, sys
d = json.load(open('$tmp/direct.json'))['values']; l = json.load(open('$tmp/learned.json'))['values']
off = max([abs(l['alpha'] - d['alpha']) / d['alpha']] + [abs(l[k][c] - d[k][c]) / d[k][c] for k in ('f0', 'diffuse') for c in range(3)])
print('largest relative difference', off); sys.exit(0 if off <= 0.05 else 1)"
done
finish
