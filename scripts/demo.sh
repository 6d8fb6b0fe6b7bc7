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

if command -v oiiotool >/dev/null 2>&1; then
    args=()
    for n in "${names[@]}"; do
        args+=("$out/$n.png" --text:x=4:y=14:size=12:color=1,1,1 "$n")
    done
    oiiotool "${args[@]}" --mosaic:pad=2 5x3 -o "$out/contact_sheet.png" 2>/dev/null &&
        echo && echo "Contact sheet: out/demo/contact_sheet.png (SSIM maps: out/demo/ssim_*.png)"
fi
