#!/usr/bin/env bash
# client_docs.sh — the documents `matremap export` writes, opened by three.js's own loaders (the smoke test of make
# evaluation-clients, docs/evaluation-clients.md): USDLoader in node (scripts/viewers/usd_materials.mjs) reads each
# material of a .usda with the values the layer holds (colour, metallic, roughness, ior) and the WaterBottle's three
# maps, and keeps its white specularColor (the metallic workflow's layer writes none: three.js would apply it);
# MaterialXLoader and USDLoader in headless Chromium (scripts/viewers/client_render.mjs, 32 x 32) render an
# open_pbr_surface and a UsdPreviewSurface material, the MaterialX log holding no error and only the two documented
# ignored inputs. Needs the npm packages of scripts/viewers (installed here with npm ci when missing, as
# gltf_outputs.sh and make evaluation-clients do) and, for the renders, Chromium; without the packages (npm ci
# failing) it says so and checks nothing. Ends with "N passed, N failed".
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
build="${MR_BUILD:-$root/build}"
bin="$build/bin/matremap"
shared="${MR_SHARED:-$root/../shared}/assets"
viewers="$root/scripts/viewers"
source "$(dirname "$0")/lib/cli_harness.sh"

# The pinned npm packages, installed as gltf_outputs.sh installs them (npm ci: the lock file's versions).
if [ ! -f "$viewers/node_modules/three/examples/jsm/loaders/USDLoader.js" ]; then
    (cd "$viewers" && npm ci --no-audit --no-fund --loglevel=error) >"$tmp/npm.log" 2>&1 ||
        echo "      npm ci failed: $(tail -n 3 "$tmp/npm.log" | tr '\n' ' ')"
fi
if [ ! -f "$viewers/node_modules/three/examples/jsm/loaders/USDLoader.js" ]; then
    echo "   skipped: $viewers/node_modules could not be installed (npm ci there, or make evaluation-clients)"
    finish
fi
cat >"$tmp/uniform.gltf" <<'EOF'
{"asset": {"version": "2.0"},
 "materials": [
  {"name": "Gold", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.77, 0.34, 1], "metallicFactor": 1.0,
   "roughnessFactor": 0.3}},
  {"name": "Red plastic", "pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.05, 0.04, 1], "metallicFactor": 0.0,
   "roughnessFactor": 0.5}}]}
EOF
expect "export the uniform materials to .usda" 0 "wrote" -- "$bin" export "$tmp/uniform.gltf" -o "$tmp/u.usda"
expect "export the WaterBottle to .usda" 0 "maps" -- "$bin" export \
    "$shared/metalrough/WaterBottle/glTF/WaterBottle.gltf" -o "$tmp/b/bottle.usda"
expect "USDLoader (node) reads both materials of u.usda" 0 "" -- node "$viewers/usd_materials.mjs" "$tmp/u.usda" Gold \
    Red_plastic
cp "$tmp/out" "$tmp/u.jsonl"
usd_values() { # the layer's constants against what three.js made of them
    python3 - "$tmp/u.usda" "$tmp/u.jsonl" <<'EOF'
import json, re, sys
text = open(sys.argv[1]).read()
for line in open(sys.argv[2]):
    got = json.loads(line)
    block = text[text.index('def Material "%s"' % got["name"]):]
    def value(name):
        v = re.search(r"inputs:%s = \(?([^)\n]+)" % name, block).group(1)
        return [float(x) for x in v.split(",")]
    assert got["type"] == "MeshPhysicalMaterial", got
    assert all(abs(a - b) < 1e-6 for a, b in zip(got["color"], value("diffuseColor"))), got
    for key, name in (("metalness", "metallic"), ("roughness", "roughness"), ("ior", "ior"),
                      ("clearcoat", "clearcoat"), ("clearcoatRoughness", "clearcoatRoughness")):
        assert abs(got[key] - value(name)[0]) < 1e-6, (key, got)
    # three.js does not read useSpecularWorkflow and would take a specularColor as its dielectric F0 tint
    # (docs/evaluation-clients.md): the metallic workflow's layer has none, so three.js keeps its white default.
    assert value("useSpecularWorkflow") == [0] and "inputs:specularColor" not in block.split("def Shader")[1], got
    assert got["specularColor"] == [1, 1, 1], got
EOF
}
check "... with the layer's values; no specularColor in the metallic workflow, three.js's white kept" usd_values
expect "USDLoader (node) reads the WaterBottle's base colour, metallic and roughness maps" 0 \
    '"maps":\["map","metalnessMap","roughnessMap"\]' -- node "$viewers/usd_materials.mjs" "$tmp/b/bottle.usda" \
    BottleMat
expect "usd_materials.mjs: a material the layer lacks" 2 "no material 'Nope'" -- node "$viewers/usd_materials.mjs" \
    "$tmp/u.usda" Nope

chromium_bin=/usr/lib/chromium/chromium
if [ -x "$chromium_bin" ]; then
    expect "export the uniform materials to .mtlx (open_pbr_surface)" 0 "wrote" -- "$bin" export "$tmp/uniform.gltf" \
        -o "$tmp/u.mtlx"
    python3 - "$tmp" "$shared/hdri/studio_small_03_1k.hdr" "$chromium_bin" >"$tmp/jobs.json" <<'EOF'
import json, math, sys
tmp, env, chromium = sys.argv[1:]
common = {"mesh": None, "fov": 35, "env": env, "envMean": 0.5, "envRotation": math.pi / 2, "flipRows": True,
          "size": 32, "supersample": 1}
print(json.dumps({"chromium": chromium, "jobs": [
    dict(common, format="mtlx", doc=tmp + "/u.mtlx", material="Gold", out=tmp + "/gold.exr"),
    dict(common, format="usda", doc=tmp + "/u.usda", material="Red_plastic", out=tmp + "/red.exr")]}))
EOF
    expect "three.js in headless Chromium renders an open_pbr_surface and a UsdPreviewSurface material" 0 "" -- \
        node "$viewers/client_render.mjs" "$tmp/jobs.json"
    cp "$tmp/out" "$tmp/done.jsonl"
    rendered() { # MaterialX's log; both spheres cover the frame's middle, gold is gold and red is red
        python3 - "$tmp/done.jsonl" <<'EOF'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
assert len(rows) == 2, rows
gold, red = rows
assert gold["report"]["material"] == "MeshPhysicalNodeMaterial" and gold["report"]["errors"] == [], gold
ignored = sorted(w.split('"')[1] for w in gold["report"]["warnings"])
assert ignored == ["base_diffuse_roughness", "coat_darkening"], gold["report"]["warnings"]
assert red["report"]["material"] == "MeshPhysicalMaterial" and red["report"]["warnings"] == [], red
EOF
    }
    check "... MaterialXLoader: no error, only base_diffuse_roughness and coat_darkening ignored" rendered
    mean() { oiiotool --stats "$1" 2>/dev/null | sed -nE 's/.*Stats Avg: ([^(]*).*/\1/p'; }
    check "... gold: red > blue, covered ($(mean "$tmp/gold.exr"))" \
        awk -v m="$(mean "$tmp/gold.exr")" 'BEGIN { split(m, c, " "); exit !(c[1] > 1.5 * c[3] && c[4] > 0.3) }'
    check "... red plastic: red > 3 x green ($(mean "$tmp/red.exr"))" \
        awk -v m="$(mean "$tmp/red.exr")" 'BEGIN { split(m, c, " "); exit !(c[1] > 3 * c[2] && c[4] > 0.3) }'
else
    echo "   skipped the Chromium check: $chromium_bin is missing (scripts/install-deps.sh installs it)"
fi
finish
