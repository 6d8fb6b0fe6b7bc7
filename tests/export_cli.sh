#!/usr/bin/env bash
# export_cli.sh — `matremap export ASSET -o OUT.mtlx|OUT.usda [--to MODEL]` on the shared glTF assets
# (../shared/assets/MANIFEST.md): a textured metal-rough asset (WaterBottle: base colour, packed ORM) to .usda and to
# .mtlx --to gltf, the outputs re-read (the MaterialX one by python3's XML parser) and checked: the images written
# beside OUT are the asset's bytes, colour maps sRGB and data maps raw/linear, metallic from B and roughness from G;
# the wraps of TextureSettingsTest's samplers; a uniform asset copied to gltf_pbr exactly; --json; output folders
# made; textured materials to openpbr and standard-surface by the direct route (a small made asset: the converted
# maps written beside OUT, referred to by the document, equal to `convert --direct`'s to the last code value; holds;
# a refusal writing nothing); refusals (exit 2, the material named, nothing written); usage errors (exit 1); the
# remap route of uniform materials (the fit scene of remap's default, 64 x 64: about a second per material), its
# outcomes converged. MaterialX input: our own documents back to .usda (maps rebased) and .mtlx (copied: the same
# text), MaterialX's examples (tests/data/materialx) remapped with the lobes not carried named, refusals (an
# unsupported node, a textured standard_surface whose maps are missing: exit 2, nothing written), a textured .mtlx
# to openpbr by the direct route (maps equal to the glTF asset's own export, byte for byte); .gltf/.glb outputs
# from a glTF and from a .mtlx, checked by the Khronos glTF validator (tests/node, npm ci). Ends with "N passed, N
# failed".
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
build="${MR_BUILD:-$root/build}"
bin="$build/bin/matremap"
shared="${MR_SHARED:-$root/../shared}/assets"
source "$(dirname "$0")/lib/cli_harness.sh"

bottle_dir="$shared/metalrough/WaterBottle/glTF"
bottle="$bottle_dir/WaterBottle.gltf"
settings="$shared/metalrough/TextureSettingsTest/glTF/TextureSettingsTest.gltf"
cat >"$tmp/uniform.gltf" <<'EOF'
{"asset": {"version": "2.0"},
 "materials": [
  {"name": "Gold", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.77, 0.34, 1], "metallicFactor": 1.0,
   "roughnessFactor": 0.3}},
  {"name": "Red plastic", "pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.05, 0.04, 1], "metallicFactor": 0.0,
   "roughnessFactor": 0.5}}]}
EOF

# ---- a textured asset to USD -------------------------------------------------------------------------------------
expect "WaterBottle to .usda (usd-preview by default)" 0 "material 0 'BottleMat': maps" -- \
    "$bin" export "$bottle" -o "$tmp/u/bottle.usda"
usd="$tmp/u/bottle.usda"
check "... the folder made, the document and two images written" test -s "$usd" -a -s "$tmp/u/bottle_image0.png" \
    -a -s "$tmp/u/bottle_image1.png"
check "... the images are the asset's own bytes" cmp -s "$tmp/u/bottle_image0.png" \
    "$bottle_dir/WaterBottle_baseColor.png"
check "... the metallic-roughness image too" cmp -s "$tmp/u/bottle_image1.png" \
    "$bottle_dir/WaterBottle_occlusionRoughnessMetallic.png"
