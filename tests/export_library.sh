#!/usr/bin/env bash
# export_library.sh — `matremap export FOLDER|GLOB|FILES... -o DIR --format F` (mr_doc_export_library: gltf/'s library
# loop with mr_doc_export_file per asset) on real assets of ../shared/assets plus a broken one (a truncated .gltf):
# exit 2 naming it, the others exported (.usda, .mtlx --to gltf, .glb) and byte-equal to the one-asset command's
# outputs, folders mirrored, summary.json (routes per material) and index.html written, .glb outputs rendered
# (thumbnails, object SSIM) and documents not, --resume exporting nothing the second time (and again with other
# options), --shard 0/2 + 1/2 the whole list, and usage errors. Needs python3. Ends with "N passed, N failed".
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
build="${MR_BUILD:-$root/build}"
bin="$build/bin/matremap"
shared="${MR_SHARED:-$root/../shared}/assets"
source "$(dirname "$0")/lib/cli_harness.sh"

lib="$tmp/lib"
mkdir -p "$lib/broken" "$lib/metal rough"
cp -r "$shared/metalrough/WaterBottle/glTF" "$lib/metal rough/bottle"
cp -r "$shared/metalrough/TextureSettingsTest/glTF" "$lib/metal rough/settings"
cp -r "$shared/specgloss/Duck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness" "$lib/duck"
head -c 300 "$lib/duck/Duck.gltf" >"$lib/broken/truncated.gltf"
assets=(duck/Duck.gltf "metal rough/bottle/WaterBottle.gltf" "metal rough/settings/TextureSettingsTest.gltf")

summary() {
    python3 -c 'import json, sys
s = json.load(open(sys.argv[1])); it = s["items"]
print(eval(sys.argv[2]))' "$1" "$2"
}

