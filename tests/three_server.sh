#!/usr/bin/env bash
# three_server.sh — matremap's three.js renderer server (data/renderers/three/server.mjs, docs/renderers.md) driven
# through the renderer-server protocol by a small client (tests/lib/three_client.py): the ready line and its caps; a
# lambert render at 64^2 that matches `matremap render lambert` (relative RMSE < 0.005, measured 0.0018) with alpha
# = matremap's coverage within one sub-pixel; a gltf render that gives the same bytes twice; one-line errors (unknown
# model or parameter, wrong value count, non-finite value, an unsupported component, malformed JSON) after which
# the server keeps serving; exit 0 at EOF and on quit. Needs node, Chromium, the server's npm packages
# (scripts/install-deps.sh runs npm ci in data/renderers/three), /usr/bin/python3 with numpy and oiiotool; without
# them it says which is missing and checks nothing. Ends with "N passed, N failed".
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
bin="${MR_BUILD:-$root/build}/bin/matremap"
source "$(dirname "$0")/lib/cli_harness.sh"

chromium_bin=${MATREMAP_CHROMIUM:-/usr/bin/chromium}
missing=""
[ -x "$chromium_bin" ] || missing="$chromium_bin (MATREMAP_CHROMIUM)"
command -v "${MATREMAP_NODE:-node}" >/dev/null || missing="node"
[ -f "$root/data/renderers/three/node_modules/three/package.json" ] ||
    missing="data/renderers/three/node_modules (scripts/install-deps.sh runs npm ci there)"
/usr/bin/python3 -c 'import numpy' 2>/dev/null || missing="/usr/bin/python3 with numpy"
command -v oiiotool >/dev/null || missing="oiiotool"
if [ -n "$missing" ]; then
    echo "   skipped: $missing is missing"
    finish
fi

while IFS= read -r line; do
    echo "$line"
    case $line in
        ok*) passed=$((passed + 1)) ;;
        FAIL*) failed=$((failed + 1)) ;;
    esac
done < <(/usr/bin/python3 "$root/tests/lib/three_client.py" session "$bin" "$tmp" 2>&1)
[ $((passed + failed)) -gt 0 ] || { echo "FAIL  the client ran no check"; failed=1; }
if [ "$failed" -gt 0 ] && [ -f "$tmp/server.log" ]; then sed 's/^/      server: /' "$tmp/server.log" | tail -n 8; fi
finish
