#!/usr/bin/env bash
# make objectives: which label objective agrees with what people see (docs/training.md, "Objectives").
# `matremap dataset --compare` fits the labels of every objective (under the built-in synthetic lights) for the
# named hard cases, 116-odd texels of the held-out FloppyDisk asset and drawn texels of the training mixture, and
# renders each answer, the analytic inverses' and the networks' on a sphere under both shared HDR maps (held out
# of training): object SSIM per texel, means by group. Networks compared: the shipped one; the same data trained
# in the plain form (the form's effect alone; when build/dataset holds the pairs: about two minutes); and the
# first network of issue 12 (from git history, when the checkout has it). Writes docs/training/objectives.md and splices it into
# docs/training.md between its objectives markers. Usage: scripts/objectives.sh [BUILD]
set -euo pipefail
build=${1:-build}
root=$(cd "$(dirname "$0")/.." && pwd)
bin="$root/$build/bin/matremap"
shared=${MR_SHARED:-$root/../shared}
[ -x "$bin" ] || { echo "objectives: $bin is missing (run make first)" >&2; exit 1; }
mkdir -p "$root/$build/objectives" "$root/docs/training"
weights=(--weights "$root/data/spec2metal.mlp")
plain="$root/$build/objectives/plain-form.mlp"
if [ -s "$root/$build/dataset/pairs.csv" ]; then
    "$bin" train "$root/$build/dataset/pairs.csv" --seed 1 --form plain -o "$plain" \
        --loss-curve "$root/$build/objectives/plain-form_loss" >/dev/null
    weights+=(--weights "$plain")
else
    echo "objectives: no $build/dataset/pairs.csv (make dataset): compared without the plain-form network" >&2
fi
first="$root/$build/objectives/first-network.mlp"
if git -C "$root" show cc66767:data/spec2metal.mlp >"$first" 2>/dev/null; then
    weights+=(--weights "$first")
else
    echo "objectives: the first network is not in this checkout's history; compared without it" >&2
fi
start=$SECONDS
table="$root/$build/objectives/table.md"
"$bin" dataset --compare --samples 400 --seed 3 \
    --env "$shared/assets/hdri/studio_small_03_1k.hdr" --env "$shared/assets/hdri/tabac_plant_vogl.hdr" \
    --asset "$shared/assets/specgloss/FloppyDisk-sketchfab/scene.gltf" "${weights[@]}" -o "$table"
{
    echo "Measured by \`make objectives\` on $(date -u +%Y-%m-%d) ($((SECONDS - start)) s): object SSIM (the sphere's"
    echo "inner square, each picture exposed to a mean luminance of 0.18) of each answer against the spec-gloss texel,"
    echo "mean over both shared HDR maps and glossiness 0.3, 0.6, 0.9. \"labels: X\" = the optimum of objective X made"
    echo "under the built-in synthetic lights; \"mlp spec2metal.mlp\" = the shipped network (new inputs, luma labels,"
    echo "residual form); \"mlp plain-form.mlp\" = the same data and training in the plain form (the network outputs the"
    echo "answer); \"mlp first-network.mlp\" = the network before issue 12 (uniform inputs, point-light linear labels,"
    echo "plain form). Drawn texels: seed 3 of the training mixture (\"asset\" = the held-out FloppyDisk)."
    echo
    cat "$table"
} >"$root/docs/training/objectives.md"
awk -v file="$root/docs/training/objectives.md" '
    /<!-- objectives:begin -->/ { print; while ((getline line < file) > 0) print line; skip = 1; next }
    /<!-- objectives:end -->/ { skip = 0 }
    !skip' "$root/docs/training.md" >"$root/$build/objectives/training.md"
mv "$root/$build/objectives/training.md" "$root/docs/training.md"
echo "objectives: docs/training/objectives.md and docs/training.md updated in $((SECONDS - start)) s"
