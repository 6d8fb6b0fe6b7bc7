#!/usr/bin/env bash
# `matremap learn` and `matremap convert` on a real (small) sweep: a parametric transform learned, written and
# refused when damaged; texture maps converted with outputs, alpha, sizes and the flag map; constants printed;
# chains given and found; the errors a user can make. Ends with "N passed, N failed".
set -u
bin="${MR_BUILD:-build}/bin/matremap"
root=$(cd "$(dirname "$0")/.." && pwd)
source "$(dirname "$0")/lib/cli_harness.sh"

"$bin" sweep --from ward diffuse=0 --to ggx diffuse=0 --grid alpha=0.03:0.4:8:log specular=0.03:0.25:3 --size 32 \
    --threads 2 -o "$tmp/wg.csv" 2>/dev/null
"$bin" sweep --from ggx diffuse=0 --to as diffuse=0 --grid alpha=0.02:0.5:8:log f0=0.02:0.3:3 --size 32 \
    --threads 2 -o "$tmp/ga.csv" 2>/dev/null
check "the sweeps are made" test -s "$tmp/wg.csv" -a -s "$tmp/ga.csv"

expect "learn --help" 0 "Usage: matremap learn" -- "$bin" learn --help
expect "learn: no sweep" 1 "no sweep file" -- "$bin" learn -o "$tmp/x.mrt"
expect "learn: no output" 1 "no output file" -- "$bin" learn "$tmp/wg.csv"
mkdir -p "$tmp/io/plots"
cp "$tmp/wg.csv" "$tmp/io/plots/rows.csv"
refuses "learn: -o over the sweep" "output '$tmp/./wg.csv' is the input sweep $tmp/wg.csv; refusing" "$tmp" -- \
    "$bin" learn "$tmp/wg.csv" -o "$tmp/./wg.csv"
refuses "learn: --plots DIR whose rows.csv is the sweep" \
    "output '$tmp/io/plots/rows.csv' \(--plots $tmp/io/plots\) is the input sweep" "$tmp/io" -- \
    "$bin" learn "$tmp/io/plots/rows.csv" -o "$tmp/io/x.mrt" --plots "$tmp/io/plots"
expect "learn: unknown method" 1 "valid: parametric, svr, mlp" -- "$bin" learn "$tmp/wg.csv" --method gp -o "$tmp/x.mrt"
expect "learn: a missing file" 2 "nope.csv" -- "$bin" learn "$tmp/nope.csv" -o "$tmp/x.mrt"
sed '12s/,0.0[0-9]*,converged/,nan,converged/' "$tmp/wg.csv" > "$tmp/nan.csv"
sed -i '12s/^\([0-9]*\),\([^,]*\),/\1,nan,/' "$tmp/nan.csv"
expect "learn: a NaN in a row names file and line" 2 "nan.csv:12: .*not a finite number" -- \
    "$bin" learn "$tmp/nan.csv" -o "$tmp/x.mrt"
check "... and writes nothing" test ! -e "$tmp/x.mrt"
head -c "$(($(wc -c < "$tmp/wg.csv") - 30))" "$tmp/wg.csv" > "$tmp/torn.csv"
expect "learn: a torn last row names file and line" 2 "torn.csv:[0-9]+: .*fields" -- \
    "$bin" learn "$tmp/torn.csv" -o "$tmp/x.mrt"
expect "learn: two sweeps of different pairs" 2 "differ" -- "$bin" learn "$tmp/wg.csv" "$tmp/ga.csv" -o "$tmp/x.mrt"

expect "learn parametric with plots" 0 "ward -> ggx by parametric" -- \
    "$bin" learn "$tmp/wg.csv" -o "$tmp/wg.mrt" --plots "$tmp/plots"
