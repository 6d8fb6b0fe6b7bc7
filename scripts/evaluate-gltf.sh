#!/usr/bin/env bash
# make evaluation-gltf: the spec-gloss glTF assets of ../shared/assets converted by `matremap gltf spec2metal` with
# every method and by gltf-transform's `metalrough` (npm, scripts/gltf-transform), each rendered as its mesh under
# each of the two shared HDR maps from four sides by `matremap report` and compared with the spec-gloss original (SSIM and
# relative RMSE over the object's pixels, the report's headline, and the whole frame's beside them), with each
# conversion's time measured in the same run. The table goes into docs/evaluation.md between the eval-gltf
# markers, one picture per asset (the first view of every conversion) into docs/evaluation/, the report folders
# into BUILD/evaluation-gltf/.
# Usage: scripts/evaluate-gltf.sh [BUILD]. Environment: EVAL_SIZE (default 384), MR_SHARED, EVAL_ONLY (a smoke
# run: only these assets, e.g. "Duck", and docs/ is left alone).
set -euo pipefail
build=${1:-build}
root=$(cd "$(dirname "$0")/.." && pwd)
bin="$root/$build/bin/matremap"
assets="${MR_SHARED:-$root/../shared}/assets"
work="$root/$build/evaluation-gltf"
size=${EVAL_SIZE:-384}
env_names=(studio tabac)
env_maps=("$assets/hdri/studio_small_03_1k.hdr" "$assets/hdri/tabac_plant_vogl.hdr")
gt="$root/scripts/gltf-transform"
only=${EVAL_ONLY:-}
pics="$root/docs/evaluation"
if [ -n "$only" ]; then pics="$work/pictures"; fi
export LC_ALL=C
[ -x "$bin" ] || { echo "evaluation-gltf: $bin is missing (run make first)" >&2; exit 1; }
if [ ! -x "$gt/node_modules/.bin/gltf-transform" ]; then
    (cd "$gt" && npm ci --no-audit --no-fund --loglevel=error) >&2
