#!/usr/bin/env bash
# renderers.sh — real renderers on either side of a remap (src/render/renderer.h, docs/renderers.md), through the
# CLI: the renderer options' errors (an unknown renderer, a model a renderer does not render, a Blender that is not
# there: exit 3 naming the package); Cycles' Principled through Blender against the built-in model of it (SSIM over
# the sphere >= 0.999: the two routes agree where they should); a remap whose source Blender renders, whose values
# match the built-in source's; a material of a .blend file (data/blender/node_materials.blend): its inputs listed,
# remapped to glTF, an input set on the command line changing the answer, and its errors (missing file, material,
# input); a sweep through Blender whose Blender processes are killed twice mid-run, finishing with every row of an
# undisturbed run (the seconds aside) and the restarts counted; a glTF fit through three.js. Needs Blender and
# three.js's packages (scripts/install-deps.sh installs both); without one, its part says so and checks nothing.
# Ends with "N passed, N failed".
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
bin="${MR_BUILD:-$root/build}/bin/matremap"
source "$(dirname "$0")/lib/cli_harness.sh"
blend="$root/data/blender/node_materials.blend"
json_field() { /usr/bin/python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))" "$@"; }

# ---- errors that need no renderer ----
expect "an unknown renderer: exit 1" 1 "unknown renderer 'nope' \(valid: builtin, blender, three\)" -- \
    "$bin" remap --from ggx --to ward --from-renderer nope
expect "a model the renderer does not render: exit 1" 1 "renderer 'three' does not render model 'ward'" -- \
    "$bin" remap --from ggx --to ward --to-renderer three
expect "--method materialx with a renderer: exit 1" 1 "go with --method fit" -- \
    "$bin" remap --from standard-surface --to gltf --method materialx --to-renderer three
expect "a Blender that is not there: exit 3 naming the package" 3 \
    "program '/nonexistent/blender' not found \(install Debian's blender package" -- \
    env MATREMAP_BLENDER=/nonexistent/blender "$bin" remap --from cycles-principled --from-renderer blender --to gltf
expect "render --renderer with --env: exit 1" 1 "renders the fit scene's sphere" -- \
    "$bin" render cycles-principled --renderer blender --env x.hdr -o "$tmp/x.exr"
expect "--list-inputs without a .blend material: exit 1" 1 "goes with --from blender:" -- \
    "$bin" remap --from ggx --list-inputs

# ---- Blender ----
if ! command -v "${MATREMAP_BLENDER:-blender}" >/dev/null; then
    echo "   skipped the Blender part: blender is missing (scripts/install-deps.sh installs it)"
else
    principled=(cycles-principled base_color=0.8,0.25,0.1 roughness=0.3 specular=0.5)
    expect "Cycles' Principled through Blender at 128^2" 0 "blender 3\." -- \
        "$bin" render "${principled[@]}" --renderer blender --samples 256 --size 128 -o "$tmp/cycles.exr" \
        --mask "$tmp/mask.exr"
    expect "... and through the built-in model" 0 "" -- "$bin" render "${principled[@]}" --size 128 -o "$tmp/ours.exr"
    expect "... compared over the sphere" 0 "" -- "$bin" ssim "$tmp/cycles.exr" "$tmp/ours.exr" --mask "$tmp/mask.exr"
    ssim=$(head -n 1 "$tmp/out")
    check "... SSIM >= 0.999 between the two routes ($ssim)" awk -v s="$ssim" 'BEGIN { exit !(s >= 0.999) }'

    expect "remap with the source rendered by Blender" 0 "" -- \
        "$bin" remap --from "${principled[@]}" --from-renderer blender --to gltf --json
    cp "$tmp/out" "$tmp/blender.json"
    expect "... and by the built-in model" 0 "" -- "$bin" remap --from "${principled[@]}" --to gltf --json
    cp "$tmp/out" "$tmp/builtin.json"
    check "... converged" [ "$(json_field "$tmp/blender.json" 'd["outcome"]')" = converged ]
    check "... the same glTF values within 3 % (base colour) and 0.02 (roughness)" /usr/bin/python3 - \
        "$tmp/blender.json" "$tmp/builtin.json" <<'EOF'
