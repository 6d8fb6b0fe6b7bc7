#!/usr/bin/env bash
# make bench: prints benchmark figures and writes them into docs/performance.md (between the bench:render,
# bench:metrics, bench:remap, bench:direct, bench:mpi, bench:workflow, bench:gltf and bench:report-accuracy markers) and
# docs/rendering.md (bench:envlight, bench:mesh, bench:reflection). Asserts nothing. Peers are measured in the same run: Blender Cycles
# renders the same fit scene with the Principled BSDF at 16 spp (scripts/cycles_fit_scene.py), and the ratio to
# our render time is printed.
# Usage: scripts/bench.sh BUILD [--quick] [--only brdf-grad|report-accuracy|reflection|workflow|png|gltf|library|remap|fit-engine|remap-processes|direct|learn|mpi]
#   --only NAME runs one section and rewrites only its markers (the full run takes long; sections written as
#   functions below can be run alone). From make: make bench BENCH_ARGS="--only report-accuracy".
set -euo pipefail
build=${1:-build}
shift || true
quick=
only=
while [ $# -gt 0 ]; do
    case $1 in
        --quick) quick=--quick ;;
        --only) only=${2:?--only needs a section name}; shift ;;
        *) echo "bench.sh: unknown argument '$1'" >&2; exit 1 ;;
    esac
    shift
done
root=$(cd "$(dirname "$0")/.." && pwd)
bin="$root/$build/bin/matremap"
work="$root/$build/bench"
mkdir -p "$work"
report="$work/render.md"

# shellcheck source=scripts/lib/timing.sh
. "$root/scripts/lib/timing.sh"

# Replace the sections between the markers in docs/performance.md (or DOC) with this run's reports.
perf="$root/docs/performance.md"
shared=${MR_SHARED:-$root/../shared}
replace_section() { # NAME REPORT [DOC]
    local doc=${3:-$perf}
    [ -f "$doc" ] && grep -q "<!-- bench:$1:begin -->" "$doc" || return 0
    awk -v report="$2" -v begin="<!-- bench:$1:begin -->" -v end="<!-- bench:$1:end -->" '
        $0 == begin { print; while ((getline line < report) > 0) print line; skip = 1; next }
        $0 == end { skip = 0 }
        !skip { print }' "$doc" > "$doc.tmp" && mv "$doc.tmp" "$doc"
    echo "${doc#"$root"/} updated (section bench:$1)."
}

# What accuracy costs in `matremap report` (docs/performance.md, bench:report-accuracy): each spec-gloss
# asset of ../shared/assets against its `gltf spec2metal --method weighted` conversion, rendered as
# meshes under the studio map in 4 rotations, at environment sample counts N (size 256) and at sizes S (N 1024),
# each with the report's default reflection samples.
# Per run: the report's time for the original and the weighted conversion (the whole process, less the render
# of a third material, below), its render time (summary.json), the rest (load, plans, pictures, SSIM), the
# report's SSIM and its distance from the converged evaluation (N 16384 at the same size; S 512 at the same N),
# and the original's own pictures against the converged ones (matremap ssim on the PNGs the report writes).
# The `mean` conversion rides along as a third material (it shares the plan; only its render is extra): it is
# further from the original (SSIM 0.994 on the Duck against weighted's 0.9993), so it shows whether a larger
# difference is as stable. CesiumMilkTruck is the multi-material case: four materials (glass, paint, tyres,
# wheels) in one scene, two of them textured, rendered in one plan.
bench_report_accuracy() {
    echo
    echo "== matremap report on glTF meshes: time and SSIM stability against --env-samples and --size"
    local shared=${MR_SHARED:-$root/../shared}
    local env_map="$shared/assets/hdri/studio_small_03_1k.hdr" out="$work/report-accuracy"
    local table="$work/report-accuracy.md" rows="$work/report-accuracy/rows.tsv"
    local ns=(64 128 256 512 1024 2048 4096) sizes=(128 192 256 384 512)
    # The sweeps are centred on the report's earlier defaults (N 1024, 256²), from which the table chose the
    # present ones (report.h: N 256, 384²); candidates N:S are each checked against N = default_n at their
    # size and at the largest size.
    local default_n=1024 default_size=256 converged_n=16384 thresholds="0.002 0.0002"
    local candidates=(256:384)
    [ "$quick" = --quick ] && ns=(64 256 1024) sizes=(128 256 384) converged_n=4096
    local assets=(Avocado-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Avocado.gltf
                  Duck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Duck.gltf FloppyDisk-sketchfab/scene.gltf
                  CesiumMilkTruck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/CesiumMilkTruck.gltf)
    if [ ! -f "$env_map" ] || [ ! -d "$shared/assets/specgloss" ]; then
        echo "(no assets at $shared/assets: the report accuracy section was skipped)"
        echo "Report accuracy skipped: ../shared/assets was not found in this run." > "$table"
        replace_section report-accuracy "$table"
        return 0
    fi
    # BENCH_REUSE=1 keeps the report folders of an earlier run, their times included, and redoes only what is
    # missing and the tables (for work on the tables; a real measurement starts afresh).
    [ -n "${BENCH_REUSE:-}" ] || rm -rf "$out"
    mkdir -p "$out"
    "$bin" render lambert --exposure 0 --size "$default_size" -o "$out/black.png" >/dev/null # RMS = RMSE to black
    # One report (NAME SOURCE N SIZE) into $out/NAME/nN_sSIZE, once per folder (the default setting is in both
    # sweeps); its wall and CPU seconds, medians of 3 runs unless the first takes 10 s or more (then the noise is
    # a few per cent of the time and the runs would dominate the bench), go to the folder's `seconds`. A failed
    # run is shown and tried once more: on a machine shared with other jobs a run can be killed for memory.
    accuracy_report() {
        local dir="$out/$1/n$3_s$4" walls=() cpus=() t run tries=0
        [ -f "$dir/seconds" ] && return 0
        for run in 1 2 3; do
            until t=$(times_of "$out/report.log" "$bin" report -o "$dir" --env "$env_map" --env-samples "$3" \
                      --size "$4" --label original "$2" -- --label weighted "$out/$1/weighted/out.gltf" \
                      -- --label mean "$out/$1/mean/out.gltf"); do
                echo "bench.sh: matremap report failed for $1 (N $3, size $4):" >&2
                tail -n 5 "$out/report.log" >&2
                tries=$((tries + 1))
                [ "$tries" -lt 2 ] || exit 1
            done
            walls+=("${t% *}")
            cpus+=("${t#* }")
            if [ "$quick" = --quick ] || awk -v t="${t% *}" 'BEGIN { exit !(t >= 10) }'; then break; fi
        done
        echo "$(printf '%s\n' "${walls[@]}" | median) $(printf '%s\n' "${cpus[@]}" | median)" > "$dir/seconds"
    }
    # The original's pictures in DIR against those in REF (same size), on the 8-bit PNGs the report shows (each
    # at its own automatic exposure): mean and lowest SSIM over the views and mean relative RMSE, as
    # "MEAN MIN REL". The lowest view catches a highlight the pattern puts where the converged render has none.
    picture_error() {
        local v json rms lines=""
        for v in 0 1 2 3; do
            json=$("$bin" ssim --json "$1/view${v}_material0.png" "$2/view${v}_material0.png")
            rms=$("$bin" ssim --json "$2/view${v}_material0.png" "$out/black.png" | sed -E 's/.*"rmse": ([^}]*)}.*/\1/')
            lines+="$(echo "$json" | sed -E 's/.*"ssim": ([^,]*), "rmse": ([^}]*)}.*/\1 \2/') $rms"$'\n'
        done
        printf '%s' "$lines" | awk '{ s += $1; m = (NR == 1 || $1 < m) ? $1 : m; r += $2 / $3 }
            END { printf "%.6f %.6f %.6f\n", s / NR, m, r / NR }'
    }
    # One line of $rows: NAME SWEEP N SIZE "PICTURE_SSIM PICTURE_MIN PICTURE_REL" and the report's own numbers.
    accuracy_row() {
        local dir="$out/$1/n$3_s$4" picture
        read -r -a picture <<< "$5"
        python3 -c 'import json, sys
d = json.load(open(sys.argv[1]))
m = d["materials"]
key = "mean_object_ssim" if "mean_object_ssim" in m[1] else "mean_ssim"  # over the object (issue 12)
print("%.6f\t%.6f\t%.9f\t%.9f" % (m[0]["seconds"] + m[1]["seconds"], m[2]["seconds"], m[1][key], m[2][key]))' \
            "$dir/summary.json" | {
            IFS=$'\t' read -r render extra ssim ssim_mean
            # The third material's render is taken off the wall time, and off the CPU time in the same proportion.
            printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$1" "$2" "$3" "$4" \
                "$(awk -v x="$extra" '{ printf "%.3f\t%.3f", $1 - x, $2 * ($1 - x) / $1 }' "$dir/seconds")" \
                "$render" "$ssim" "$ssim_mean" "${picture[0]}" "${picture[1]}" "${picture[2]}"
        } >> "$rows"
    }
    printf 'asset\tsweep\tn\tsize\tseconds\tcpu\trender\tssim\tssim_mean\tpicture_ssim\tpicture_min\tpicture_rel\n' \
        > "$rows"
    local asset source name n size method candidate
    for asset in "${assets[@]}"; do
        source="$shared/assets/specgloss/$asset"
        name=${asset%%-*}
        echo "-- $name"
        for method in weighted mean; do
            mkdir -p "$out/$name/$method"
            "$bin" gltf spec2metal "$source" -o "$out/$name/$method/out.gltf" --method "$method" \
                --overwrite-metal-rough --core-only >/dev/null # the conversion, not the artists' own values
        done
        for n in "${ns[@]}" "$converged_n"; do
            accuracy_report "$name" "$source" "$n" "$default_size"
        done
        for size in "${sizes[@]}"; do
            accuracy_report "$name" "$source" "$default_n" "$size"
        done
        for candidate in "${candidates[@]}"; do
            accuracy_report "$name" "$source" "${candidate%:*}" "${candidate#*:}"
            accuracy_report "$name" "$source" "$default_n" "${candidate#*:}"
        done
        for n in "${ns[@]}" "$converged_n"; do
            accuracy_row "$name" n "$n" "$default_size" \
                "$(picture_error "$out/$name/n${n}_s$default_size" "$out/$name/n${converged_n}_s$default_size")"
        done
        for size in "${sizes[@]}"; do
            accuracy_row "$name" s "$default_n" "$size" "- - -"
        done
        for candidate in "${candidates[@]}"; do
            accuracy_row "$name" c "${candidate%:*}" "${candidate#*:}" "- - -"
            [[ " ${sizes[*]} " == *" ${candidate#*:} "* ]] ||
                accuracy_row "$name" c "$default_n" "${candidate#*:}" "- - -"
        done
    done
    {
        echo "Measured by \`make bench\` on $(date -u +%Y-%m-%d), $(nproc) cores ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')), matremap $("$bin" --version | cut -d' ' -f2)."
        echo
        python3 - "$rows" "$default_n" "$default_size" "$converged_n" "$thresholds" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1]), delimiter="\t"))
