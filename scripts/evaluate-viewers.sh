#!/usr/bin/env bash
# make evaluation-viewers: the spec-gloss glTF assets of ../shared/assets and their metal-rough conversions as the
# viewers people use show them (docs/evaluation.md, "What viewers show"):
#   - Blender Cycles (Debian's Blender 3.4, its own glTF importer; scripts/viewers/blender_render.py),
#   - three.js r146 in headless Chromium (the last GLTFLoader that reads KHR_materials_pbrSpecularGlossiness, so it
#     renders the spec-gloss originals too) and the current three.js (metal-rough only) (scripts/viewers/), once as
#     it ships and once with KHR_materials_specular and KHR_materials_ior stripped from the files (a core-only
#     engine).
# For every asset (and DuckPlastic, the Duck as a specular-0.04 dielectric, made here) and both HDR maps each viewer
# renders the spec-gloss original (where it can), the asset's own metal-rough material (where it has one),
# `matremap gltf spec2metal` with weighted and mean in both conventions, khronos, mlp (core only), the default (both
# readings: weighted + KHR_materials_specular) and its variants (other core methods, the gltf convention, ior 1000),
# extension, and gltf-transform's metalrough. Each render is compared with the viewer's reference on the object's
# pixels (BUILD/tools/object_metrics: SSIM from mr_ssim's map, mean luminance ratio). The tables go
# into docs/evaluation.md between the eval-viewers markers, one picture per asset into docs/evaluation/, renders
# and job files into BUILD/evaluation-viewers/.
# Installs what it needs: Blender and Chromium (scripts/install-deps.sh --bench), the pinned npm packages
# (scripts/viewers, scripts/gltf-transform; npm ci).
# Usage: scripts/evaluate-viewers.sh [BUILD]. Environment: VIEWERS_SIZE (three.js, default 384),
# VIEWERS_CYCLES_SIZE (default 256), VIEWERS_CYCLES_SAMPLES (default 128), VIEWERS_THREADS (Cycles, default 2),
# VIEWERS_ASSETS (a subset of "Avocado CesiumMilkTruck Duck FloppyDisk DuckPlastic", for trying things out),
# VIEWERS_SKIP_CYCLES=1 (three.js only, Blender not run: its rows are "-"; the tables stay in BUILD, docs/ is left as
# it is: for trying things out), MR_SHARED.
set -euo pipefail
build=${1:-build}
root=$(cd "$(dirname "$0")/.." && pwd)
bin="$root/$build/bin/matremap"
metrics="$root/$build/tools/object_metrics"
assets="${MR_SHARED:-$root/../shared}/assets"
work="$root/$build/evaluation-viewers"
viewers="$root/scripts/viewers"
gt="$root/scripts/gltf-transform"
export LC_ALL=C
export VIEWERS_SIZE=${VIEWERS_SIZE:-384} VIEWERS_CYCLES_SIZE=${VIEWERS_CYCLES_SIZE:-256}
export VIEWERS_CYCLES_SAMPLES=${VIEWERS_CYCLES_SAMPLES:-128} VIEWERS_THREADS=${VIEWERS_THREADS:-2}
if [ ! -x "$bin" ] || [ ! -x "$metrics" ]; then
    echo "evaluation-viewers: $bin or $metrics is missing (run make evaluation-viewers)" >&2
    exit 1
fi
t_start=$(date +%s)

"$root/scripts/install-deps.sh" --bench
for d in "$viewers" "$gt"; do
    if [ ! -d "$d/node_modules" ] || [ "$d/package-lock.json" -nt "$d/node_modules/.package-lock.json" ]; then
        (cd "$d" && npm ci --no-audit --no-fund --loglevel=error) >&2
    fi
done
chromium_bin=/usr/lib/chromium/chromium # /usr/bin/chromium is Debian's wrapper script around it
[ -x "$chromium_bin" ] || { echo "evaluation-viewers: $chromium_bin is missing" >&2; exit 1; }

rm -rf "$work"
mkdir -p "$work/renders" "$root/docs/evaluation"

