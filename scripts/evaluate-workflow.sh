#!/usr/bin/env bash
# make evaluation: the workflow converters on real texture sets (docs/evaluation.md). For each set of
# ../shared/assets it converts the maps with every spec2metal method, renders the original and each converted
# material on a textured sphere under two HDR environment maps, and reports SSIM and relative RMSE against the
# original's render over the sphere's pixels (its coverage mask, `matremap ssim --mask`; docs/metrics.md), with
# the whole frame's SSIM beside them. Pictures (original | each method | SSIM maps) go to docs/evaluation/, the
# tables into docs/evaluation.md between the eval:* markers, raw renders into BUILD/evaluation/.
#
#   Avocado (KHR_materials_pbrSpecularGlossiness maps; the asset also ships its authors' metal-rough maps, rendered
#            as one more "method"), FloppyDisk (spec-gloss maps times the material's factors), WaterBottle
#            (metal-rough maps through metal2spec and back with every method).
#
# Usage: scripts/evaluate-workflow.sh [BUILD]
# Environment: EVAL_SIZE (render side, default 512), EVAL_SAMPLES (environment directions, default 4096),
#              EVAL_MAP_SIZE (textures are shrunk to this before rendering, default 1024), MR_SHARED,
#              EVAL_ONLY (a smoke run: only these sets, e.g. "bottle", and docs/ is left alone).
set -euo pipefail
build=${1:-build}
root=$(cd "$(dirname "$0")/.." && pwd)
bin="$root/$build/bin/matremap"
shared=${MR_SHARED:-$root/../shared}
assets="$shared/assets"
work="$root/$build/evaluation"
pics="$root/docs/evaluation"
size=${EVAL_SIZE:-512}
samples=${EVAL_SAMPLES:-4096}
map_size=${EVAL_MAP_SIZE:-1024}
only=${EVAL_ONLY:-}
export LC_ALL=C
want() { [ -z "$only" ] || [[ " $only " == *" $1 "* ]]; }
# shellcheck source=scripts/lib/evaluation.sh
. "$root/scripts/lib/evaluation.sh"
if [ -n "$only" ]; then pics="$work/pictures"; fi # a smoke run writes nothing into docs/

[ -x "$bin" ] || { echo "evaluation: $bin is missing (run make first)" >&2; exit 1; }
[ -d "$assets/specgloss" ] || { echo "evaluation: no assets in $assets (set MR_SHARED)" >&2; exit 1; }
command -v oiiotool >/dev/null || { echo "evaluation: oiiotool is missing (make deps)" >&2; exit 1; }
rm -rf "$work"
mkdir -p "$work" "$pics"
results="$work/results.tsv" # set, convention, method, env, object ssim, object rmse, object relative rmse,
                             # convert seconds, whole-frame ssim
: > "$results"
t_start=$(date +%s)

avocado="$assets/specgloss/Avocado-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness"
floppy="$assets/specgloss/FloppyDisk-sketchfab/textures"
bottle="$assets/metalrough/WaterBottle/glTF"
envs=(studio tabac)
methods=(mlp weighted mean khronos)

# The maps' RGB and alpha read as stored: OpenImageIO premultiplies PNG alpha unless told not to.
unassoc=(--iconfig oiio:UnassociatedAlpha 1)

# Environment scale: the maps differ by 200x in level (MANIFEST.md), so each is scaled to a mean luminance of 0.5
# (a white Lambertian sphere then renders about 0.5, well inside the display range SSIM sees).
env_scale() {
    oiiotool --stats "$(env_file "$1")" 2>/dev/null | awk '/Stats Avg/ {
        print 0.5 / (0.2126 * $3 + 0.7152 * $4 + 0.0722 * $5); exit }'
}
declare -A scale
for e in "${envs[@]}"; do scale[$e]=$(env_scale "$e"); done

# shrink IN OUT: a texture filtered down to map_size for rendering (the renderer has no mipmaps, render.h), with a
# triangle filter: no negative lobes, so no ringing below 0 at sharp edges (oiiotool's default filter rings).
shrink() { oiiotool "${unassoc[@]}" "$1" --resize:filter=triangle "${map_size}x${map_size}" -o "$2"; }