default_n, default_size, converged_n = int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
thresholds = [float(t) for t in sys.argv[5].split()]
assets = list(dict.fromkeys(r["asset"] for r in rows))
for r in rows:
    for k in ("n", "size"):
        r[k] = int(r[k])
    for k in ("seconds", "cpu", "render", "ssim", "ssim_mean"):
        r[k] = float(r[k])

def sweep(kind):
    """{asset: rows of the sweep in increasing order}, each with its |dSSIM| (both conversions) from the sweep's
    converged row, and the larger of the two as `worst`."""
    out = {}
    for a in assets:
        rs = [r for r in rows if r["asset"] == a and r["sweep"] == kind]
        rs.sort(key=lambda r: r["n"] if kind == "n" else r["size"])
        for r in rs:
            r["delta"] = abs(r["ssim"] - rs[-1]["ssim"])
            r["delta_mean"] = abs(r["ssim_mean"] - rs[-1]["ssim_mean"])
            r["worst"] = max(r["delta"], r["delta_mean"])
        out[a] = rs
    return out

def cheapest(by_asset, key, threshold):
    """The smallest setting from which every larger one keeps |dSSIM| < threshold on every asset."""
    settings = sorted({r[key] for rs in by_asset.values() for r in rs})
    good = [all(r["worst"] < threshold for rs in by_asset.values() for r in rs if r[key] == s) for s in settings]
    for i, s in enumerate(settings):
        if all(good[i:]):
            return s
    return None

n_sweep, s_sweep = sweep("n"), sweep("s")
largest = max(r["size"] for r in rows if r["sweep"] == "s")
print("`matremap report ORIGINAL.gltf -- WEIGHTED.gltf -- MEAN.gltf --env studio_small_03_1k.hdr` (4 rotations) "
      "on each asset\nand its `gltf spec2metal` conversions. *report s*: the whole process, wall clock, less the "
      "third material's\nrender (what a report of the original and one conversion costs; median of 3 runs under "
      "10 s, one run above);\n*CPU s*: its user + system time (scaled the same way), the work done, which other "
      "jobs on the machine inflate\nless than the wall clock; *render s*: the renders of the original and the "
      "weighted conversion over the 4 views\n(the report's own timer, wall clock); *rest s*: report s less render "
      "s: loading, one render plan per view\n(with shadow rays where the mesh hides itself), pictures, SSIM. "
      "*SSIM w / m*: the report's mean object SSIM (over the\nobject's pixels) of the weighted / mean conversion "
      "against the original; *|ΔSSIM|*: "
      "its distance from the converged evaluation.\n*picture SSIM / worst view / rel. RMSE*: the original's own "
      "pictures (the report's 8-bit PNGs) against its\npictures at N = %d: mean and lowest SSIM over the 4 views, "
      "mean relative RMSE.\n" % converged_n)
print("Environment sample count N at --size %d (converged: N = %d):\n" % (default_size, converged_n))
print("| asset | N | report s | CPU s | render s | rest s | SSIM w | \\|ΔSSIM\\| w | SSIM m | \\|ΔSSIM\\| m | "
      "picture SSIM | worst view | picture rel. RMSE |")
print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
for a in assets:
    for r in n_sweep[a]:
        print("| %s | %d%s | %.2f | %.2f | %.2f | %.2f | %.5f | %.5f | %.5f | %.5f | %.5f | %.4f | %.4f |" % (
            a, r["n"], " (converged)" if r["n"] == converged_n else "", r["seconds"], r["cpu"], r["render"],
            r["seconds"] - r["render"], r["ssim"], r["delta"], r["ssim_mean"], r["delta_mean"],
            float(r["picture_ssim"]), float(r["picture_min"]), float(r["picture_rel"])))
print("\nImage size S at --env-samples %d (converged: S = %d; SSIM is measured at each size, so the distance "
      "includes\nwhat the size itself changes in the SSIM, not only sampling):\n" % (default_n, largest))
print("| asset | S | report s | CPU s | render s | rest s | SSIM w | \\|ΔSSIM\\| w | SSIM m | \\|ΔSSIM\\| m |")
print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
for a in assets:
    for r in s_sweep[a]:
        print("| %s | %d² | %.2f | %.2f | %.2f | %.2f | %.5f | %.5f | %.5f | %.5f |" % (
            a, r["size"], r["seconds"], r["cpu"], r["render"], r["seconds"] - r["render"], r["ssim"], r["delta"],
            r["ssim_mean"], r["delta_mean"]))
def find(a, n, size):
    """The row of asset a at (n, size) from any sweep."""
    return next((r for r in rows if r["asset"] == a and r["n"] == n and r["size"] == size), None)

cands = sorted({(r["n"], r["size"]) for r in rows if r["sweep"] == "c" and r["n"] != default_n})
if cands:
    print("\nThe report's defaults (report.h) against the earlier ones (N %d, %d²): *|ΔSSIM| N*: the "
          "larger of the two\nconversions' distances from N = %d at the same size (what the smaller N changes); "
          "*|ΔSSIM| to %d²*: from\nN = %d at %d² (what the size changes, against the largest size measured):\n"
          % (default_n, default_size, default_n, largest, default_n, largest))
    print("| asset | setting | report s | CPU s | SSIM w | SSIM m | \\|ΔSSIM\\| N | \\|ΔSSIM\\| to %d² |" % largest)
    print("|---|---|---:|---:|---:|---:|---:|---:|")
    for a in assets:
        top = find(a, default_n, largest)
        for n, size in [(default_n, default_size)] + cands:
            r, same = find(a, n, size), find(a, default_n, size)
            dn = max(abs(r["ssim"] - same["ssim"]), abs(r["ssim_mean"] - same["ssim_mean"]))
            ds = max(abs(r["ssim"] - top["ssim"]), abs(r["ssim_mean"] - top["ssim_mean"]))
            print("| %s | N %d, %d²%s | %.2f | %.2f | %.5f | %.5f | %.5f | %.5f |" % (
                a, n, size, " (earlier)" if (n, size) == (default_n, default_size) else "", r["seconds"], r["cpu"],
                r["ssim"], r["ssim_mean"], dn, ds))
print("\nWorst case per setting over the %d assets (largest |ΔSSIM| of either conversion, lowest picture SSIM "
      "of a\nview, slowest report):\n" % len(assets))
print("| setting | max \\|ΔSSIM\\| | worst picture view | max report s | max CPU s |")
print("|---|---:|---:|---:|---:|")
for n in sorted({r["n"] for rs in n_sweep.values() for r in rs}):
    at = [r for rs in n_sweep.values() for r in rs if r["n"] == n]
    print("| N %d, %d² | %.5f | %.5f | %.2f | %.2f |" % (n, default_size, max(r["worst"] for r in at),
                                                     min(float(r["picture_min"]) for r in at),
                                                     max(r["seconds"] for r in at), max(r["cpu"] for r in at)))
for s in sorted({r["size"] for rs in s_sweep.values() for r in rs}):
    at = [r for rs in s_sweep.values() for r in rs if r["size"] == s]
    print("| N %d, %d² | %.5f | - | %.2f | %.2f |" % (default_n, s, max(r["worst"] for r in at),
                                                 max(r["seconds"] for r in at), max(r["cpu"] for r in at)))
print()
for t in thresholds:
    n, s = cheapest(n_sweep, "n", t), cheapest(s_sweep, "size", t)
    print("Cheapest setting with |ΔSSIM| < %g for both conversions of every asset (and at every larger setting): "
          "N = %s at %d², S = %s at N = %d.  " % (t, n if n is not None else "none measured", default_size,
                                                 "%d²" % s if s is not None else "none measured", default_n))
PY
    } | tee "$table"
    replace_section report-accuracy "$table"
}

