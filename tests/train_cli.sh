#!/usr/bin/env bash
# `matremap train` and the dataset files it reads: a tiny seeded dataset (two sweeps at 16 pixels), training that
# reproduces its weights byte for byte, a loss curve, a held-out evaluation of every method, the shipped network's
# shape, and the errors a user can make. Ends with "N passed, N failed".
set -u
bin="${MR_BUILD:-build}/bin/matremap"
root=$(cd "$(dirname "$0")/.." && pwd)
source "$(dirname "$0")/lib/cli_harness.sh"

sweep() { # SOURCE COUNT SEED FILE
    "$bin" sweep --from "$1" alpha=0.2 --to ggx-metallic alpha=0.2 --hold alpha --random "$2" --seed "$3" --size 16 \
        --threads 2 -o "$tmp/$4" 2>/dev/null
}
sweep ggx-metallic 60 1 on.csv && sweep ggx 60 2 off.csv && sweep ggx-metallic 30 3 test.csv
check "the tiny dataset is made" test -s "$tmp/on.csv" -a -s "$tmp/off.csv" -a -s "$tmp/test.csv"

expect "train --help" 0 "Usage: matremap train" -- "$bin" train --help
expect "train: no dataset" 1 "no dataset" -- "$bin" train -o "$tmp/x.mlp"
expect "train: no output" 1 "missing -o" -- "$bin" train "$tmp/on.csv"
expect "train: -o over a dataset file" 1 "overwrite a dataset" -- "$bin" train "$tmp/on.csv" -o "$tmp/on.csv"
expect "train: missing file" 2 "nope.csv" -- "$bin" train "$tmp/nope.csv" -o "$tmp/x.mlp"
"$bin" sweep --from ggx --to ward --random 3 --size 16 -o "$tmp/ward.csv" 2>/dev/null
expect "train: a sweep into another workflow" 2 "to_albedo" -- "$bin" train "$tmp/ward.csv" -o "$tmp/x.mlp"
head -c 2000 "$tmp/on.csv" > "$tmp/torn.csv"
expect "train: a torn file names its line" 2 "torn.csv:[0-9]+" -- "$bin" train "$tmp/torn.csv" -o "$tmp/x.mlp"
expect "train: --hidden 0" 1 "--hidden" -- "$bin" train "$tmp/on.csv" -o "$tmp/x.mlp" --hidden 0

expect "train a small network" 0 "validation loss" -- \
    "$bin" train "$tmp/on.csv" "$tmp/off.csv" -o "$tmp/a.mlp" --hidden 8 --epochs 40 --seed 3 --test "$tmp/test.csv"
check "the default (residual) network is a version 2 file" grep -q "^matremap-mlp 2$" "$tmp/a.mlp"
check "... of kind spec2metal-residual" grep -q "^kind spec2metal-residual$" "$tmp/a.mlp"
check "the loss curve is written next to it" test -s "$tmp/a_loss.csv"
check "the loss curve has a row per epoch" test "$(wc -l < "$tmp/a_loss.csv")" -ge 3
check "the test table lists every method" grep -qE "^  khronos " "$tmp/out"
# weighted is exact on the Eq. 2 manifold up to the optimiser's labels
check "weighted is near exact on manifold test pairs" \
    awk '$1 == "weighted" { exit !($3 < 0.02) }' "$tmp/out"
"$bin" train "$tmp/on.csv" "$tmp/off.csv" -o "$tmp/b.mlp" --hidden 8 --epochs 40 --seed 3 --threads 1 >/dev/null
check "training is reproducible byte for byte (2 threads vs 1)" cmp -s "$tmp/a.mlp" "$tmp/b.mlp"
"$bin" train "$tmp/on.csv" "$tmp/off.csv" -o "$tmp/c.mlp" --hidden 8 --epochs 40 --seed 4 >/dev/null
check "another seed gives another network" bash -c "! cmp -s '$tmp/a.mlp' '$tmp/c.mlp'"
"$bin" train "$tmp/on.csv" -o "$tmp/plain.mlp" --hidden 4 --epochs 3 --form plain >/dev/null
check "--form plain writes a version 1 file without a kind" bash -c \
    "grep -q '^matremap-mlp 1$' '$tmp/plain.mlp' && ! grep -q '^kind' '$tmp/plain.mlp'"
expect "train: --form other" 1 "--form 'other'" -- "$bin" train "$tmp/on.csv" -o "$tmp/x.mlp" --form other
expect "train --json" 0 '"best_validation_loss": [0-9]' -- \
    "$bin" train "$tmp/on.csv" -o "$tmp/d.mlp" --hidden 4 --epochs 3 --json --loss-curve "$tmp/curve"
check "--loss-curve PREFIX" test -s "$tmp/curve.csv"
# The loss curve is committed with the network: when it cannot be written, no network is left either.
expect "train: a loss curve in a missing folder" 2 "nodir/curve.csv" -- \
    "$bin" train "$tmp/on.csv" -o "$tmp/e.mlp" --hidden 4 --epochs 3 --loss-curve "$tmp/nodir/curve"
check "... and writes no network" test ! -e "$tmp/e.mlp"

check "the shipped network is 6 x 300 x 4" bash -c \
    "grep -q '^n_in 6$' $root/data/spec2metal.mlp && grep -q '^n_hidden 300$' $root/data/spec2metal.mlp && grep -q '^n_out 4$' $root/data/spec2metal.mlp"

finish