# render NAME MODEL PARAMS...: NAME_ENV.exr (linear) for every environment.
render() {
    local name=$1; shift
    for e in "${envs[@]}"; do
        "$bin" render "$@" --env "$(env_file "$e")" --env-scale "${scale[$e]}" --env-samples "$samples" \
            --size "$size" -o "$work/${name}_$e.exr" 2>/dev/null
    done
}

# The metrics look at the sphere: every render is of the same scene, so one coverage mask (matremap render --mask,
# whatever the material) serves them all. SSIM counts the pixels whose window touches the sphere, RMSE its pixels
# (docs/metrics.md); the whole frame's SSIM, black background included, is kept beside them.
mask="$work/mask.exr"
"$bin" render lambert --size "$size" -o "$work/mask_probe.exr" --mask "$mask" 2>/dev/null
# luminance_mean IMAGE: the mean Rec. 709 luminance over all its pixels (oiiotool --stats).
luminance_mean() {
    oiiotool --stats "$1" 2>/dev/null | awk '/Stats Avg/ { print 0.2126 * $3 + 0.7152 * $4 + 0.0722 * $5; exit }'
}
coverage_mean=$(oiiotool --stats "$mask" 2>/dev/null | awk '/Stats Avg/ { print $3; exit }')

# Exposure per set and environment: the original's sphere to a mean luminance of 0.18 (mid grey), so that dark
# assets (the black floppy disk) are judged, and pictured, in the display range rather than in their shadows. The
# background is black, so the sphere's coverage-weighted mean is the frame's mean over the mask's. Every render of
# the set is compared and pictured with the original's exposure.
declare -A exposure
expose() { # SET ORIGINAL
    for e in "${envs[@]}"; do
        exposure[$1/$e]=$(awk -v l="$(luminance_mean "$work/${2}_$e.exr")" -v c="$coverage_mean" \
            'BEGIN { print 0.18 * c / l }')
    done
}
# picture NAME SET ENV: NAME_ENV.png, display-referred at the set's exposure (sRGB-encoded, as matremap render).
picture() { oiiotool "$work/${1}_$3.exr" --mulc "${exposure[$2/$3]}" --colorconvert linear sRGB -o "$work/${1}_$3.png"; }

# compare SET CONVENTION METHOD NAME REFERENCE SECONDS: SSIM and RMSE of NAME's renders against REFERENCE's over
# the sphere, and the whole frame's SSIM; the SSIM map (for the pictures) over the whole image.
compare() {
    local set=$1 convention=$2 method=$3 name=$4 reference=$5 seconds=$6
    for e in "${envs[@]}"; do
        "$bin" ssim --json "$work/${reference}_$e.exr" "$work/${name}_$e.exr" --exposure "${exposure[$set/$e]}" \
            --mask "$mask" --map "$work/ssimmap_${name}_$e.png" |
            awk -v s="$set" -v c="$convention" -v m="$method" -v e="$e" -v t="$seconds" '
            function field(key) { match($0, "\"" key "\": [^,}]*"); return substr($0, RSTART + length(key) + 4,
                                                                               RLENGTH - length(key) - 4) }
            { printf "%s\t%s\t%s\t%s\t%.5f\t%.6f\t%.4f\t%s\t%.5f\n", s, c, m, e, field("object_ssim"),
                     field("object_rmse"), field("object_relative_rmse"), t, field("ssim") }' >> "$results"
    done
}

# spec2metal_all SET CONVENTION ARGS...: converts with every method into SET_CONVENTION_METHOD_*.png (glTF
# packing), shrinks the results and renders them. Prints nothing; timings go into the results.
declare -A convert_seconds
spec2metal_all() {
    local set=$1 convention=$2; shift 2
    for m in "${methods[@]}"; do
        [ "$m" = khronos ] && [ "$convention" = paper ] && continue # Khronos has one convention of its own
        local prefix="$work/${set}_${convention}_$m"
        local json
        json=$("$bin" spec2metal "$@" --method "$m" --convention "$convention" --pack --format png -o "$prefix" \
               --json 2>/dev/null)
        convert_seconds[$set/$convention/$m]=$(echo "$json" | sed -E 's/.*"convert": ([0-9.]+).*/\1/')
        shrink "${prefix}_basecolor.png" "${prefix}_b_small.png"
        shrink "${prefix}_metallicRoughness.png" "${prefix}_mr_small.png"
        render "${set}_${convention}_$m" gltf "base_color=@${prefix}_b_small.png" \
            "metallic=@${prefix}_mr_small.png:b" "roughness=@${prefix}_mr_small.png:g"
    done
}

