#!/usr/bin/env bash
# `matremap train` and the dataset files it reads: a tiny seeded dataset (two sweeps at 16 pixels), training that
# reproduces its weights byte for byte, a loss curve, a held-out evaluation of every method, the shipped network's
# shape, and the errors a user can make. Ends with "N passed, N failed".
set -u
bin="${MR_BUILD:-build}/bin/matremap"
root=$(cd "$(dirname "$0")/.." && pwd)
source "$(dirname "$0")/lib/cli_harness.sh"

sweep() { # SOURCE COUNT SEED FILE
    "$bin" sweep --from "$1" alpha=0.2 --to ggx-metallic alpha=0.2 --hold alpha --random "$2" --region range \
        --seed "$3" --size 16 \
        --threads 2 -o "$tmp/$4" 2>/dev/null
}
sweep ggx-metallic 60 1 on.csv && sweep ggx 60 2 off.csv && sweep ggx-metallic 30 3 test.csv
check "the tiny dataset is made" test -s "$tmp/on.csv" -a -s "$tmp/off.csv" -a -s "$tmp/test.csv"

expect "train --help" 0 "Usage: matremap train" -- "$bin" train --help
expect "train: no dataset" 1 "no dataset" -- "$bin" train -o "$tmp/x.mlp"
expect "train: no output" 1 "missing -o" -- "$bin" train "$tmp/on.csv"
# No output (the weights, the loss curve's PREFIX.csv and PREFIX.svg) replaces an input: exit 2, both named.
mkdir -p "$tmp/io"
cp "$tmp/on.csv" "$tmp/io/ds.csv"
cp "$tmp/test.csv" "$tmp/io/t.csv"
cp "$tmp/test.csv" "$tmp/io/t_loss.csv"
ln "$tmp/io/ds.csv" "$tmp/io/ds_link.mlp"
abs_bin=$(realpath "$bin")
cd "$tmp/io"
refuses "train: -o ./ds.csv is the dataset ds.csv" "output './ds.csv' is the input dataset ds.csv; refusing" \
    "$tmp/io" -- "$abs_bin" train ds.csv -o ./ds.csv
refuses "train: -o is the --test file" "output 't.csv' is the input --test t.csv" "$tmp/io" -- \
    "$abs_bin" train ds.csv --test t.csv -o t.csv
refuses "train: --loss-curve ds writes ds.csv, the dataset" \
    "output 'ds.csv' \(--loss-curve ds\) is the input dataset ds.csv" "$tmp/io" -- \
    "$abs_bin" train ds.csv -o w.mlp --loss-curve ds
refuses "train: the default loss curve over the --test file" "output 't_loss.csv' \(the loss curve of -o t.mlp\)" \
    "$tmp/io" -- "$abs_bin" train ds.csv --test t_loss.csv -o t.mlp
cd "$OLDPWD"
refuses "train: -o a hard link to the dataset" "output '$tmp/io/ds_link.mlp' is the input dataset" "$tmp/io" -- \
    "$bin" train "$tmp/io/ds.csv" -o "$tmp/io/ds_link.mlp"
expect "train: missing file" 2 "nope.csv" -- "$bin" train "$tmp/nope.csv" -o "$tmp/x.mlp"
"$bin" sweep --from ggx --to ward --random 3 --size 16 -o "$tmp/ward.csv" 2>/dev/null
expect "train: a sweep into another workflow" 2 "to_albedo" -- "$bin" train "$tmp/ward.csv" -o "$tmp/x.mlp"
head -c 2000 "$tmp/on.csv" > "$tmp/torn.csv"
expect "train: a torn file names its line" 2 "torn.csv:[0-9]+" -- "$bin" train "$tmp/torn.csv" -o "$tmp/x.mlp"
# Every outcome a sweep writes is known to the reader: an under-resolved row is a pair like the others (it was once
# "unknown outcome", which stopped train on any real sweep holding one).
python3 - "$tmp/on.csv" "$tmp/under.csv" <<'PY'
import sys
lines = open(sys.argv[1]).read().split("\n")
header = next(i for i, l in enumerate(lines) if l and not l.startswith("#"))
column = lines[header].split(",").index("outcome")
row = lines[header + 1].split(",")
row[column] = "under-resolved"
lines[header + 1] = ",".join(row)
open(sys.argv[2], "w").write("\n".join(lines))
PY
expect "train: an under-resolved row is read" 0 "validation loss" -- \
    "$bin" train "$tmp/under.csv" -o "$tmp/under.mlp" --hidden 4 --epochs 2
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
touch "$tmp/plain"
expect "train: a loss curve in a folder that cannot be made" 2 "plain/nodir/curve.csv" -- \
    "$bin" train "$tmp/on.csv" -o "$tmp/e.mlp" --hidden 4 --epochs 3 --loss-curve "$tmp/plain/nodir/curve"
check "... and writes no network" test ! -e "$tmp/e.mlp"

check "the shipped network is 6 x 300 x 4" bash -c \
    "grep -q '^n_in 6$' $root/data/spec2metal.mlp && grep -q '^n_hidden 300$' $root/data/spec2metal.mlp && grep -q '^n_out 4$' $root/data/spec2metal.mlp"

finish
