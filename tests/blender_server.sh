#!/usr/bin/env bash
# blender_server.sh — the Blender renderer server (data/renderers/blender_server.py, the renderer-server protocol
# v1) driven through one session by a small client (tests/lib/renderer_client.py, checks in
# tests/lib/blender_server_check.py): its ready line and caps; a cycles-principled and a lambert render at 64^2
# against `matremap render` of the same material (object SSIM and relative RMSE of full, diffuse and specular over
# the sphere's mask); full = diffuse + specular; alpha = the sphere's coverage (computed here) in every component;
# rows from the top; a moved and scaled scene, coloured and several lights; a .blend material made here (Diffuse +
# Glossy through Add) described with its inputs, rendered, changed by an input override and restored; every error
# answered on one line naming the value or file while the server keeps serving and writes nothing; EOF exits 0.
# Needs Blender (3.x; scripts/install-deps.sh) and /usr/bin/python3 with numpy; without Blender it says so and
# checks nothing. Ends with "N passed, N failed".
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
build="${MR_BUILD:-$root/build}"
bin="$build/bin/matremap"
blender="${MATREMAP_BLENDER:-blender}"
source "$(dirname "$0")/lib/cli_harness.sh"

if ! command -v "$blender" >/dev/null 2>&1; then
    echo "   skipped: '$blender' not found (scripts/install-deps.sh installs Blender)"
    finish
fi
python=/usr/bin/python3
[ -x "$python" ] || python=python3

# A tiny .blend: TinyMat = Diffuse BSDF (0.6,0.3,0.2; roughness 0) + Glossy BSDF (0.5 grey, GGX, roughness 0.3)
# through an Add Shader; NoOutput has nodes but no Material Output; Other does not use nodes.
expect "make a tiny .blend with blender -b" 0 "" -- "$blender" -b --factory-startup --python-exit-code 3 \
    --python-expr '
import bpy, sys
def material(name, output=True):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    m.use_fake_user = True
    nt = m.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    d = nt.nodes.new("ShaderNodeBsdfDiffuse")
    d.inputs["Color"].default_value = (0.6, 0.3, 0.2, 1.0)
    d.inputs["Roughness"].default_value = 0.0
    g = nt.nodes.new("ShaderNodeBsdfGlossy")
    g.distribution = "GGX"
    g.inputs["Color"].default_value = (0.5, 0.5, 0.5, 1.0)
    g.inputs["Roughness"].default_value = 0.3
    a = nt.nodes.new("ShaderNodeAddShader")
    nt.links.new(d.outputs[0], a.inputs[0])
    nt.links.new(g.outputs[0], a.inputs[1])
    if output:
        nt.links.new(a.outputs[0], nt.nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
material("TinyMat")
material("NoOutput", output=False)
bpy.data.materials.new("Other").use_fake_user = True
bpy.ops.wm.save_as_mainfile(filepath=sys.argv[-1])
' -- "$tmp/tiny.blend"

"$python" "$root/tests/lib/blender_server_check.py" "$bin" "$blender" "$root/data/renderers/blender_server.py" \
    "$tmp" "$tmp/tiny.blend" | tee "$tmp/checks"
line=$(grep -E '^checks: [0-9]+ passed, [0-9]+ failed$' "$tmp/checks")
if [ -z "$line" ]; then
    echo "FAIL  the checks did not finish (server log: $(tail -n 5 "$tmp/server.log" 2>/dev/null | tr '\n' ' '))"
    failed=$((failed + 1))
else
    passed=$((passed + $(echo "$line" | cut -d' ' -f2)))
    failed=$((failed + $(echo "$line" | cut -d' ' -f4)))
fi
finish