compare_all() {
    local set=$1 convention=$2 reference=$3
    for m in "${methods[@]}"; do
        [ "$m" = khronos ] && [ "$convention" = paper ] && continue
        compare "$set" "$convention" "$m" "${set}_${convention}_$m" "$reference" "${convert_seconds[$set/$convention/$m]}"
    done
}

# ---- Avocado: spec-gloss maps; its own metal-rough maps are the asset authors' conversion ----------------------
if want avocado; then
    echo "== Avocado (spec-gloss 2048² maps -> metal-rough)"
    oiiotool "${unassoc[@]}" "$avocado/Avocado_specularGlossiness.png" --ch R,G,B -o "$work/avocado_specular.png"
    oiiotool "${unassoc[@]}" "$avocado/Avocado_specularGlossiness.png" --ch A -o "$work/avocado_glossiness.png"
    shrink "$avocado/Avocado_diffuse.png" "$work/avocado_d_small.png"
    shrink "$work/avocado_specular.png" "$work/avocado_s_small.png"
    shrink "$work/avocado_glossiness.png" "$work/avocado_g_small.png"
    render avocado_original gltf-specgloss "diffuse=@$work/avocado_d_small.png" "specular=@$work/avocado_s_small.png" \
        "glossiness=@$work/avocado_g_small.png"
    expose avocado avocado_original
    shrink "$avocado/Avocado_baseColor.png" "$work/avocado_authors_b_small.png"
    shrink "$avocado/Avocado_roughnessMetallic.png" "$work/avocado_authors_mr_small.png"
    render avocado_authors gltf "base_color=@$work/avocado_authors_b_small.png" \
        "metallic=@$work/avocado_authors_mr_small.png:b" "roughness=@$work/avocado_authors_mr_small.png:g"
    compare avocado asset authors avocado_authors avocado_original -
    for convention in gltf paper; do
        spec2metal_all avocado "$convention" --diffuse "$avocado/Avocado_diffuse.png" \
            --specular-glossiness "$avocado/Avocado_specularGlossiness.png"
        compare_all avocado "$convention" avocado_original
    done
fi

# ---- FloppyDisk: spec-gloss maps times the factors of its material (scene.gltf) --------------------------------
if want floppy; then
    echo "== FloppyDisk (spec-gloss 2048² maps x factors 0.93 / 0.89 / 0.91 -> metal-rough)"
    # Factors multiply linear values: colour maps are decoded to linear float EXR first, glossiness is linear already.
    oiiotool "$floppy/material_0_diffuse.png" --colorconvert sRGB linear --mulc 0.93 -d float \
        -o "$work/floppy_diffuse.exr"
    oiiotool "${unassoc[@]}" "$floppy/material_0_specularGlossiness.png" --ch R,G,B --colorconvert sRGB linear \
        --mulc 0.89 -d float -o "$work/floppy_specular.exr"
    oiiotool "${unassoc[@]}" "$floppy/material_0_specularGlossiness.png" --ch A --mulc 0.91 -d float \
        -o "$work/floppy_glossiness.exr"
    for k in diffuse specular glossiness; do shrink "$work/floppy_$k.exr" "$work/floppy_${k:0:1}_small.exr"; done
    render floppy_original gltf-specgloss "diffuse=@$work/floppy_d_small.exr" "specular=@$work/floppy_s_small.exr" \
        "glossiness=@$work/floppy_g_small.exr"
    expose floppy floppy_original
    for convention in gltf paper; do
        spec2metal_all floppy "$convention" --diffuse "$work/floppy_diffuse.exr" \
            --specular "$work/floppy_specular.exr" --glossiness "$work/floppy_glossiness.exr"
        compare_all floppy "$convention" floppy_original
    done
fi

# ---- gltf-transform's metalrough: the lossless extension route, rendered as what it means ------------------------
# It keeps the diffuse as the base colour (metallic 0), the specular colour in KHR_materials_specular and sets
# KHR_materials_ior's ior to 1000, whose dielectric F0 is 0.996 x the specular colour. Our `gltf` model spans
# ior 1..5, and F0 depends only on F0(ior) x specular colour, so the same material renders at ior 5 with the
# specular colour scaled by F0(1000)/F0(5) = 2.241. Factors are folded into linear EXR maps as for the floppy.
gt="$root/scripts/gltf-transform"
if [ ! -x "$gt/node_modules/.bin/gltf-transform" ]; then
    (cd "$gt" && npm ci --no-audit --no-fund --loglevel=error) >"$work/gltf-transform-npm.log" 2>&1 || true