usd_check() { # python over the .usda text: every asset file exists beside it; the wiring
    python3 - "$usd" <<'EOF'
import os, re, sys
text = open(sys.argv[1]).read()
folder = os.path.dirname(sys.argv[1])
assert text.startswith("#usda 1.0")
for f in re.findall(r"asset inputs:file = @([^@]+)@", text):
    assert os.path.isfile(os.path.join(folder, f)), f
shaders = dict(re.findall(r'def Shader "(\w+)"\s*\{(.*?)\n        \}', text, re.S))
surface = shaders["Surface"]
assert 'info:id = "UsdPreviewSurface"' in surface
assert "int inputs:useSpecularWorkflow = 0" in surface
assert "inputs:diffuseColor.connect = </Materials/BottleMat/diffuseColor_texture.outputs:rgb>" in surface
assert "inputs:metallic.connect = </Materials/BottleMat/metallic_texture.outputs:b>" in surface
assert "inputs:roughness.connect = </Materials/BottleMat/roughness_texture.outputs:g>" in surface
assert 'sourceColorSpace = "sRGB"' in shaders["diffuseColor_texture"]
assert 'sourceColorSpace = "raw"' in shaders["metallic_texture"]
assert 'sourceColorSpace = "raw"' in shaders["roughness_texture"]
assert 'token inputs:varname = "st"' in shaders["uv0_reader"]
assert 'info:id = "UsdPrimvarReader_float2"' in shaders["uv0_reader"]
assert text.count("{") == text.count("}")
EOF
}
check "... re-read: UsdPreviewSurface wired to UsdUVTexture rgb/b/g, sRGB and raw, st" usd_check

# ---- the same asset to MaterialX gltf_pbr --------------------------------------------------------------------------
expect "WaterBottle to .mtlx --to gltf" 0 "wrote .*bottle.mtlx \(gltf, 1 material\)" -- \
    "$bin" export "$bottle" -o "$tmp/m/bottle.mtlx" --to gltf
mtlx_check() { # python's XML parser over the document
    python3 - "$tmp/m/bottle.mtlx" <<'EOF'
import os, sys, xml.etree.ElementTree as ET
root = ET.parse(sys.argv[1]).getroot()
folder = os.path.dirname(sys.argv[1])
assert root.tag == "materialx" and root.get("version") == "1.39" and root.get("colorspace") == "lin_rec709"
graph = root.find("nodegraph")
images = {n.get("name"): n for n in graph.findall("image")}
for n in images.values():
    f = n.find("input[@name='file']")
    assert os.path.isfile(os.path.join(folder, f.get("value")))
assert images["base_color_image"].find("input[@name='file']").get("colorspace") == "srgb_texture"
assert images["metallic_image"].find("input[@name='file']").get("colorspace") is None
assert images["roughness_image"].find("input[@name='file']").get("colorspace") is None
idx = {n.get("name"): n.find("input[@name='index']").get("value") for n in graph.findall("extract")}
assert idx == {"metallic_extract": "2", "roughness_extract": "1"}, idx
shader = root.find("gltf_pbr")
inputs = {i.get("name"): i for i in shader.findall("input")}
assert inputs["base_color"].get("output") == "base_color_out" and inputs["base_color"].get("nodegraph") == graph.get("name")
assert set(inputs) <= {"base_color", "metallic", "roughness", "specular", "specular_color", "ior"}
mat = root.find("surfacematerial")
assert mat.get("name") == "BottleMat" and mat.find("input").get("nodename") == shader.get("name")
EOF
}
check "... re-read by an XML parser: image nodes, colorspaces, extract B and G, gltf_pbr, surfacematerial" mtlx_check

# ---- samplers' wraps ---------------------------------------------------------------------------------------------
# (Its BackgroundMaterial is uniform: to usd-preview it would be remapped; gltf_pbr copies it. The USD wraps are
# checked by tests/test_doc.c.)
expect "TextureSettingsTest to .mtlx --to gltf: ten materials" 0 "wrote .*ts.mtlx \(gltf, 10 materials\)" -- "$bin" export "$settings" -o "$tmp/ts/ts.mtlx" --to gltf
check "... well-formed; MIRRORED_REPEAT, CLAMP_TO_EDGE, REPEAT as mirror, clamp, periodic" python3 -c "
import sys, xml.etree.ElementTree as ET
r = ET.parse(sys.argv[1]).getroot()
modes = {i.get('value') for i in r.iter('input') if i.get('name') in ('uaddressmode', 'vaddressmode')}
assert modes == {'periodic', 'clamp', 'mirror'}, modes
assert len(r.findall('surfacematerial')) == 10" "$tmp/ts/ts.mtlx"

# ---- a uniform asset: copy to gltf_pbr -----------------------------------------------------------------------------
expect "uniform asset to .mtlx --to gltf: copied" 0 "material 1 'Red plastic': copy" -- \
    "$bin" export "$tmp/uniform.gltf" -o "$tmp/c/uniform.mtlx" --to gltf
