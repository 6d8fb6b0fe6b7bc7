#!/usr/bin/env bash
# faults.sh — allocation and I/O fault injection over the main commands (issue 16, part 7; docs/reliability.md).
#
# Usage: scripts/faults.sh [BUILD [STEP [ONLY]]]     (make faults: BUILD=build/faults, STEP=1, every command)
#   BUILD  a fault build (make faults builds build/faults: ASan + UBSan + LSan, the tool linked with
#          tests/fault_inject.c, which fails the N-th allocation or I/O call it is told to)
#   STEP   try every STEP-th N only (1: every N; a quick pass: 7)
#   ONLY   run one scenario (its name, e.g. render-png), or several separated by commas
#
# For each scenario (a command on small inputs made here): one fault-free run gives the reference outputs and the
# number of allocations A and I/O calls W the command makes (fault_inject.c: MR_FAULT_COUNT_FILE). Then for every
# N in 1..A the N-th allocation fails, once (one-shot) and from there on (persistent, MR_FAULT_PERSIST=1), and the
# same for N in 1..W and the I/O calls. Each run passes when:
#   - it ends by itself (no hang: 120 s), with one line "matremap ...: error:" naming the injected cause, last on
#     stderr (before it only progress lines the fault-free run printed too, figures aside), and the exit code of
#     that cause (cli.h): 3 and "out of memory" for an allocation, 2 and the system's "No space left on device"
#     or "Input/output error" for an I/O call (a file that cannot be written); or with exit 0 and outputs equal
#     to the reference (the failure was legitimately recovered from);
#   - ASan, LSan and UBSan report nothing (their logs go to files, so stderr is the command's own);
#   - it leaves no partial output: after a failure the output folder is as empty as before (no output file, no
#     temporary file, no scratch folder); the exceptions are the scenario kinds below;
#   - the inputs are unchanged (sha256 of every input before and after).
# Scenario kinds: "atomic" (all of the above); "sweep" and "cache" (a sweep file and convert --direct's cache are
# crash-safe by design: the rows kept so far may stay, but nothing else, and a fault-free rerun, with --resume for
# the sweep, must then give the reference outputs); "report" (the report folder is another helper's subject: only no
# temporary file may be left, besides exit code, message and sanitizers).
# Prints one line per scenario and mode, the problems found, and a table for docs/reliability.md; exit status 1 if
# any run failed. Runs with OMP_NUM_THREADS=1, so that the N-th call is the same call in every run.
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-build/faults}
step=${2:-1}
only=${3:-}
case $build in /*) ;; *) build=$root/$build ;; esac
bin=$build/bin/matremap
if ! nm "$bin" 2>/dev/null | grep -q __wrap_malloc; then
    echo "faults.sh: $bin is not a fault build (make faults builds build/faults)" >&2
    exit 2
fi
for tool in oiiotool python3 sha256sum timeout; do
    command -v $tool >/dev/null || { echo "faults.sh: needs $tool" >&2; exit 2; }
done

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
in=$work/in out=$work/out ref=$work/ref san=$work/san
mkdir -p "$in" "$out" "$ref" "$san"
export OMP_NUM_THREADS=1
# Sanitizer reports go to files named after the process (a run passes only if none appears); LeakSanitizer is on
# (ASan's default on Linux, said explicitly).
export ASAN_OPTIONS="detect_leaks=1:log_path=$san/asan:handle_abort=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:log_path=$san/ubsan"
export LSAN_OPTIONS="log_path=$san/lsan"
unset MR_FAULT_ALLOC MR_FAULT_IO MR_FAULT_PERSIST MR_FAULT_TRACE

# ---- inputs ---------------------------------------------------------------------------------------------------
cd "$in"
oiiotool --pattern checker:width=2:height=2:color1=0.8,0.3,0.2:color2=0.2,0.5,0.7 8x8 3 -d uint8 -o diff.png
oiiotool --pattern checker:width=4:height=4:color1=0.04,0.04,0.04:color2=0.9,0.8,0.5 8x8 3 -d uint8 -o spec.png
oiiotool --pattern fill:top=0.2:bottom=0.9 8x8 1 -d uint8 -o gloss.png
oiiotool diff.png --ch R,G,B,A=1.0 -o diffa.png
oiiotool spec.png gloss.png --chappend -o specgloss.png
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 3/3 2/2\nf 1/1 2/2 4/3\nf 1/1 4/3 3/2\nf 2/1 3/2 4/3\n' \
    > tet.obj # a tetrahedron for render --mesh
"$bin" render ggx diffuse=0.5 f0=0.04 alpha=0.3 --size 16 -o a.png 2>/dev/null &&
    "$bin" render ggx diffuse=0.5 f0=0.04 alpha=0.35 --size 16 -o b.png 2>/dev/null &&
    "$bin" sweep --from ward diffuse=0 --to ggx diffuse=0 --grid alpha=0.03:0.4:4:log specular=0.03:0.25:3 --size 16 \
        -o wg.csv 2>/dev/null &&
    "$bin" sweep --from ggx-metallic alpha=0.2 --to ggx-metallic alpha=0.2 --hold alpha --random 12 --size 16 \
        -o on.csv 2>/dev/null &&
    "$bin" learn wg.csv -o wg.mrt >/dev/null 2>&1 || { echo "faults.sh: cannot make the inputs" >&2; exit 1; }
# A small spec-gloss glTF: a triangle, one material with both textures (files), one with an embedded (data URI)
# diffuse texture and factors.
python3 - <<'EOF'
import base64, json, struct
pos = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
uv = struct.pack("<6f", 0, 0, 1, 0, 0, 1)
open("tri.bin", "wb").write(pos + uv)
png = base64.b64encode(open("diff.png", "rb").read()).decode()
SG = "KHR_materials_pbrSpecularGlossiness"
prim = lambda m: {"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": m}
d = {"asset": {"version": "2.0"}, "extensionsUsed": [SG],
     "buffers": [{"uri": "tri.bin", "byteLength": 60}],
     "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 24}],
     "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
                   {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}],
     "images": [{"uri": "diffa.png"}, {"uri": "specgloss.png"}, {"uri": "data:image/png;base64," + png}],
     "textures": [{"source": 0}, {"source": 1}, {"source": 2}],
     "materials": [{"name": "files", "extensions": {SG: {"diffuseTexture": {"index": 0},
                                                        "specularGlossinessTexture": {"index": 1}}}},
                   {"name": "embedded", "extensions": {SG: {"diffuseTexture": {"index": 2},
                                                           "specularFactor": [0.2, 0.2, 0.2], "glossinessFactor": 0.6}}}],
     "meshes": [{"primitives": [prim(0), prim(1)]}], "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0}
json.dump(d, open("sg.gltf", "w"))
EOF
rm -rf "$san"/*
sha256sum -- * > "$work/inputs.sha256"

# ---- scenarios: NAME KIND ARGS... (run in $out, inputs in $in) -----------------------------------------------
scenarios=()
args_of=()
kinds=()
add() { scenarios+=("$1"); kinds+=("$2"); shift 2; args_of+=("$(printf '%q ' "$@")"); }
add render-png atomic render ggx diffuse=@"$in/diff.png" f0=0.04 alpha=0.3 --size 16 -o r.png
add render-mesh atomic render ggx diffuse=@"$in/diff.png" alpha=0.3 --mesh "$in/tet.obj" --size 16 -o m.png
add render-exr atomic render gltf base_color=0.8,0.2,0.1 metallic=0.4 roughness=@"$in/gloss.png" --size 16 -o r.exr
add ssim atomic ssim "$in/a.png" "$in/b.png" --map map.png
add remap atomic remap --from ggx alpha=0.2 --to ward --size 16 --images rm
add sweep sweep sweep --from ward diffuse=0 --to ggx diffuse=0 --grid alpha=0.03:0.4:3:log specular=0.03:0.25:2 \
    --size 16 --threads 1 -o s.csv
add dataset atomic dataset -o pairs.csv --samples 4 --size 16
add train atomic train "$in/on.csv" -o w.mlp --hidden 4 --epochs 3 --test "$in/on.csv"
add learn-parametric atomic learn "$in/wg.csv" -o t.mrt
add learn-svr atomic learn "$in/wg.csv" -o t.mrt --method svr --svr-c 1 --svr-gamma 1 --svr-epsilon 0.01
add learn-mlp atomic learn "$in/wg.csv" -o t.mrt --method mlp --hidden 4 --epochs 5 --plots plots
add convert atomic convert --from ward --to ggx alpha=@"$in/gloss.png" specular=@"$in/spec.png" \
    diffuse=@"$in/diff.png" --transform "$in/wg.mrt" --format png -o c_
add spec2metal atomic spec2metal --diffuse "$in/diff.png" --specular "$in/spec.png" --glossiness "$in/gloss.png" -o m
add metal2spec atomic metal2spec --basecolor "$in/diff.png" --metallic "$in/gloss.png" --roughness "$in/gloss.png" \
    -o s
add gltf-spec2metal atomic gltf spec2metal "$in/sg.gltf" -o o.gltf --method weighted
add convert-direct cache convert --from ward --to ggx alpha=0.2 specular=@"$in/spec.png" diffuse=0.3 --direct \
    --cache cache.csv --size 16 --format png -o d_
add report report report -o rep --size 16 ggx alpha=0.3 -- ward

# ---- one run ---------------------------------------------------------------------------------------------------
log=$work/problems.txt
: > "$log"
problem() { # SCENARIO MODE N WHAT (judge runs in a subshell: the log file is the count)
    printf '%s %s N=%s: %s\n' "$1" "$2" "$3" "$4" | tee -a "$log" >&2
}

# run_cmd ARGS-STRING: runs in a fresh $out, stdout/stderr in $work/stdout, $work/stderr; sets rc.
run_cmd() {
    rm -rf "$out" "$san"/* "$work/count"
    mkdir -p "$out"
    (cd "$out" && eval "MR_FAULT_COUNT_FILE=\$work/count timeout 120 \"\$bin\" $1" >"$work/stdout" 2>"$work/stderr")
    rc=$?
}

# The output folder's files, contents normalised: a sweep's seconds column and a report's timings vary.
snapshot() { # DIR -> listing on stdout
    (cd "$1" && find . -type f | LC_ALL=C sort | while read -r f; do
        case $f in
            *.csv) if grep -q ',seconds$' "$f"; then # a sweep's: the time each row took
                       printf '%s ' "$f"; sed -E '/^[0-9]/s/,[^,]*$//' "$f" | sha256sum | cut -d' ' -f1
                   else sha256sum "$f" | awk '{print $2, $1}'; fi ;;
            *.json) printf '%s ' "$f"; sed -E 's/"seconds": [^,}]*//g' "$f" | sha256sum | cut -d' ' -f1 ;;
            *.html) printf '%s ' "$f"; sed -E 's/[0-9.]+ s\b//g' "$f" | sha256sum | cut -d' ' -f1 ;;
            *) sha256sum "$f" | awk '{print $2, $1}' ;;
        esac
    done)
}

