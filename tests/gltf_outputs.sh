#!/usr/bin/env bash
# gltf_outputs.sh — what `matremap gltf` writes beside its output, and what it says (issue 26):
#   1. side files (buffers, copied and converted images) are named after the output, so two assets whose files
#      share names (every Sketchfab export's buffer is scene.bin) converted into one folder both stay valid (the
#      Khronos validator, 0 errors, on both; the first one's files unchanged; three.js in headless Chromium loads
#      both with their textures); an existing file in a side file's
#      way that the earlier output does not refer to is refused (exit 2, named, nothing written) unless
#      --replace-files; the same command run again replaces its own files;
#   2. metal2spec writes no empty KHR_materials_specular beside the spec-gloss extension (no MULTIPLE_EXTENSIONS
#      warning), and spec2metal does not carry one (an input holding `{}`, as earlier versions wrote) back;
#   3. the flagged texels are counted by reason, per material and in total, in text and in --json, as the
#      standalone `matremap metal2spec` counts them on the same textures.
# Needs node/npm (the validator, tests/node; three.js, scripts/viewers), Chromium and python3. Ends with
# "N passed, N failed".
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
build="${MR_BUILD:-$root/build}"
bin="$build/bin/matremap"
shared="${MR_SHARED:-$root/../shared}/assets"
node_dir=$root/tests/node
# shellcheck source=tests/lib/cli_harness.sh
source "$(dirname "$0")/lib/cli_harness.sh"

floppy_dir="$shared/specgloss/FloppyDisk-sketchfab"
duck_dir="$shared/specgloss/Duck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness"
bottle="$shared/metalrough/WaterBottle/glTF/WaterBottle.gltf"

if [ ! -f "$node_dir/node_modules/gltf-validator/package.json" ]; then
    (cd "$node_dir" && npm ci --no-audit --no-fund --loglevel=error) >"$tmp/npm.log" 2>&1 ||
        echo "      npm ci failed: $(tail -n 3 "$tmp/npm.log" | tr '\n' ' ')"
fi
# The validator's counts of file $1 ("errors=N warnings=N ..."), its messages in $tmp/validator.txt.
validate() {
    node "$node_dir/gltf_validate.js" --all "$1" >"$tmp/validator.txt" 2>&1
    head -n 1 "$tmp/validator.txt" | sed -nE 's/.* (errors=[0-9]+ warnings=[0-9]+).*/\1/p'
}
# A Python expression over the JSON `d` of file $1.
gltf() {
    python3 -c 'import json, sys
d = json.load(open(sys.argv[1]))
print(eval(sys.argv[2]))' "$1" "$2"
}
# The same over the last command's stdout (a --json summary).
summary() {
    python3 -c 'import json, sys
d = json.load(open(sys.argv[1]))
print(eval(sys.argv[2]))' "$tmp/out" "$1"
}

# ---- 1. side files named after the output; nothing else replaced ----------------------------------------------
# Two Sketchfab-style assets: the FloppyDisk (scene.gltf, scene.bin, textures/material_0_normal.png, ...) and the
# Duck renamed like one, its texture named like the FloppyDisk's normal map.
mkdir -p "$tmp/floppy" "$tmp/duck/textures" "$tmp/coll"
cp -r "$floppy_dir"/. "$tmp/floppy/"
cp "$duck_dir/Duck0.bin" "$tmp/duck/scene.bin"
cp "$duck_dir/DuckCM.png" "$tmp/duck/textures/material_0_normal.png"
sed -e 's/Duck0\.bin/scene.bin/' -e 's#DuckCM\.png#textures/material_0_normal.png#' "$duck_dir/Duck.gltf" \
    >"$tmp/duck/scene.gltf"
expect "FloppyDisk into coll/floppy.gltf" 0 "1 of 1 materials converted" -- "$bin" gltf spec2metal \
    "$tmp/floppy/scene.gltf" -o "$tmp/coll/floppy.gltf" --method weighted --core-only
check "... its side files are named after it" test \
    "$(gltf "$tmp/coll/floppy.gltf" '[b["uri"] for b in d["buffers"]] + [i["uri"] for i in d["images"]]')" = \
    "['floppy.bin', 'textures/floppy_material_0_normal.png', 'floppy_m0_basecolor.png', 'floppy_m0_metallicRoughness.png']"
