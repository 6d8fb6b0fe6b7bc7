#!/usr/bin/env bash
# `matremap report`: the folder it writes (index.html, every picture the page shows, summary.json with known
# answers: a material compared with itself has SSIM 1 and relative RMSE 0), environment views and map thumbnails,
# HTML escaping, its errors, and the page opened in headless Chromium (a screenshot that is not blank). Needs
# oiiotool, python3 and chromium (scripts/install-deps.sh). Ends with "N passed, N failed".
set -u
bin="${MR_BUILD:-build}/bin/matremap"
source "$(dirname "$0")/lib/cli_harness.sh"

# A Python expression over summary.json `d` of report folder $1.
summary() {
    python3 -c 'import json, re, sys; d = json.load(open(sys.argv[1] + "/summary.json")); print(eval(sys.argv[2]))' \
        "$1" "$2"
}
# Every src="..." of index.html names a file of the folder.
all_pictures_exist() {
    python3 - "$1" <<'PY'
import html.parser, os, sys, urllib.parse
folder = sys.argv[1]
class Pictures(html.parser.HTMLParser):
    def __init__(self):
        super().__init__(); self.sources = []
    def handle_starttag(self, tag, attrs):
        self.sources += [urllib.parse.unquote(v) for k, v in attrs if tag == "img" and k == "src"]
p = Pictures(); p.feed(open(os.path.join(folder, "index.html"), encoding="utf-8").read())
missing = [s for s in p.sources if not os.path.isfile(os.path.join(folder, s))]
print(len(p.sources), "pictures", "missing: " + ", ".join(missing) if missing else "")
sys.exit(1 if missing or not p.sources else 0)
PY
}

# ---- the fit scene: a material against itself and against another roughness --------------------------------------
expect "report --help" 0 "Usage: matremap report" -- "$bin" report --help
expect "three materials in the fit scene" 0 "report: $tmp/fit/index.html" -- "$bin" report -o "$tmp/fit" --size 64 \
    --title "GGX roughness" ggx alpha=0.2 f0=0.5 -- --label same ggx alpha=0.2 f0=0.5 -- --label rougher ggx \
    alpha=0.4 f0=0.5
check "index.html and summary.json written" test -s "$tmp/fit/index.html" -a -s "$tmp/fit/summary.json"
check "every picture of the page exists" all_pictures_exist "$tmp/fit"
check "one view, named" test "$(summary "$tmp/fit" 'd["views"]')" = "['fit scene']"
check "a material against itself: SSIM 1, relative RMSE 0" test \
    "$(summary "$tmp/fit" '(d["materials"][1]["mean_ssim"], d["materials"][1]["mean_relative_rmse"])')" = "(1, 0)"
check "another roughness: SSIM below 0.999" test "$(summary "$tmp/fit" 'd["materials"][2]["mean_ssim"] < 0.999')" = True
check "itself over the object: SSIM 1, relative RMSE 0" test "$(summary "$tmp/fit" \
    '(d["materials"][1]["mean_object_ssim"], d["materials"][1]["mean_object_relative_rmse"])')" = "(1, 0)"
# The renders differ only on the sphere, so the object's SSIM is below the whole frame's, which counts the
# background's identical windows too; its relative RMSE (over the object's mean radiance) is above the frame's.
check "another roughness: object SSIM < whole-frame SSIM, object rel. RMSE > whole-frame" test "$(summary "$tmp/fit" \
    '(lambda m: m["mean_object_ssim"] < m["mean_ssim"] and m["object_ssim"][0] == m["mean_object_ssim"] and
      m["mean_object_relative_rmse"] > m["mean_relative_rmse"] > 0)(d["materials"][2])')" = True
check "the page's summary leads with the object's SSIM" python3 -c '
import re, sys
page = open(sys.argv[1], encoding="utf-8").read()
heads = re.findall(r"<th>([^<]*)</th>", page.split("<h2>Summary</h2>")[1].split("</tr>")[0])
sys.exit(0 if heads[:2] == ["object SSIM (mean)", "object rel. RMSE (mean)"] and
         "whole-frame SSIM (mean)" in heads else 1)' "$tmp/fit/index.html"
check "the printed table: object SSIM first, the whole frame beside it" grep -qE \
    "^material +object SSIM +object rel. RMSE +frame SSIM +frame rel. RMSE +render s$" "$tmp/out"