import json, sys
a, b = (json.load(open(p))["values"] for p in sys.argv[1:3])
ok = all(abs(x - y) <= 0.03 * max(y, 0.05) for x, y in zip(a["base_color"], b["base_color"]))
sys.exit(0 if ok and abs(a["roughness"] - b["roughness"]) <= 0.02 else 1)
EOF
    check "... the JSON names Blender as the source's renderer" \
        grep -q '"source": {"renderer": "blender 3\.' "$tmp/blender.json"

    if [ ! -f "$blend" ]; then
        echo "FAIL  $blend is missing (scripts/blender/make_node_materials.py makes it)"
        failed=$((failed + 1))
    else
        expect "--list-inputs of a .blend material" 0 "Diffuse BSDF\.Color" -- \
            "$bin" remap --from "blender:$blend:DiffuseGlossyAdd" --list-inputs
        expect "a .blend material remapped to glTF" 0 "" -- \
            "$bin" remap --from "blender:$blend:DiffuseGlossyAdd" --to gltf --json
        cp "$tmp/out" "$tmp/node.json"
        check "... converged (within 25 %: core glTF's 4 % dielectric cannot show its 8 % glossy lobe)" \
            /usr/bin/python3 -c '
import json, sys; d = json.load(open(sys.argv[1]))
sys.exit(0 if d["outcome"] == "converged" and d["relative_rmse"] < 0.25 else 1)' "$tmp/node.json"
        expect "... with KHR_materials_specular's colour freed and metallic held at 0" 0 "" -- \
            "$bin" remap --from "blender:$blend:DiffuseGlossyAdd" --to gltf --free specular_color --hold metallic=0 --json
        check "... within 2 %, the glossy colour 0.08 as specular_color 2 (0.08 / 0.04) and its roughness 0.25" \
            /usr/bin/python3 -c '
import json, sys; d = json.load(open(sys.argv[1])); v = d["values"]
ok = d["outcome"] == "converged" and d["relative_rmse"] < 0.02 and d["freed"] == ["specular_color"]
sys.exit(0 if ok and all(abs(c - 2) < 0.1 for c in v["specular_color"]) and abs(v["roughness"] - 0.25) < 0.01 else 1)' \
            "$tmp/out"
        expect "--free of a parameter the model fits already: exit 1" 1 "'gltf' fits roughness already" -- \
            "$bin" remap --from ggx --to gltf --free roughness
        check "... its inputs in the JSON" grep -q '"inputs": {.*"Diffuse BSDF.Color"' "$tmp/node.json"
        expect "... an input set on the command line" 0 "" -- \
            "$bin" remap --from "blender:$blend:DiffuseGlossyAdd" 'Diffuse BSDF.Color=0.05,0.1,0.7' --to gltf --json
        check "... turns the glTF base colour blue" /usr/bin/python3 -c '
import json, sys; c = json.load(open(sys.argv[1]))["values"]["base_color"]; sys.exit(0 if c[2] > 2 * c[0] else 1)' \
            "$tmp/out"
        expect "a .blend file that is not there: exit 2" 2 "cannot open '$tmp/none.blend'" -- \
            "$bin" remap --from "blender:$tmp/none.blend:X" --to gltf
        expect "a material that is not in the file: exit 2, listing those that are" 2 \
            "no material 'Nope' in .*DiffuseGlossyAdd" -- "$bin" remap --from "blender:$blend:Nope" --to gltf
        expect "an input the material does not have: exit 2, listing those it has" 2 \
            "has no input 'Nope.Fac' \(it has .*Diffuse BSDF.Color" -- \
            "$bin" remap --from "blender:$blend:DiffuseGlossyAdd" 'Nope.Fac=1' --to gltf
    fi

    # A see-through material: refused by name, not blamed on the framing.
    "${MATREMAP_BLENDER:-blender}" -b --factory-startup --python-expr "