# The outputs of asset $1 (relative to $lib) with extension $2 in folder $3 equal the one-asset command's ($4...).
same_as_single() {
    local a=$1 ext=$2 dir=$3; shift 3
    local stem="${a%.*}" single="$tmp/single$ext"
    "$bin" export "$lib/$a" -o "$single/$stem$ext" "$@" >/dev/null 2>&1 || { echo "single export failed"; return 1; }
    local f
    for f in "$single/$(dirname "$a")"/*; do
        cmp -s "$f" "$dir/$(dirname "$a")/$(basename "$f")" || { echo "differs: $f"; return 1; }
    done
    [ "$(ls "$single/$(dirname "$a")" | wc -l)" = "$(ls "$dir/$(dirname "$a")" | wc -l)" ]
}

expect "a folder with a broken asset to .usda: exit 2" 2 "" -- "$bin" export "$lib" -o "$tmp/u" --format usda
check "the broken asset named with its reason" grep -qE "broken/truncated.gltf failed: .*invalid JSON" "$tmp/err"
check "one line per asset" test "$(grep -c '^\[[0-9]/4\]' "$tmp/out")" = 4
check "the total line" grep -q "4 assets: 3 exported, 0 resumed, 1 failed" "$tmp/out"
check "folders mirrored, the extension .usda" test -f "$tmp/u/metal rough/bottle/WaterBottle.usda" -a \
    -f "$tmp/u/metal rough/settings/TextureSettingsTest.usda" -a -f "$tmp/u/duck/Duck.usda"
check "nothing written for the broken asset" test ! -e "$tmp/u/broken"
for a in "${assets[@]}"; do
    check ".usda: $a the same files, byte for byte, as the one-asset export" same_as_single "$a" .usda "$tmp/u"
done
check "summary.json: 4 assets, 1 failed" test "$(summary "$tmp/u/summary.json" 's["assets"], s["failed"]')" = "(4, 1)"
check "summary.json: each exported asset's materials with routes, format and target" test "$(summary \
    "$tmp/u/summary.json" 'all(x["format"] == "usda" and x["target"] == "usd-preview" and len(x["materials"]) > 0 \
    and all(m["route"] in ("maps", "remap", "copy") for m in x["materials"]) for x in it[1:])')" = True
check "summary.json: documents not rendered (SSIM and thumbnails null)" test "$(summary "$tmp/u/summary.json" \
    'all(x["object_ssim"] is None and x["before"] is None for x in it)')" = True
check "index.html lists every asset" test "$(grep -c '<tr class=' "$tmp/u/index.html")" = 4

# .mtlx (gltf_pbr: maps carried) and .glb (the asset itself, rendered before/after).
expect "to .mtlx --to gltf" 2 "4 assets: 3 exported" -- "$bin" export "$lib" -o "$tmp/m" --format mtlx --to gltf
for a in "${assets[@]}"; do
    check ".mtlx: $a byte for byte as the one-asset export" same_as_single "$a" .mtlx "$tmp/m" --to gltf
done
expect "to .glb" 2 "4 assets: 3 exported" -- "$bin" export "$lib" -o "$tmp/g" --format glb
check ".glb: Duck byte for byte as the one-asset export" same_as_single duck/Duck.gltf .glb "$tmp/g"
check ".glb: rendered before/after, object SSIM near 1 (the same materials)" test "$(summary "$tmp/g/summary.json" \
    'all(0.99 <= x["object_ssim"] <= 1 and x["after"].endswith(".after.png") for x in it[1:])')" = True

# --resume: nothing exported again; other options export again.
expect "--resume: nothing exported again" 2 "4 assets: 0 exported, 3 resumed, 1 failed" -- \
    "$bin" export "$lib" -o "$tmp/u" --format usda --resume
check "--resume: the summary keeps every asset" test "$(summary "$tmp/u/summary.json" 'len(it)')" = 4
expect "--resume with another --size exports again" 2 "4 assets: 3 exported, 0 resumed" -- \
    "$bin" export "$lib" -o "$tmp/u" --format usda --resume --size 32

# --shard K/N: the two halves are the whole, without overlap.
expect "--shard 0/2" 2 "2 assets" -- "$bin" export "$lib" -o "$tmp/s0" --format usda --shard 0/2
expect "--shard 1/2" 0 "2 assets" -- "$bin" export "$lib" -o "$tmp/s1" --format usda --shard 1/2
whole=$(summary "$tmp/u/summary.json" 'sorted(x["input"] for x in it)')
union=$(python3 -c 'import json, sys
a = [x["input"] for f in sys.argv[1:] for x in json.load(open(f))["items"]]
print(sorted(a) if len(a) == len(set(a)) else "overlap")' "$tmp/s0/summary.json" "$tmp/s1/summary.json")
check "--shard 0/2 + 1/2 = the whole" test "$whole" = "$union"

# Files and quoted globs; --json.
expect "two files and a quoted glob, --json" 0 '"assets": 3, "exported": 3' -- "$bin" export "$lib/duck/Duck.gltf" \
    "$lib/metal rough/bottle/WaterBottle.gltf" "$lib/metal rough/settings/*.gltf" -o "$tmp/j" --format usda --json

# The direct route with a --cache over two small textured assets (6 x 6 maps): the assets run one at a time (the
# cache's lock), the second finds every answer of the first in the cache; each output equals the one-asset export.
mkdir -p "$tmp/tex/a" "$tmp/tex/b"
oiiotool --pattern fill:topleft=0.6,0.3,0.1:topright=0.1,0.4,0.6:bottomleft=0.3,0.3,0.3:bottomright=0.7,0.7,0.2 \
    6x6 3 -d uint8 -o "$tmp/tex/a/base.png" >/dev/null 2>&1
oiiotool --pattern fill:topleft=0,0.2,0:topright=0,0.8,0:bottomleft=0,0.4,1:bottomright=0,0.6,1 6x6 3 -d uint8 \
    -o "$tmp/tex/a/mr.png" >/dev/null 2>&1
cat >"$tmp/tex/a/tex.gltf" <<'JSON'
{"asset": {"version": "2.0"}, "images": [{"uri": "base.png"}, {"uri": "mr.png"}],
 "textures": [{"source": 0}, {"source": 1}],
 "materials": [{"name": "Tex", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
   "metallicRoughnessTexture": {"index": 1}}}]}
JSON
cp "$tmp/tex/a/"* "$tmp/tex/b/"
expect "two textured assets to openpbr by the direct route, one --cache" 0 "2 assets: 2 exported" -- \
    "$bin" export "$tmp/tex/a" "$tmp/tex/b" -o "$tmp/tex/o" --format mtlx --size 16 --cache "$tmp/c.cache"
check "... the summary says the direct route" test "$(summary "$tmp/tex/o/summary.json" \
    'all(x["materials"][0]["route"] == "direct" and x["materials"][0]["texels"] == 36 for x in it)')" = True
check "... the cache holds the distinct values once (36 answers)" test "$(grep -vc '^#' "$tmp/c.cache")" = 37
"$bin" export "$tmp/tex/a/tex.gltf" -o "$tmp/tex/single/a/tex.mtlx" --size 16 >/dev/null 2>&1
check "... the first asset's files equal the one-asset export's" diff -r -q "$tmp/tex/single/a" "$tmp/tex/o/a"

# A MaterialX document among the inputs: exported too (fingerprint: its one file), not rendered into a .glb.
gold="$root/tests/data/materialx/standard_surface_gold.mtlx"
expect "a .mtlx and a glTF asset into .glb" 0 "2 assets: 2 exported" -- \
    "$bin" export "$gold" "$lib/duck/Duck.gltf" -o "$tmp/mx" --format glb
check "... the document's output not rendered, the asset's rendered" test "$(summary "$tmp/mx/summary.json" \
    'sorted((x["input"].endswith(".mtlx"), x["object_ssim"] is None) for x in it)')" = "[(False, False), (True, True)]"
expect "... --resume: both resumed" 0 "2 assets: 0 exported, 2 resumed" -- \
    "$bin" export "$gold" "$lib/duck/Duck.gltf" -o "$tmp/mx" --format glb --resume

# Usage errors.
expect "many assets without --format" 1 "give -o DIR --format" -- "$bin" export "$lib" -o "$tmp/x"
expect "--format of another kind" 1 "expected mtlx, usda, gltf or glb" -- "$bin" export "$lib" -o "$tmp/x" --format obj
expect "many assets into one file" 1 "into a folder" -- "$bin" export "$lib" -o "$tmp/x.usda" --format usda
expect "--resume with one asset" 1 "go with many assets" -- "$bin" export "$lib/duck/Duck.gltf" -o "$tmp/d.usda" \
    --resume
expect "--to a .glb cannot hold" 1 "holds gltf materials only" -- "$bin" export "$lib" -o "$tmp/x" --format glb \
    --to openpbr
mkdir -p "$tmp/two"
cp "$lib/duck/"* "$tmp/two/" && "$bin" gltf spec2metal "$tmp/two/Duck.gltf" -o "$tmp/two/Duck.glb" >/dev/null 2>&1
refuses "Duck.gltf and Duck.glb into one Duck.usda" "would both be written to .*Duck.usda" "$tmp/two" -- \
    "$bin" export "$tmp/two" -o "$tmp/twoout" --format usda
refuses "an output folder inside an input folder" "lies inside the input folder" "$lib" -- \
    "$bin" export "$lib" -o "$lib/out" --format usda
finish
