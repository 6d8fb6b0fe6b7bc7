#!/usr/bin/env bash
# `matremap gltf spec2metal FOLDER|GLOB|FILES... -o DIR` (mr_gltf_convert_library) on real assets of ../shared/assets
# plus two broken ones (a truncated .gltf, one whose texture is missing): exit 2 naming the broken ones with their
# reasons, the others converted and byte-equal to the one-asset command's outputs, nested folders mirrored,
# summary.json and index.html written and sorted worst first, --resume converting nothing the second time and again
# an asset whose input changed, --shard 0/2 + 1/2 the whole list, quoted globs, and refusals (an output folder inside
# an input folder; a summary.json this command did not write). Needs python3. Ends with "N passed, N failed".
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
build="${MR_BUILD:-$root/build}"
bin="$build/bin/matremap"
shared="${MR_SHARED:-$root/../shared}/assets"
source "$(dirname "$0")/lib/cli_harness.sh"

sg="$shared/specgloss"
lib="$tmp/lib"
mkdir -p "$lib/nested/deep er" "$lib/broken"
cp -r "$sg/Duck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness" "$lib/duck"
cp -r "$sg/Avocado-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness" "$lib/nested/deep er/avocado"
cp -r "$sg/CesiumMilkTruck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness" "$lib/nested/truck"
head -c 300 "$lib/duck/Duck.gltf" >"$lib/broken/truncated.gltf"
cp -r "$lib/duck" "$lib/broken/missing"
rm "$lib/broken/missing/DuckCM.png"

# JSON facts of summary.json $1 (a Python expression over `s`, its items `it`).
summary() {
    python3 -c 'import json, sys
s = json.load(open(sys.argv[1])); it = s["items"]
print(eval(sys.argv[2]))' "$1" "$2"
}

expect "a folder with two broken assets: exit 2" 2 "" -- "$bin" gltf spec2metal "$lib" -o "$tmp/o"
check "the truncated asset named with its reason" grep -qE "broken/truncated.gltf failed: .*truncated.gltf" "$tmp/err"
check "the asset with a missing texture named with its reason" \
    grep -qE "broken/missing/Duck.gltf failed: .*DuckCM.png" "$tmp/err"
check "one plain line per finished asset" test "$(grep -c '^\[[0-9]/5\]' "$tmp/out")" = 5
check "the total line" grep -q "5 assets: 3 converted, 0 resumed, 2 failed" "$tmp/out"
check "nested folders mirrored" test -f "$tmp/o/nested/deep er/avocado/Avocado.gltf" -a \
    -f "$tmp/o/nested/truck/CesiumMilkTruck.gltf" -a -f "$tmp/o/duck/Duck.gltf"
check "nothing written for the broken assets" test ! -e "$tmp/o/broken/truncated.gltf" -a \
    ! -e "$tmp/o/broken/missing/Duck.gltf"

# Each converted asset equals what the one-asset command writes (the same file names: side files named after OUT).
for a in duck/Duck.gltf "nested/deep er/avocado/Avocado.gltf" nested/truck/CesiumMilkTruck.gltf; do
    "$bin" gltf spec2metal "$lib/$a" -o "$tmp/single/$a" >/dev/null 2>&1
    same=yes
    for f in "$tmp/single/$(dirname "$a")"/*; do
        cmp -s "$f" "$tmp/o/$(dirname "$a")/$(basename "$f")" || same="no: $(basename "$f")"
    done
    [ "$(ls "$tmp/single/$(dirname "$a")" | wc -l)" = "$(ls "$tmp/o/$(dirname "$a")" | wc -l)" ] || same="no: count"
    check "$a: the same files, byte for byte, as 'gltf spec2metal $(basename "$a") -o ...' ($same)" test "$same" = yes
done

check "summary.json: 5 assets, 2 failed" test "$(summary "$tmp/o/summary.json" 's["assets"], s["failed"]')" = "(5, 2)"
check "summary.json: worst first (failed, then object SSIM ascending)" test "$(summary "$tmp/o/summary.json" \
    '[x["status"] for x in it[:2]] == ["failed"] * 2 and all(it[i]["object_ssim"] <= it[i + 1]["object_ssim"] \
     for i in range(2, 4))')" = True
check "summary.json: materials, flags, SSIM and thumbnails of each converted asset" test "$(summary \
    "$tmp/o/summary.json" 'all(len(x["materials"]) > 0 and "off_manifold" in x["flags"] and \
    0.5 < x["object_ssim"] <= 1 and x["before"].endswith(".before.png") for x in it[2:])')" = True
check "summary.json: the failures' reasons" test "$(summary "$tmp/o/summary.json" \
    'all(x["error"] and not x["materials"] for x in it[:2])')" = True
check "thumbnails written" test -f "$tmp/o/thumbnails/duck/Duck.gltf.before.png" -a \
    -f "$tmp/o/thumbnails/duck/Duck.gltf.after.png"
order=$(summary "$tmp/o/summary.json" '" ".join(x["input"].split("/")[-1] for x in it)')
html_order=$(grep -oE '<tr class="[a-z]+"><td>[^<]*' "$tmp/o/index.html" | sed 's|.*/||' | tr '\n' ' ' | sed 's/ $//')
check "index.html: every asset, in summary.json's order ($html_order)" test "$order" = "$html_order"
check "index.html: before/after images" test "$(grep -o '<img src="thumbnails/' "$tmp/o/index.html" | wc -l)" = 6

