#!/usr/bin/env bash
# The Blender add-on, headless (docs/blender-addon.md): installs build/matremap_blender_addon.zip into a scratch
# user-scripts folder, imports the shared Avocado spec-gloss glTF, converts it, renders before/after in Cycles
# (128x128, 32 samples) and checks the object SSIM and the node tree; remaps a Principled to gltf and back.
# Skips (one line, "0 passed, 0 failed") without Blender, the shared asset, the add-on zip or libmatremap.so.0.
set -u
root=${MR_ROOT:-$(cd "$(dirname "$0")/.." && pwd)}
build=${MR_BUILD:-$root/build}
shared=${MR_SHARED:-$root/../shared}
asset=${MR_ADDON_ASSET:-$shared/assets/specgloss/Avocado-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Avocado.gltf}
zip=$build/matremap_blender_addon.zip
lib=${MATREMAP_LIBRARY:-$build/lib/libmatremap.so.0}
skip() { echo "blender_addon: skipped: $1"; echo "0 passed, 0 failed"; exit 0; }
command -v blender >/dev/null 2>&1 || skip "no blender on PATH (scripts/install-deps.sh installs it)"
[ -f "$asset" ] || skip "no shared asset $asset"
[ -f "$lib" ] || skip "no $lib (the shared library: make)"
# A sanitizer build's library cannot load into Blender (its runtime must come first); make check runs this test.
nm -D "$lib" 2>/dev/null | grep -q ' U __asan_init' && skip "$lib is built with AddressSanitizer (make check runs this)"
[ -f "$zip" ] || skip "no $zip (make builds it)"
python3 -m zipfile -l "$zip" 2>/dev/null | grep -q '_vendor/matremap/__init__.py' || \
    skip "$zip bundles no matremap package (python/matremap missing when it was built)"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/scripts" "$work/out"
# a scratch user scripts folder and config: the test installs the zip there, not in the user's Blender
BLENDER_USER_SCRIPTS=$work/scripts BLENDER_USER_CONFIG=$work/config MATREMAP_LIBRARY=$lib \
    blender -b --factory-startup --python-exit-code 1 --python "$root/tests/blender/test_addon.py" -- \
    "$zip" "$asset" "$work/out" "$build/bin/matremap" > "$work/log" 2>&1
rc=$?
grep -E '^(ok|FAIL) |^object SSIM|^convert_specgloss|^remap |^  (gltf values|back)|^addon test took' "$work/log"
grep -E 'passed, [0-9]+ failed$|Error|Traceback|^matremap ssim failed' "$work/log"
if ! grep -qE '^[0-9]+ passed, [0-9]+ failed$' "$work/log"; then
    tail -n 30 "$work/log"
    echo "0 passed, 1 failed"
    exit 1
fi
exit $rc