check "... the factors exactly, names made identifiers" python3 -c "
import sys, xml.etree.ElementTree as ET
r = ET.parse(sys.argv[1]).getroot()
s = {n.get('name'): {i.get('name'): i.get('value') for i in n} for n in r.findall('gltf_pbr')}
assert s['SR_Gold']['base_color'] == '1, 0.77, 0.34' and s['SR_Gold']['roughness'] == '0.3', s
assert s['SR_Red_plastic']['metallic'] == '0'
assert [m.get('name') for m in r.findall('surfacematerial')] == ['Gold', 'Red_plastic']" "$tmp/c/uniform.mtlx"
expect "--json" 0 "" -- "$bin" export "$tmp/uniform.gltf" -o "$tmp/c/j.mtlx" --to gltf --json
check "... the summary" python3 -c "
import json, sys
d = json.load(open(sys.argv[1]))
assert d['command'] == 'export' and d['format'] == 'mtlx' and d['target'] == 'gltf' and d['images'] == []
assert [(m['name'], m['route']) for m in d['materials']] == [('Gold', 'copy'), ('Red plastic', 'copy')]" "$tmp/out"

expect "uniform asset to .usda: remapped, the outcome printed" 0 "'Gold': remap \(converged, SSIM 1\.0000" -- \
    "$bin" export "$tmp/uniform.gltf" -o "$tmp/r/uniform.usda"
expect "uniform asset to .mtlx (openpbr): the plastic remapped and converged" 0 \
    "'Red plastic': remap \(converged, SSIM 0\.99[0-9]*" -- "$bin" export "$tmp/uniform.gltf" -o "$tmp/r/uniform.mtlx"

# ---- textured materials to openpbr and standard-surface: the direct route --------------------------------------
# A small textured asset (6 x 6 maps, clamped sampler) with a uniform material beside it; the maps are converted as
# `convert --direct` converts them (export's default tolerance is convert's, 6/255), in a 32 x 32 fit scene.
mkdir -p "$tmp/tex"
oiiotool --pattern fill:topleft=0.6,0.3,0.1:topright=0.1,0.4,0.6:bottomleft=0.3,0.3,0.3:bottomright=0.7,0.7,0.2 \
    6x6 3 -d uint8 -o "$tmp/tex/base.png" >/dev/null 2>&1
oiiotool --pattern fill:topleft=0,0.2,0:topright=0,0.8,0:bottomleft=0,0.4,1:bottomright=0,0.6,1 6x6 3 -d uint8 \
    -o "$tmp/tex/mr.png" >/dev/null 2>&1
cat >"$tmp/tex/tex.gltf" <<'EOF'
{"asset": {"version": "2.0"}, "images": [{"uri": "base.png"}, {"uri": "mr.png"}],
 "samplers": [{"wrapS": 33071, "wrapT": 33071}],
 "textures": [{"source": 0, "sampler": 0}, {"source": 1, "sampler": 0}],
 "materials": [{"name": "Tex", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
   "metallicRoughnessTexture": {"index": 1}}},
  {"name": "Red plastic", "pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.05, 0.04, 1], "metallicFactor": 0.0,
   "roughnessFactor": 0.5}}]}
EOF
check "the small textured asset is made" test -s "$tmp/tex/base.png" -a -s "$tmp/tex/mr.png"
expect "a textured material to openpbr: converted by the direct route, counted" 0 \
    "material 0 'Tex': direct \(6x6 = 36 texels, 36 distinct values at tolerance 0\.02353: 36 converged; 0 texels" \
    -- "$bin" export "$tmp/tex/tex.gltf" -o "$tmp/tex/out/doc.mtlx" --size 32
check "... the uniform one still remapped" grep -q "material 1 'Red plastic': remap (converged" "$tmp/out"
check "... the holds said" grep -q "^held: base_weight=1, .* (default for openpbr)" "$tmp/out"
check "... the converted maps written beside OUT, named after it, with the flag picture" test -s \
    "$tmp/tex/out/doc_Tex_base_color.png" -a -s "$tmp/tex/out/doc_Tex_base_metalness.png" -a -s \
    "$tmp/tex/out/doc_Tex_specular_roughness.png" -a -s "$tmp/tex/out/doc_Tex_flags.png"