check "the reference carries no SSIM" test "$(summary "$tmp/fit" '"ssim" in d["materials"][0]')" = False
check "labels: given, or the model" test "$(summary "$tmp/fit" '[m["label"] for m in d["materials"]]')" = \
    "['ggx', 'same', 'rougher']"
check "the title is on the page" grep -q "<title>GGX roughness</title>" "$tmp/fit/index.html"

# ---- an environment seen from two directions, with maps ---------------------------------------------------------
oiiotool --pattern fill:top=1,0.9,0.8:bottom=0.1,0.1,0.2 64x32 3 -d float -o "$tmp/sky.exr"
oiiotool --pattern checker:width=8:height=8:color1=0.8,0.2,0.1:color2=0.1,0.3,0.8 64x64 3 -o "$tmp/albedo.png"
oiiotool --pattern constant:color=0.4,0.6,0.2 8x8 3 -d float -o "$tmp/mr.exr"
expect "two views under an environment, maps" 0 "" -- "$bin" report -o "$tmp/env" --size 64 --env "$tmp/sky.exr" \
    --rotations 2 --env-samples 256 --label "<b>&amp" gltf base_color=@"$tmp/albedo.png" metallic=@"$tmp/mr.exr":b \
    roughness=@"$tmp/mr.exr":g -- gltf base_color=0.5 metallic=0.2 roughness=0.6
check "two views, 180° apart" test "$(summary "$tmp/env" 'd["views"]')" = "['rotation 0°', 'rotation 180°']"
check "every picture of the page exists" all_pictures_exist "$tmp/env"
check "three map thumbnails for the textured material" test \
    "$(summary "$tmp/env" '[t["label"] for t in d["materials"][0]["thumbnails"]]')" = \
    "['base_color ($tmp/albedo.png)', 'metallic ($tmp/mr.exr, channel B)', 'roughness ($tmp/mr.exr, channel G)']"
check "a thumbnail is at most 128 pixels" test \
    "$(oiiotool --info "$tmp/env/map_material0_0.png" | grep -c '64 x   64')" = 1
check "the label is escaped in HTML" grep -q "&lt;b&gt;&amp;amp" "$tmp/env/index.html"
check "... and kept as it is in JSON" test "$(summary "$tmp/env" 'd["materials"][0]["label"]')" = "<b>&amp"

# ---- errors: usage (1), bad input (2), nothing half-written -------------------------------------------------------
expect "missing -o" 1 "missing -o DIR" -- "$bin" report ggx
expect "no material" 1 "missing the reference MODEL" -- "$bin" report -o "$tmp/e1"
expect "'--' without a model" 1 "without a MODEL" -- "$bin" report -o "$tmp/e2" ggx --
expect "--rotations without --env" 1 "needs --env" -- "$bin" report -o "$tmp/e3" --rotations 3 ggx
expect "--env-reflection-samples without --env" 1 "need --env" -- "$bin" report -o "$tmp/e3" --env-reflection-samples 8 ggx
expect "--reflection-samples is renamed" 1 "is now --env-reflection-samples" -- "$bin" report -o "$tmp/e3" --reflection-samples 8 ggx
expect "--from is renamed" 1 "is now --camera-direction" -- "$bin" report -o "$tmp/e3" --from 0,0,1 ggx
expect "an unknown model" 2 "frobnicate" -- "$bin" report -o "$tmp/e4" frobnicate
expect "a missing map is named" 2 "nomap.png" -- "$bin" report -o "$tmp/e5" ggx diffuse=@"$tmp/nomap.png"
expect "a missing environment is named" 2 "nosky.hdr" -- "$bin" report -o "$tmp/e6" --env "$tmp/nosky.hdr" ggx
oiiotool --pattern constant:color=nan,nan,nan 1x1 3 -d float --pattern constant:color=0.2,0.2,0.2 16x8 3 -d float \
    --paste +3+5 -o "$tmp/nan_env.exr"
expect "an environment with a NaN is named, with the pixel" 2 \
    "environment map '$tmp/nan_env.exr': pixel \(3, 5\), channel 0 holds nan" -- "$bin" report -o "$tmp/e10" --size 32 \
    --env "$tmp/nan_env.exr" ggx