# Reflection samples (docs/rendering.md, bench:reflection): what M directions about each pixel's mirror
# direction buy and cost. (1) A GGX sphere (f0 0.9/0.6/0.3, dark diffuse) under the studio map at N 256, 256²,
# for alpha from the models' floor to 0.3 and M = 0 ... 160, against N 16384 with M 1000: SSIM (display, the
# map scaled to the report's mean luminance 0.5), relative RMSE, plan and render ms (the tool's own timers,
# one run each: they are below a second). (2) The CesiumMilkTruck, whose four materials are all glossiness 1,
# in `matremap report` at its defaults but M: the original's pictures against a report at N 4096 and M 1000,
# the weighted conversion's report SSIM, and the report's wall and CPU seconds (medians of 3 runs).
bench_reflection() {
    echo
    echo "== reflection samples: smooth materials under an environment map, accuracy and cost against M"
    local shared=${MR_SHARED:-$root/../shared}
    local env_map="$shared/assets/hdri/studio_small_03_1k.hdr" out="$work/reflection" table="$work/reflection.md"
    local truck="$shared/assets/specgloss/CesiumMilkTruck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/CesiumMilkTruck.gltf"
    if [ ! -f "$env_map" ] || [ ! -f "$truck" ]; then
        echo "(no assets at $shared/assets: the reflection section was skipped)"
        echo "Reflection samples skipped: ../shared/assets was not found in this run." > "$table"
        replace_section reflection "$table" "$root/docs/rendering.md"
        return 0
    fi
    rm -rf "$out"
    mkdir -p "$out"
    local alphas=(0.0001 0.003 0.02 0.1 0.3) ms=(0 10 40 160) scale=0.2706 alpha m log t
    [ "$quick" = --quick ] && alphas=(0.0001 0.02 0.3) ms=(0 40)
    sphere() { # ALPHA N M OUT: one render, prints "PLAN_MS RENDER_MS"
        "$bin" render ggx alpha="$1" f0=0.9,0.6,0.3 diffuse=0.02,0.02,0.02 --env "$env_map" --env-scale "$scale" \
            --env-samples "$2" --env-reflection-samples "$3" --size 256 -o "$4" 2>&1 |
            sed -nE 's/.*plan ([0-9.]+) ms, rendered in ([0-9.]+) ms.*/\1 \2/p'
    }
    "$bin" render lambert --exposure 0 --size 256 -o "$out/black.exr" >/dev/null
    {
        echo "Measured by \`make bench\` on $(date -u +%Y-%m-%d), $(nproc) cores ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')), matremap $("$bin" --version | cut -d' ' -f2)."
        echo
        echo "A GGX sphere (f0 0.9, 0.6, 0.3; diffuse 0.02) under studio_small_03 (scaled to mean luminance 0.5), 256²,"
        echo "N = 256 pattern directions and M reflection samples, against N = 16384 with M = 1000. SSIM on the display"
        echo "(sRGB luma), relative RMSE on linear RGB; plan and render: the tool's timers, 2 threads."
        echo
        echo "| GGX alpha | M | SSIM | rel. RMSE | plan ms | render ms |"
        echo "|---:|---:|---:|---:|---:|---:|"
    } > "$table"
    for alpha in "${alphas[@]}"; do
        sphere "$alpha" 16384 1000 "$out/ref_$alpha.exr" >/dev/null
        local rms
        rms=$("$bin" ssim --json "$out/ref_$alpha.exr" "$out/black.exr" | sed -E 's/.*"rmse": ([^}]*)}.*/\1/')
        for m in "${ms[@]}"; do
            read -r plan_ms render_ms < <(sphere "$alpha" 256 "$m" "$out/s_${alpha}_$m.exr")
            "$bin" ssim --json "$out/s_${alpha}_$m.exr" "$out/ref_$alpha.exr" |
                sed -E 's/.*"ssim": ([^,]*), "rmse": ([^}]*)}.*/\1 \2/' |
                awk -v a="$alpha" -v m="$m" -v rms="$rms" -v p="$plan_ms" -v r="$render_ms" \
                    '{ printf "| %g | %d | %.4f | %.4f | %.0f | %.0f |\n", a, m, $1, $2 / rms, p, r }' | tee -a "$table"
        done
    done
    # The truck: the original against its weighted conversion, as `matremap report` shows them.
    local weighted="$out/truck_weighted.gltf" v
    "$bin" gltf spec2metal "$truck" -o "$weighted" --method weighted --overwrite-metal-rough --core-only >/dev/null
    "$bin" report -o "$out/truck_ref" --env "$env_map" --env-samples 4096 --env-reflection-samples 1000 "$truck" \
        -- "$weighted" >/dev/null
    {
        echo
        echo "CesiumMilkTruck (every material glossiness 1) in \`matremap report\` at its defaults (N 256, 384², 4 views) but M,"
        echo "with its weighted conversion: the original's pictures against a report at N 4096, M 1000 (mean and worst"
        echo "view), the conversion's report SSIM, and the whole report's time (median of 3 runs):"
        echo
        echo "| M | picture SSIM | worst view | report SSIM (weighted) | report s | CPU s |"
        echo "|---:|---:|---:|---:|---:|---:|"
    } >> "$table"
    for m in 0 10 40 160; do
        local walls=() cpus=() run
        for run in 1 2 3; do
            t=$(times_of "$out/report.log" "$bin" report -o "$out/truck_$m" --env "$env_map" --env-reflection-samples "$m" \
                "$truck" -- "$weighted")
            walls+=("${t% *}")
            cpus+=("${t#* }")
            [ "$quick" = --quick ] && break
        done
        local lines=""
        for v in 0 1 2 3; do
            lines+="$("$bin" ssim --json "$out/truck_$m/view${v}_material0.png" "$out/truck_ref/view${v}_material0.png" |
                sed -E 's/.*"ssim": ([^,]*),.*/\1/')"$'\n'
        done
        local report_ssim
        report_ssim=$(python3 -c 'import json, sys; print("%.5f" % json.load(open(sys.argv[1]))["materials"][1]["mean_ssim"])' \
            "$out/truck_$m/summary.json")
        printf '%s' "$lines" | awk -v m="$m" -v r="$report_ssim" -v w="$(printf '%s\n' "${walls[@]}" | median)" \
            -v c="$(printf '%s\n' "${cpus[@]}" | median)" '{ s += $1; lo = (NR == 1 || $1 < lo) ? $1 : lo }
            END { printf "| %d | %.4f | %.4f | %s | %.2f | %.2f |\n", m, s / NR, lo, r, w, c }' | tee -a "$table"
    done
    replace_section reflection "$table" "$root/docs/rendering.md"
}

# Uniform remaps against fit-scene size and strategy (docs/performance.md, bench:remap).
bench_remap_table() {
    echo "== uniform remaps: time and accuracy against fit-scene size and strategy, one thread (tests/bench_remap.c)"
    "$root/$build/tests/bench_remap" $quick | tee "$work/remap_table.md"
    {
        echo "Measured by \`make bench\` on $(date -u +%Y-%m-%d), one thread of $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')."
        echo
        cat "$work/remap_table.md"
    } > "$work/remap.md"
}

# The fit engine (docs/performance.md, bench:fit-engine): the bench pairs at 64^2 with the default engine against
# the derivative-free local stage in the same run, and what accuracy costs in time per fit size x local method
# (tests/bench_fit.c).
bench_fit_engine() {
    echo
    echo "== the fit engine: 13 model pairs at 64², and fit size x local method (tests/bench_fit.c)"
    local fit="$root/$build/tests/bench_fit"
    "$fit" $quick --local bobyqa --save "$work/fit_bobyqa.txt" > "$work/fit_bobyqa.md"
    "$fit" $quick --against "$work/fit_bobyqa.txt" | tee "$work/fit_pairs.md"
    "$fit" $quick --table | tee "$work/fit_table.md"
    {
        echo "Measured by \`make bench\` on $(date -u +%Y-%m-%d), one thread of $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'), matremap $("$bin" --version | cut -d' ' -f2)."
        echo
        echo "**The bench pairs at 64²** (the default engine; the reference columns compare it, material by material,"
        echo "with the derivative-free local stage, \`--local bobyqa\`, run just before on the same materials):"
        echo
        cat "$work/fit_pairs.md"
        echo
        echo "**Fit size × local method** (materials: the pair's first 8, 4 for the layered targets). *floor ms*:"
        echo "median renders × the median time of one full render of the target at that size, measured in the same"
        echo "run: what the fit would cost if it did nothing but render. ΔSSIM@512: the fits rendered at 512² beside"
        echo "the source, |SSIM − SSIM of the gradient fit at 128²| per material, mean (max). *precision*: the"
        echo "plan's renders in double (the engine) or with the float kernels (src/brdf/brdf_float.h, for targets that"
        echo "have one; the source is rendered on the same plan, so in float too; derivative renders and the 512²"
        echo "judge stay double); the second table compares the float fits with the double ones material by material."
        echo
        cat "$work/fit_table.md"
    } > "$work/fit_engine.md"
}

# The direct remap of real texture sets (docs/performance.md, bench:direct): distinct values against the
# quantisation step, a whole 1024^2 set on 2 threads, and its answers against single remaps (tests/bench_direct.c).
bench_direct() {
    echo
    echo "== direct remaps of texture sets: unique values, time on 2 threads, error against single remaps (tests/bench_direct.c)"
    local sets="$shared/assets/specgloss"
    if [ ! -d "$sets" ]; then
        echo "(no assets at $sets: the direct remap section was skipped)"
        echo "Direct remaps skipped: ../shared/assets was not found in this run." > "$work/direct.md"
        return 0
    fi
    "$root/$build/tests/bench_direct" "$sets" $quick | tee "$work/direct_table.md"
    {
        echo "Measured by \`make bench\` on $(date -u +%Y-%m-%d), $(nproc) cores ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'))."
        echo
        cat "$work/direct_table.md"
    } > "$work/direct.md"
}