check "... held parameters are constants: no map for them" test ! -e "$tmp/tex/out/doc_Tex_specular_ior.png"
mtlx_converted_check() { # the document refers to the maps: colour sRGB, data linear, clamped wraps; holds constant
    python3 - "$1" "$2" <<'EOF'
import os, sys, xml.etree.ElementTree as ET
path, prefix = sys.argv[1], sys.argv[2]
root = ET.parse(path).getroot()
folder = os.path.dirname(path)
images = {}
for image in root.iter("image"):
    inputs = {i.get("name"): i for i in image.findall("input")}
    f = inputs["file"]
    assert os.path.isfile(os.path.join(folder, f.get("value"))), f.get("value")
    assert inputs["uaddressmode"].get("value") == "clamp" and inputs["vaddressmode"].get("value") == "clamp"
    images[f.get("value")] = (image.get("type"), f.get("colorspace"))
assert images[prefix + "base_color.png"] == ("color3", "srgb_texture"), images
assert images[prefix + "base_metalness.png"] == ("float", None), images
assert images[prefix + "specular_roughness.png"] == ("float", None), images
surface = [n for n in root if n.get("name") == "SR_Tex"][0]
inputs = {i.get("name"): i for i in surface.findall("input")}
assert inputs["base_color"].get("nodegraph") == "NG_Tex", inputs["base_color"].attrib
assert inputs["specular_roughness"].get("output") == "specular_roughness_out"
assert inputs["specular_ior"].get("value") == "1.5", inputs["specular_ior"].attrib
EOF
}
check "... re-read: the surface's inputs come from the converted maps (sRGB colour, linear data)" \
    mtlx_converted_check "$tmp/tex/out/doc.mtlx" doc_Tex_
expect "convert --direct on the same maps, with its defaults, in the same scene" 0 "" -- "$bin" convert --from gltf \
    --to openpbr base_color="$tmp/tex/base.png" metallic="$tmp/tex/mr.png:b" roughness="$tmp/tex/mr.png:g" --direct \
    --size 32 --format png -o "$tmp/tex/convert/"
for p in base_color base_metalness specular_roughness; do
    check "... $p: export's map equals convert --direct's, every code value" \
        cmp -s "$tmp/tex/out/doc_Tex_$p.png" "$tmp/tex/convert/$p.png"
done
expect "--to standard-surface: direct too" 0 "material 0 'Tex': direct \(6x6 = 36 texels" -- \
    "$bin" export "$tmp/tex/tex.gltf" -o "$tmp/tex/ss/doc.mtlx" --size 32 --to standard-surface
check "... standard_surface referring to the converted maps" grep -q \
    'value="doc_Tex_base_color.png" colorspace="srgb_texture"' "$tmp/tex/ss/doc.mtlx"
expect "--json: the route and the conversion's counts" 0 '"route": "direct", "width": 6, "height": 6, "texels": 36' \
    -- "$bin" export "$tmp/tex/tex.gltf" -o "$tmp/tex/j/doc.mtlx" --size 32 --json
check "... the maps listed, the holds too" grep -q '"maps": \[".*doc_Tex_base_color.png".*"held": \[' "$tmp/out"
expect "--hold: held by the direct route too" 0 "held: specular_roughness=0.4 \(--hold\)" -- \
    "$bin" export "$tmp/tex/tex.gltf" -o "$tmp/tex/h/doc.mtlx" --size 32 --hold specular_roughness=0.4
check "... a held parameter is a constant" grep -q '<input name="specular_roughness" type="float" value="0.4" />' \
    "$tmp/tex/h/doc.mtlx"
# Refusals: nothing written.
mkdir -p "$tmp/tex/refused"
sed 's/"metallicRoughnessTexture": {"index": 1}/"metallicRoughnessTexture": {"index": 1, "texCoord": 1}/' \
    "$tmp/tex/tex.gltf" >"$tmp/tex/uv1.gltf"