fi
rm -rf "$work"
mkdir -p "$work" "$pics"
# shellcheck source=scripts/lib/timing.sh
. "$root/scripts/lib/timing.sh"
# shellcheck source=scripts/lib/evaluation.sh
. "$root/scripts/lib/evaluation.sh"
table="$work/table.md"
{
    echo "Measured by \`make evaluation-gltf\` on $(date -u +%Y-%m-%d), matremap $("$bin" --version | cut -d' ' -f2),"
    echo "gltf-transform $("$gt/node_modules/.bin/gltf-transform" --version 2>/dev/null | tail -n 1): each asset's mesh,"
    echo "${size}², under studio_small_03 and under the Tabac Plant probe, each turned in 4 steps of 90° (\`matremap"
    echo "report\`, its default 256 environment directions); SSIM (display-referred, at the original's mid-grey"
    echo "exposure) and relative RMSE against the spec-gloss original, means over the four views, **over the object**"
    echo "(SSIM over the pixels whose window touches it, relative RMSE over its pixels as a fraction of the original's"
    echo "mean radiance there), and the whole frame's SSIM beside them (background included); the best per-texel"
    echo "conversion of each asset in bold; conversion time = the whole conversion process, read to written."
    echo
    echo -n "| asset | conversion | object SSIM studio | object SSIM tabac | **object SSIM mean** "
    echo "| object rel. RMSE (mean) | whole-frame SSIM (mean) | conversion s | time vs gltf-transform |"
    echo "|---|---|---:|---:|---:|---:|---:|---:|---:|"
} > "$table"
for asset in Avocado-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Avocado.gltf \
             CesiumMilkTruck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/CesiumMilkTruck.gltf \
             Duck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Duck.gltf FloppyDisk-sketchfab/scene.gltf; do
    source_gltf="$assets/specgloss/$asset"
    name=${asset%%-*}
    name=${name%%/*}
    if [ -n "$only" ] && [[ " $only " != *" $name "* ]]; then continue; fi
    echo "== $name"
    declare -A seconds=()
    args=(--label "spec-gloss original" "$source_gltf")
    for method in mlp weighted mean khronos extension; do
        mkdir -p "$work/$name/$method"
        # --overwrite-metal-rough: the Avocado, the Duck and the truck carry the artists' own metal-rough values
        # beside spec-gloss, which the command otherwise keeps; the conversion is what is evaluated here, its core
        # values alone (--core-only; the default's KHR_materials_specular is measured by make evaluation-viewers).
        core_only=--core-only
        [ "$method" = extension ] && core_only=
        seconds[$method]=$(seconds_of "$bin" gltf spec2metal "$source_gltf" -o "$work/$name/$method/out.gltf" \
            --method "$method" --overwrite-metal-rough $core_only)
        args+=(-- --label "$method" "$work/$name/$method/out.gltf")
    done
    mkdir -p "$work/$name/gltf-transform"
    seconds[gltf-transform]=$(seconds_of "$gt/node_modules/.bin/gltf-transform" metalrough "$source_gltf" \
        "$work/$name/gltf-transform/out.gltf")
    args+=(-- --label gltf-transform "$work/$name/gltf-transform/out.gltf")
    for e in 0 1; do
        "$bin" report -o "$work/$name/report-${env_names[$e]}" --env "${env_maps[$e]}" --rotations 4 --size "$size" \
            --title "$name: spec-gloss to metal-rough (${env_names[$e]})" "${args[@]}"
    done
    python3 - "$work/$name/report-studio/summary.json" "$work/$name/report-tabac/summary.json" "$name" \
        "${seconds[mlp]}" "${seconds[weighted]}" "${seconds[mean]}" "${seconds[khronos]}" "${seconds[extension]}" \
        "${seconds[gltf-transform]}" >> "$table" <<'PY'
import json, sys
studio, tabac = (json.load(open(p))["materials"][1:] for p in sys.argv[1:3])
name = sys.argv[3]
times = dict(zip(["mlp", "weighted", "mean", "khronos", "extension", "gltf-transform"], map(float, sys.argv[4:10])))
mean = {a["label"]: (a["mean_object_ssim"] + b["mean_object_ssim"]) / 2 for a, b in zip(studio, tabac)}
best = max(mean[k] for k in ("mlp", "weighted", "mean", "khronos"))
for a, b in zip(studio, tabac):
    label, t = a["label"], times[a["label"]]
    m = "**%.4f**" % mean[label] if label != "extension" and label != "gltf-transform" and mean[label] == best \
        else "%.4f" % mean[label]
    print("| %s | %s | %.4f | %.4f | %s | %.4f | %.4f | %.2f | %.2f× |" % (
        name, label, a["mean_object_ssim"], b["mean_object_ssim"], m,
        (a["mean_object_relative_rmse"] + b["mean_object_relative_rmse"]) / 2,
        (a["mean_ssim"] + b["mean_ssim"]) / 2, t, t / times["gltf-transform"]))
PY
    # One picture: the first view of the original and of every conversion, labelled.
    pictures=()
    labels=("spec-gloss original" mlp weighted mean khronos extension gltf-transform)
    for k in 0 1 2 3 4 5 6; do
        pictures+=("$work/$name/report-studio/view0_material$k.png"
                   "--text:x=6:y=18:size=16:color=1,1,1:font=DejaVuSans" "${labels[$k]}")
    done
    oiiotool "${pictures[@]}" --mosaic:pad=4 7x1 -o "$pics/gltf_$name.png"
done
cat "$table"
if [ -z "$only" ] && splice_table "$root/docs/evaluation.md" eval-gltf "$table"; then
    echo "evaluation-gltf: table written into docs/evaluation.md, pictures into docs/evaluation/gltf_*.png"
fi