# What accuracy costs for learned transforms (docs/performance.md, bench:learn): the paper's Mitsuba Ward -> GGX on
# the Avocado spec-gloss set read as a Ward SVBRDF (tests/bench_direct.c's mapping: diffuse and specular as stored,
# alpha = (1 - glossiness)^2), 1024^2. Sweeps of growing size (alpha x grey specular grids, diffuse held at 0),
# each learned by every method; per method and sweep: the sweep's time, training time, conversion throughput of the
# whole set on 2 threads (M texels/s: the convert step alone, from --json), the share of texels outside the training
# domain, and the mean absolute difference of alpha and F0 from `convert --direct` (the reference) on the same set.
bench_learn() {
    echo
    echo "== learned transforms: sweep size, training time, throughput, error against --direct (ward -> ggx)"
    local dir="$shared/assets/specgloss/Avocado-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness"
    local out="$work/learn" table="$work/learn.md"
    if [ ! -d "$dir" ]; then
        echo "(no assets at $dir: the learned-transform section was skipped)"
        echo "Learned transforms skipped: ../shared/assets was not found in this run." > "$table"
        return 0
    fi
    rm -rf "$out" && mkdir -p "$out"
    oiiotool "$dir/Avocado_diffuse.png" --ch R,G,B --resize 1024x1024 -d uint8 -o "$out/diffuse.png"
    oiiotool "$dir/Avocado_specularGlossiness.png" --ch R,G,B --resize 1024x1024 -d uint8 -o "$out/specular.png"
    oiiotool "$dir/Avocado_specularGlossiness.png" --ch A --resize 1024x1024 --mulc -1 --addc 1 --powc 2 \
        --clamp:min=0.0001:max=1 -d float -o "$out/alpha.exr"
    local maps=(alpha="$out/alpha.exr" specular="$out/specular.png" diffuse="$out/diffuse.png")
    local s e
    s=$(date +%s%N)
    "$bin" convert --from ward --to ggx "${maps[@]}" --direct -o "$out/direct_" 2>"$out/direct.log" >/dev/null
    e=$(date +%s%N)
    local direct_s
    direct_s=$(awk -v a="$s" -v b="$e" 'BEGIN {printf "%.1f", (b - a) / 1e9}')
    echo "convert --direct: $direct_s s ($(grep -o '[0-9]* distinct values' "$out/direct.log"))"
    local grids=("5 2" "10 3" "20 5" "30 8")
    [ "$quick" = --quick ] && grids=("5 2" "10 3")
    {
        echo "Measured by \`make bench\` on $(date -u +%Y-%m-%d), $(nproc) cores ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'))."
        echo "The Avocado spec-gloss set at 1024² read as a Mitsuba Ward SVBRDF (alpha = (1 - glossiness)², diffuse and"
        echo "specular as stored), converted to GGX; the reference is \`convert --direct\` (default tolerance 6/255,"
        echo "$(grep -o '[0-9]* distinct values' "$out/direct.log"), $direct_s s on 2 cores). Sweeps: ward alpha 0.005–1 (log)"
        echo "× grey specular 0.001–0.05 (log; the set's specular map, sRGB-decoded, holds 0–0.037), diffuse 0, the"
        echo "default fit scene (64², 45°). Train s includes learn's check against the held-out remaps (its verdict:"
        echo "check). Throughput: the conversion alone (repeated texels converted once), 2 threads. Errors: mean"
        echo "|learned − direct| over the set's texels."
        echo
        echo "| sweep (alpha × specular) | sweep s | method | train s | check | held-out RMSE alpha / F0 | M texels/s | extrapolated | mean abs. error vs direct: alpha / F0 |"
        echo "|---|---:|---|---:|---|---|---:|---:|---|"
    } > "$table"
    for g in "${grids[@]}"; do
        read -r na ns <<<"$g"
        local csv="$out/sweep_${na}x${ns}.csv"
        s=$(date +%s%N)
        # The set's specular, sRGB-decoded as every command reads a Ward specular map: 0 to 0.037 (codes 0-54).
        "$bin" sweep --from ward diffuse=0 --to ggx diffuse=0 --grid alpha=0.005:1:"$na":log \
            specular=0.001:0.05:"$ns":log -o "$csv" >/dev/null 2>&1
        e=$(date +%s%N)
        local sweep_s
        sweep_s=$(awk -v a="$s" -v b="$e" 'BEGIN {printf "%.1f", (b - a) / 1e9}')
        for method in parametric svr mlp; do
            local mrt="$out/${method}_${na}x${ns}.mrt" json="$out/${method}_${na}x${ns}.json"
            "$bin" learn "$csv" --method "$method" -o "$mrt" --json > "$json.learn" 2>/dev/null || continue
            "$bin" convert --from ward --to ggx "${maps[@]}" --transform "$mrt" -o "$out/${method}_${na}x${ns}_" \
                --json > "$json" 2>/dev/null || continue
            local ea ef
            # (oiiotool --diff exits non-zero when the images differ, which they do)
            ea=$({ oiiotool --diff "$out/${method}_${na}x${ns}_alpha.exr" "$out/direct_alpha.exr" 2>/dev/null || true; } \
                | awk '/Mean error/ {print $4}')
            ef=$({ oiiotool --diff "$out/${method}_${na}x${ns}_f0.exr" "$out/direct_f0.exr" 2>/dev/null || true; } \
                | awk '/Mean error/ {print $4}')
            python3 - "$json.learn" "$json" "$na" "$ns" "$sweep_s" "$method" "$ea" "$ef" <<'PY' | tee -a "$table"
import json, sys
learn, conv = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
na, ns, sweep_s, method, ea, ef = sys.argv[3:9]
r = learn["validation_rmse"]
rate = conv["texels"] / conv["seconds"]["convert"] / 1e6
ext = 100.0 * conv["flags"]["extrapolated_or_unconverged"] / conv["texels"]
check = "passed" if learn["check"]["passed"] else "failed"
print(f"| {na} × {ns} = {int(na) * int(ns)} | {sweep_s} | {method} | {learn['seconds']:.2f} | {check} | "
      f"{r.get('alpha', float('nan')):.4f} / {r.get('f0', float('nan')):.4f} | {rate:.1f} | {ext:.1f} % | "
      f"{float(ea):.4f} / {float(ef):.4f} |")
PY
        done
    done
}

# Remaps as users run them (docs/performance.md, bench:remap-processes): whole `matremap remap` processes at the
# default size, alone and two started together, with the default (automatic) threads, with --threads 2 (a team for
# every render, as before issue 13), and with OMP_NUM_THREADS=1 (the old workaround). Median of 21 runs each; the
# pair's figure is each process's own wall time. MR_BENCH_PEER=PATH (optional) measures another build's matremap in
# the same run, named by MR_BENCH_PEER_LABEL (e.g. the commit before a change, built in a scratch worktree): the
# default row and the peer's are then measured in turns, run by run, so that both see the same load. Then what
# building the remap's plans costs (tests/bench_plan: the 64² plan, its closer look, 512²).
bench_remap_processes() {
    echo
    echo "== remap processes: alone and two side by side (whole processes, default size)"
    local out="$work/remap_processes.md" runs=21 cmd=("$bin" remap --from ggx alpha=0.2 f0=0.04 diffuse=0.3 --to ward)
    [ "$quick" = "--quick" ] && runs=5
    # The clock is bash's own ($EPOCHREALTIME, no process): `$(date +%s%N)` after the command counted the start of a
    # date process, about 1 ms, in every figure before 2026-11-29.
    one_ms() {
        local s e
        s=${EPOCHREALTIME/[.,]/}
        "$@" >/dev/null 2>&1
        e=${EPOCHREALTIME/[.,]/}
        echo $((e - s)) # microseconds
    }
    alone() { for _ in $(seq "$runs"); do one_ms "$@"; done | median; }
    together() {
        for _ in $(seq "$runs"); do
            one_ms "$@" >"$work/pair_a" &
            one_ms "$@" >"$work/pair_b"
            wait
            cat "$work/pair_a" "$work/pair_b"
        done | median
    }
    local peer_cmd=("${MR_BENCH_PEER:-}" "${cmd[@]:1}")
    in_turns() { # alone|together: our command and the peer's in turns; prints both medians, ours first
        local mode=$1 k
        : >"$work/turns_ours"
        : >"$work/turns_peer"
        for _ in $(seq "$runs"); do
            for k in ours peer; do
                local c=("${cmd[@]}")
                [ "$k" = peer ] && c=("${peer_cmd[@]}")
                if [ "$mode" = alone ]; then
                    one_ms "${c[@]}" >>"$work/turns_$k"
                else
                    one_ms "${c[@]}" >"$work/pair_a" &
                    one_ms "${c[@]}" >"$work/pair_b"
                    wait
                    cat "$work/pair_a" "$work/pair_b" >>"$work/turns_$k"
                fi
            done
        done
        echo "$(median <"$work/turns_ours") $(median <"$work/turns_peer")"
    }
    {
        echo "Measured by \`make bench\` on $(date -u +%Y-%m-%d), $(nproc) cores ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')), load $(cut -d' ' -f1 /proc/loadavg) at the start:"
        echo "\`${cmd[*]#"$root/"}\` (64², the 45° light), median of $runs whole processes (process start, plan, fit and"
        echo "verdict), alone and two started together (each process's own time)."
        echo
        echo "| threads | alone (ms) | two together, each (ms) | together / alone |"
        echo "|---|---:|---:|---:|"
        local a t peer_a peer_t
        if [ -n "${MR_BENCH_PEER:-}" ]; then
            read -r a peer_a <<<"$(in_turns alone)"
            read -r t peer_t <<<"$(in_turns together)"
        else
            a=$(alone "${cmd[@]}"); t=$(together "${cmd[@]}")
        fi
        printf '| automatic (default) | %.1f | %.1f | %.2f× |\n' "$(awk -v x="$a" 'BEGIN {print x / 1000}')" \
            "$(awk -v x="$t" 'BEGIN {print x / 1000}')" "$(awk -v a="$a" -v t="$t" 'BEGIN {print t / a}')"
        a=$(alone "${cmd[@]}" --threads 2); t=$(together "${cmd[@]}" --threads 2)
        printf '| --threads 2 (a team per render) | %.1f | %.1f | %.2f× |\n' "$(awk -v x="$a" 'BEGIN {print x / 1000}')" \
            "$(awk -v x="$t" 'BEGIN {print x / 1000}')" "$(awk -v a="$a" -v t="$t" 'BEGIN {print t / a}')"
        a=$(OMP_NUM_THREADS=1 alone "${cmd[@]}"); t=$(OMP_NUM_THREADS=1 together "${cmd[@]}")
        printf '| OMP_NUM_THREADS=1 | %.1f | %.1f | %.2f× |\n' "$(awk -v x="$a" 'BEGIN {print x / 1000}')" \
            "$(awk -v x="$t" 'BEGIN {print x / 1000}')" "$(awk -v a="$a" -v t="$t" 'BEGIN {print t / a}')"
        if [ -n "${MR_BENCH_PEER:-}" ]; then
            printf '| automatic, peer: %s (in turns with the first row) | %.1f | %.1f | %.2f× |\n' \
                "${MR_BENCH_PEER_LABEL:-$MR_BENCH_PEER}" "$(awk -v x="$peer_a" 'BEGIN {print x / 1000}')" \
                "$(awk -v x="$peer_t" 'BEGIN {print x / 1000}')" \
                "$(awk -v a="$peer_a" -v t="$peer_t" 'BEGIN {print t / a}')"
        fi
        if [ -x "$root/$build/tests/bench_plan" ]; then
            echo
            echo "What building the plans costs, one thread, in-process (\`$build/tests/bench_plan\`; a remap builds"
            echo "the first two):"
            echo
            "$root/$build/tests/bench_plan" $quick
        fi
    } | tee "$out"
}