check "the summary gives the held-out error" grep -q "held-out RMSE" "$tmp/out"
check "the transform file starts with its magic" grep -q "^matremap-transform 2$" "$tmp/wg.mrt"
check "it records where its data came from" grep -q "^| # from: ward diffuse=0" "$tmp/wg.mrt"
check "the cross-section data is written" test -s "$tmp/plots/rows.csv" -a -s "$tmp/plots/curves.csv"
if command -v gnuplot >/dev/null; then
    check "the cross sections are plotted" grep -q "<svg" "$tmp/plots/specular.svg"
fi
# The plots are committed with the transform: when they cannot be written, no transform is left either.
touch "$tmp/plainfile"
expect "learn: --plots under a file" 2 "plainfile/sub" -- \
    "$bin" learn "$tmp/wg.csv" -o "$tmp/np.mrt" --plots "$tmp/plainfile/sub"
check "... and writes no transform" test ! -e "$tmp/np.mrt"
mkdir -p "$tmp/p2/rows.csv"
expect "learn: a plot file that is a folder" 2 "rows.csv" -- \
    "$bin" learn "$tmp/wg.csv" -o "$tmp/np.mrt" --plots "$tmp/p2"
check "... removes the transform it had written and leaves no temporary file" \
    test ! -e "$tmp/np.mrt" -a -z "$(ls -A "$tmp/p2" | grep -v '^rows.csv$')"
"$bin" learn "$tmp/wg.csv" -o "$tmp/wg2.mrt" >/dev/null
check "learning is reproducible byte for byte" cmp -s "$tmp/wg.mrt" "$tmp/wg2.mrt"
expect "learn --json" 0 '"validation_rmse": \{"alpha": [0-9]' -- "$bin" learn "$tmp/ga.csv" -o "$tmp/ga.mrt" --json
check "learn --json writes no NUL byte" test "$(tr -cd '\000' < "$tmp/out" | wc -c)" -eq 0
check "learn --json is valid JSON naming the outputs" python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
assert set(d["validation_rmse"]) == {"alpha", "f0", "diffuse"}, d["validation_rmse"]
assert len(d["roughness"]) == 5 and len(d["slope"]) in (5, 6)' "$tmp/out"

sed 's/^validation 0x1.999999999999ap-3/validation 0x1.999999999999bp-3/' "$tmp/wg.mrt" > "$tmp/edited.mrt"
expect "convert: an edited transform is refused" 2 "edited.mrt.*checksum mismatch" -- \
    "$bin" convert --from ward --to ggx alpha=0.1 --transform "$tmp/edited.mrt"
head -c 300 "$tmp/wg.mrt" > "$tmp/cut.mrt"
expect "convert: a truncated transform is refused" 2 "cut.mrt.*line" -- \
    "$bin" convert --from ward --to ggx alpha=0.1 --transform "$tmp/cut.mrt"

expect "convert --help" 0 "Usage: matremap convert" -- "$bin" convert --help
expect "convert: constants print the texel" 0 "^ggx alpha=0\.[0-9]+ f0=(0\.1[0-9]*),\1,\1 diffuse=0.3,0.3,0.3$" -- \
    "$bin" convert --from ward --to ggx alpha=0.1 specular=0.15 diffuse=0.3 --transform "$tmp/wg.mrt"
expect "convert: beyond the training domain is noted" 0 "extrapolated" -- \
    "$bin" convert --from ward --to ggx alpha=0.9 specular=0.15 --transform "$tmp/wg.mrt"
expect "convert: the transform must fit the pair" 2 "converts ward to ggx" -- \
    "$bin" convert --from ggx --to as alpha=0.1 --transform "$tmp/wg.mrt"
expect "convert: no transform" 1 "--transform" -- "$bin" convert --from ward --to ggx alpha=0.1
expect "convert: an unknown parameter" 2 "alfa" -- \
    "$bin" convert --from ward --to ggx alfa=0.1 --transform "$tmp/wg.mrt"

