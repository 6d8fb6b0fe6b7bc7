#!/usr/bin/env bash
# The node materials of issue 29 (docs/evaluation-renderers.md), a smoke test of make evaluation-renderers' Blender
# scripts: scripts/blender/make_node_materials.py rebuilds data/blender/node_materials.blend into a file that renders
# the same (oiiotool --diff on 16² Cycles renders of every material); scripts/blender/export_gltf.py exports them
# with Blender's glTF exporter and reads back what it wrote (nothing for a Glossy/Diffuse/Mix tree; roughness and
# metallic but no base colour for the ColorRamp-fed Principled); a missing material is refused naming the file's;
# scripts/blender/render_back.py renders a node material and an imported glTF as RGBA EXRs of the asked size.
# Runs only where Blender is installed (scripts/install-deps.sh --bench); otherwise it says so and counts nothing.
# Ends with "N passed, N failed".
set -u
. "$(dirname "$0")/lib/cli_harness.sh"
root="${MR_ROOT:-$(cd "$(dirname "$0")/.." && pwd)}"
blender="${MATREMAP_BLENDER:-blender}"
blend="$root/data/blender/node_materials.blend"
names="ConstantMixGlossy ControlPrincipled DiffuseGlossyAdd LayerWeightMix RampPrincipled TintedGlossyMetal"
if ! command -v "$blender" >/dev/null 2>&1; then
    echo "   skipped: '$blender' is not on PATH (scripts/install-deps.sh --bench installs it)"
    finish
fi
same_pixels() { oiiotool "$1" "$2" --diff >"$tmp/diff.txt" 2>&1 && grep -q PASS "$tmp/diff.txt"; }
run_blender() { "$blender" -b --factory-startup --python-exit-code 3 --python "$root/scripts/blender/$1" -- "${@:2}"; }

expect "make_node_materials rebuilds the file" 0 "wrote .*ConstantMixGlossy, ControlPrincipled, DiffuseGlossyAdd, LayerWeightMix" -- \
    run_blender make_node_materials.py -o "$tmp/again.blend"

expect "export_gltf exports every material" 0 "" -- run_blender export_gltf.py --blend "$blend" --out-dir "$tmp/exp"
grep '^{' "$tmp/out" >"$tmp/export.jsonl"
check "export_gltf: one line per material, sorted" \
    test "$(/usr/bin/python3 -c 'import json,sys; print(" ".join(json.loads(l)["material"] for l in sys.stdin))' \
        <"$tmp/export.jsonl")" = "$names"
pick() { /usr/bin/python3 -c "import json,sys
for l in sys.stdin:
    r = json.loads(l)
    if r['material'] == '$1': print(' '.join(json.dumps(x) for x in ($2,)))" <"$tmp/export.jsonl"; }
check "export_gltf: a Glossy BSDF alone is exported as nothing (the glTF defaults: a white rough metal)" \
    test "$(pick TintedGlossyMetal "r['written']['pbrMetallicRoughness'], r['values']['metallic']")" = "{} 1.0"
check "export_gltf: the ColorRamp-fed Principled keeps metallic and roughness, loses its base colour" \
    test "$(pick RampPrincipled "sorted(r['written']['pbrMetallicRoughness']), r['values']['base_color']")" \
        = '["metallicFactor", "roughnessFactor"] [1.0, 1.0, 1.0]'
check "export_gltf: the .gltf files are there" test -s "$tmp/exp/LayerWeightMix/exporter.gltf"

expect "export_gltf refuses a material the file lacks, naming what it has" 2 \
    "no material 'Nope' in '.*node_materials.blend' \(it has: ConstantMixGlossy, ControlPrincipled, DiffuseGlossyAdd" -- \
    run_blender export_gltf.py --blend "$blend" --out-dir "$tmp/exp2" --materials Nope

# One Blender renders every material from both files, and the exporter's glTF through the importer.
/usr/bin/python3 - "$blend" "$tmp" $names >"$tmp/jobs.json" <<'PY'
import json, sys
blend, tmp, names = sys.argv[1], sys.argv[2], sys.argv[3:]
jobs = [{"output": "%s/%s-%s.exr" % (tmp, n, tag), "size": 16, "samples": 4, "seed": 0,
         "material": {"blend": b, "name": n}} for n in names for b, tag in ((blend, "a"), (tmp + "/again.blend", "b"))]
jobs.append({"output": tmp + "/gltf.exr", "size": 24, "samples": 4, "seed": 0, "rgb": True,
             "material": {"gltf": tmp + "/exp/TintedGlossyMetal/exporter.gltf"}})
print(json.dumps(jobs))
PY
expect "render_back renders .blend materials and an imported glTF" 0 "gltf.exr" -- \
    run_blender render_back.py --jobs "$tmp/jobs.json" --threads 1
for n in $names; do
    check "the rebuilt file renders $n the same" same_pixels "$tmp/$n-a.exr" "$tmp/$n-b.exr"
done
check "render_back: RGBA at 16², RGB at 24² when asked" \
    test "$(oiiotool --info "$tmp/LayerWeightMix-a.exr" "$tmp/gltf.exr" | grep -oE '[0-9]+ x +[0-9]+, [0-9] channel' |
        tr -s ' ' | paste -sd ';')" = "16 x 16, 4 channel;24 x 24, 3 channel"
check "render_back: the node material is lit (not black)" \
    test "$(oiiotool --stats "$tmp/LayerWeightMix-a.exr" | awk '/Stats Max/ { print ($3 > 0.05) }')" = 1
finish
