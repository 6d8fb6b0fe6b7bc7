#!/usr/bin/env bash
# renderer_faults.sh — a renderer server that misbehaves (tests/lib/fake_renderer.py, started as three.js's server
# through MATREMAP_NODE): half an image, a NaN pixel, a server that ends before it is ready or names another renderer,
# one that dies on every render (restarted, then given up after three attempts), one that answers with an error. Each
# is exit 3 with a message saying what went wrong, no output image, and no temporary folder left behind; a server
# that behaves renders. Needs three.js's npm packages installed (the library checks for them before it starts the
# server); without them it says so and checks nothing. Ends with "N passed, N failed".
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
bin="${MR_BUILD:-$root/build}/bin/matremap"
source "$(dirname "$0")/lib/cli_harness.sh"
if [ ! -f "$root/data/renderers/three/node_modules/three/package.json" ]; then
    echo "   skipped: data/renderers/three/node_modules is missing (scripts/install-deps.sh runs npm ci there)"
    finish
fi
export TMPDIR="$tmp/scratch"
mkdir -p "$TMPDIR"
fake() { FAKE_MODE=$1 MATREMAP_NODE="$root/tests/lib/fake_renderer.py" "$bin" render gltf --renderer three --size 32 \
    -o "$tmp/$1.exr"; }
expect "a server that behaves renders" 0 "three 0\.0\.1" -- fake ok
check "... its image written" [ -f "$tmp/ok.exr" ]
expect "half an image: exit 3" 3 "r1\.full\.f32' holds 2048 floats: expected 32x32x4 = 4096" -- fake truncated
expect "a NaN pixel: exit 3" 3 "full render, pixel \(16, 16\) channel 0 is nan: expected finite radiance >= 0" -- \
    fake nan
expect "ends before it is ready: exit 3, its log's last line said" 3 \
    "ended before it was ready: fake renderer: cannot start \(as asked\)" -- fake noready
expect "names another renderer: exit 3" 3 "answered 'ready blender 0\.0\.1.*' instead of 'ready three \.\.\.'" -- \
    fake badready
expect "dies on every render: exit 3 after three attempts" 3 "after 3 attempts: renderer 'three': its process died" \
    -- fake die
expect "answers with an error: exit 3, its message passed on" 3 "renderer 'three': the fake renderer refuses" -- \
    fake error
for m in truncated nan noready badready die error; do
    check "$m: no image written" [ ! -e "$tmp/$m.exr" ]
done
check "no temporary folder left behind" [ -z "$(ls -A "$TMPDIR")" ]
finish