# --resume: nothing converted again; an asset whose input changed converted again.
expect "--resume: nothing converted again" 2 "5 assets: 0 converted, 3 resumed, 2 failed" -- \
    "$bin" gltf spec2metal "$lib" -o "$tmp/o" --resume
check "--resume: the summary keeps every asset" test "$(summary "$tmp/o/summary.json" 'len(it)')" = 5
printf ' ' >>"$lib/duck/Duck.gltf"
expect "--resume: the changed asset converted again" 2 "5 assets: 1 converted, 2 resumed, 2 failed" -- \
    "$bin" gltf spec2metal "$lib" -o "$tmp/o" --resume
expect "--resume with other settings converts again" 2 "5 assets: 3 converted, 0 resumed" -- \
    "$bin" gltf spec2metal "$lib" -o "$tmp/o" --resume --core-only

# --shard K/N: sorted paths, index % N == K; the two shards are the whole, without overlap.
expect "--shard 0/2" 2 "" -- "$bin" gltf spec2metal "$lib" -o "$tmp/s0" --shard 0/2
expect "--shard 1/2" 2 "" -- "$bin" gltf spec2metal "$lib" -o "$tmp/s1" --shard 1/2
whole=$(summary "$tmp/o/summary.json" 'sorted(x["input"] for x in it)')
union=$(python3 -c 'import json, sys
a = [x["input"] for f in sys.argv[1:] for x in json.load(open(f))["items"]]
print(sorted(a) if len(a) == len(set(a)) else "overlap")' "$tmp/s0/summary.json" "$tmp/s1/summary.json")
check "--shard 0/2 + 1/2 = the whole" test "$whole" = "$union"
check "--shard 0/2 holds sorted indices 0, 2, 4" test "$(summary "$tmp/s0/summary.json" 'len(it)')" = 3

# Globs (quoted: expanded by matremap) and several files.
expect "a quoted glob" 2 "2 assets: 1 converted, 0 resumed, 1 failed" -- \
    "$bin" gltf spec2metal "$lib/*/*.gltf" -o "$tmp/g"
check "a glob's assets mirrored below their common root" test -f "$tmp/g/duck/Duck.gltf"
expect "a glob matching nothing" 2 "matches no" -- "$bin" gltf spec2metal "$lib/*/*.nothing" -o "$tmp/g2"
expect "two files into a folder" 0 "2 assets: 2 converted" -- "$bin" gltf spec2metal "$lib/duck/Duck.gltf" \
    "$lib/nested/truck/CesiumMilkTruck.gltf" -o "$tmp/two"
check "two files: mirrored below their common folder" test -f "$tmp/two/duck/Duck.gltf" -a \
    -f "$tmp/two/nested/truck/CesiumMilkTruck.gltf"

expect "--no-renders" 0 "2 assets: 2 converted" -- "$bin" gltf spec2metal "$lib/duck/Duck.gltf" \
    "$lib/nested/truck/CesiumMilkTruck.gltf" -o "$tmp/bare" --no-renders
check "--no-renders: no thumbnails, SSIM null" test ! -e "$tmp/bare/thumbnails" -a \
    "$(summary "$tmp/bare/summary.json" 'all(x["object_ssim"] is None for x in it)')" = True

"$bin" gltf spec2metal "$lib/duck/Duck.gltf" "$lib/nested/truck/CesiumMilkTruck.gltf" -o "$tmp/t1" --no-renders \
    --threads 1 >/dev/null 2>&1
check "--threads 1 writes the same assets as the automatic team" \
    diff -r -q -x summary.json -x index.html "$tmp/bare" "$tmp/t1"

# Refusals.
refuses "an output folder inside an input folder" "lies inside the input folder" "$lib" -- \
    "$bin" gltf spec2metal "$lib" -o "$lib/converted"
mkdir -p "$tmp/theirs"
echo '{"not": "ours"}' >"$tmp/theirs/summary.json"
refuses "a summary.json this command did not write" "not written by a library conversion" "$tmp/theirs" -- \
    "$bin" gltf spec2metal "$lib/duck" -o "$tmp/theirs"
mkdir -p "$tmp/pre/duck" && echo '{}' >"$tmp/pre/duck/Duck.gltf"
expect "an existing output this command did not write: that asset fails" 2 \
    "Duck.gltf' exists and no earlier library run into .* wrote it; refusing to replace it" -- \
    "$bin" gltf spec2metal "$lib/duck" "$lib/nested/truck" -o "$tmp/pre"
check "... left as it was, the other asset converted" test "$(cat "$tmp/pre/duck/Duck.gltf")" = '{}' -a \
    -f "$tmp/pre/nested/truck/CesiumMilkTruck.gltf"
expect "--resume with one asset: a usage error" 1 "go with many assets" -- \
    "$bin" gltf spec2metal "$lib/duck/Duck.gltf" -o "$tmp/x.gltf" --resume
expect "--shard out of range" 1 "expected K/N" -- "$bin" gltf spec2metal "$lib" -o "$tmp/y" --shard 2/2
expect "many assets into one .gltf: a usage error" 1 "into a folder" -- \
    "$bin" gltf spec2metal "$lib" -o "$tmp/y.gltf"
finish