check "no folder after a failure" test ! -e "$tmp/e4" -a ! -e "$tmp/e5" -a ! -e "$tmp/e6" -a ! -e "$tmp/e10"
touch "$tmp/afile"
expect "-o naming a file" 2 "not a folder" -- "$bin" report -o "$tmp/afile" ggx

# ---- the folder is an output as a whole: written beside it, renamed in, or nothing ---------------------------------
mkdir -p "$tmp/rep"
expect "a report to replace" 0 "report: $tmp/rep/r/index.html" -- "$bin" report -o "$tmp/rep/r" --size 32 ggx \
    alpha=0.2 -- ggx alpha=0.4 -- ggx alpha=0.6
expect "... replaced by one with fewer materials" 0 "report:" -- "$bin" report -o "$tmp/rep/r/" --size 32 ggx \
    alpha=0.2 -- ggx alpha=0.3
check "... which leaves none of the old pictures" test ! -e "$tmp/rep/r/view0_material2.png" -a \
    -s "$tmp/rep/r/view0_material1.png"
check "... and no scratch folder beside it" test "$(ls -A "$tmp/rep")" = r
ln -s r/view0_material1.png "$tmp/rep/link.png"
refuses "an input inside the folder is refused (replacing the folder would delete it)" \
    "output folder '$tmp/rep/r' holds the input base_color=@$tmp/rep/r/view0_material0.png; refusing to replace it" \
    "$tmp/rep" -- "$bin" report -o "$tmp/rep/r" --size 32 gltf base_color=@"$tmp/rep/r/view0_material0.png"
refuses "... also through a symbolic link" "holds the input roughness=@$tmp/rep/link.png:g" "$tmp/rep" -- \
    "$bin" report -o "$tmp/rep/r" --size 32 gltf roughness=@"$tmp/rep/link.png":g
echo mine >"$tmp/rep/r/notes.txt"
refuses "a folder holding what no report writes is refused, untouched" \
    "report folder '$tmp/rep/r' holds 'notes.txt', which no report writes" "$tmp/rep" -- \
    "$bin" report -o "$tmp/rep/r" --size 32 ggx alpha=0.2
rm "$tmp/rep/r/notes.txt" "$tmp/rep/link.png"
# A write failing midway (a file-size limit, as a full disk would) leaves the previous report as it was, every file.
refuses "a write failing midway leaves the previous report" \
    "report '$tmp/rep/r' not written \(a previous report there is left as it was\): .*'$tmp/rep/r/view" "$tmp/rep" -- \
    bash -c 'trap "" XFSZ; ulimit -f 8; exec "$@"' _ "$bin" report -o "$tmp/rep/r" --size 512 ggx alpha=0.2 -- \
    ggx alpha=0.5
expect "... and a new folder is not made at all" 2 "not written" -- bash -c 'trap "" XFSZ; ulimit -f 8; exec "$@"' _ \
    "$bin" report -o "$tmp/rep/new" --size 512 ggx alpha=0.2 -- ggx alpha=0.5
check "... nothing left of it" test "$(ls -A "$tmp/rep")" = r
# A real full disk: a 200 KiB tmpfs (needs root to mount; skipped otherwise). The first report fits, the second
# runs out of space midway (after several pictures): the first stays, byte for byte.
mkdir -p "$tmp/disk"
if [ "$(id -u)" = 0 ] && mount -t tmpfs -o size=200k tmpfs "$tmp/disk" 2>/dev/null; then
    trap 'umount "$tmp/disk" 2>/dev/null; rm -rf "$tmp"' EXIT
    expect "a report on a small disk" 0 "report:" -- "$bin" report -o "$tmp/disk/r" --size 32 ggx alpha=0.2 -- \
        ggx alpha=0.4
    refuses "a full disk midway leaves the previous report" "not written .*No space left on device" "$tmp/disk" -- \
        "$bin" report -o "$tmp/disk/r" --size 512 ggx alpha=0.2 -- ggx alpha=0.4 -- ggx alpha=0.6 -- ggx alpha=0.8
    umount "$tmp/disk"
else
    echo "skip  a full disk midway (mounting a tmpfs needs root)"
fi