# The workflow converters' speed and accuracy (docs/performance.md, bench:workflow): tests/bench_workflow.c on
# random texels and on two real texture sets (Avocado, used in training's asset texels, and FloppyDisk, held out),
# the first shipped network (git history, cc66767) measured beside the default as the peer when git has it.
bench_workflow() {
    local shared=${MR_SHARED:-$root/../shared} first="$work/first-network.mlp" extra=()
    local avocado="$shared/assets/specgloss/Avocado-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness"
    local floppy="$shared/assets/specgloss/FloppyDisk-sketchfab/textures"
    echo
    echo "== workflow conversion: methods, accuracy, MLP width (tests/bench_workflow.c)"
    [ -s "$root/$build/dataset/test-pairs.csv" ] || echo "(no dataset in $build/dataset: make dataset first for the accuracy tables)"
    if git -C "$root" show cc66767:data/spec2metal.mlp >"$first" 2>/dev/null; then
        extra+=(--peer "first network (plain form, cc66767)" "$first")
    fi
    [ -f "$avocado/Avocado_diffuse.png" ] &&
        extra+=(--texture "Avocado" "$avocado/Avocado_diffuse.png" "$avocado/Avocado_specularGlossiness.png")
    [ -f "$floppy/material_0_diffuse.png" ] &&
        extra+=(--texture "FloppyDisk (held out)" "$floppy/material_0_diffuse.png" "$floppy/material_0_specularGlossiness.png")
    {
        echo "Measured by \`make bench\` on $(date -u +%Y-%m-%d), $(nproc) cores ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'))."
        echo
        "$root/$build/tests/bench_workflow" "$root/data/spec2metal.mlp" "$root/$build/dataset" \
            "$shared/assets/hdri/studio_small_03_1k.hdr" "$shared/assets/hdri/tabac_plant_vogl.hdr" $quick "${extra[@]}"
    } | tee "$work/workflow.md"
}

# spec2metal / metal2spec end to end (docs/performance.md, bench:workflow-e2e).
bench_workflow_e2e() {
    echo
    echo "== spec2metal / metal2spec end to end on a real 2048² texture set (read, convert, write)"
    # The Avocado spec-gloss maps (2048², 8-bit PNG) of ../shared/assets, converted by the command a user runs, against
    # a peer measured in the same run: oiiotool reading the same two files and writing the same number of PNG outputs
    # (pure image I/O, no conversion), so the ratio is what the conversion adds to the files' own cost.
    local avocado="$shared/assets/specgloss/Avocado-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness"
    e2e="$work/e2e.md"
    if [ -f "$avocado/Avocado_diffuse.png" ]; then
        runs=3
        [ "$quick" = "--quick" ] && runs=1
        peer=()
        for run in $(seq "$runs"); do
            peer+=("$(seconds_of oiiotool --iconfig oiio:UnassociatedAlpha 1 "$avocado/Avocado_diffuse.png" -o "$work/e2e_peer_a.png" \
                "$avocado/Avocado_specularGlossiness.png" --ch R,G,B -o "$work/e2e_peer_b.png")")
        done
        peer_s=$(printf '%s\n' "${peer[@]}" | median)
        {
            echo "Measured by \`make bench\` on $(date -u +%Y-%m-%d), $(nproc) cores: \`matremap spec2metal --diffuse Avocado_diffuse.png"
            echo "--specular-glossiness Avocado_specularGlossiness.png --pack -o PREFIX\` (2048², 4.2 M texels, two 8-bit PNG"
            echo "inputs, two PNG outputs) per method, and \`metal2spec\` on WaterBottle's maps; median of $runs runs of the whole"
            echo "process. Read / convert / write are the command's own split (its --json). Peer: oiiotool reading the"
            echo "same two files and writing two PNGs, ${peer_s} s in this run; the ratio is ours over the peer."
            echo
            echo "| command | method | total s | read s | convert s | write s | M texels/s (convert) | ratio to oiiotool I/O |"
            echo "|---|---|---:|---:|---:|---:|---:|---:|"
        } > "$e2e"
        e2e_row() { # LABEL METHOD COMMAND...
            local label=$1 method=$2; shift 2
            local totals=() json=""
            for run in $(seq "$runs"); do
                local t0 t1
                t0=$(date +%s.%N)
                json=$("$@" --json 2>/dev/null)
                t1=$(date +%s.%N)
                totals+=("$(awk -v a="$t0" -v b="$t1" 'BEGIN {print b - a}')")
            done
            local total read convert write
            total=$(printf '%s\n' "${totals[@]}" | median)
            read=$(echo "$json" | sed -E 's/.*"read": ([0-9.]+).*/\1/')
            convert=$(echo "$json" | sed -E 's/.*"convert": ([0-9.]+).*/\1/')
            write=$(echo "$json" | sed -E 's/.*"write": ([0-9.]+).*/\1/')
            printf '| %s | %s | %.2f | %.2f | %.3f | %.2f | %.1f | %.2f |\n' "$label" "$method" "$total" "$read" "$convert" \
                "$write" "$(awk -v c="$convert" 'BEGIN {print 4194304 / c / 1e6}')" \
                "$(awk -v a="$total" -v b="$peer_s" 'BEGIN {print a / b}')" | tee -a "$e2e"
        }
        for method in mlp weighted mean khronos; do
            e2e_row spec2metal "$method" "$bin" spec2metal --diffuse "$avocado/Avocado_diffuse.png" \
                --specular-glossiness "$avocado/Avocado_specularGlossiness.png" --method "$method" --pack -o "$work/e2e_$method"
        done
        bottle="$shared/assets/metalrough/WaterBottle/glTF"
        e2e_row metal2spec eq2 "$bin" metal2spec --basecolor "$bottle/WaterBottle_baseColor.png" \
            --metallic-roughness "$bottle/WaterBottle_occlusionRoughnessMetallic.png" --pack -o "$work/e2e_m2s"
    else
        echo "(no assets at $shared/assets: the end-to-end conversion was skipped)"
        echo "End-to-end conversion skipped: ../shared/assets was not found in this run." > "$e2e"
    fi
}

