#!/usr/bin/env bash
# make demo: renders every material of data/demo/materials.txt in the fit scene (EXR + PNG), compares the pairs of
# data/demo/comparisons.txt with SSIM (+ SSIM maps), and assembles a contact sheet. Output in out/demo/.
set -euo pipefail
build=${1:-build}
root=$(cd "$(dirname "$0")/.." && pwd)
bin="$root/$build/bin/matremap"
out="$root/out/demo"
size=${MR_DEMO_SIZE:-256}
mkdir -p "$out"

echo "Rendering the demo materials at ${size}² (fit scene: unit sphere, point light at 45°) into out/demo/"
names=()
while read -r name model params; do
    case "$name" in ''|'#'*) continue ;; esac
    # shellcheck disable=SC2086  # params are separate name=value words
    "$bin" render "$model" $params --size "$size" -o "$out/$name.exr" 2>/dev/null
    "$bin" render "$model" $params --size "$size" -o "$out/$name.png" 2>/dev/null
    printf '  %-22s %-18s %s\n' "$name" "$model" "$params"
    names+=("$name")
done < "$root/data/demo/materials.txt"

echo
echo "Same intent, different models: SSIM (1 = identical) and RMSE (linear radiance) of the fit-scene renders"
printf '  %-22s %-22s %8s %8s\n' A B SSIM RMSE
while read -r a b; do
    case "$a" in ''|'#'*) continue ;; esac
    json=$("$bin" ssim --json "$out/$a.exr" "$out/$b.exr" --map "$out/ssim_${a}_vs_${b}.png")
    ssim=$(echo "$json" | sed -E 's/.*"ssim": ([^,]*),.*/\1/')
    rmse=$(echo "$json" | sed -E 's/.*"rmse": ([^}]*)}.*/\1/')
    printf '  %-22s %-22s %8.4f %8.4f\n' "$a" "$b" "$ssim" "$rmse"
done < "$root/data/demo/comparisons.txt"

# Pictures: a contact sheet of every material and one of every comparison (A | B | SSIM map), labelled.
label() { echo "--text:x=4:y=14:size=12:color=1,1,1:font=DejaVuSans"; }
sheet=("$out/contact_sheet.png" "$out/comparisons.png")
args=()
for n in "${names[@]}"; do args+=("$out/$n.png" "$(label)" "$n"); done
oiiotool "${args[@]}" --mosaic:pad=2 5x3 -o "${sheet[0]}"
args=()
rows=0
while read -r a b; do
    case "$a" in ''|'#'*) continue ;; esac
    args+=("$out/$a.png" "$(label)" "$a" "$out/$b.png" "$(label)" "$b" \
           "$out/ssim_${a}_vs_${b}.png" "$(label)" "SSIM map")
    rows=$((rows + 1))
done < "$root/data/demo/comparisons.txt"
oiiotool "${args[@]}" --mosaic:pad=2 "3x$rows" -o "${sheet[1]}"
# Workflow conversion: a real spec-gloss texture set (the Avocado's maps, shrunk to 256², data/README.md) to
# metal-rough with every spec2metal method, each rendered on a sphere under a studio HDR map beside the original.
maps="$root/data/demo/avocado"
env_map="$root/data/demo/studio_small_03_256.hdr"
light=(--env "$env_map" --env-scale 0.5 --env-samples 1024 --size "$size")
echo
echo "Spec-gloss -> metal-rough: the Avocado's 256² maps (data/demo/avocado) through spec2metal, each result"
echo "rendered on a sphere under a studio HDR map and compared with the spec-gloss original (SSIM, 1 = identical)"
"$bin" render gltf-specgloss diffuse=@"$maps/diffuse.png" specular=@"$maps/specular.png" \
    glossiness=@"$maps/glossiness.png" "${light[@]}" -o "$out/avocado_original.exr" 2>/dev/null
"$bin" render gltf-specgloss diffuse=@"$maps/diffuse.png" specular=@"$maps/specular.png" \
    glossiness=@"$maps/glossiness.png" "${light[@]}" -o "$out/avocado_original.png" 2>/dev/null
printf '  %-10s %8s %10s\n' method SSIM "convert ms"
args=("$out/avocado_original.png" "$(label)" "spec-gloss original")
for method in mlp weighted mean khronos; do
    json=$("$bin" spec2metal --diffuse "$maps/diffuse.png" --specular "$maps/specular.png" \
        --glossiness "$maps/glossiness.png" --method "$method" --pack -o "$out/avocado_$method" --json 2>/dev/null)
    for ext in exr png; do
        "$bin" render gltf base_color=@"$out/avocado_${method}_basecolor.png" \
            metallic=@"$out/avocado_${method}_metallicRoughness.png":b \
            roughness=@"$out/avocado_${method}_metallicRoughness.png":g "${light[@]}" \
            -o "$out/avocado_$method.$ext" 2>/dev/null
    done
    ssim=$("$bin" ssim "$out/avocado_original.exr" "$out/avocado_$method.exr")
    ms=$(echo "$json" | sed -E 's/.*"convert": ([0-9.]+).*/\1/' | awk '{printf "%.1f", $1 * 1000}')
    printf '  %-10s %8.4f %10s\n' "$method" "$ssim" "$ms"
    args+=("$out/avocado_$method.png" "$(label)" "$method")
done
oiiotool "${args[@]}" --mosaic:pad=2 5x1 -o "$out/workflow.png"

echo
echo "Pictures: out/demo/contact_sheet.png (every material), out/demo/comparisons.png (A | B | SSIM map,"
echo "black = identical), out/demo/workflow.png (the Avocado's spec-gloss original and each method's"
echo "metal-rough conversion), and each render as EXR (linear) and PNG."