before=$(cd "$tmp/coll" && find . -type f -print | LC_ALL=C sort | xargs md5sum)
expect "the Duck, its files named like the FloppyDisk's, into coll/duck.gltf" 0 "0 of 1 materials converted, 1 kept" \
    -- "$bin" gltf spec2metal "$tmp/duck/scene.gltf" -o "$tmp/coll/duck.gltf" --method weighted
check "... leaves every file of coll/floppy.gltf as it was" test \
    "$(cd "$tmp/coll" && find . -type f -print | LC_ALL=C sort | grep -v duck | xargs md5sum)" = "$before"
check "... and shares no side file with it" test \
    "$(gltf "$tmp/coll/duck.gltf" '[b["uri"] for b in d["buffers"]] + [i["uri"] for i in d["images"]]')" = \
    "['duck.bin', 'textures/duck_material_0_normal.png']"
for f in floppy duck; do
    check "validator: coll/$f.gltf: $(validate "$tmp/coll/$f.gltf")" grep -q " errors=0 " "$tmp/validator.txt"
done
# The normal map of the FloppyDisk is still its own (the Duck's texture went to another file).
check "coll/floppy.gltf's normal map is the FloppyDisk's" cmp -s "$floppy_dir/textures/material_0_normal.png" \
    "$tmp/coll/textures/floppy_material_0_normal.png"
# The client that opens them: three.js in headless Chromium (scripts/viewers/three_render.mjs) loads both assets of
# the one folder with every file found: the Duck shows its texture (yellow: red far above blue over the frame; a
# missing texture renders the factor's white), the FloppyDisk covers pixels.
viewers="$root/scripts/viewers"
if [ -x /usr/lib/chromium/chromium ]; then
    if [ ! -f "$viewers/node_modules/three/package.json" ]; then
        (cd "$viewers" && npm ci --no-audit --no-fund --loglevel=error) >"$tmp/npm_viewers.log" 2>&1 ||
            echo "      npm ci failed: $(tail -n 3 "$tmp/npm_viewers.log" | tr '\n' ' ')"
    fi
    python3 - "$tmp" "$shared/hdri/studio_small_03_1k.hdr" >"$tmp/three_jobs.json" <<'PY'
import json, sys
tmp, env = sys.argv[1], sys.argv[2]
view = {"azimuth": 30, "elevation": 20, "fov": 35, "margin": 1.05}
print(json.dumps({"chromium": "/usr/lib/chromium/chromium", "jobs": [
    {"three": "three", "gltf": f"{tmp}/coll/{name}.gltf", "env": env, "out": f"{tmp}/three_{name}.exr", "size": 96,
     "supersample": 1, "envMean": 0.5, "view": view} for name in ("floppy", "duck")]}))
PY
    check "three.js (headless Chromium) renders coll/floppy.gltf and coll/duck.gltf" \
        bash -c "node '$viewers/three_render.mjs' '$tmp/three_jobs.json' >'$tmp/three.log' 2>&1"
    mean() { oiiotool --stats "$1" 2>/dev/null | sed -nE 's/.*Stats Avg: ([^(]*).*/\1/p'; }
    check "... the Duck with its texture (red $(mean "$tmp/three_duck.exr" | cut -d' ' -f1) over blue $(mean \
        "$tmp/three_duck.exr" | cut -d' ' -f3), at least 5 times)" \
        awk -v m="$(mean "$tmp/three_duck.exr")" 'BEGIN { split(m, c, " "); exit !(c[1] > 5 * c[3] && c[1] > 0.01) }'
    check "... the FloppyDisk on the frame (coverage $(mean "$tmp/three_floppy.exr" | cut -d' ' -f4))" \
        awk -v m="$(mean "$tmp/three_floppy.exr")" 'BEGIN { split(m, c, " "); exit !(c[4] > 0.05) }'
else
    echo "   skipped the three.js check: /usr/lib/chromium/chromium is missing (scripts/install-deps.sh installs it)"
fi

# The same command again: it replaces its own side files (the existing output refers to them).
expect "the same conversion again into coll/floppy.gltf" 0 "1 of 1 materials converted" -- "$bin" gltf spec2metal \
    "$tmp/floppy/scene.gltf" -o "$tmp/coll/floppy.gltf" --method weighted --core-only