# Texture maps: a roughness map with alpha reaching beyond the rows, a coloured specular map with an alpha channel.
oiiotool --pattern fill:top=0.02:bottom=0.6 64x32 1 -d float -o "$tmp/rough.exr" >/dev/null 2>&1
oiiotool --pattern fill:left=0.05,0.1,0.02,1:right=0.3,0.2,0.1,0.5 64x32 4 -d uint8 -o "$tmp/spec.png" >/dev/null 2>&1
expect "convert maps" 0 "64x32 = 2048 texels" -- "$bin" convert --from ward --to ggx alpha="$tmp/rough.exr" \
    specular=@"$tmp/spec.png" diffuse=0.2 --transform "$tmp/wg.mrt" -o "$tmp/o/ggx_"
check "every target parameter is written" test -s "$tmp/o/ggx_alpha.exr" -a -s "$tmp/o/ggx_f0.exr" \
    -a -s "$tmp/o/ggx_diffuse.exr" -a -s "$tmp/o/ggx_flags.png"
check "outputs keep the size" bash -c "oiiotool --info '$tmp/o/ggx_alpha.exr' | grep -q '64 x  *32'"
check "RGB outputs carry the input's alpha" bash -c "oiiotool --info -v '$tmp/o/ggx_f0.exr' | grep -q '4 channel'"
check "texels beyond the rows are flagged red" bash -c \
    "oiiotool --stats '$tmp/o/ggx_flags.png' | grep -q 'Max: 255 0 0 '"
check "and the summary counts them" grep -qE "[1-9][0-9]* extrapolated" "$tmp/out"
expect "convert --format png" 0 "texels" -- "$bin" convert --from ward --to ggx alpha=@"$tmp/rough.exr" \
    specular=@"$tmp/spec.png" --transform "$tmp/wg.mrt" -o "$tmp/png_" --format png
check "png outputs" test -s "$tmp/png_f0.png"
oiiotool --pattern constant:color=0.1 32x32 1 -d float -o "$tmp/rough32.exr" >/dev/null 2>&1
expect "convert: maps of different sizes are refused" 2 "64x32" -- "$bin" convert --from ward --to ggx \
    alpha="$tmp/rough32.exr" specular=@"$tmp/spec.png" --transform "$tmp/wg.mrt" -o "$tmp/sz_"
check "... and nothing is written" bash -c "! ls '$tmp'/sz_* >/dev/null 2>&1"
# No output replaces an input: maps (as given, NAME=FILE or NAME=@FILE), transforms, and --cache against both.
cp "$tmp/spec.png" "$tmp/io/x_f0.png"
cp "$tmp/rough.exr" "$tmp/io/r.exr"
cp "$tmp/wg.mrt" "$tmp/io/t.mrt"
ln "$tmp/io/t.mrt" "$tmp/io/y_alpha.exr"
refuses "convert: an output that is an input map is refused" \
    "output '$tmp/io/x_f0.png' \(-o $tmp/io/x_\) is the input specular=@$tmp/io/x_f0.png; refusing" "$tmp/io" -- \
    "$bin" convert --from ward --to ggx specular=@"$tmp/io/x_f0.png" --transform "$tmp/wg.mrt" -o "$tmp/io/x_" \
    --format png
refuses "convert: ... named as given (NAME=FILE)" "is the input specular=$tmp/io/x_f0.png;" "$tmp/io" -- \
    "$bin" convert --from ward --to ggx specular="$tmp/io/x_f0.png" --transform "$tmp/wg.mrt" -o "$tmp/io/./x_" \
    --format png
refuses "convert: an output that is a hard link of the transform" \
    "output '$tmp/io/y_alpha.exr' \(-o $tmp/io/y_\) is the input transform $tmp/io/t.mrt" "$tmp/io" -- \
    "$bin" convert --from ward --to ggx alpha=@"$tmp/io/r.exr" --transform "$tmp/io/t.mrt" -o "$tmp/io/y_"