# The conversions: one folder per asset and route, each with out.gltf. The variant list of each asset is its line
# in variants.tsv (asset, source glTF, view azimuth, elevation, variants...).
sg="$assets/specgloss"
declare -A source=(
    [Avocado]="$sg/Avocado-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Avocado.gltf"
    [CesiumMilkTruck]="$sg/CesiumMilkTruck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/CesiumMilkTruck.gltf"
    [Duck]="$sg/Duck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Duck.gltf"
    [FloppyDisk]="$sg/FloppyDisk-sketchfab/scene.gltf"
    [DuckPlastic]="$work/DuckPlastic/source/Duck.gltf"
)
# Views (azimuth, elevation in degrees; azimuth 0 looks from glTF's +Z): the disk stands in the YZ plane.
declare -A view=([Avocado]="30 20" [CesiumMilkTruck]="30 20" [Duck]="30 20" [FloppyDisk]="120 15"
                 [DuckPlastic]="30 20")
# DuckPlastic: the Duck as an ordinary dielectric exactly on the metallic manifold, specular 0.04 instead of its 0
# and no metal-rough material of its own, the case the two conventions disagree on (base colour 0.96 d or d, metallic
# 0). Made here from the Duck's files; nothing of it is committed.
mkdir -p "$work/DuckPlastic/source"
duck_dir=$(dirname "${source[Duck]}")
ln -s "$duck_dir/Duck0.bin" "$duck_dir/DuckCM.png" "$work/DuckPlastic/source/"
python3 - "${source[Duck]}" "${source[DuckPlastic]}" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
for m in d["materials"]:
    m.pop("pbrMetallicRoughness", None)
    m["extensions"]["KHR_materials_pbrSpecularGlossiness"]["specularFactor"] = [0.04, 0.04, 0.04]
json.dump(d, open(sys.argv[2], "w"), indent=1)
PY
: > "$work/variants.tsv"
t_convert=$(date +%s)
for name in ${VIEWERS_ASSETS:-Avocado CesiumMilkTruck Duck FloppyDisk DuckPlastic}; do
    src=${source[$name]}
    line=("$name" "$src" ${view[$name]} specgloss)
    # The asset's own metal-rough material (its core pbrMetallicRoughness beside the extension): the extension
    # dropped, the rest kept (spec2metal's default for such a material; --core-only: nothing added). FloppyDisk and
    # DuckPlastic have none.
    if [ "$name" != FloppyDisk ] && [ "$name" != DuckPlastic ]; then
        mkdir -p "$work/$name/authors"
        "$bin" gltf spec2metal "$src" -o "$work/$name/authors/out.gltf" --core-only --method weighted >/dev/null
        line+=(authors)
    fi
    # Every conversion route converts the authors' materials too (--overwrite-metal-rough); the core routes write
    # the core values alone (--core-only); hybrid is spec2metal's default (weighted + KHR_materials_specular).
    # The default reads the spec-gloss diffuse as paper does (the base colour gltf-transform keeps); hybrid-gltf reads
    # it as glTF does, hybrid-ior1000 solves the specular colour for ior 1000 (KHR_materials_ior written): the two
    # choices measured. hybrid-mlp, -mean, -khronos: both readings over another core method than the default's
    # weighted (--method M), the choice of the default's core method measured.
    routes=(weighted:gltf weighted:paper mean:gltf mean:paper khronos: mlp: hybrid: hybrid:gltf hybrid-ior1000:
            hybrid-mlp: hybrid-mean: hybrid-khronos: extension: gltf-transform:)
    # DuckPlastic only asks the convention question: mean equals weighted on its grey specular.
    [ "$name" = DuckPlastic ] && routes=(weighted:gltf weighted:paper khronos: mlp: hybrid: hybrid:gltf
                                         hybrid-mlp: hybrid-khronos: extension:)
    for route in "${routes[@]}"; do
        method=${route%%:*} convention=${route#*:}
        label=$method${convention:+-$convention}
        mkdir -p "$work/$name/$label"
        if [ "$method" = gltf-transform ]; then
            "$gt/node_modules/.bin/gltf-transform" metalrough "$src" "$work/$name/$label/out.gltf" >/dev/null 2>&1
        elif [ "${method%%-*}" = hybrid ]; then
            ior= core=
            [ "$method" = hybrid-ior1000 ] && ior="--extension-ior 1000"
            case $method in hybrid-mlp|hybrid-mean|hybrid-khronos) core="--method ${method#hybrid-}" ;; esac
            # shellcheck disable=SC2086
            "$bin" gltf spec2metal "$src" -o "$work/$name/$label/out.gltf" --overwrite-metal-rough $ior $core \
                ${convention:+--convention "$convention"} > "$work/$name/$label/summary.txt"
        else
            core_only=--core-only
            [ "$method" = extension ] && core_only=
            "$bin" gltf spec2metal "$src" -o "$work/$name/$label/out.gltf" --method "$method" $core_only \
                --overwrite-metal-rough ${convention:+--convention "$convention"} >/dev/null
        fi
        line+=("$label")
    done
    (IFS=$'\t'; echo "${line[*]}") >> "$work/variants.tsv"