check "... the folder holds the same files" test \
    "$(cd "$tmp/coll" && find . -type f -print | LC_ALL=C sort | grep -v duck | xargs md5sum)" = "$before"
check "validator after the re-run: coll/floppy.gltf: $(validate "$tmp/coll/floppy.gltf")" \
    grep -q " errors=0 " "$tmp/validator.txt"
expect "metal2spec into a .glb beside them" 0 "" -- "$bin" gltf metal2spec "$tmp/coll/floppy.gltf" \
    -o "$tmp/coll/floppy_sg.glb"
expect "... and again (a .glb has no side files)" 0 "" -- "$bin" gltf metal2spec "$tmp/coll/floppy.gltf" \
    -o "$tmp/coll/floppy_sg.glb"

# A file in a side file's way that is not the earlier output's: refused (exit 2, named with the option that allows
# it), nothing written; with --replace-files, replaced.
mkdir -p "$tmp/own"
echo "not a buffer" >"$tmp/own/scene.bin"
refuses "an unrelated scene.bin where -o own/scene.gltf's buffer goes" \
    "buffer 0 would be written to '$tmp/own/scene.bin', which exists .*refusing to replace it \\(--replace-files" \
    "$tmp/own" -- "$bin" gltf spec2metal "$tmp/floppy/scene.gltf" -o "$tmp/own/scene.gltf" --method weighted
check "... the file is untouched" grep -qx "not a buffer" "$tmp/own/scene.bin"
expect "... and with --replace-files, replaced" 0 "1 of 1 materials converted" -- "$bin" gltf spec2metal \
    "$tmp/floppy/scene.gltf" -o "$tmp/own/scene.gltf" --method weighted --replace-files
check "... the buffer is the asset's now" cmp -s "$floppy_dir/scene.bin" "$tmp/own/scene.bin"
check "validator: own/scene.gltf: $(validate "$tmp/own/scene.gltf")" grep -q " errors=0 " "$tmp/validator.txt"
# A converted texture's name taken by another file: refused too, also when the output exists already (an earlier
# output that does not refer to the file grants nothing).
mkdir -p "$tmp/img"
echo "someone's picture" >"$tmp/img/x_m0_basecolor.png"
refuses "an unrelated file named like a converted texture" "image [0-9]+ would be written to '$tmp/img/x_m0_basecolor.png'" \
    "$tmp/img" -- "$bin" gltf spec2metal "$tmp/floppy/scene.gltf" -o "$tmp/img/x.gltf" --method weighted
cp "$tmp/coll/duck.gltf" "$tmp/img/x.gltf"
refuses "... also over an existing output that does not refer to it" "x_m0_basecolor.png" "$tmp/img" -- \
    "$bin" gltf spec2metal "$tmp/floppy/scene.gltf" -o "$tmp/img/x.gltf" --method weighted
expect "--replace-files is in --help" 0 "--replace-files" -- "$bin" gltf --help

# ---- 2. no empty KHR_materials_specular --------------------------------------------------------------------------
mkdir -p "$tmp/bottle" "$tmp/back" "$tmp/old" "$tmp/old_back"
expect "WaterBottle, metal2spec" 0 "1 of 1 materials converted" -- "$bin" gltf metal2spec "$bottle" \
    -o "$tmp/bottle/bottle.gltf"
check "metal2spec: no KHR_materials_specular (the input has none)" test \
    "$(gltf "$tmp/bottle/bottle.gltf" '(sorted(d["materials"][0]["extensions"]), d["extensionsUsed"])')" = \
    "(['KHR_materials_pbrSpecularGlossiness'], ['KHR_materials_pbrSpecularGlossiness'])"
check "validator: bottle.gltf: $(validate "$tmp/bottle/bottle.gltf"), no MULTIPLE_EXTENSIONS" \
    test "$(grep -c MULTIPLE_EXTENSIONS "$tmp/validator.txt")" = 0
expect "... and back (spec2metal --overwrite-metal-rough)" 0 "1 of 1 materials converted" -- "$bin" gltf \
    spec2metal "$tmp/bottle/bottle.gltf" -o "$tmp/back/back.gltf" --method weighted --overwrite-metal-rough \
    --core-only
check "the round trip carries no extension, empty or not" test \
    "$(gltf "$tmp/back/back.gltf" '([m.get("extensions") for m in d["materials"]], d.get("extensionsUsed"))')" = \
    "([None], None)"