refuses "convert: --cache over an input map" "output '$tmp/io/r.exr' \(--cache\) is the input alpha=$tmp/io/r.exr" \
    "$tmp/io" -- "$bin" convert --from ward --to ggx alpha="$tmp/io/r.exr" --direct --cache "$tmp/io/r.exr" \
    -o "$tmp/io/z_"
# A failed write (a file-size limit, as a full disk) leaves the previous outputs as they were and nothing else:
# every output is written to a hidden temporary file beside it, all renamed into place only once all are written.
refuses "convert: a write failing midway leaves the outputs as they were" "error: writing '$tmp/o/ggx_" "$tmp/o" -- \
    bash -c 'trap "" XFSZ; ulimit -f 4; exec "$@"' _ "$bin" convert --from ward --to ggx alpha="$tmp/rough.exr" \
    specular=@"$tmp/spec.png" diffuse=0.3 --transform "$tmp/wg.mrt" -o "$tmp/o/ggx_"
expect "convert: ... and into a new folder, no folder is left" 2 "error: writing '$tmp/new/ggx_" -- \
    bash -c 'trap "" XFSZ; ulimit -f 4; exec "$@"' _ "$bin" convert --from ward --to ggx alpha="$tmp/rough.exr" \
    specular=@"$tmp/spec.png" diffuse=0.3 --transform "$tmp/wg.mrt" -o "$tmp/new/ggx_"
check "... no folder left" test ! -e "$tmp/new"
mkdir -p "$tmp/io/w_flags.png"
refuses "convert: a folder in an output's way is refused before anything is written" \
    "output '$tmp/io/w_flags.png' \(-o $tmp/io/w_\) is a folder" "$tmp/io" -- "$bin" convert --from ward --to ggx \
    alpha=@"$tmp/rough.exr" --transform "$tmp/wg.mrt" -o "$tmp/io/w_"

# Chains: given in order, and found in a folder (fewest hops), with --via.
mkdir -p "$tmp/mrt" && cp "$tmp/wg.mrt" "$tmp/ga.mrt" "$tmp/mrt/"
expect "convert through a given chain" 0 "^as alpha=" -- "$bin" convert --from ward --to as alpha=0.1 specular=0.1 \
    --transform "$tmp/wg.mrt" --transform "$tmp/ga.mrt"
chained=$(sed -n 1p "$tmp/out")
expect "convert through a found chain" 0 "^as alpha=" -- "$bin" convert --from ward --to as alpha=0.1 specular=0.1 \
    --transforms "$tmp/mrt" --via ggx
check "the found chain is the given one" test "$(sed -n 1p "$tmp/out")" = "$chained"
step=$("$bin" convert --from ward --to ggx alpha=0.1 specular=0.1 --transform "$tmp/wg.mrt" | sed 's/^ggx //')
# shellcheck disable=SC2086 # the step's name=value words
stepwise=$("$bin" convert --from ggx --to as $step --transform "$tmp/ga.mrt" | sed -n 1p)
# the steps pass through 6-digit text, so they agree with the chain to about 1e-5
check "the chain equals its steps" awk -v a="$chained" -v b="$stepwise" 'BEGIN {
    n = split(a, x, /[ =,]/); split(b, y, /[ =,]/)
    for (i = 1; i <= n; i++) if (x[i] + 0 != 0 && (x[i] - y[i]) ^ 2 > (1e-5 * x[i]) ^ 2) exit 1 }'
expect "convert: no chain" 2 "no chain of transforms from as to ward" -- \
    "$bin" convert --from as --to ward alpha=0.1 --transforms "$tmp/mrt"

# --direct: the image-based optimiser on every distinct texel; a cache answers a second run with the same bits.
oiiotool --pattern fill:top=0.03:bottom=0.3 16x8 1 -d float -o "$tmp/r16.exr" >/dev/null 2>&1
oiiotool --pattern fill:left=0.05,0.1,0.02:right=0.2,0.15,0.1 16x8 3 -d uint8 -o "$tmp/s16.png" >/dev/null 2>&1
expect "convert --direct" 0 "by direct remaps, 16x8 = 128 texels" -- "$bin" convert --from ward --to ggx \
    alpha="$tmp/r16.exr" specular="$tmp/s16.png" diffuse=0 --direct --size 32 --cache "$tmp/d.cache" -o "$tmp/d1_"
