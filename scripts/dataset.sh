#!/usr/bin/env bash
# make dataset: the specular -> metallic training set of paper section 8 (docs/workflow.md, "The dataset").
# Two seeded, resumable `matremap sweep` runs into DIR (default build/dataset), GGX throughout, roughness held
# at alpha 0.2 on both sides (the MLP sees no roughness: the conversion must not trade it for colour):
#   on-manifold.csv   metallic materials (albedo RGB, metallic drawn uniformly) rendered as the specular
#                     material Eq. 2 makes of them (`ggx-metallic` renders exactly that `ggx` material), remapped
#                     back to metallic parameters by the image-based optimiser;
#   off-manifold.csv  specular materials (diffuse RGB, F0 RGB drawn uniformly, each channel independently) that
#                     Eq. 2 mostly cannot produce, remapped the same way: the visually best metallic approximation.
#   test-on-manifold.csv, test-off-manifold.csv   the same with other seeds: held out for evaluation
#                     (`matremap train --test`), never trained on.
# Usage: scripts/dataset.sh [BUILD] [DIR]. Environment: DATASET_ON, DATASET_OFF (sample counts, default 6000
# each), DATASET_TEST (each test file, default 1000), DATASET_THREADS (default: all cores), DATASET_SIZE
# (fit-scene side, default 64).
# A killed run continues where it stopped when started again (--resume); a finished file is left as it is.
set -euo pipefail
build=${1:-build}
dir=${2:-$build/dataset}
bin="$build/bin/matremap"
on=${DATASET_ON:-6000}
off=${DATASET_OFF:-6000}
test=${DATASET_TEST:-1000}
size=${DATASET_SIZE:-64}
threads=${DATASET_THREADS:-$(nproc)}
[ -x "$bin" ] || { echo "dataset: $bin is missing (run make first)" >&2; exit 1; }
mkdir -p "$dir"
start=$SECONDS
# sweep SOURCE-MODEL COUNT SEED FILE
sweep() {
    "$bin" sweep --from "$1" alpha=0.2 --to ggx-metallic alpha=0.2 --hold alpha --random "$2" --seed "$3" \
        --size "$size" --threads "$threads" --resume -o "$dir/$4"
}
sweep ggx-metallic "$on" 1 on-manifold.csv
sweep ggx "$off" 2 off-manifold.csv
sweep ggx-metallic "$test" 3 test-on-manifold.csv
sweep ggx "$test" 4 test-off-manifold.csv
echo "dataset: $dir: $on + $off training samples, 2 x $test test samples, in $((SECONDS - start)) s"