# An input holding the empty object earlier versions wrote: not carried into the converted material.
python3 - "$tmp/bottle/bottle.gltf" "$tmp/old/bottle.gltf" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
d["materials"][0]["extensions"]["KHR_materials_specular"] = {}
d["extensionsUsed"].append("KHR_materials_specular")
json.dump(d, open(sys.argv[2], "w"), indent=1)
PY
cp "$tmp/bottle/"*.png "$tmp/bottle/"*.bin "$tmp/old/"
expect "spec2metal of an asset holding an empty KHR_materials_specular" 0 "1 of 1 materials converted" -- "$bin" \
    gltf spec2metal "$tmp/old/bottle.gltf" -o "$tmp/old_back/back.gltf" --method weighted --overwrite-metal-rough \
    --core-only
check "... drops it" test \
    "$(gltf "$tmp/old_back/back.gltf" '([m.get("extensions") for m in d["materials"]], d.get("extensionsUsed"))')" = \
    "([None], None)"
check "validator: the round trip: $(validate "$tmp/back/back.gltf")" grep -q " errors=0 warnings=0" "$tmp/validator.txt"

# ---- 3. flagged texels by reason, as the standalone converter counts them ----------------------------------------
# The Duck as metal-rough (its spec-gloss converted), then metal2spec: most of its yellow base colour needs a
# spec-gloss diffuse above 1 (glTF convention), clamped and flagged off-manifold.
mkdir -p "$tmp/mr" "$tmp/sg" "$tmp/maps"
expect "the Duck to metal-rough" 0 "1 of 1 materials converted" -- "$bin" gltf spec2metal "$duck_dir/Duck.gltf" \
    -o "$tmp/mr/duck.gltf" --method weighted --overwrite-metal-rough
base=$(gltf "$tmp/mr/duck.gltf" 'd["images"][d["textures"][d["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["index"]]["source"]]["uri"]')
mrt=$(gltf "$tmp/mr/duck.gltf" 'd["images"][d["textures"][d["materials"][0]["pbrMetallicRoughness"]["metallicRoughnessTexture"]["index"]]["source"]]["uri"]')
expect "the standalone metal2spec on its textures" 0 "" -- "$bin" metal2spec --basecolor "$tmp/mr/$base" \
    --metallic-roughness "$tmp/mr/$mrt" -o "$tmp/maps/duck" --json
standalone=$(summary '(d["flags"]["off_manifold"], d["flags"]["nonfinite_input"], d["flags"]["clamped_input"],
                       d["flags"]["method_failed"])')
expect "gltf metal2spec --json" 0 "" -- "$bin" gltf metal2spec "$tmp/mr/duck.gltf" -o "$tmp/sg/duck.gltf" --json
reasons='(f["off_manifold"], f["nonfinite_input"], f["clamped_input"], f["method_failed"])'
check "... the material's reasons are the standalone's $standalone" test \
    "$(summary "(lambda f: $reasons)(d[\"materials\"][0][\"flags\"])")" = "$standalone"
check "... and so are the totals" test "$(summary "(lambda f: $reasons)(d[\"flags\"])")" = "$standalone"
check "... off-manifold is named (> 0) and the reasons cover the flagged count" \
    test "$(summary '(d["flags"]["off_manifold"] > 0 and sum(d["flags"].values()) >= d["flagged"] > 0 and
                      d["flagged"] == d["materials"][0]["flagged"])')" = True
off=$(summary 'd["flags"]["off_manifold"]')
flagged=$(summary 'd["flagged"]')
mkdir -p "$tmp/sgt"
expect "gltf metal2spec, text: the material's line names the reason" 0 \
    "converted, 512x512 textures, $flagged texels flagged \\($off off-manifold \\(spec-gloss diffuse above 1, clamped\\), 0 non-finite input, 0 clamped input, 0 method failed\\)" \
    -- "$bin" gltf metal2spec "$tmp/mr/duck.gltf" -o "$tmp/sgt/duck.gltf"
check "... and the total line too" grep -qE \
    "^matremap gltf metal2spec: $flagged of 262144 texels flagged: $off off-manifold \\(spec-gloss diffuse above 1, clamped\\)" \
    "$tmp/out"

finish
