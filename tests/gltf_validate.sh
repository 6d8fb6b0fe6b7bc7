#!/usr/bin/env bash
# gltf_validate.sh — the glTF shim's output against the Khronos glTF validator and against its input's JSON.
#
#   1. build/tests/test_gltf round-trips every asset of $MR_SHARED/assets (specgloss/*, metalrough/*) through
#      mr_gltf_load -> mr_gltf_save as .gltf and .glb (MR_GLTF_KEEP keeps the copies), and a generated
#      "kitchen sink" (tests/lib/gltf_kitchen_sink.py: extras and extensions everywhere, lights, camera, skin,
#      animation, morph target, sparse accessor, named sampler, data URIs) as .gltf and .glb; and keeps the edited
#      FloppyDisk of test_gltf's drop_spec_gloss_set_metal_rough_add_texture case.
#   2. The Khronos validator (npm gltf-validator, pinned in tests/node/package-lock.json; tests/node/
#      gltf_validate.js, external resources resolved) must report 0 errors on every copy.
#   3. Each .gltf copy's JSON must equal its original's (tests/lib/gltf_json_compare.py: key order, number
#      spelling and default-valued fields ignored; anything else that differs is printed and fails).
# Requirements: node, npm (tests/node/node_modules is installed with `npm ci` when gltf-validator is missing),
# python3, a built test_gltf (make check builds it). Anything missing is a failure, not a skip.
# Output: ok/FAIL lines, then "N passed, N failed" as the last line; exit status 1 on any failure.
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
build=${MR_BUILD:-$root/build}
shared=${MR_SHARED:-$root/../shared}
node_dir=$root/tests/node
# shellcheck source=tests/lib/cli_harness.sh
. "$root/tests/lib/cli_harness.sh"

missing=""
for tool in node npm python3; do
    command -v "$tool" >/dev/null 2>&1 || missing="$missing $tool"
done
[ -x "$build/tests/test_gltf" ] || missing="$missing $build/tests/test_gltf (make check builds it)"
if [ -n "$missing" ]; then
    echo "FAIL  prerequisites: not found:$missing"
    failed=$((failed + 1))
    finish
fi
if [ ! -f "$node_dir/node_modules/gltf-validator/package.json" ]; then
    if ! (cd "$node_dir" && npm ci --no-audit --no-fund --loglevel=error >"$tmp/npm.log" 2>&1); then
        echo "FAIL  prerequisites: npm ci in tests/node failed: $(tail -n 3 "$tmp/npm.log" | tr '\n' ' ')"
        failed=$((failed + 1))
        finish
    fi
fi

# ---- round trips ------------------------------------------------------------------------------------------
mkdir -p "$tmp/keep"
expect "round trip of every asset (test_gltf)" 0 "1 passed, 0 failed" -- \
    env MR_SHARED="$shared" MR_GLTF_KEEP="$tmp/keep" "$build/tests/test_gltf" round_trip_every_asset
expect "edited FloppyDisk (SG dropped; MR, specular, ior, transforms, a new image) kept" 0 "1 passed, 0 failed" \
    -- env MR_SHARED="$shared" MR_GLTF_KEEP="$tmp/keep" "$build/tests/test_gltf" \
    drop_spec_gloss_set_metal_rough_add_texture
python3 "$root/tests/lib/gltf_kitchen_sink.py" "$tmp/sink.gltf"
mkdir -p "$tmp/keep/KitchenSink"
for ext in gltf glb; do
    expect "round trip of the kitchen sink as .$ext (test_gltf)" 0 "1 passed, 0 failed" -- \
        env MR_GLTF_IN="$tmp/sink.gltf" MR_GLTF_OUT="$tmp/keep/KitchenSink/KitchenSink.$ext" \
        "$build/tests/test_gltf" round_trip_file_from_env
done

declare -A original=(
    [Avocado]=specgloss/Avocado-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Avocado.gltf
    [CesiumMilkTruck]=specgloss/CesiumMilkTruck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/CesiumMilkTruck.gltf
    [Duck]=specgloss/Duck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Duck.gltf
    [FloppyDisk]=specgloss/FloppyDisk-sketchfab/scene.gltf
    [TextureSettingsTest]=metalrough/TextureSettingsTest/glTF/TextureSettingsTest.gltf
    [WaterBottle]=metalrough/WaterBottle/glTF/WaterBottle.gltf
)

# ---- the validator --------------------------------------------------------------------------------------------
for name in $(printf '%s\n' "${!original[@]}" | sort) KitchenSink Edited; do
    for ext in gltf glb; do
        copy=$tmp/keep/$name/$name.$ext
        [ "$ext" = glb ] && [ ! -f "$copy" ] && continue
        expect "validator: $name.$ext has 0 errors" 0 "errors=0 " -- node "$node_dir/gltf_validate.js" "$copy"
    done
done

# ---- the JSON, semantically -----------------------------------------------------------------------------------
for name in $(printf '%s\n' "${!original[@]}" | sort); do
    expect "JSON: $name.gltf equals the original" 0 "" -- \
        python3 "$root/tests/lib/gltf_json_compare.py" "$shared/assets/${original[$name]}" "$tmp/keep/$name/$name.gltf"
done
expect "JSON: the kitchen sink equals the original" 0 "" -- \
    python3 "$root/tests/lib/gltf_json_compare.py" "$tmp/sink.gltf" "$tmp/keep/KitchenSink/KitchenSink.gltf"

# The shared assets themselves were not touched (the copies went to the scratch directory only).
check "no output beside the shared assets" \
    test -z "$(find "$shared/assets" -newer "$tmp/sink.gltf" \( -name '*.gltf' -o -name '*.glb' -o -name '*.bin' \
    -o -name '*.tmp*' \) 2>/dev/null)"
finish