# ---- glTF assets rendered as their meshes ------------------------------------------------------------------------
shared="${MR_SHARED:-$(cd "$(dirname "$0")/.." && pwd)/../shared}/assets"
duck="$shared/specgloss/Duck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Duck.gltf"
mkdir -p "$tmp/duck"
# The Duck and the truck carry metal-rough values of their own beside spec-gloss: converted only on request.
"$bin" gltf spec2metal "$duck" -o "$tmp/duck/duck.gltf" --method weighted --overwrite-metal-rough >/dev/null 2>&1
expect "glTF assets: the Duck, itself and converted" 0 "report: $tmp/gl/index.html" -- "$bin" report -o "$tmp/gl" \
    --size 96 --env "$tmp/sky.exr" --rotations 2 --env-samples 128 --label original "$duck" -- --label same "$duck" \
    -- --label weighted "$tmp/duck/duck.gltf"
check "an asset against itself: SSIM 1" test "$(summary "$tmp/gl" 'd["materials"][1]["mean_ssim"]')" = 1
check "the converted Duck: SSIM between 0.95 and 1" test \
    "$(summary "$tmp/gl" '0.95 < d["materials"][2]["mean_ssim"] < 1')" = True
check "the spec-gloss original is rendered with gltf-specgloss, the conversion with gltf" test \
    "$(summary "$tmp/gl" '[re.findall(r"[(](\S+) model[)]", m["description"]) for m in d["materials"]]')" = \
    "[['gltf-specgloss'], ['gltf-specgloss'], ['gltf']]"
check "every picture of the page exists" all_pictures_exist "$tmp/gl"
# The mesh is in the picture: the object covers a good part of the frame.
covered=$(oiiotool "$tmp/gl/view0_material0.png" --ch R,G,B --chsum --printstats 2>/dev/null |
    sed -nE 's/.*Stats Avg: ([0-9.e+-]+).*/\1/p')
check "the Duck is in the picture (mean luminance $covered > 0)" awk -v v="${covered:-0}" 'BEGIN { exit !(v > 0.01) }'
# An asset with geometry of its own (the Duck moved sideways by a tenth of its size) gets its own plan, and is
# compared over both objects' coverage: the moved parts count, so the object's SSIM is far below the frame's.
mkdir -p "$tmp/moved"
cp "$(dirname "$duck")"/Duck0.bin "$(dirname "$duck")"/DuckCM.png "$tmp/moved/"
python3 - "$duck" "$tmp/moved/duck.gltf" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
d["nodes"][0]["matrix"][12] += 0.15
json.dump(d, open(sys.argv[2], "w"))
PY
expect "an asset with other geometry" 0 "report: $tmp/moved/r/index.html" -- "$bin" report -o "$tmp/moved/r" \
    --size 64 --env "$tmp/sky.exr" --rotations 1 --env-samples 64 "$duck" -- "$tmp/moved/duck.gltf"
check "... is compared over both objects: object SSIM < whole-frame SSIM < 0.95" test "$(summary "$tmp/moved/r" \
    '(lambda m: m["mean_object_ssim"] < m["mean_ssim"] < 0.95)(d["materials"][1])')" = True
truck="$shared/specgloss/CesiumMilkTruck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/CesiumMilkTruck.gltf"
"$bin" gltf spec2metal "$truck" -o "$tmp/duck/truck.gltf" --method weighted --overwrite-metal-rough >/dev/null 2>&1
expect "a multi-material asset: the truck and its conversion" 0 "report: $tmp/truck/index.html" -- "$bin" report \
    -o "$tmp/truck" --size 96 --env "$tmp/sky.exr" --rotations 1 --env-samples 128 "$truck" -- "$tmp/duck/truck.gltf"
check "its four materials, each with its model" test "$(summary "$tmp/truck" \
    '[re.findall(r"(\w+) [(](\S+) model[)]", m["description"]) for m in d["materials"]]')" = "$(printf '%s' \
    "[[('truck', 'gltf-specgloss'), ('glass', 'gltf-specgloss'), ('window_trim', 'gltf-specgloss'), " \
    "('wheels', 'gltf-specgloss')], [('truck', 'gltf'), ('glass', 'gltf'), ('window_trim', 'gltf'), " \
    "('wheels', 'gltf')]]")"
check "the converted truck: SSIM between 0.95 and 1" test \
    "$(summary "$tmp/truck" '0.95 < d["materials"][1]["mean_ssim"] < 1')" = True
check "the page says how the light was sampled" test \
    "$(summary "$tmp/truck" '"128 fixed directions and 40 about each pixel" in d["scene"]')" = True
