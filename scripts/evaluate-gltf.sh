#!/usr/bin/env bash
# make evaluation-gltf: the spec-gloss glTF assets of ../shared/assets converted by `matremap gltf spec2metal` with
# every method and by gltf-transform's `metalrough` (npm, scripts/gltf-transform), each rendered as its mesh under
# the studio HDR map from four sides by `matremap report` and compared with the spec-gloss original (SSIM,
# relative RMSE), with each conversion's time measured in the same run. The table goes into docs/evaluation.md
# between the eval-gltf markers, one picture per asset (the first view of every conversion) into
# docs/evaluation/, the report folders into BUILD/evaluation-gltf/.
# Usage: scripts/evaluate-gltf.sh [BUILD]. Environment: EVAL_SIZE (default 384), MR_SHARED.
set -euo pipefail
build=${1:-build}
root=$(cd "$(dirname "$0")/.." && pwd)
bin="$root/$build/bin/matremap"
assets="${MR_SHARED:-$root/../shared}/assets"
work="$root/$build/evaluation-gltf"
size=${EVAL_SIZE:-384}
env_map="$assets/hdri/studio_small_03_1k.hdr"
gt="$root/scripts/gltf-transform"
export LC_ALL=C
[ -x "$bin" ] || { echo "evaluation-gltf: $bin is missing (run make first)" >&2; exit 1; }
if [ ! -x "$gt/node_modules/.bin/gltf-transform" ]; then
    (cd "$gt" && npm ci --no-audit --no-fund --loglevel=error) >&2
fi
rm -rf "$work"
mkdir -p "$work" "$root/docs/evaluation"
# shellcheck source=scripts/lib/timing.sh
. "$root/scripts/lib/timing.sh"
table="$work/table.md"
{
    echo "Measured by \`make evaluation-gltf\` on $(date -u +%Y-%m-%d), matremap $("$bin" --version | cut -d' ' -f2),"
    echo "gltf-transform $("$gt/node_modules/.bin/gltf-transform" --version 2>/dev/null | tail -n 1): each asset's mesh,"
    echo "${size}², under studio_small_03 turned in 4 steps of 90° (\`matremap report\`, its default 256 environment"
    echo "directions); SSIM (display-referred, at the original's mid-grey exposure) and relative RMSE against the"
    echo "spec-gloss original, means over the four views; conversion time = the whole conversion process, read to"
    echo "written."
    echo
    echo "| asset | conversion | mean SSIM | mean rel. RMSE | conversion s | time vs gltf-transform |"
    echo "|---|---|---:|---:|---:|---:|"
} > "$table"
for asset in Avocado-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Avocado.gltf \
             CesiumMilkTruck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/CesiumMilkTruck.gltf \
             Duck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Duck.gltf FloppyDisk-sketchfab/scene.gltf; do
    source_gltf="$assets/specgloss/$asset"
    name=${asset%%-*}
    name=${name%%/*}
    echo "== $name"
    declare -A seconds=()
    args=(--label "spec-gloss original" "$source_gltf")
    for method in mlp weighted mean khronos extension; do
        mkdir -p "$work/$name/$method"
        # --overwrite-metal-rough: the Avocado, the Duck and the truck carry the artists' own metal-rough values
        # beside spec-gloss, which the command otherwise keeps; the conversion is what is evaluated here.
        seconds[$method]=$(seconds_of "$bin" gltf spec2metal "$source_gltf" -o "$work/$name/$method/out.gltf" \
            --method "$method" --overwrite-metal-rough)
        args+=(-- --label "$method" "$work/$name/$method/out.gltf")
    done
    mkdir -p "$work/$name/gltf-transform"
    seconds[gltf-transform]=$(seconds_of "$gt/node_modules/.bin/gltf-transform" metalrough "$source_gltf" \
        "$work/$name/gltf-transform/out.gltf")
    args+=(-- --label gltf-transform "$work/$name/gltf-transform/out.gltf")
    "$bin" report -o "$work/$name/report" --env "$env_map" --rotations 4 --size "$size" \
        --title "$name: spec-gloss to metal-rough" "${args[@]}"
    python3 - "$work/$name/report/summary.json" "$name" "${seconds[mlp]}" "${seconds[weighted]}" \
        "${seconds[mean]}" "${seconds[khronos]}" "${seconds[extension]}" "${seconds[gltf-transform]}" \
        >> "$table" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
name = sys.argv[2]
times = dict(zip(["mlp", "weighted", "mean", "khronos", "extension", "gltf-transform"], map(float, sys.argv[3:9])))
for m in d["materials"][1:]:
    t = times[m["label"]]
    print("| %s | %s | %.4f | %.4f | %.2f | %.2f× |" % (name, m["label"], m["mean_ssim"], m["mean_relative_rmse"], t,
                                                     t / times["gltf-transform"]))
PY
    # One picture: the first view of the original and of every conversion, labelled.
    pictures=()
    labels=("spec-gloss original" mlp weighted mean khronos extension gltf-transform)
    for k in 0 1 2 3 4 5 6; do
        pictures+=("$work/$name/report/view0_material$k.png"
                   "--text:x=6:y=18:size=16:color=1,1,1:font=DejaVuSans" "${labels[$k]}")
    done
    oiiotool "${pictures[@]}" --mosaic:pad=4 7x1 -o "$root/docs/evaluation/gltf_$name.png"
done
cat "$table"
doc="$root/docs/evaluation.md"
if grep -q '<!-- eval-gltf:begin -->' "$doc"; then
    awk -v table="$table" '
        /<!-- eval-gltf:begin -->/ { print; while ((getline line < table) > 0) print line; skip = 1; next }
        /<!-- eval-gltf:end -->/ { skip = 0 }
        !skip' "$doc" > "$doc.tmp" && mv "$doc.tmp" "$doc"
    echo "evaluation-gltf: table written into docs/evaluation.md, pictures into docs/evaluation/gltf_*.png"
fi
