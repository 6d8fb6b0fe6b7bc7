#!/usr/bin/env bash
# `matremap learn` and `matremap convert` as a script uses them (scripts/paper-appendix.sh): a tiny real sweep (ward
# -> ggx, 12 rows at 16 pixels), its parametric transform with --json (valid JSON, no NUL bytes), and one texel
# queried through convert. Ends with "N passed, N failed".
set -u
bin="${MR_BUILD:-build}/bin/matremap"
source "$(dirname "$0")/lib/cli_harness.sh"

"$bin" sweep --from ward diffuse=0 --to ggx diffuse=0 --grid alpha=0.05:0.5:6 specular=0.05:0.3:2 --size 16 \
    --threads 2 -o "$tmp/wg.csv" 2>/dev/null
check "the tiny sweep is made" test -s "$tmp/wg.csv"

expect "learn --json" 0 '"validation_rmse"' -- "$bin" learn "$tmp/wg.csv" -o "$tmp/wg.mrt" --json
check "learn --json writes no NUL byte" test "$(tr -cd '\000' < "$tmp/out" | wc -c)" -eq 0
check "learn --json is valid JSON naming the outputs" python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
assert set(d["validation_rmse"]) == {"alpha", "f0"}, d["validation_rmse"]
assert len(d["roughness"]) == 5 and len(d["slope"]) in (5, 6)' "$tmp/out"
expect "convert queries one texel" 0 "^ggx alpha=" -- \
    "$bin" convert --from ward --to ggx alpha=0.2 specular=0.1 diffuse=0 --transform "$tmp/wg.mrt"
finish