check "thumbnails name their material" test \
    "$(summary "$tmp/truck" '[t["label"].split(":")[0] for t in d["materials"][0]["thumbnails"]]')" = \
    "['truck', 'wheels']"
# A texture read through TEXCOORD_2 (the renderer reads sets 0 and 1): refused, naming the file, the map and the set.
mkdir -p "$tmp/uv2"
cp "$(dirname "$duck")"/Duck0.bin "$(dirname "$duck")"/DuckCM.png "$tmp/uv2/"
python3 - "$duck" "$tmp/uv2/duck.gltf" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
d["materials"][0]["extensions"]["KHR_materials_pbrSpecularGlossiness"]["diffuseTexture"]["texCoord"] = 2
json.dump(d, open(sys.argv[2], "w"))
PY
expect "a texture on TEXCOORD_2 is refused, naming the file" 2 "$tmp/uv2/duck.gltf.*TEXCOORD_2" -- "$bin" report \
    -o "$tmp/e7" --size 32 "$tmp/uv2/duck.gltf"
check "no folder after the refusal" test ! -e "$tmp/e7"
# Khronos' TextureSettingsTest: single-sided polygons seen from behind are culled and the samplers' REPEAT,
# CLAMP_TO_EDGE and MIRRORED_REPEAT modes are honoured exactly when no red failure mark shows and every box of the
# "Test" column is a green mark like its "Sample pass" neighbour (the Test column is a little smaller on screen;
# measured 0.92 of the sample's green; ignoring culling hides the single-sided row's mark: 0.86).
settings="$shared/metalrough/TextureSettingsTest/glTF/TextureSettingsTest.gltf"
"$bin" report -o "$tmp/settings" --size 384 --env "$shared/hdri/studio_small_03_1k.hdr" --rotations 1 \
    --env-samples 256 "$settings" \
    >/dev/null 2>&1 && oiiotool "$tmp/settings/view0_material0.png" -o "$tmp/settings.ppm" 2>/dev/null
read -r _ red _ test_green _ sample_green < <(python3 "$(dirname "$0")/lib/checker_columns.py" "$tmp/settings.ppm" \
    2>/dev/null || echo "red -1 test 0 sample 0")
check "TextureSettingsTest: no red failure mark (red pixels: $red)" test "$red" = 0
check "TextureSettingsTest: Test green $test_green ~ Sample green $sample_green" awk -v t="$test_green" \
    -v s="$sample_green" 'BEGIN { exit !(s > 500 && t > 0.89 * s && t < 1.05 * s) }'
check "TextureSettingsTest: its 10 materials rendered" test "$(summary "$tmp/settings" \
    're.search(r"(\d+) materials", d["materials"][0]["description"]).group(1)')" = 10
# Seen head-on (--from) under the fit scene's point light: the culled polygon casts no shadow either.
"$bin" report -o "$tmp/settings2" --size 384 --camera-direction 0,0,1 "$settings" >/dev/null 2>&1 &&
    oiiotool "$tmp/settings2/view0_material0.png" -o "$tmp/settings2.ppm" 2>/dev/null
read -r _ red _ test_green _ sample_green < <(python3 "$(dirname "$0")/lib/checker_columns.py" "$tmp/settings2.ppm" \
    2>/dev/null || echo "red -1 test 0 sample 0")
check "head-on, point light: no red mark ($red), Test green $test_green ~ Sample green $sample_green" awk \
    -v r="$red" -v t="$test_green" -v s="$sample_green" 'BEGIN { exit !(r == 0 && s > 500 && t > 0.95 * s) }'
expect "--camera-direction needs three numbers" 1 "expected three numbers" -- "$bin" report -o "$tmp/e9" \
    --camera-direction 1,2 "$settings"
expect "--camera-direction is for glTF assets" 1 "spheres use the fit camera" -- "$bin" report -o "$tmp/e9" \
    --camera-direction 0,0,1 ggx
# WaterBottle: normal, occlusion and emissive maps are read and shown beside the BRDF maps.
bottle="$shared/metalrough/WaterBottle/glTF/WaterBottle.gltf"
expect "an asset with normal, occlusion and emissive maps" 0 "report: $tmp/bottle/index.html" -- "$bin" report \
    -o "$tmp/bottle" --size 64 --env "$tmp/sky.exr" --rotations 1 --env-samples 64 "$bottle"
