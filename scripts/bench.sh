#!/usr/bin/env bash
# make bench: prints benchmark figures and writes them into docs/performance.md (between the bench:render,
# bench:metrics, bench:remap and bench:workflow markers) and docs/rendering.md (bench:envlight, bench:mesh).
# Asserts nothing. Peers are measured in the same run: Blender Cycles
# renders the same fit scene with the Principled BSDF at 16 spp (scripts/cycles_fit_scene.py), and the ratio to
# our render time is printed.
# Usage: scripts/bench.sh BUILD [--quick]
set -euo pipefail
build=${1:-build}
quick=${2:-}
root=$(cd "$(dirname "$0")/.." && pwd)
bin="$root/$build/bin/matremap"
work="$root/$build/bench"
mkdir -p "$work"
report="$work/render.md"

# shellcheck source=scripts/lib/timing.sh
. "$root/scripts/lib/timing.sh"

echo "== fit-scene render time per model (tests/bench_render.c)"
"$root/$build/tests/bench_render" $quick | tee "$work/render_table.md"

echo
echo "== image metrics (tests/bench_metrics.c)"
"$root/$build/tests/bench_metrics" | tee "$work/metrics_table.md"

echo
echo "== uniform remaps: time and accuracy against fit-scene size and strategy, one thread (tests/bench_remap.c)"
"$root/$build/tests/bench_remap" $quick | tee "$work/remap_table.md"
{
    echo "Measured by \`make bench\` on $(date -u +%Y-%m-%d), one thread of $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')."
    echo
    cat "$work/remap_table.md"
} > "$work/remap.md"

echo
echo "== workflow conversion: methods, accuracy, MLP width (tests/bench_workflow.c)"
[ -s "$root/$build/dataset/test-off-manifold.csv" ] || echo "(no dataset in $build/dataset: make dataset first for the accuracy tables)"
{
    echo "Measured by \`make bench\` on $(date -u +%Y-%m-%d), $(nproc) cores ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'))."
    echo
    "$root/$build/tests/bench_workflow" "$root/data/spec2metal.mlp" "$root/$build/dataset" $quick
} | tee "$work/workflow.md"

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
        ours_ms=$(grep '^| cycles-principled ' "$work/render_table.md" | awk -F'|' -v col=$([ "$size" = 256 ] && echo 4 || echo 6) '{gsub(/ /, "", $col); print $col}')
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
    echo "(Blender not installed: the Cycles peer was skipped; scripts/install-deps.sh --bench installs it)"
    echo "Cycles peer skipped: Blender was not installed in this run." >> "$report"
fi

echo
echo "== spec2metal / metal2spec end to end on a real 2048² texture set (read, convert, write)"
# The Avocado spec-gloss maps (2048², 8-bit PNG) of ../shared/assets, converted by the command a user runs, against
# a peer measured in the same run: oiiotool reading the same two files and writing the same number of PNG outputs
# (pure image I/O, no conversion), so the ratio is what the conversion adds to the files' own cost.
shared=${MR_SHARED:-$root/../shared}
avocado="$shared/assets/specgloss/Avocado-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness"
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
        echo "Measured by \`make bench\` on $(date -u +%Y-%m-%d), $(nproc) cores: whole processes, median of $runs runs;"
        echo "gltf-transform $("$gt/node_modules/.bin/gltf-transform" --version 2>/dev/null | tail -n 1) (node $(node --version))."
        echo
        echo "| asset | materials | matremap weighted (s) | matremap mlp (s) | gltf-transform metalrough (s) | ratio weighted / gltf-transform |"
        echo "|---|---:|---:|---:|---:|---:|"
    } > "$gltf_report"
    for asset in "$shared"/assets/specgloss/*/*/*.gltf "$shared"/assets/specgloss/FloppyDisk-sketchfab/scene.gltf; do
        [ -f "$asset" ] || continue
        name=$(basename "$(dirname "$asset")")
        [ "$name" = glTF-pbrSpecularGlossiness ] && name=$(basename "$(dirname "$(dirname "$asset")")")
        out="$work/gltf/$name"
        rm -rf "$out" && mkdir -p "$out/w" "$out/m" "$out/g"
        ours=() mlp=() peer=()
        for run in $(seq "$runs"); do
            ours+=("$(seconds_of "$bin" gltf spec2metal "$asset" -o "$out/w/out.gltf" --method weighted)")
            mlp+=("$(seconds_of "$bin" gltf spec2metal "$asset" -o "$out/m/out.gltf" --method mlp)")
            peer+=("$(seconds_of "$gt/node_modules/.bin/gltf-transform" metalrough "$asset" "$out/g/out.gltf")")
        done
        o_s=$(printf '%s\n' "${ours[@]}" | median)
        m_s=$(printf '%s\n' "${mlp[@]}" | median)
        p_s=$(printf '%s\n' "${peer[@]}" | median)
        materials=$(python3 -c 'import json, sys; print(len(json.load(open(sys.argv[1]))["materials"]))' "$asset")
        printf '| %s | %s | %.2f | %.2f | %.2f | %.2f× |\n' "$name" "$materials" "$o_s" "$m_s" "$p_s" \
            "$(awk -v a="$o_s" -v b="$p_s" 'BEGIN {print a / b}')" | tee -a "$gltf_report"
    done
else
    echo "(gltf-transform could not be installed from the npm registry, or no assets: the glTF comparison was skipped)"
    echo "glTF comparison skipped: gltf-transform or ../shared/assets missing in this run." > "$gltf_report"
fi

# Replace the sections between the markers in docs/performance.md (or DOC) with this run's reports.
perf="$root/docs/performance.md"
replace_section() { # NAME REPORT [DOC]
    local doc=${3:-$perf}
    [ -f "$doc" ] && grep -q "<!-- bench:$1:begin -->" "$doc" || return 0
    awk -v report="$2" -v begin="<!-- bench:$1:begin -->" -v end="<!-- bench:$1:end -->" '
        $0 == begin { print; while ((getline line < report) > 0) print line; skip = 1; next }
        $0 == end { skip = 0 }
        !skip { print }' "$doc" > "$doc.tmp" && mv "$doc.tmp" "$doc"
    echo "${doc#"$root"/} updated (section bench:$1)."
}
if [ -f "$perf" ]; then
    echo
    replace_section render "$report"
    replace_section metrics "$work/metrics_table.md"
    replace_section remap "$work/remap.md"
    replace_section workflow "$work/workflow.md"
    replace_section workflow-e2e "$work/e2e.md"
    replace_section gltf "$work/gltf.md"
fi
replace_section envlight "$work/envlight.md" "$root/docs/rendering.md"
replace_section mesh "$work/mesh.md" "$root/docs/rendering.md"