fi
if [ -x "$gt/node_modules/.bin/gltf-transform" ]; then
    echo "== gltf-transform metalrough on the spec-gloss assets"
    for set in avocado floppy; do
        want "$set" || continue
        case $set in
            avocado) source_gltf="$avocado/Avocado.gltf" ;;
            floppy) source_gltf="$(dirname "$floppy")/scene.gltf" ;;
        esac
        out="$work/gt_$set"
        mkdir -p "$out"
        "$gt/node_modules/.bin/gltf-transform" metalrough "$source_gltf" "$out/out.gltf" >/dev/null 2>&1
        # base URI, base factor r g b, specular-colour URI, factor r g b, metallic-roughness URI, roughness, ior
        read -r base_uri br bg bb spec_uri sr sg sb mr_uri rough ior < <(python3 - "$out/out.gltf" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
m = d["materials"][0]
p, e = m.get("pbrMetallicRoughness", {}), m["extensions"]
uri = lambda ref: d["images"][d["textures"][ref["index"]]["source"]]["uri"]
spec = e["KHR_materials_specular"]
print(uri(p["baseColorTexture"]), *p.get("baseColorFactor", [1, 1, 1, 1])[:3], uri(spec["specularColorTexture"]),
      *spec.get("specularColorFactor", [1, 1, 1]), uri(p["metallicRoughnessTexture"]), p.get("roughnessFactor", 1),
      e["KHR_materials_ior"]["ior"])
PY
        )
        k=$(awk -v n="$ior" 'BEGIN { f = ((n - 1) / (n + 1)) ^ 2; print f / (4.0 / 9.0) }')
        oiiotool "${unassoc[@]}" "$out/$base_uri" --ch R,G,B --colorconvert sRGB linear --mulc "$br,$bg,$bb" -d float \
            --resize:filter=triangle "${map_size}x${map_size}" -o "$out/b.exr"
        oiiotool "${unassoc[@]}" "$out/$spec_uri" --ch R,G,B --colorconvert sRGB linear \
            --mulc "$(awk -v a="$sr" -v b="$sg" -v c="$sb" -v k="$k" 'BEGIN { print a * k "," b * k "," c * k }')" \
            -d float --resize:filter=triangle "${map_size}x${map_size}" -o "$out/s.exr"
        oiiotool "${unassoc[@]}" "$out/$mr_uri" --ch G --mulc "$rough" -d float \
            --resize:filter=triangle "${map_size}x${map_size}" -o "$out/r.exr"
        render "${set}_ext_gltf-transform" gltf "base_color=@$out/b.exr" metallic=0 "roughness=@$out/r.exr" \
            "specular_color=@$out/s.exr" ior=5 specular=1
        compare "$set" extension gltf-transform "${set}_ext_gltf-transform" "${set}_original" -
    done
else
    echo "(gltf-transform could not be installed from the npm registry: its rows are missing)"
fi

# ---- WaterBottle: metal-rough maps -> metal2spec -> spec2metal with every method ------------------------------
if want bottle; then
    echo "== WaterBottle (metal-rough 2048² maps -> spec-gloss -> metal-rough)"
    shrink "$bottle/WaterBottle_baseColor.png" "$work/bottle_b_small.png"
    shrink "$bottle/WaterBottle_occlusionRoughnessMetallic.png" "$work/bottle_orm_small.png"
    render bottle_original gltf "base_color=@$work/bottle_b_small.png" "metallic=@$work/bottle_orm_small.png:b" \
        "roughness=@$work/bottle_orm_small.png:g"
    expose bottle bottle_original
    for convention in gltf paper; do
        sg="$work/bottle_${convention}_sg"
        "$bin" metal2spec --basecolor "$bottle/WaterBottle_baseColor.png" \
            --metallic-roughness "$bottle/WaterBottle_occlusionRoughnessMetallic.png" --convention "$convention" \
            --format png -o "$sg" 2>/dev/null >/dev/null
        for k in diffuse specular glossiness; do shrink "${sg}_$k.png" "${sg}_${k:0:1}_small.png"; done
        render "bottle_${convention}_sg" gltf-specgloss "diffuse=@${sg}_d_small.png" "specular=@${sg}_s_small.png" \
            "glossiness=@${sg}_g_small.png"
        compare bottle "$convention" metal2spec "bottle_${convention}_sg" bottle_original -
        spec2metal_all bottle "$convention" --diffuse "${sg}_diffuse.png" --specular "${sg}_specular.png" \
            --glossiness "${sg}_glossiness.png"
        compare_all bottle "$convention" bottle_original
    done