check "its surface maps have thumbnails" test "$(summary "$tmp/bottle" \
    '[t["label"] for t in d["materials"][0]["thumbnails"]][-3:]')" = \
    "['normal map', 'occlusion (channel R)', 'emissive map']"
expect "materials and assets are not mixed" 1 "not both" -- "$bin" report -o "$tmp/e8" "$duck" -- ggx

# ---- materials on an OBJ mesh (the paper's material-test sphere) under a turning map --------------------------------
sphere="${MR_SHARED:-../shared}/assets/paper/matsphere.obj"
expect "materials on matsphere.obj, 3 rotations, paper camera" 0 "report: $tmp/mesh/index.html" -- "$bin" report \
    -o "$tmp/mesh" --mesh "$sphere" --camera paper --env "$tmp/sky.exr" --rotations 3 --size 32 --env-samples 32 \
    --label source ward specular=0.2 alpha=0.1 -- --label same ward specular=0.2 alpha=0.1 -- --label ggx ggx \
    alpha=0.1 f0=0.2
check "three views, 120° apart" test "$(summary "$tmp/mesh" 'd["views"]')" = \
    "['rotation 0°', 'rotation 120°', 'rotation 240°']"
check "the same material on the mesh: object SSIM 1 in every view" test \
    "$(summary "$tmp/mesh" 'd["materials"][1]["object_ssim"]')" = "[1, 1, 1]"
check "another model: object SSIM below 1" test "$(summary "$tmp/mesh" 'd["materials"][2]["mean_object_ssim"] < 1')" \
    = True
check "the scene line names the mesh" test "$(summary "$tmp/mesh" '"matsphere.obj (55742 triangles)" in d["scene"]')" \
    = True
"$bin" report -o "$tmp/mesh2" --mesh "$sphere" --camera paper --env "$tmp/sky.exr" --rotations 3 --size 32 \
    --env-samples 32 --label source ward specular=0.2 alpha=0.1 -- --label same ward specular=0.2 alpha=0.1 -- \
    --label ggx ggx alpha=0.1 f0=0.2 >/dev/null 2>&1
figures='[(m["object_ssim"], m["object_relative_rmse"], m["ssim"]) for m in d["materials"][1:]]'
check "deterministic: a second run's figures are the same" test "$(summary "$tmp/mesh" "$figures")" = \
    "$(summary "$tmp/mesh2" "$figures")"
expect "a missing OBJ file is named" 2 "nosuch.obj" -- "$bin" report -o "$tmp/e9" --mesh "$tmp/nosuch.obj" \
    --env "$tmp/sky.exr" ward
expect "--mesh needs --env" 1 "--mesh needs --env" -- "$bin" report -o "$tmp/e10" --mesh "$sphere" ward
expect "--camera paper needs --mesh" 1 "--camera paper places the camera for --mesh" -- "$bin" report -o "$tmp/e11" \
    --env "$tmp/sky.exr" --camera paper ward
expect "--camera takes auto or paper" 1 "expected auto or paper" -- "$bin" report -o "$tmp/e12" --mesh "$sphere" \
    --env "$tmp/sky.exr" --camera side ward
check "nothing written for the refusals" test ! -e "$tmp/e9" -a ! -e "$tmp/e10"

# ---- the page in a browser --------------------------------------------------------------------------------------
browser=$(command -v chromium || command -v chromium-browser || true)
if [ -z "$browser" ]; then
    check "chromium is installed (scripts/install-deps.sh)" false
else
    timeout 120 "$browser" --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
        --disable-background-networking --disable-component-update --disable-sync --user-data-dir="$tmp/chromium" \
        --window-size=1200,1600 --screenshot="$tmp/shot.png" "file://$tmp/env/index.html" >"$tmp/browser.log" 2>&1
    check "Chromium renders the page to a screenshot" test -s "$tmp/shot.png"
    # Not blank: the page's pictures and text make the screenshot's values vary.
    deviation=$(oiiotool "$tmp/shot.png" --printstats 2>/dev/null | sed -nE 's/.*Stats StdDev: ([0-9.e+-]+).*/\1/p')
    check "the screenshot is not blank (standard deviation ${deviation:-none})" \
        awk -v d="${deviation:-0}" 'BEGIN { exit !(d > 0.05) }'
fi

finish