# PNG read and write (docs/performance.md, bench:png): tests/bench_png.c on the 2048^2 spec-gloss textures of
# ../shared/assets, libpng against OpenImageIO and the writer's settings (file size against speed).
bench_png() {
    echo
    echo "== PNG read and write: libpng against OpenImageIO, writer settings (tests/bench_png.c)"
    local shared=${MR_SHARED:-$root/../shared} files=()
    if [ -d "$shared/assets/specgloss" ]; then
        while IFS= read -r f; do
            # the 2048-pixel-wide ones (IHDR width, bytes 16-19)
            [ "$(od -An -tu1 -j16 -N4 "$f" | tr -s ' ' | sed 's/^ //')" = "0 0 8 0" ] && files+=("$f")
        done < <(find "$shared/assets/specgloss" -name '*.png' | sort)
    fi
    if [ ${#files[@]} -eq 0 ]; then
        echo "PNG comparison skipped: no 2048² PNG in ../shared/assets/specgloss in this run." | tee "$work/png.md"
        return
    fi
    {
        echo "Measured by \`make bench\` on $(date -u +%Y-%m-%d), $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')."
        echo
        "$root/$build/tests/bench_png" "${files[@]}"
    } | tee "$work/png.md"
}

# glTF assets (docs/performance.md, bench:gltf): matremap gltf spec2metal against gltf-transform metalrough, whole
# processes, wall clock and peak memory, same assets, same run.
bench_gltf() {
    echo
    echo "== glTF assets: matremap gltf spec2metal against gltf-transform metalrough (same assets, same run)"
    # gltf-transform's `metalrough` is the lossless route (KHR_materials_specular + KHR_materials_ior: textures
    # rearranged, nothing converted per texel); ours converts every texel. Both write a .gltf with its textures.
    gt="$root/scripts/gltf-transform"
    gltf_report="$work/gltf.md"
    if [ ! -x "$gt/node_modules/.bin/gltf-transform" ]; then
        (cd "$gt" && npm ci --no-audit --no-fund --loglevel=error) >"$work/gltf-transform-npm.log" 2>&1 || true
    fi
    if [ -x "$gt/node_modules/.bin/gltf-transform" ] && [ -d "$shared/assets/specgloss" ]; then
        runs=3
        [ "$quick" = "--quick" ] && runs=1
        {
            echo "Measured by \`make bench\` on $(date -u +%Y-%m-%d), $(nproc) cores: whole processes, wall clock and peak"
            echo "resident memory (medians of $runs runs), \`--overwrite-metal-rough\` so that every material converts;"
            echo "gltf-transform $("$gt/node_modules/.bin/gltf-transform" --version 2>/dev/null | tail -n 1) (node $(node --version))."
            echo
            echo "| asset | texture | matremap weighted: s, MB | matremap mlp: s, MB | gltf-transform metalrough: s, MB | speed-up of weighted | its memory / gltf-transform's |"
            echo "|---|---|---:|---:|---:|---:|---:|"
        } > "$gltf_report"
        for asset in "$shared"/assets/specgloss/*/*/*.gltf "$shared"/assets/specgloss/FloppyDisk-sketchfab/scene.gltf; do
            [ -f "$asset" ] || continue
            name=$(basename "$(dirname "$asset")")
            [ "$name" = glTF-pbrSpecularGlossiness ] && name=$(basename "$(dirname "$(dirname "$asset")")")
            out="$work/gltf/$name"
            rm -rf "$out" && mkdir -p "$out/w" "$out/m" "$out/g"
            ours=() ours_mb=() mlp=() mlp_mb=() peer=() peer_mb=()
            for run in $(seq "$runs"); do
                read -r s mb < <(wall_peak_of "$bin" gltf spec2metal "$asset" -o "$out/w/out.gltf" --method weighted \
                    --overwrite-metal-rough)
                ours+=("$s") ours_mb+=("$mb")
                read -r s mb < <(wall_peak_of "$bin" gltf spec2metal "$asset" -o "$out/m/out.gltf" --method mlp \
                    --overwrite-metal-rough)
                mlp+=("$s") mlp_mb+=("$mb")
                read -r s mb < <(wall_peak_of "$gt/node_modules/.bin/gltf-transform" metalrough "$asset" "$out/g/out.gltf")
                peer+=("$s") peer_mb+=("$mb")
            done
            o_s=$(printf '%s\n' "${ours[@]}" | median) o_mb=$(printf '%s\n' "${ours_mb[@]}" | median)
            m_s=$(printf '%s\n' "${mlp[@]}" | median) m_mb=$(printf '%s\n' "${mlp_mb[@]}" | median)
            p_s=$(printf '%s\n' "${peer[@]}" | median) p_mb=$(printf '%s\n' "${peer_mb[@]}" | median)
            texture=$(python3 - "$asset" <<'PY'
import json, os, struct, sys
d = json.load(open(sys.argv[1]))
sizes = []
for im in d.get("images", []):
    with open(os.path.join(os.path.dirname(sys.argv[1]), im["uri"]), "rb") as f:
        head = f.read(33)
    if head[:8] == b"\x89PNG\r\n\x1a\n":
        sizes.append((struct.unpack(">II", head[16:24]), head[25] == 3))
(w, h), paletted = max(sizes) if sizes else ((0, 0), False)
print("%dx%d%s" % (w, h, " paletted" if paletted else ""))
PY
            )
            printf '| %s | %s | %.2f, %.0f | %.2f, %.0f | %.2f, %.0f | %.2f× | %.2f |\n' "$name" "$texture" "$o_s" "$o_mb" \
                "$m_s" "$m_mb" "$p_s" "$p_mb" "$(awk -v a="$p_s" -v b="$o_s" 'BEGIN {print a / b}')" \
                "$(awk -v a="$o_mb" -v b="$p_mb" 'BEGIN {print a / b}')" | tee -a "$gltf_report"
        done
    else
        echo "(gltf-transform could not be installed from the npm registry, or no assets: the glTF comparison was skipped)"
        echo "glTF comparison skipped: gltf-transform or ../shared/assets missing in this run." > "$gltf_report"
    fi
}

# Whole libraries (docs/performance.md, bench:library): `matremap gltf spec2metal DIR -o OUT` over the spec-gloss
# variants of glTF-Sample-Models (laid out by scripts/gltf-library.sh from MR_GLTF_SAMPLE_MODELS: a checkout or a
# bare git directory; "shared", the default, takes ../shared/assets/specgloss) against a shell loop over
# gltf-transform metalrough, in the same run: assets per minute (wall clock) and peak resident memory of the largest
# process (/usr/bin/time -v), medians of RUNS. Ours includes the thumbnails, object SSIM and index.html.
peak_time() { # CMD... -> "WALL PEAK_MB CPU" (CPU: user + system seconds, children included)
    local t0 t1 log
    log=$(mktemp)
    t0=$(date +%s.%N)
    /usr/bin/time -v -o "$log" "$@" >/dev/null 2>&1 || true
    t1=$(date +%s.%N)
    awk -v a="$t0" -v b="$t1" '/Maximum resident set size/ {kb = $NF} /User time|System time/ {cpu += $NF}
        END {printf "%.4f %.1f %.3f\n", b - a, kb / 1024, cpu}' "$log"
    rm -f "$log"
}

bench_library() {
    echo
    echo "== glTF libraries: matremap gltf spec2metal DIR -o OUT against a shell loop over gltf-transform metalrough"
    gt="$root/scripts/gltf-transform"
    lib_report="$work/library.md"
    if [ ! -x "$gt/node_modules/.bin/gltf-transform" ]; then
        (cd "$gt" && npm ci --no-audit --no-fund --loglevel=error) >"$work/gltf-transform-npm.log" 2>&1 || true
    fi
    local lib="$work/library/in" src=${MR_GLTF_SAMPLE_MODELS:-shared}
    rm -rf "$work/library" && mkdir -p "$work/library"
    MR_SHARED="$shared" "$root/scripts/gltf-library.sh" "$src" "$lib" >/dev/null
    local assets
    assets=$(find "$lib" -name '*.gltf' -o -name '*.glb' | wc -l)
    if [ ! -x "$gt/node_modules/.bin/gltf-transform" ] || [ "$assets" = 0 ]; then
        echo "library comparison skipped: gltf-transform or assets missing in this run." | tee "$lib_report"
        return
    fi
    runs=5
    [ "$quick" = "--quick" ] && runs=1
    local rows=() cmd name s mb cpu
    local -A walls=() mbs=() cpus=()
    local names=("matremap gltf spec2metal DIR -o OUT (threads 0: automatic)" \
        "matremap gltf spec2metal DIR -o OUT --threads 1" "matremap gltf spec2metal DIR -o OUT --no-renders" \
        "for a in DIR/*/*.gltf: gltf-transform metalrough")
    for run in $(seq "$runs"); do
        for k in 0 1 2 3; do
            rm -rf "$work/library/out$k"
            case $k in
                0) cmd=("$bin" gltf spec2metal "$lib" -o "$work/library/out0") ;;
                1) cmd=("$bin" gltf spec2metal "$lib" -o "$work/library/out1" --threads 1) ;;
                2) cmd=("$bin" gltf spec2metal "$lib" -o "$work/library/out2" --no-renders) ;;
                3) cmd=(bash -c 'cd "$1" && find . -name "*.gltf" -o -name "*.glb" | sort | while read -r a; do
                       mkdir -p "$2/$(dirname "$a")" && "$3" metalrough "$a" "$2/$a" || exit 1; done' _ "$lib" \
                       "$work/library/out3" "$gt/node_modules/.bin/gltf-transform") ;;
            esac
            read -r s mb cpu < <(peak_time "${cmd[@]}")
            walls[$k]+="$s " mbs[$k]+="$mb " cpus[$k]+="$cpu "
        done
    done
    {
        echo "Measured by \`make bench BENCH_ARGS=\"--only library\"\` on $(date -u +%Y-%m-%d), $(nproc) cores (load average"
        echo "$(cut -d' ' -f1 /proc/loadavg) at the end: other jobs shared the machine); library: $(head -n 1 "$lib/SOURCE.txt")."
        echo "Whole commands, wall clock, CPU seconds (user + system) and peak resident memory of the largest process"
        echo "(/usr/bin/time -v), medians of $runs runs, interleaved; gltf-transform $("$gt/node_modules/.bin/gltf-transform" --version 2>/dev/null | tail -n 1) (node $(node --version))."
        echo
        echo "| command | assets | wall s | assets per minute | CPU s | peak MB |"
        echo "|---|---:|---:|---:|---:|---:|"
        for k in 0 1 2 3; do
            s=$(tr ' ' '\n' <<<"${walls[$k]}" | grep . | median)
            mb=$(tr ' ' '\n' <<<"${mbs[$k]}" | grep . | median)
            cpu=$(tr ' ' '\n' <<<"${cpus[$k]}" | grep . | median)
            awk -v name="${names[$k]}" -v n="$assets" -v s="$s" -v mb="$mb" -v cpu="$cpu" \
                'BEGIN {printf "| %s | %d | %.2f | %.1f | %.2f | %.0f |\n", name, n, s, 60 * n / s, cpu, mb}'
        done
        sed -n '2,$p' "$lib/SOURCE.txt"
    } | tee "$lib_report"
}