refuses "maps on different UV sets: refused, naming the material" \
    "material 0 \('Tex'\): baseColorTexture and metallicRoughnessTexture differ in UV set or wrap mode" \
    "$tmp/tex/refused" -- "$bin" export "$tmp/tex/uv1.gltf" -o "$tmp/tex/refused/doc.mtlx" --size 32
# The learned route: a small gltf -> openpbr transform (the default tie: base_metalness carried from metallic).
expect "a small gltf -> openpbr sweep and transform" 0 "" -- bash -c "'$bin' sweep --from gltf --to openpbr \
    --grid roughness=0.2:0.8:3 metallic=0:1:2 base_color=0.1:0.8:3 --size 16 -o '$tmp/tex/small.csv' && \
    '$bin' learn '$tmp/tex/small.csv' --method svr -o '$tmp/tex/mrt/small.mrt'"
expect "--transforms FILE: the learned route, counted" 0 \
    "material 0 'Tex': learned \(1 transform, 6x6 = 36 texels: [0-9]+ extrapolated, 0 by a transform that failed" \
    -- "$bin" export "$tmp/tex/tex.gltf" -o "$tmp/tex/l/doc.mtlx" --transforms "$tmp/tex/mrt/small.mrt" --size 16
expect "convert --transform on the same maps" 0 "" -- "$bin" convert --from gltf --to openpbr \
    base_color="$tmp/tex/base.png" metallic="$tmp/tex/mr.png:b" roughness="$tmp/tex/mr.png:g" \
    --transform "$tmp/tex/mrt/small.mrt" --format png -o "$tmp/tex/lconvert/"
for p in base_color base_metalness specular_roughness; do
    check "... $p: export's learned map equals convert's" cmp -s "$tmp/tex/l/doc_Tex_$p.png" "$tmp/tex/lconvert/$p.png"
done
expect "--transforms DIR: the chain found there" 0 "'Tex': learned \(1 transform" -- \
    "$bin" export "$tmp/tex/tex.gltf" -o "$tmp/tex/l2/doc.mtlx" --transforms "$tmp/tex/mrt" --size 16
refuses "--transforms DIR without a transform: refused, nothing written" "no \*.mrt files there" "$tmp/tex/refused" -- \
    "$bin" export "$tmp/tex/tex.gltf" -o "$tmp/tex/refused/doc.mtlx" --transforms "$tmp/tex/refused"
sed 's/"name": "Red plastic"/"name": "Tex"/; s/"roughnessFactor": 0.5}}]}/"roughnessFactor": 0.5}}, {"name": "Tex", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicRoughnessTexture": {"index": 1}}}]}/' \
    "$tmp/tex/tex.gltf" >"$tmp/tex/dup.gltf"
expect "two textured materials of one name: their maps named apart" 0 "wrote .*dup_Tex_2_base_color.png" -- \
    "$bin" export "$tmp/tex/dup.gltf" -o "$tmp/tex/d/dup.mtlx" --size 16
check "... the first keeps its name" test -s "$tmp/tex/d/dup_Tex_base_color.png"
oiiotool --pattern constant:color=0,0.5,0.5 4x4 3 -d uint8 -o "$tmp/tex/mr4.png" >/dev/null 2>&1
sed 's/"uri": "mr.png"/"uri": "mr4.png"/' "$tmp/tex/tex.gltf" >"$tmp/tex/size.gltf"
refuses "maps of different sizes: refused, naming the material and the sizes" \
    "material 0 \('Tex'\): .*map 'metallic' is 4x4 but map 'base_color' is 6x6" "$tmp/tex/refused" -- \
    "$bin" export "$tmp/tex/size.gltf" -o "$tmp/tex/refused/doc.mtlx" --size 16
expect "--direct and --transforms together" 1 "give --direct or --transforms, not both" -- \
    "$bin" export "$tmp/tex/tex.gltf" -o "$tmp/tex/refused/doc.mtlx" --direct --transforms x.mrt