done
echo "evaluation-viewers: conversions in $(($(date +%s) - t_convert)) s" >&2

# Job files for both viewers (the reference of each asset is rendered a second time: in Cycles with another seed,
# the noise floor; in three.js, to show the render is deterministic).
python3 "$viewers/evaluate_viewers.py" jobs "$work" "$assets/hdri" "$chromium_bin"

# shellcheck source=scripts/lib/timing.sh
. "$root/scripts/lib/timing.sh"
# Wall-clock and CPU seconds of each viewer's whole run (the machine is shared: CPU time is the work done).
if [ "${VIEWERS_SKIP_CYCLES:-0}" = 1 ]; then
    cycles_times="0 0"
    : > "$work/cycles-done.jsonl"
    echo "evaluation-viewers: VIEWERS_SKIP_CYCLES=1: no Cycles renders" >&2
else
    cycles_times=$(times_of "$work/cycles.log" nice -n 10 blender -b --factory-startup --python-exit-code 3 \
        --python "$viewers/blender_render.py" -- "$work/cycles-jobs.json") \
        || { echo "evaluation-viewers: Blender failed, see $work/cycles.log" >&2; exit 3; }
    grep '^{' "$work/cycles.log" > "$work/cycles-done.jsonl"
fi
echo "evaluation-viewers: Cycles renders: wall, CPU s $cycles_times" >&2
three_times=$(times_of "$work/three.log" nice -n 10 node "$viewers/three_render.mjs" "$work/three-jobs.json") \
    || { echo "evaluation-viewers: three.js failed, see $work/three.log" >&2; exit 3; }
grep '^{' "$work/three.log" > "$work/three-done.jsonl"
echo "evaluation-viewers: three.js renders: wall, CPU s $three_times" >&2

python3 "$viewers/evaluate_viewers.py" metrics "$work" "$metrics" > "$work/metrics.jsonl"
[ "${VIEWERS_SKIP_CYCLES:-0}" = 1 ] || python3 "$viewers/evaluate_viewers.py" pictures "$work" "$root/docs/evaluation"
python3 "$viewers/evaluate_viewers.py" table "$work" "$(date -u +%Y-%m-%d)" "$("$bin" --version | cut -d' ' -f2)" \
    "$(blender --version 2>/dev/null | head -n 1)" "$cycles_times" "$three_times" "$(($(date +%s) - t_start))" \
    > "$work/table.md"
cat "$work/table.md"
# shellcheck source=scripts/lib/doc_section.sh
. "$root/scripts/lib/doc_section.sh"
if [ "${VIEWERS_SKIP_CYCLES:-0}" = 1 ]; then
    echo "evaluation-viewers: VIEWERS_SKIP_CYCLES=1: tables in $work/table.md only, docs/evaluation.md left as it is"
elif replace_doc_section "$root/docs/evaluation.md" eval-viewers "$work/table.md"; then
    echo "evaluation-viewers: tables written into docs/evaluation.md, pictures into docs/evaluation/viewers_*.png"
fi