import bpy
m = bpy.data.materials.new('Glass30'); m.use_nodes = True; m.use_fake_user = True; nt = m.node_tree
d = nt.nodes['Principled BSDF']; t = nt.nodes.new('ShaderNodeBsdfTransparent'); x = nt.nodes.new('ShaderNodeMixShader')
x.inputs[0].default_value = 0.3; nt.links.new(d.outputs[0], x.inputs[1]); nt.links.new(t.outputs[0], x.inputs[2])
nt.links.new(x.outputs[0], nt.nodes['Material Output'].inputs['Surface'])
bpy.ops.wm.save_as_mainfile(filepath='$tmp/glass.blend')" >/dev/null 2>&1
    expect "a material that is not opaque: exit 2, saying so" 2 "the material is not opaque: its alpha inside the sphere is 0\.7" \
        -- "$bin" remap --from "blender:$tmp/glass.blend:Glass30" --to gltf

    # A sweep through Blender, its Blender processes killed twice mid-run: every row of an undisturbed run.
    args=(--from cycles-principled --to gltf --random 16 --seed 5 --from-renderer blender --threads 2)
    expect "a sweep with Blender rendering its sources" 0 "" -- "$bin" sweep "${args[@]}" -o "$tmp/ref.csv"
    "$bin" sweep "${args[@]}" -o "$tmp/killed.csv" --json >"$tmp/killed.json" 2>"$tmp/killed.err" &
    sweep=$!
    kills=0
    for delay in 1.5 1.0; do
        sleep "$delay"
        victims=$(pgrep -P "$sweep" -f blender_server.py | head -n 1)
        [ -n "$victims" ] && kill -KILL $victims 2>/dev/null && kills=$((kills + 1))
    done
    wait "$sweep"
    rc=$?
    echo "   killed a Blender process $kills times"
    check "... killed mid-run, the sweep still succeeds (exit $rc)" [ "$rc" -eq 0 ]
    check "... the kills landed" [ "$kills" -ge 1 ]
    check "... every row of the undisturbed run, the seconds aside" \
        cmp -s <(grep -v '^#' "$tmp/ref.csv" | rev | cut -d, -f2- | rev) \
        <(grep -v '^#' "$tmp/killed.csv" | rev | cut -d, -f2- | rev)
    check "... the restarts counted (more process starts than threads)" \
        [ "$(json_field "$tmp/killed.json" 'd["renderers"]["process_starts"]')" -gt 2 ]
fi

# ---- three.js ----
if [ ! -f "$root/data/renderers/three/node_modules/three/package.json" ] || [ ! -x "${MATREMAP_CHROMIUM:-/usr/bin/chromium}" ]; then
    echo "   skipped the three.js part: its npm packages or chromium are missing (scripts/install-deps.sh)"
else
    expect "a glTF fit through three.js" 0 "" -- \
        "$bin" remap --from gltf base_color=0.7,0.3,0.2 metallic=0 roughness=0.5 --to gltf --to-renderer three --json
    check "... converged with the source's values within 2 % (three.js shades a rough dielectric as glTF does)" \
        /usr/bin/python3 -c '
import json, sys; d = json.load(open(sys.argv[1])); v = d["values"]
ok = d["outcome"] == "converged" and all(abs(a - b) <= 0.02 * b for a, b in zip(v["base_color"], [0.7, 0.3, 0.2]))
sys.exit(0 if ok and abs(v["roughness"] - 0.5) <= 0.02 and d["renders"] < 200 else 1)' "$tmp/out"
    check "... the JSON names three.js as the target's renderer" grep -q '"target": {"renderer": "three 0\.' "$tmp/out"
    expect "a rough glTF metal through three.js" 0 "" -- \
        "$bin" remap --from gltf base_color=0.9,0.6,0.3 metallic=1 roughness=0.7 --to gltf --to-renderer three --json
    check "... a darker base colour than the source's: three.js adds multiple scattering to a metal's highlight" \
        /usr/bin/python3 -c '
import json, sys; v = json.load(open(sys.argv[1]))["values"]["base_color"]; sys.exit(0 if v[0] < 0.88 else 1)' "$tmp/out"
fi
finish