check "the direct summary counts distinct values and remaps" grep -qE "[0-9]+ distinct values .* 0 from the cache" \
    "$tmp/err"
# The verdicts: the glossy top row (alpha 0.03) is under-resolved at 32² (remap says so), the rough bottom row is not.
check "unconverged direct texels are counted" grep -qE "[1-9][0-9]* not converged" "$tmp/out"
check "... and red in the flag map where remap says under-resolved (the top row)" bash -c \
    "oiiotool --dumpdata '$tmp/d1_flags.png' | grep -q 'Pixel (0, 0): 255 0 0' && \
     oiiotool --dumpdata '$tmp/d1_flags.png' | grep -q 'Pixel (0, 7): 0 0 0' && \
     '$bin' remap --from ward alpha=0.03 specular=0.05,0.1,0.02 diffuse=0 --to ggx --size 32 | grep -q 'outcome: under-resolved'"
expect "convert --direct again, from the cache" 0 "from the cache" -- "$bin" convert --from ward --to ggx \
    alpha="$tmp/r16.exr" specular="$tmp/s16.png" diffuse=0 --direct --size 32 --cache "$tmp/d.cache" -o "$tmp/d2_"
check "every value came from the cache" grep -qE "([0-9]+) distinct values \(tolerance [0-9.]+\): \1 from the cache" \
    "$tmp/err"
check "cached answers are the same bits" cmp -s "$tmp/d1_f0.exr" "$tmp/d2_f0.exr"
expect "convert --direct: a cache of another scene is refused" 2 "d.cache" -- "$bin" convert --from ward --to ggx \
    alpha="$tmp/r16.exr" --direct --size 48 --cache "$tmp/d.cache" -o "$tmp/d3_"
expect "convert: --tolerance without --direct" 1 "go with --direct" -- "$bin" convert --from ward --to ggx \
    alpha=0.1 --transform "$tmp/wg.mrt" --tolerance 0.01
# The learned transform against the direct reference on the same texels: close inside the training domain.
"$bin" convert --from ward --to ggx alpha="$tmp/r16.exr" specular="$tmp/s16.png" diffuse=0 --transform "$tmp/wg.mrt" \
    -o "$tmp/l_" >/dev/null 2>&1
check "learned alpha within 0.02 of direct alpha" bash -c \
    "oiiotool --diff --fail 0.02 --failpercent 0 '$tmp/l_alpha.exr' '$tmp/d1_alpha.exr' >/dev/null"
# The README's sweep (issue 26): 'sweep --random N' draws where texture maps lie (grey, untrimmed), so every method's
# transform gives an ordinary texel within 5 % of the remap itself ('--direct' on constants remaps the exact values),
# SVR keeps a grey texel grey, and learn checks each transform against the held-out remaps and says so.
"$bin" sweep --from ward --to ggx --random 300 --threads 2 -o "$tmp/rw.csv" 2>/dev/null
check "the random sweep says its region" grep -q "^# sampling: random=300 seed=1 region=texture over" "$tmp/rw.csv"
texel="diffuse=0.5 specular=0.2 alpha=0.1"
# shellcheck disable=SC2086
"$bin" convert --from ward --to ggx $texel --direct --json > "$tmp/direct.json" 2>/dev/null
# shellcheck disable=SC2086
"$bin" remap --from ward $texel --to ggx > "$tmp/remap.txt" 2>/dev/null
check "--direct on constants is the remap of the exact values" python3 -c "
import json, re, sys
d = json.load(open('$tmp/direct.json'))['values']
r = dict(re.findall(r'(\w+)=([0-9.e+-]+)', open('$tmp/remap.txt').readline()))
sys.exit(0 if abs(d['f0'][0] - float(r['f0'])) < 1e-3 * float(r['f0']) and abs(d['alpha'] - float(r['alpha'])) < 1e-3 * float(r['alpha']) else 1)"
for method in parametric svr mlp; do
    expect "learn the README's sweep by $method" 0 "check  passed|check  FAILED" -- \
        "$bin" learn "$tmp/rw.csv" --method $method --threads 2 -o "$tmp/rw_$method.mrt"
    check "... prints each output's error against the remaps" grep -q "against the remaps: median .*, 9 in 10 within" \
        "$tmp/out"
    # shellcheck disable=SC2086
    "$bin" convert --from ward --to ggx $texel --transform "$tmp/rw_$method.mrt" --json > "$tmp/l.json" 2>/dev/null
    check "... its texel is within 5 % of --direct, and grey stays grey ($method)" python3 -c "