# A figure of the last run's count file (fault_inject.c); 0 when there is none (a run that crashed writes none).
count_of() {
    local v
    v=$(sed -n "s/^$1 //p" "$work/count" 2>/dev/null)
    echo "${v:-0}"
}

# judge SCENARIO KIND MODE N CAUSE-PATTERN EXIT: checks the run just made; prints the outcome class on stdout.
judge() {
    local name=$1 kind=$2 mode=$3 n=$4 cause=$5 code=$6 bad=""
    if ls "$san"/* >/dev/null 2>&1; then
        bad="sanitizer: $(grep -m1 -hE 'ERROR|SUMMARY|runtime error' "$san"/* | cut -c1-160)"
    elif [ "$rc" -eq 124 ]; then
        bad="hang (killed after 120 s)"
    elif [ "$rc" -ge 128 ]; then
        bad="crash (exit $rc)"
    fi
    if [ -z "$bad" ] && ! (cd "$in" && sha256sum --quiet -c "$work/inputs.sha256" >/dev/null 2>&1); then
        bad="an input changed"
    fi
    if [ -z "$bad" ] && [ "$rc" -eq 0 ]; then
        if [ "$kind" = report ]; then
            [ -z "$(find "$out" -name '*.tmp.*')" ] || bad="exit 0 with a temporary file left"
        elif ! snapshot "$out" | cmp -s - "$ref/$name.snapshot"; then
            bad="exit 0 with outputs unlike the fault-free run's: $(snapshot "$out" | diff - "$ref/$name.snapshot" |
                grep '^[<>]' | head -3 | tr '\n' ' ')"
        fi
        [ -z "$bad" ] && { echo recovered; return; }
    fi
    if [ -z "$bad" ] && [ "$rc" -ne "$code" ]; then bad="exit $rc, not $code: $(cut -c1-200 "$work/stderr")"; fi
    if [ -z "$bad" ]; then
        local lines
        # The last line is the one message; lines before it may only be progress the fault-free run printed too.
        lines=$(wc -l < "$work/stderr")
        local last extra
        last=$(tail -n 1 "$work/stderr")
        extra=$(head -n -1 "$work/stderr" | tr '0-9' '#' | grep -vxF -f "$ref/$name.stderr" | head -2 | tr '\n' '|')
        if [ "$lines" -lt 1 ]; then
            bad="nothing on stderr"
        elif [ -n "$extra" ]; then
            bad="$lines lines on stderr, not only the message and the usual progress: ${extra:0:200}"
        elif [[ ! $last =~ ^matremap\ [a-z0-9]+:\ error:\  ]]; then
            bad="the last line is not 'matremap CMD: error: ...': ${last:0:200}"
        elif [ "$(grep -c ': error: ' "$work/stderr")" -ne 1 ]; then
            bad="more than one error line: $(grep ': error: ' "$work/stderr" | head -2 | cut -c1-150 | tr '\n' '|')"
        elif ! grep -qiE "$cause" <<< "$last"; then
            bad="message does not name the cause: ${last:0:240}"
        fi
    fi
    local kept="" again=""
    case $kind in
        sweep) kept=s.csv again=--resume ;;
        cache) kept=cache.csv ;;
    esac
    if [ -z "$bad" ]; then
        local left
        case $kind in
            report) left=$(cd "$out" && find . -name '*.tmp.*' | head -3 | tr '\n' ' ') ;;
            *) left=$(cd "$out" && find . -mindepth 1 ! -name "${kept:-.}" | head -3 | tr '\n' ' ') ;;
        esac
        [ -n "$left" ] && bad="partial output left after exit $rc: $left"
    fi
    if [ -z "$bad" ] && [ -n "$kept" ] && [ -e "$out/$kept" ]; then
        # The rows kept must lead a fault-free rerun to the reference.
        (cd "$out" && eval "timeout 120 \"\$bin\" ${args_of[$index]} $again" >/dev/null 2>"$work/rerun.err")
        if [ $? -ne 0 ] || ! snapshot "$out" | cmp -s - "$ref/$name.snapshot"; then
            bad="the $kept left after exit $rc does not lead a rerun to the reference: $(head -c 200 "$work/rerun.err")"
            bad+="$(snapshot "$out" | diff - "$ref/$name.snapshot" | grep '^[<>]' | head -2 | tr '\n' ' ')"
        fi
    fi
    if [ -n "$bad" ]; then
        problem "$name" "$mode" "$n" "$bad"
        if [ -n "${MR_FAULT_KEEP:-}" ]; then cp "$work/stderr" "$MR_FAULT_KEEP.$name.$mode.$n.stderr"; fi
        echo problem
    else
        echo "exit$rc"
    fi
}

# ---- the scenarios -------------------------------------------------------------------------------------------
table=$work/table.txt
: > "$table"
start=$(date +%s)
for index in "${!scenarios[@]}"; do
    name=${scenarios[$index]}
    kind=${kinds[$index]}
    if [ -n "$only" ] && [[ ",$only," != *",$name,"* ]]; then continue; fi
    run_cmd "${args_of[$index]}"
    if [ "$rc" -ne 0 ] || ls "$san"/* >/dev/null 2>&1; then
        problem "$name" reference 0 "the fault-free run failed (exit $rc): $(head -c 300 "$work/stderr")"
        continue
    fi
    snapshot "$out" > "$ref/$name.snapshot"
    tr '0-9' '#' < "$work/stderr" > "$ref/$name.stderr" # its progress lines, figures blanked
    allocs=$(count_of alloc)
    ios=$(count_of io)
    row="$name $allocs $ios"
    injected=0 spared=0
    for mode in alloc alloc-persistent io io-persistent; do
        case $mode in
            alloc*) total=$allocs var=MR_FAULT_ALLOC cause='out of memory|no memory|cannot allocate memory' code=3 ;;
            io*) total=$ios var=MR_FAULT_IO cause='no space left on device|input/output error' code=2 ;;
        esac
        persist=0
        [[ $mode == *persistent ]] && persist=1
        declare -A outcome=()
        runs=0
        for ((n = 1; n <= total; n += step)); do
            export "$var=$n" MR_FAULT_PERSIST=$persist
            run_cmd "${args_of[$index]}"
            unset MR_FAULT_ALLOC MR_FAULT_IO MR_FAULT_PERSIST
            injected=$((injected + $(count_of injected_alloc) + $(count_of injected_io)))
            spared=$((spared + $(count_of spared)))
            o=$(judge "$name" "$kind" "$mode" "$n" "$cause" "$code")
            outcome[$o]=$((${outcome[$o]:-0} + 1))
            runs=$((runs + 1))
        done
        summary="runs $runs: exit 2: ${outcome[exit2]:-0}, exit 3: ${outcome[exit3]:-0}, recovered: ${outcome[recovered]:-0}"
        summary+=", problems: ${outcome[problem]:-0}"
        printf '%-17s %-16s %6s calls  %s\n' "$name" "$mode" "$total" "$summary"
        row+=" $runs ${outcome[exit2]:-0} ${outcome[exit3]:-0} ${outcome[recovered]:-0} ${outcome[problem]:-0}"
        unset outcome
    done
    echo "$row $injected $spared" >> "$table"
done
elapsed=$(($(date +%s) - start))

echo
echo "Per scenario: calls counted in the fault-free run, then per mode (alloc, alloc persistent, io, io persistent):"
echo "runs: exit 2 / exit 3 / recovered (exit 0, outputs as without the fault) / problems; then the failures injected"
echo "over all runs (persistent runs inject many) and the allocations of nlohmann/json's destructor let through"
echo "(fault_inject_new.cpp). Step $step, ${elapsed} s."
printf '| %s | %s | %s | %s | %s | %s | %s | %s | %s |\n' scenario allocs "I/O calls" "alloc one-shot" \
    "alloc persistent" "I/O one-shot" "I/O persistent" "failures injected" spared
printf '|---|---:|---:|---|---|---|---|---:|---:|\n'
total_runs=0 total_injected=0
while read -r name a w r1 a2 a3 a0 ap r2 b2 b3 b0 bp r3 c2 c3 c0 cp r4 d2 d3 d0 dp inj sp; do
    printf '| %s | %s | %s | %s | %s | %s | %s | %s | %s |\n' "$name" "$a" "$w" "$r1: $a2/$a3/$a0/$ap" \
        "$r2: $b2/$b3/$b0/$bp" "$r3: $c2/$c3/$c0/$cp" "$r4: $d2/$d3/$d0/$dp" "$inj" "$sp"
    total_runs=$((total_runs + r1 + r2 + r3 + r4))
    total_injected=$((total_injected + inj))
done < "$table"
echo "In all: $total_runs runs, $total_injected failures injected."
echo
problems=$(wc -l < "$log")
if [ "$problems" -gt 0 ]; then
    echo "faults.sh: $problems problem(s):"
    cat "$log"
    exit 1
fi
echo "faults.sh: no problem: every injected fault ended in a clean failure or a correct recovery"
