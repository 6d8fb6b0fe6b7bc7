#!/usr/bin/env bash
# make dataset: the specular -> metallic training set of the learned converter (docs/training.md).
# `matremap dataset` draws spec-gloss texels as 8-bit textures store them (uniform codes, the dielectric F0 band
# with dark and saturated diffuse, grey inputs, metals, Eq. 2 of partly metallic texels, and texels of three of
# the shared spec-gloss assets) and labels each with the glTF metal-rough material that renders most like it
# under two synthetic grey environments at four glossinesses, by the display-referred objective (chosen by
# `make objectives`, docs/training.md). Held out of everything here, for evaluation only: the FloppyDisk asset
# and both shared HDR maps.
#   pairs.csv        training pairs (seed 1)
#   test-pairs.csv   held-out pairs (seed 2, other texels of the same mixture): `matremap train --test`
# Usage: scripts/dataset.sh [BUILD] [DIR]. Environment: DATASET_SAMPLES (default 16000), DATASET_TEST (default
# 2000), DATASET_THREADS (default: all cores). Each file is a pure function of its seed (any thread count);
# a finished file is left as it is.
set -euo pipefail
build=${1:-build}
dir=${2:-$build/dataset}
bin="$build/bin/matremap"
samples=${DATASET_SAMPLES:-16000}
test=${DATASET_TEST:-2000}
threads=${DATASET_THREADS:-$(nproc)}
root=$(cd "$(dirname "$0")/.." && pwd)
assets="$root/../shared/assets/specgloss"
[ -x "$bin" ] || { echo "dataset: $bin is missing (run make first)" >&2; exit 1; }
[ -d "$assets" ] || { echo "dataset: $assets is missing (../shared beside the project)" >&2; exit 1; }
mkdir -p "$dir"
start=$SECONDS
# make FILE SAMPLES SEED
make_pairs() {
    if [ -f "$dir/$1" ]; then echo "dataset: $dir/$1 exists, kept"; return; fi
    "$bin" dataset -o "$dir/$1" --samples "$2" --seed "$3" --threads "$threads" \
        --asset "$assets/Avocado-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Avocado.gltf" \
        --asset "$assets/Duck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Duck.gltf" \
        --asset "$assets/CesiumMilkTruck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/CesiumMilkTruck.gltf"
}
make_pairs pairs.csv "$samples" 1
make_pairs test-pairs.csv "$test" 2
echo "dataset: $dir: $samples training pairs, $test test pairs, in $((SECONDS - start)) s"