# Sweeps across processes (docs/performance.md, bench:mpi): one random sweep (ggx -> ward-balanced, default fit
# scene) as one process with 1 thread, mpirun -np 1 and -np 2 with 1 thread per rank, and one process with 2
# threads; whole commands (MPI's start included), wall and CPU seconds, medians of RUNS; the files checked to hold the
# same rows. Then the cost model for a cluster: remaps per second on one core for the model pairs the project sweeps,
# and what the sweep sizes the regressions need cost on C cores at the measured efficiency.
bench_mpi() {
    echo
    echo "== sweeps across processes: mpirun -np 2 against one process, and the cost model for a cluster"
    local out="$work/mpi.md" dir="$work/mpi" runs=3 n=400 m=60
    [ "$quick" = --quick ] && runs=1 n=120 m=20
    rm -rf "$dir" && mkdir -p "$dir"
    if ! command -v mpirun >/dev/null 2>&1 || [ ! -f "$root/$build/lib/matremap/libmatremap-mpi.so" ]; then
        echo "MPI section skipped: mpirun or the MPI module (libmatremap-mpi.so) was missing in this run." | tee "$out"
        return 0
    fi
    local mpi=(mpirun --oversubscribe)
    [ "$(id -u)" -eq 0 ] && mpi+=(--allow-run-as-root)
    local sweep=(sweep --from ggx --to ward-balanced --random "$n" --seed 7)
    local labels=() walls=() cpus=()
    mpi_case() { # LABEL COMMAND...: median wall and CPU seconds of RUNS runs into a fresh file
        local label=$1 w c ws=() cs=()
        shift
        for _ in $(seq "$runs"); do
            rm -f "$dir/$label.csv"
            read -r w c < <(times_of "$dir/$label.log" "$@" -o "$dir/$label.csv")
            ws+=("$w") cs+=("$c")
        done
        labels+=("$label") walls+=("$(printf '%s\n' "${ws[@]}" | median)") cpus+=("$(printf '%s\n' "${cs[@]}" | median)")
        echo "   $label: wall ${walls[-1]} s, CPU ${cpus[-1]} s ($(tail -n 1 "$dir/$label.log"))"
    }
    local load load_end
    load=$(cut -d' ' -f1 /proc/loadavg)
    mpi_case one "$bin" "${sweep[@]}" --threads 1
    mpi_case np1 "${mpi[@]}" -np 1 "$bin" "${sweep[@]}" --threads 1
    mpi_case np2 "${mpi[@]}" -np 2 "$bin" "${sweep[@]}"
    mpi_case threads2 "$bin" "${sweep[@]}" --threads 2
    load_end=$(cut -d' ' -f1 /proc/loadavg)
    local same=yes
    for l in np1 np2 threads2; do
        diff <(grep -v '^# command:' "$dir/one.csv" | sed '/^#/!s/,[^,]*$//') \
            <(grep -v '^# command:' "$dir/$l.csv" | sed '/^#/!s/,[^,]*$//') >/dev/null || same="no ($l differs)"
    done
    local speedup
    speedup=$(awk -v a="${walls[0]}" -v b="${walls[2]}" 'BEGIN {printf "%.2f", a / b}')
    {
        echo "Measured by \`make bench\` on $(date -u +%Y-%m-%d), $(nproc) cores ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')), load average $load before and $load_end after, niceness $(nice) (scheduler autogroup: $(cut -d' ' -f2- /proc/self/autogroup 2>/dev/null || echo none)), $(mpirun --version | head -n 1):"
        echo "\`matremap ${sweep[*]}\` (default fit scene, 64²), whole commands (MPI's start included), medians of $runs runs."
        echo "The four files hold the same rows in the same order (seconds and command line aside): $same."
        echo
        echo "| run | ranks × threads | wall s | CPU s | rows/s | speed-up over 1 × 1 |"
        echo "|---|---|---:|---:|---:|---:|"
        local names=("\`matremap sweep ... --threads 1\`" "\`mpirun -np 1 matremap sweep ... --threads 1\`"
            "\`mpirun -np 2 matremap sweep ...\` (1 thread per rank: the default)" "\`matremap sweep ... --threads 2\`")
        local shapes=("1 × 1" "1 × 1" "2 × 1" "1 × 2")
        for i in 0 1 2 3; do
            printf '| %s | %s | %.2f | %.2f | %.1f | %.2f× |\n' "${names[$i]}" "${shapes[$i]}" "${walls[$i]}" "${cpus[$i]}" \
                "$(awk -v w="${walls[$i]}" -v n="$n" 'BEGIN {print n / w}')" \
                "$(awk -v a="${walls[0]}" -v b="${walls[$i]}" 'BEGIN {print a / b}')"
        done
        echo
        echo "Speed-up of 2 ranks over 1 (whole commands): **${speedup}×** (target ≥ 1.8×); the work MPI adds: CPU"
        echo "$(awk -v a="${cpus[2]}" -v b="${cpus[0]}" 'BEGIN {printf "%.2f", a / b}')× that of one process. On a machine that other jobs share, the wall clock measures them too"
        echo "(a load average above the core count means this process did not have its cores)."
    } >"$out"

    # The cost model: one core's rate per model pair (1 thread), from M random samples in the default fit scene and
    # M/6 in the paper's (512², 64 times the pixels): remaps per CPU second, which other jobs on a shared machine
    # inflate much less than the wall clock.
    local pairs=("ward diffuse=0|ggx diffuse=0|the learned transforms' pair (docs/learn.md)"
        "ggx|ward-balanced|this section's sweep" "as diffuse=0|ward trim=1|the paper's Appendix pair"
        "ggx-metallic|ggx|the workflow pair (docs/workflow.md)" "gltf|blender-ward|glTF into Blender's Ward")
    local efficiency big=$((m / 6))
    efficiency=$(awk -v s="$speedup" 'BEGIN {e = s / 2; if (e > 1) e = 1; printf "%.2f", e}')
    {
        echo
        echo "Remaps per second on one core (\`--threads 1\`, random samples, seed 3: $m in the default fit scene, 64², and"
        echo "$big in the paper's, \`--size 512\`; samples per CPU second), and what sweeps cost on C cores at the efficiency"
        echo "measured above (${efficiency} = speed-up / ranks): T = N / (rate × C × ${efficiency}), plus MPI's start."
        echo
        echo "| from → to | pair | remaps/s per core, 64² | renders per remap | remaps/s per core, 512² | 10,000 rows, 64², 2 cores | 10,000 rows, 512², 2 cores | 10,000 rows, 512², 64 cores | 100,000 rows, 512², 1,024 cores |"
        echo "|---|---|---:|---:|---:|---:|---:|---:|---:|"
    } >>"$out"
    human() { awk -v t="$1" 'BEGIN { if (t < 120) printf "%.0f s", t; else if (t < 7200) printf "%.0f min", t / 60; else printf "%.1f h", t / 3600 }'; }
    cost() { awk -v n="$1" -v r="$2" -v c="$3" -v e="$efficiency" 'BEGIN {print n / (r * c * e)}'; }
    local entry from to what w c rate rate512 renders
    for entry in "${pairs[@]}"; do
        IFS='|' read -r from to what <<<"$entry"
        rm -f "$dir/pair.csv" "$dir/pair512.csv"
        # shellcheck disable=SC2086 # the model's values are separate words
        read -r w c < <(times_of "$dir/pair.log" "$bin" sweep --from $from --to $to --random "$m" --seed 3 --threads 1 \
            -o "$dir/pair.csv")
        rate=$(awk -v n="$m" -v c="$c" 'BEGIN {printf "%.1f", n / c}')
        renders=$(grep -v '^#' "$dir/pair.csv" | tail -n +2 | awk -F, '{ s += $(NF - 1) } END { printf "%.0f", s / NR }')
        # shellcheck disable=SC2086
        read -r w c < <(times_of "$dir/pair512.log" "$bin" sweep --from $from --to $to --random "$big" --seed 3 \
            --threads 1 --size 512 -o "$dir/pair512.csv")
        rate512=$(awk -v n="$big" -v c="$c" 'BEGIN {printf "%.2f", n / c}')
        printf '| %s → %s | %s | %s | %s | %s | %s | %s | %s | %s |\n' "$from" "$to" "$what" "$rate" "$renders" "$rate512" \
            "$(human "$(cost 10000 "$rate" 2)")" "$(human "$(cost 10000 "$rate512" 2)")" \
            "$(human "$(cost 10000 "$rate512" 64)")" "$(human "$(cost 100000 "$rate512" 1024)")" | tee -a "$out"
    done
    cat "$out"
}

# What the analytic parameter derivatives cost against the evaluation, per model (docs/performance.md,
# bench:brdf-grad): tests/bench_brdf_grad.c, one thread.
bench_brdf_grad() {
    echo
    echo "== parameter derivatives: eval_grad against eval, per model, one thread (tests/bench_brdf_grad.c)"
    {
        echo "Measured by \`make bench\` on $(date -u +%Y-%m-%d), $(nproc) cores ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'))."
        echo
        "$root/$build/tests/bench_brdf_grad" $quick
    } | tee "$work/brdf_grad.md"
}