# ---- refusals ----------------------------------------------------------------------------------------------------
mkdir -p "$tmp/refused"
# An image named after OUT that is the asset's own file: refused before anything is written.
mkdir -p "$tmp/own"
cp "$bottle_dir/WaterBottle_baseColor.png" "$tmp/own/doc_image0.png"
cat >"$tmp/own/own.gltf" <<'EOF'
{"asset": {"version": "2.0"}, "images": [{"uri": "doc_image0.png"}], "textures": [{"source": 0}],
 "materials": [{"name": "Own", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]}
EOF
refuses "an image output that is a file of the asset" "doc_image0.png" "$tmp/own" -- \
    "$bin" export "$tmp/own/own.gltf" -o "$tmp/own/doc.usda"
expect "usd-preview is not written to .mtlx" 1 "--to usd-preview: .mtlx does not write it" -- \
    "$bin" export "$bottle" -o "$tmp/refused/b.mtlx" --to usd-preview
expect "openpbr is not written to .usda" 1 "--to openpbr: .usda does not write it" -- \
    "$bin" export "$bottle" -o "$tmp/refused/b.usda" --to openpbr
expect "an unknown model" 1 "--to 'nope'" -- "$bin" export "$bottle" -o "$tmp/refused/b.usda" --to nope
expect "another extension" 1 "the extension chooses the format: .mtlx, .usda, .gltf or .glb" -- \
    "$bin" export "$bottle" -o "$tmp/refused/b.usd"
expect "another input" 1 "the input is a glTF asset \\(.gltf or .glb\\) or a MaterialX document \\(.mtlx\\)" -- \
    "$bin" export "$tmp/u/bottle.usda" -o "$tmp/refused/b.mtlx"
expect "a glTF output takes --to gltf only" 1 "--to openpbr: a glTF output .* holds gltf materials only" -- \
    "$bin" export "$bottle" -o "$tmp/refused/b.glb" --to openpbr
expect "no -o" 1 "missing -o OUT" -- "$bin" export "$bottle"
check "... nothing written by the refusals" test -z "$(ls -A "$tmp/refused")"
# ---- MaterialX input ---------------------------------------------------------------------------------------------
# Our own gltf_pbr document of WaterBottle (maps through extract, the images beside it) read back: to .usda the maps
# are carried (gltf -> usd-preview), relative to the new folder; to .mtlx --to gltf copied, the same text.
expect "bottle.mtlx to .usda: maps carried" 0 "material 0 'BottleMat': maps" -- \
    "$bin" export "$tmp/m/bottle.mtlx" -o "$tmp/x/sub/bottle.usda"
usd_from_mtlx() {
    python3 - "$tmp/x/sub/bottle.usda" <<'PY'
import os, re, sys
text = open(sys.argv[1]).read()
folder = os.path.dirname(sys.argv[1])
files = re.findall(r"asset inputs:file = @([^@]+)@", text)
assert files and all(f.startswith("../../m/") for f in files), files
assert all(os.path.isfile(os.path.join(folder, f)) for f in files)
assert "inputs:metallic.connect = </Materials/BottleMat/metallic_texture.outputs:b>" in text
assert "inputs:roughness.connect = </Materials/BottleMat/roughness_texture.outputs:g>" in text
assert text.count('sourceColorSpace = "sRGB"') == 1 and text.count('sourceColorSpace = "raw"') == 2
PY
}
check "... the maps named from the new folder, wired as from the glTF" usd_from_mtlx
expect "bottle.mtlx to .mtlx --to gltf: copied" 0 "material 0 'BottleMat': copy" -- \
    "$bin" export "$tmp/m/bottle.mtlx" -o "$tmp/m/again.mtlx" --to gltf
check "... the same document" cmp -s "$tmp/m/bottle.mtlx" "$tmp/m/again.mtlx"
# MaterialX's own examples (tests/data/materialx): standard_surface gold to open_pbr_surface by a remap; the
# OpenPBR pearl to gltf_pbr, its subsurface and thin film reported as not carried (text and --json).
examples="$root/tests/data/materialx"
expect "standard_surface gold to .mtlx (openpbr): remapped" 0 "material 0 'Gold': remap \(" -- \
    "$bin" export "$examples/standard_surface_gold.mtlx" -o "$tmp/x/gold.mtlx"
check "... an open_pbr_surface, metallic" python3 -c "
import sys, xml.etree.ElementTree as ET
r = ET.parse(sys.argv[1]).getroot()
s = {i.get('name'): i.get('value') for i in r.find('open_pbr_surface')}
assert float(s['base_metalness']) > 0.9, s
assert r.find('surfacematerial').get('name') == 'Gold'" "$tmp/x/gold.mtlx"
expect "open_pbr pearl to .mtlx --to gltf: the lobes not carried are named" 0 \
    "'Pearl': remap \(.*\); not carried: subsurface_weight, subsurface_color, subsurface_radius_scale, thin_film_weight, thin_film_thickness, thin_film_ior" -- \
    "$bin" export "$examples/open_pbr_pearl.mtlx" -o "$tmp/x/pearl.mtlx" --to gltf
expect "... and with --json" 0 "" -- \
    "$bin" export "$examples/open_pbr_pearl.mtlx" -o "$tmp/x/pearl2.mtlx" --to gltf --json
check "... the list in the summary" python3 -c "
import json, sys
d = json.load(open(sys.argv[1]))
assert d['materials'][0]['not_carried'] == ['subsurface_weight', 'subsurface_color', 'subsurface_radius_scale',
    'thin_film_weight', 'thin_film_thickness', 'thin_film_ior'], d" "$tmp/out"
expect "open_pbr pearl to .mtlx (openpbr): copied, its extras kept" 0 "'Pearl': copy$" -- \
    "$bin" export "$examples/open_pbr_pearl.mtlx" -o "$tmp/x/pearl_op.mtlx"
check "... subsurface and thin film written unchanged" python3 -c "
import sys, xml.etree.ElementTree as ET
s = {i.get('name'): i.get('value') for i in ET.parse(sys.argv[1]).getroot().find('open_pbr_surface')}
assert s['subsurface_weight'] == '1' and s['thin_film_thickness'] == '0.42' and s['coat_ior'] == '1.68', s" \
    "$tmp/x/pearl_op.mtlx"
mkdir -p "$tmp/mrefused"
cp "$examples/gltf_pbr_boombox.mtlx" "$tmp/mrefused/"
refuses "an unsupported node: exit 2, file, line, material and node named" \
    "error: MaterialX '.*gltf_pbr_boombox.mtlx' line 3: material 'Material_boombox': node 'image_basecolor' is a gltf_colorimage, which export cannot follow" \
    "$tmp/mrefused" -- "$bin" export "$tmp/mrefused/gltf_pbr_boombox.mtlx" -o "$tmp/mrefused/out.usda"
refuses "a textured standard_surface to openpbr whose maps are missing: the map named, nothing written" \
    "material 'Tiled_Brass' \(standard-surface\) to openpbr by the direct route: map of specular_roughness: image '.*/Images/brass_roughness.jpg': cannot open" \
    "$tmp/mrefused" -- "$bin" export "$examples/standard_surface_brass_tiled.mtlx" -o "$tmp/mrefused/brass.mtlx"

# A textured .mtlx to openpbr by the direct route: the small asset (factors as scales) written as a gltf_pbr
# document, that document exported to openpbr from another folder; its converted maps equal the asset's own export's
# (tex/out/doc_*, the same tolerance and scene) byte for byte, named relative to OUT.
expect "the small asset as a gltf_pbr document (maps carried)" 0 "material 0 'Tex': maps" -- \
    "$bin" export "$tmp/tex/tex.gltf" -o "$tmp/tex/gl/gl.mtlx" --to gltf
expect "that document's textured material to openpbr: the direct route" 0 \
    "material 0 'Tex': direct \(6x6 = 36 texels, 36 distinct values at tolerance 0\.02353: 36 converged; 0 texels" \
    -- "$bin" export "$tmp/tex/gl/gl.mtlx" -o "$tmp/tex/glop/doc.mtlx" --size 32
for p in base_color base_metalness specular_roughness flags; do
    check "... $p: the .mtlx's converted map equals the glTF asset's" cmp -s "$tmp/tex/glop/doc_Tex_$p.png" \
        "$tmp/tex/out/doc_Tex_$p.png"
done
check "... the document refers to the maps beside it" grep -q 'value="doc_Tex_base_color.png"' "$tmp/tex/glop/doc.mtlx"
expect "that document through --transforms: the learned route" 0 "material 0 'Tex': learned \(1 transform" -- \
    "$bin" export "$tmp/tex/gl/gl.mtlx" -o "$tmp/tex/gll/doc.mtlx" --transforms "$tmp/tex/mrt/small.mrt" --size 16
for p in base_color base_metalness specular_roughness; do
    check "... $p: the .mtlx's learned map equals the glTF asset's" cmp -s "$tmp/tex/gll/doc_Tex_$p.png" \
        "$tmp/tex/l/doc_Tex_$p.png"
done
mkdir -p "$tmp/tex/glb"
refuses "a .mtlx's converted maps into a glTF output: refused before the work, nothing written" \
    "material 'Tex' \(openpbr\) converts its maps to gltf by the direct route, whose maps a glTF output cannot hold yet" \
    "$tmp/tex/glb" -- "$bin" export "$tmp/tex/glop/doc.mtlx" -o "$tmp/tex/glb/doc.glb"

# ---- glTF outputs ------------------------------------------------------------------------------------------------
validate() { # the Khronos validator (tests/node, pinned; installed with npm ci when missing): 0 errors
    [ -d "$root/tests/node/node_modules/gltf-validator" ] ||
        (cd "$root/tests/node" && npm ci --no-audit --no-fund >/dev/null 2>&1) || return 1
    node "$root/tests/node/gltf_validate.js" "$@"
}
expect "WaterBottle to .gltf: the asset itself" 0 "wrote .*g/bottle.gltf \(gltf, 1 material\)" -- \
    "$bin" export "$bottle" -o "$tmp/g/bottle.gltf"
check "... its mesh and textures kept" python3 -c "
import json, sys
d = json.load(open(sys.argv[1]))
assert d['meshes'] and len(d['textures']) == 4 and d['materials'][0]['name'] == 'BottleMat'" "$tmp/g/bottle.gltf"
check "... valid (Khronos validator)" validate "$tmp/g/bottle.gltf"
expect "WaterBottle to .glb" 0 "wrote .*g/bottle.glb \(gltf, 1 material\)" -- \
    "$bin" export "$bottle" -o "$tmp/g/bottle.glb"
check "... valid" validate "$tmp/g/bottle.glb"
expect "bottle.mtlx to .gltf: a glTF of the materials and their images" 0 \
    "wrote .*g/mtlx.gltf \(gltf, 1 material\)" -- "$bin" export "$tmp/m/bottle.mtlx" -o "$tmp/g/mtlx.gltf"
gltf_from_mtlx() {
    python3 - "$tmp/g/mtlx.gltf" <<'PY'
import json, os, sys
d = json.load(open(sys.argv[1]))
m = d['materials'][0]['pbrMetallicRoughness']
assert 'baseColorTexture' in m and 'metallicRoughnessTexture' in m and 'meshes' not in d, d
assert 'extensionsUsed' not in d, d   # specular 1, ior 1.5: the extensions' defaults, not written
for im in d['images']:
    assert os.path.isfile(os.path.join(os.path.dirname(sys.argv[1]), im['uri'])), im
PY
}
check "... base colour and metallic-roughness textures, the images beside it, no meshes" gltf_from_mtlx
check "... the base colour image is the asset's bytes" cmp -s "$tmp/g/mtlx_bottle_image0.png" \
    "$bottle_dir/WaterBottle_baseColor.png"
check "... valid (Khronos validator)" validate "$tmp/g/mtlx.gltf"
expect "standard_surface copper to .glb: remapped to gltf" 0 "'Copper': remap" -- \
    "$bin" export "$examples/standard_surface_copper.mtlx" -o "$tmp/g/copper.glb"
check "... valid" validate "$tmp/g/copper.glb"
expect "help export" 0 "usage: matremap export" -- "$bin" help export
finish