fi

# ---- pictures: per set and environment, original | each method (glTF convention) over their SSIM maps ---------
label() { echo "--text:x=6:y=18:size=16:color=1,1,1:font=DejaVuSans"; }
sheet() {
    local set=$1 e=$2 first=$3 first_label=$4 second=$5 second_label=$6
    picture "$first" "$set" "$e"
    picture "$second" "$set" "$e"
    local top=("$work/${first}_$e.png" "$(label)" "$first_label")
    local bottom=("$work/${second}_$e.png" "$(label)" "$second_label")
    local columns=1
    for m in "${methods[@]}"; do
        picture "${set}_gltf_$m" "$set" "$e"
        top+=("$work/${set}_gltf_${m}_$e.png" "$(label)" "$m")
        bottom+=("$work/ssimmap_${set}_gltf_${m}_$e.png" "$(label)" "SSIM map, $m")
        columns=$((columns + 1))
    done
    oiiotool "${top[@]}" "${bottom[@]}" --mosaic:pad=4 "${columns}x2" --resize "$((columns * 256))x512" \
        -o "$pics/${set}_$e.png"
}
for e in "${envs[@]}"; do
    if want avocado; then
        sheet avocado "$e" avocado_original "spec-gloss original" avocado_authors "the asset's own metal-rough"
    fi
    if want floppy; then
        sheet floppy "$e" floppy_original "spec-gloss original" floppy_paper_weighted "weighted, paper convention"
    fi
    if want bottle; then
        sheet bottle "$e" bottle_original "metal-rough original" bottle_gltf_sg "metal2spec (spec-gloss)"
    fi
done

# ---- tables --------------------------------------------------------------------------------------------------
table="$work/tables.md"
{
    echo "Measured by \`make evaluation\` on $(date -u +%Y-%m-%d), matremap $("$bin" --version | cut -d' ' -f2):"
    echo "${size}² renders of a textured sphere (maps shrunk to ${map_size}²), $samples environment directions,"
    echo "environments scaled to a mean luminance of 0.5, SSIM exposed so that the original's sphere has a mean"
    echo "luminance of 0.18. Each converted material's render against the original's **over the sphere**"
    echo "(\`matremap ssim --mask\`: SSIM over the pixels whose window touches it, relative RMSE over its pixels as a"
    echo "fraction of the original's mean radiance there), per environment and their mean, and the **whole frame's**"
    echo "SSIM (black background included; the mean of the two environments) beside them; convert = seconds of the"
    echo "conversion alone on 2 threads (2048² maps)."
    echo
    echo -n "| set | convention | method | object SSIM studio | object SSIM tabac | object SSIM (mean) "
    echo "| object rel. RMSE (mean) | whole-frame SSIM (mean) | convert s |"
    echo "|---|---|---|---:|---:|---:|---:|---:|---:|"
    awk -F'\t' '{
        key = $1 "\t" $2 "\t" $3
        if (!(key in seen)) { order[++n] = key; seen[key] = 1 }
        ssim[key, $4] = $5; rel[key] += $7 / 2; t[key] = $8; frame[key] += $9 / 2
    } END {
        for (i = 1; i <= n; i++) {
            k = order[i]; split(k, f, "\t")
            printf "| %s | %s | %s | %.4f | %.4f | %.4f | %.4f | %.4f | %s |\n", f[1], f[2], f[3], ssim[k, "studio"],
                   ssim[k, "tabac"], (ssim[k, "studio"] + ssim[k, "tabac"]) / 2, rel[k], frame[k], t[k]
        }
    }' "$results"
    echo
    echo "Total wall time $(( $(date +%s) - t_start )) s."
} > "$table"
cat "$table"

if [ -z "$only" ] && splice_table "$root/docs/evaluation.md" eval "$table"; then
    echo "evaluation: tables written into docs/evaluation.md, pictures into docs/evaluation/"
fi
