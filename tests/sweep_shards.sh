#!/usr/bin/env bash
# `matremap sweep --shard K/N` and `matremap sweep merge` as a job array uses them (docs/sweep.md, "Shards"): three
# shards merged in any order give the single run's file (the seconds column and the command line aside); merge
# refuses, with exit 2 and a message naming the file and what disagrees, and without writing anything: a missing
# shard, a shard given twice, shards of another seed, of another target model or of another N, an unfinished or
# torn shard, an edited row, an existing output (left untouched). Also the checks of resumed rows at the command
# line (exit 2 naming the file, the line and the column; the file untouched), --shard's usage errors, and the
# refusal of an MPI launch without the MPI module (no mpirun needed: the launcher's variables are set by hand).
# Ends with "N passed, N failed".
set -u
. "$(dirname "$0")/lib/cli_harness.sh"
bin="${MR_BUILD:-build}/bin/matremap"
args=(--from ggx --to ward-balanced --random 12 --seed 5 --size 32 --threads 2)
rows() { grep -v '^#' "$1" | tail -n +2; }
values() { grep -v '^# command:' "$1" | sed '/^#/!s/,[^,]*$//'; }

expect "the single run" 0 "is complete: 12 samples" -- "$bin" sweep "${args[@]}" -o "$tmp/ref.csv"
for k in 0 1 2; do
    expect "shard $k/3" 0 "'$tmp/s$k.csv' \\(shard $k/3 of 12 samples\\) is complete: 4 samples" -- \
        "$bin" sweep "${args[@]}" --shard "$k/3" -o "$tmp/s$k.csv"
done
check "shard 1 holds samples 1, 4, 7, 10" [ "$(rows "$tmp/s1.csv" | cut -d, -f1 | tr '\n' ' ')" = "1 4 7 10 " ]
check "... and says which shard it is" grep -qx '# shard: 1/3' "$tmp/s1.csv"
expect "a finished shard resumes to nothing" 0 "nothing to do" -- \
    "$bin" sweep "${args[@]}" --shard 1/3 -o "$tmp/s1.csv" --resume
expect "a shard resumed as another shard: exit 2" 2 "line 8 is '# shard: 1/3', this run's is '# shard: 2/3'" -- \
    "$bin" sweep "${args[@]}" --shard 2/3 -o "$tmp/s1.csv" --resume

expect "merge in any order" 0 "written: 12 samples from 3 shards" -- \
    "$bin" sweep merge "$tmp/s2.csv" "$tmp/s0.csv" "$tmp/s1.csv" -o "$tmp/merged.csv"
check "... the single run's file (seconds, command line aside)" diff <(values "$tmp/ref.csv") <(values "$tmp/merged.csv")
check "... with no shard line and merge's command line" \
    bash -c "! grep -q '^# shard:' '$tmp/merged.csv' && grep -q '^# command: matremap sweep merge ' '$tmp/merged.csv'"
expect "the merged file resumes to nothing" 0 "nothing to do" -- "$bin" sweep "${args[@]}" -o "$tmp/merged.csv" --resume

# Refusals: exit 2, the file and the disagreement named, nothing written.
refuse() { # NAME PATTERN SHARD...
    local name=$1 pattern=$2
    shift 2
    rm -f "$tmp/out.csv"
    expect "merge refuses $name: exit 2" 2 "$pattern" -- "$bin" sweep merge "$@" -o "$tmp/out.csv"
    check "... and writes nothing" [ ! -e "$tmp/out.csv" ]
}
cp "$tmp/s1.csv" "$tmp/s1_copy.csv"
"$bin" sweep --from ggx --to ward-balanced --random 12 --seed 6 --size 32 --shard 1/3 -o "$tmp/seed6_1.csv" 2>/dev/null
"$bin" sweep --from ggx --to ward --random 12 --seed 5 --size 32 --shard 1/3 -o "$tmp/ward_1.csv" 2>/dev/null
"$bin" sweep "${args[@]}" --shard 1/2 -o "$tmp/half_1.csv" 2>/dev/null
refuse "a missing shard" "3 shards; missing: 1/3" "$tmp/s0.csv" "$tmp/s2.csv"
refuse "a shard given twice" "'$tmp/s1.csv' and '$tmp/s1_copy.csv' are both shard 1/3" \
    "$tmp/s0.csv" "$tmp/s1.csv" "$tmp/s1_copy.csv" "$tmp/s2.csv"
refuse "shards of another seed" "'$tmp/s0.csv' and '$tmp/seed6_1.csv' are from different sweeps: .*seed=6" \
    "$tmp/s0.csv" "$tmp/seed6_1.csv" "$tmp/s2.csv"
refuse "shards of another model" "from different sweeps: '# to: ward-balanced .*' in the first, '# to: ward " \
    "$tmp/s0.csv" "$tmp/ward_1.csv" "$tmp/s2.csv"
refuse "shards of another N" "split the sweep differently: shard 0/3 and 1/2" "$tmp/s0.csv" "$tmp/half_1.csv" \
    "$tmp/s2.csv"