import json, sys
d = json.load(open('$tmp/direct.json'))['values']; l = json.load(open('$tmp/l.json'))['values']
ok = all(abs(l[k] - d[k]) <= 0.05 * d[k] for k in ['alpha'])
ok = ok and all(abs(l[k][c] - d[k][c]) <= 0.05 * d[k][c] for k in ['f0', 'diffuse'] for c in range(3))
ok = ok and all(l[k][0] == l[k][1] == l[k][2] for k in ['f0', 'diffuse'])
print(d, l); sys.exit(0 if ok else 1)"
done
"$bin" learn "$tmp/rw.csv" -o "$tmp/rw_p.mrt" --json > "$tmp/learn.json" 2>/dev/null
check "learn --json gives the check" python3 -c "
import json, sys
c = json.load(open('$tmp/learn.json'))['check']
sys.exit(0 if c['done'] and c['passed'] and c['rows'] == 60 and c['relative_error']['f0']['p90'] <= 0.1 else 1)"
# The sweep as it was drawn before regions (Ward's whole specular range, channels apart: 95 % trimmed): learn
# leaves the trimmed rows out and says why, instead of a transform ten times off.
"$bin" sweep --from ward --to ggx --random 300 --region range --threads 2 -o "$tmp/range.csv" 2>/dev/null
expect "learn refuses a sweep whose every row is trimmed, saying why" 2 \
    "300 because model 'ward' rescales .*--region texture" -- "$bin" learn "$tmp/range.csv" -o "$tmp/range.mrt"
check "... and writes nothing" test ! -e "$tmp/range.mrt"
expect "learn --keep-trimmed learns them anyway, and the check fails it" 0 "check  FAILED" -- \
    "$bin" learn "$tmp/range.csv" --keep-trimmed -o "$tmp/range.mrt"
check "... with a warning naming what is off" grep -q "warning: the transform fails its check.* is more than 10 % off" \
    "$tmp/err"
# shellcheck disable=SC2086
expect "convert with a transform that failed its check warns and flags the texel" 0 "ggx alpha=" -- \
    "$bin" convert --from ward --to ggx $texel --transform "$tmp/range.mrt"
check "... the warning names the transform" grep -q "warning: transform $tmp/range.mrt .* failed its check" "$tmp/err"
check "... and the note says the texel is flagged for it" grep -q "failed its check against the remaps" "$tmp/err"
oiiotool --pattern constant:color=0.2 4x4 1 -d float -o "$tmp/a4.exr" >/dev/null 2>&1
expect "convert maps with it: every texel red in the flag map" 0 "16 by a transform that failed its check" -- \
    "$bin" convert --from ward --to ggx alpha="$tmp/a4.exr" specular=0.2 diffuse=0.5 --transform "$tmp/range.mrt" \
    -o "$tmp/failed_"
check "... red" bash -c "oiiotool --dumpdata '$tmp/failed_flags.png' | grep -q 'Pixel (3, 3): 255 0 0'"
finish