if [ -n "$only" ]; then
    case $only in
        brdf-grad)
            bench_brdf_grad
            replace_section brdf-grad "$work/brdf_grad.md"
            ;;
        report-accuracy) bench_report_accuracy ;;
        gltf)
            bench_gltf
            replace_section gltf "$work/gltf.md"
            ;;
        library)
            bench_library
            replace_section library "$work/library.md"
            ;;
        reflection) bench_reflection ;;
        remap)
            bench_remap_table
            bench_remap_processes
            replace_section remap "$work/remap.md"
            replace_section remap-processes "$work/remap_processes.md"
            ;;
        direct)
            bench_direct
            replace_section direct "$work/direct.md"
            ;;
        learn)
            bench_learn
            replace_section learn "$work/learn.md"
            ;;
        mpi)
            bench_mpi
            replace_section mpi "$work/mpi.md"
            ;;
        fit-engine)
            bench_fit_engine
            replace_section fit-engine "$work/fit_engine.md"
            ;;
        remap-processes)
            bench_remap_processes
            replace_section remap-processes "$work/remap_processes.md"
            ;;
        png)
            bench_png
            replace_section png "$work/png.md"
            ;;
        workflow)
            bench_workflow
            bench_workflow_e2e
            replace_section workflow "$work/workflow.md"
            replace_section workflow-e2e "$work/e2e.md"
            ;;
        *) echo "bench.sh: --only: unknown section '$only' (sections: brdf-grad, report-accuracy, reflection, workflow, png, gltf, library, remap, fit-engine, remap-processes, direct, learn, mpi)" >&2; exit 1 ;;
    esac
    exit 0
fi


echo "== fit-scene render time per model (tests/bench_render.c)"
"$root/$build/tests/bench_render" $quick | tee "$work/render_table.md"

echo
echo "== image metrics (tests/bench_metrics.c)"
"$root/$build/tests/bench_metrics" | tee "$work/metrics_table.md"

bench_brdf_grad

echo
bench_remap_table
bench_fit_engine
bench_remap_processes
bench_direct
bench_learn
bench_mpi

bench_workflow

echo
echo "== environment lights: error and cost against the pattern size N (tests/bench_envlight.c)"
{
    echo "Measured by \`make bench\` on $(date -u +%Y-%m-%d), $(nproc) cores ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'))."
    echo
    "$root/$build/tests/bench_envlight" "${MR_SHARED:-$root/../shared}/assets/hdri" $quick
} | tee "$work/envlight.md"

echo
echo "== triangle meshes: plan, render and BVH cost against the triangle count (tests/bench_mesh.c)"
{
    echo "Measured by \`make bench\` on $(date -u +%Y-%m-%d), $(nproc) cores ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'))."
    echo
    "$root/$build/tests/bench_mesh" "${MR_SHARED:-$root/../shared}/assets/hdri" $quick
} | tee "$work/mesh.md"

{
    echo "Measured by \`make bench\` on $(date -u +%Y-%m-%d), $(nproc) cores ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')), matremap $("$bin" --version | cut -d' ' -f2)."
    echo
    cat "$work/render_table.md"
    echo
} > "$report"

if command -v blender >/dev/null 2>&1; then
    echo
    echo "== peer: Blender Cycles, Principled BSDF (single-scatter GGX), 16 spp, same fit scene, 2 threads"
    params="base_color=0.8,0.8,0.8 metallic=0 specular=0.5 roughness=0.5"
    {
        echo "Peer, same run: Blender $(blender --version 2>/dev/null | head -1 | cut -d' ' -f2) Cycles renders the fit scene with the Principled BSDF (GGX,"
        echo "16 spp, 2 threads, box filter, direct light only). 'Cycles render' is Cycles' own render time (scene"
        echo "built, Blender start-up excluded); 'ours' is \`matremap render cycles-principled\` with the plan prepared"
        echo "(median of the table above, 2 threads) and as a whole process (start-up, plan, render, EXR write)."
        echo "SSIM compares the two images (display-referred, docs/metrics.md): Cycles' 16-spp noise keeps it"
        echo "below 1."
        echo
        echo "| size | Cycles render ms | Cycles process s | ours render ms | ours process ms | render ratio Cycles/ours | SSIM ours vs Cycles |"
        echo "|---:|---:|---:|---:|---:|---:|---:|"
    } >> "$report"
    for size in 256 512; do
        cycles_ms=()
        cycles_total=()
        for run in 1 2 3; do
            t0=$(date +%s.%N)
            "$root/scripts/cycles-render.sh" --size "$size" --samples 16 --threads 2 --light 45 \
                --material principled --base-color 0.8,0.8,0.8 --metallic 0 --specular 0.5 --roughness 0.5 \
                --distribution GGX -o "$work/cycles_$size.exr" --timing-json "$work/cycles_$size.json" >/dev/null 2>&1
            t1=$(date +%s.%N)
            cycles_ms+=("$(sed -E 's/.*"render_seconds": ([0-9.eE+-]+).*/\1/' "$work/cycles_$size.json" | awk '{print $1 * 1000}')")
            cycles_total+=("$(awk -v a="$t0" -v b="$t1" 'BEGIN {print b - a}')")
        done
        c_ms=$(printf '%s\n' "${cycles_ms[@]}" | median)
        c_total=$(printf '%s\n' "${cycles_total[@]}" | median)
        ours_ms=$(grep -m1 '^| cycles-principled ' "$work/render_table.md" | awk -F'|' -v col=$([ "$size" = 256 ] && echo 4 || echo 6) '{gsub(/ /, "", $col); print $col}')
        ours_total=()
        for run in 1 2 3; do
            t0=$(date +%s.%N)
            OMP_NUM_THREADS=2 "$bin" render cycles-principled $params --size "$size" -o "$work/ours_$size.exr" 2>/dev/null
            t1=$(date +%s.%N)
            ours_total+=("$(awk -v a="$t0" -v b="$t1" 'BEGIN {print (b - a) * 1000}')")
        done
        o_total=$(printf '%s\n' "${ours_total[@]}" | median)
        ssim=$("$bin" ssim "$work/ours_$size.exr" "$work/cycles_$size.exr")
        ratio=$(awk -v a="$c_ms" -v b="$ours_ms" 'BEGIN {print a / b}')
        printf '| %s² | %.0f | %.2f | %.2f | %.0f | %.0f× | %s |\n' "$size" "$c_ms" "$c_total" "$ours_ms" "$o_total" \
            "$ratio" "$ssim" | tee -a "$report"
    done
    # Accuracy of the cycles-principled descriptor against Cycles itself, for materials across the parameter
    # space (256², 64 spp to keep Cycles' noise out of the comparison, single-scatter GGX as the model).
    {
        echo
        echo "Agreement of our \`cycles-principled\` model with Cycles' Principled BSDF (GGX), 256², Cycles at 64 spp:"
        echo
        echo "| material | SSIM ours vs Cycles | RMSE (linear) | peak radiance |"
        echo "|---|---:|---:|---:|"
    } >> "$report"
    echo
    echo "== agreement of cycles-principled with Cycles (256², 64 spp)"
    while read -r label base metallic specular roughness tint; do
        "$root/scripts/cycles-render.sh" --size 256 --samples 64 --threads 2 --light 45 --material principled \
            --base-color "$base" --metallic "$metallic" --specular "$specular" --roughness "$roughness" \
            --specular-tint "$tint" --distribution GGX -o "$work/agree_cycles.exr" >/dev/null 2>&1
        "$bin" render cycles-principled base_color="$base" metallic="$metallic" specular="$specular" \
            roughness="$roughness" specular_tint="$tint" --size 256 -o "$work/agree_ours.exr" 2>/dev/null
        json=$("$bin" ssim --json "$work/agree_ours.exr" "$work/agree_cycles.exr")
        peak=$(oiiotool --stats "$work/agree_ours.exr" 2>/dev/null | sed -n 's/.*Stats Max: *//p' |
            awk '{m = $1; for (i = 2; i <= 3; i++) if ($i + 0 > m + 0) m = $i; printf "%.3g", m}')
        printf '| %s (base %s, metallic %s, specular %s, roughness %s, tint %s) | %.4f | %.4g | %s |\n' "$label" "$base" \
            "$metallic" "$specular" "$roughness" "$tint" "$(echo "$json" | sed -E 's/.*"ssim": ([^,]*),.*/\1/')" \
            "$(echo "$json" | sed -E 's/.*"rmse": ([^}]*)}.*/\1/')" "${peak:-?}" | tee -a "$report"
    done <<'MATERIALS'
grey-plastic 0.8,0.8,0.8 0 0.5 0.5 0
red-glossy 0.8,0.1,0.05 0 0.5 0.2 0
tinted-rough 0.2,0.5,0.8 0 1 0.8 1
gold 1,0.766,0.336 1 0.5 0.3 0
half-metal 0.5,0.6,0.2 0.5 0.5 0.4 0.5
MATERIALS
else
    echo
    echo "(Blender not installed: the Cycles peer was skipped; scripts/install-deps.sh installs it)"
    echo "Cycles peer skipped: Blender was not installed in this run." >> "$report"
fi

bench_workflow_e2e

bench_gltf
bench_report_accuracy
bench_reflection
bench_png

if [ -f "$perf" ]; then
    echo
    replace_section render "$report"
    replace_section metrics "$work/metrics_table.md"
    replace_section remap "$work/remap.md"
    replace_section fit-engine "$work/fit_engine.md"
    replace_section remap-processes "$work/remap_processes.md"
    replace_section direct "$work/direct.md"
    replace_section learn "$work/learn.md"
    replace_section mpi "$work/mpi.md"
    replace_section workflow "$work/workflow.md"
    replace_section workflow-e2e "$work/e2e.md"
    replace_section gltf "$work/gltf.md"
    replace_section png "$work/png.md"
    replace_section brdf-grad "$work/brdf_grad.md"
fi
replace_section envlight "$work/envlight.md" "$root/docs/rendering.md"
replace_section mesh "$work/mesh.md" "$root/docs/rendering.md"