head -n -1 "$tmp/s1.csv" >"$tmp/short_1.csv"
refuse "an unfinished shard" "'$tmp/short_1.csv' \\(shard 1/3\\) ends after 3 of its 4 rows.*--resume" \
    "$tmp/s0.csv" "$tmp/short_1.csv" "$tmp/s2.csv"
head -c -1 "$tmp/s1.csv" >"$tmp/torn_1.csv"
refuse "a torn shard" "'$tmp/torn_1.csv': line 14 is torn" "$tmp/s0.csv" "$tmp/torn_1.csv" "$tmp/s2.csv"
awk -F, -v OFS=, '!/^#/ && $1 == "4" { $9 = "-0.25" } { print }' "$tmp/s1.csv" >"$tmp/edited_1.csv"
refuse "an edited row" "'$tmp/edited_1.csv': line 12: column 9 \\(to_diffuse_r\\): -0.25 is outside diffuse's range" \
    "$tmp/s0.csv" "$tmp/edited_1.csv" "$tmp/s2.csv"
refuse "a whole sweep given as a shard" "is a whole sweep, not a shard" "$tmp/ref.csv"
sum=$(md5sum <"$tmp/merged.csv")
expect "merge over an existing file: exit 2" 2 "'$tmp/merged.csv' already exists; not overwriting it" -- \
    "$bin" sweep merge "$tmp/s0.csv" "$tmp/s1.csv" "$tmp/s2.csv" -o "$tmp/merged.csv"
check "... the file untouched" [ "$(md5sum <"$tmp/merged.csv")" = "$sum" ]
expect "merge without -o: exit 1" 1 "missing -o" -- "$bin" sweep merge "$tmp/s0.csv"
expect "merge --help" 0 "Usage: matremap sweep merge" -- "$bin" sweep merge --help

# --shard's usage errors.
expect "--shard 3/3: exit 1" 1 "--shard '3/3': expected K/N with integers 0 <= K < N" -- \
    "$bin" sweep "${args[@]}" --shard 3/3 -o "$tmp/x.csv"
expect "--shard x: exit 1" 1 "--shard 'x'" -- "$bin" sweep "${args[@]}" --shard x -o "$tmp/x.csv"
expect "--shard 0/13 of 12 samples: exit 1" 1 "13 shards for a sweep of 12 samples" -- \
    "$bin" sweep "${args[@]}" --shard 0/13 -o "$tmp/x.csv"
check "... and no file" [ ! -e "$tmp/x.csv" ]

# Resumed rows are read for sense: a bad value is exit 2 naming the file, the line and the column, and the file is
# left as it was (sample 2 is line 12: eight '#' lines, the column line, samples 0 and 1).
insane() { # NAME FIELD VALUE PATTERN
    awk -F, -v OFS=, -v f="$2" -v v="$3" '!/^#/ && $1 == "2" { $f = v } { print }' "$tmp/ref.csv" >"$tmp/insane.csv"
    local before
    before=$(md5sum <"$tmp/insane.csv")
    expect "resume refuses $1: exit 2" 2 "$4" -- "$bin" sweep "${args[@]}" -o "$tmp/insane.csv" --resume
    check "... the file untouched" [ "$(md5sum <"$tmp/insane.csv")" = "$before" ]
}
insane "a negative reflectance" 9 -0.5 \
    "sweep file '$tmp/insane.csv': line 12: column 9 \\(to_diffuse_r\\): -0.5 is outside diffuse's range \\[0, 1\\]"
insane "1e300" 12 1e300 "'$tmp/insane.csv': line 12: column 12 \\(to_specular_r\\): 1.0000000000000001e\\+300 is outside"
insane "inf" 15 inf "'$tmp/insane.csv': line 12: column 15 \\(to_alpha\\): inf is not a finite number"
insane "nan" 17 nan "'$tmp/insane.csv': line 12: column 17 \\(rmse\\): nan is not a finite number"
insane "a NaN source value" 2 nan "'$tmp/insane.csv': line 12: column 2 \\(alpha\\): nan is not a finite number"

# Started by an MPI launcher without the module: exit 2 naming it, no file (the launcher's variables set by hand).
expect "an MPI launch without the module: exit 2" 2 \
    "rank 0 of 2 \\(OMPI_COMM_WORLD_SIZE\\): started by an MPI launcher, but this matremap has no MPI module" -- \
    env OMPI_COMM_WORLD_SIZE=2 OMPI_COMM_WORLD_RANK=0 MR_MPI_MODULE="$tmp/none.so" \
    "$bin" sweep "${args[@]}" -o "$tmp/mpi.csv"
check "... and no file" [ ! -e "$tmp/mpi.csv" ]
expect "a launch of one process is an ordinary run" 0 "is complete" -- \
    env OMPI_COMM_WORLD_SIZE=1 OMPI_COMM_WORLD_RANK=0 MR_MPI_MODULE="$tmp/none.so" \
    "$bin" sweep "${args[@]}" -o "$tmp/one.csv"

finish
