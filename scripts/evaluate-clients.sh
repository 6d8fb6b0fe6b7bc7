#!/usr/bin/env bash
# make evaluation-clients: the documents `matremap export` writes, opened by a real client (docs/evaluation-clients.md):
# three.js's MaterialXLoader (.mtlx: open_pbr_surface, standard_surface, gltf_pbr) and USDLoader (.usda:
# UsdPreviewSurface) in headless Chromium (scripts/viewers/client_render.mjs, client_page.js), each material on a
# sphere (the textured asset on its own meshes) under both shared HDR maps, beside `matremap render` of the same
# material with the same camera, map orientation and scale. Per material, document and map: object SSIM and the mean
# luminance ratio (BUILD/tools/object_metrics), and what the loader reported. The materials: uniform glTF materials
# exported to each document (a remap, or a copy to gltf_pbr), materials glTF cannot hold written by the library's
# writer (BUILD/tools/doc_write: coats, a metal's edge tint, a rough diffuse), and the WaterBottle exported where a
# texture route exists. The table goes into docs/evaluation-clients.md between the eval-clients markers, one
# picture per material into docs/evaluation-clients/, documents, renders and job files into BUILD/evaluation-clients/.
# Installs what it needs: Chromium (scripts/install-deps.sh --bench) and the pinned npm packages of scripts/viewers
# (npm ci).
# Usage: scripts/evaluate-clients.sh [BUILD]. Environment: CLIENTS_SIZE (default 256), CLIENTS_CELL (picture cell,
# default 128), MR_SHARED.
set -euo pipefail
build=${1:-build}
root=$(cd "$(dirname "$0")/.." && pwd)
bin="$root/$build/bin/matremap"
metrics="$root/$build/tools/object_metrics"
doc_write="$root/$build/tools/doc_write"
assets="${MR_SHARED:-$root/../shared}/assets"
work="$root/$build/evaluation-clients"
viewers="$root/scripts/viewers"
export LC_ALL=C
for tool in "$bin" "$metrics" "$doc_write"; do
    [ -x "$tool" ] || { echo "evaluation-clients: $tool is missing (run make evaluation-clients)" >&2; exit 1; }
done
t_start=$(date +%s)

"$root/scripts/install-deps.sh" --bench
if [ ! -d "$viewers/node_modules" ] || [ "$viewers/package-lock.json" -nt "$viewers/node_modules/.package-lock.json" ]
then
    (cd "$viewers" && npm ci --no-audit --no-fund --loglevel=error) >&2
fi
chromium_bin=/usr/lib/chromium/chromium # /usr/bin/chromium is Debian's wrapper script around it
[ -x "$chromium_bin" ] || { echo "evaluation-clients: $chromium_bin is missing" >&2; exit 1; }

rm -rf "$work"
mkdir -p "$work" "$root/docs/evaluation-clients"
py="python3 $viewers/evaluate_clients.py"
$py prepare "$work" "$assets" "$bin" "$doc_write"
$py jobs "$work" "$assets/hdri" "$chromium_bin"

# shellcheck source=scripts/lib/timing.sh
. "$root/scripts/lib/timing.sh"
three_times=$(times_of "$work/three.log" nice -n 10 node "$viewers/client_render.mjs" "$work/client-jobs.json") \
    || { echo "evaluation-clients: three.js failed, see $work/three.log" >&2; exit 3; }
grep '^{' "$work/three.log" > "$work/three-done.jsonl"
echo "evaluation-clients: three.js renders: wall, CPU s $three_times" >&2
t_matremap=$(date +%s)
$py matremap "$work" "$assets/hdri" "$bin"
echo "evaluation-clients: matremap renders in $(($(date +%s) - t_matremap)) s" >&2

$py metrics "$work" "$metrics" > "$work/metrics.jsonl"
rm -f "$root"/docs/evaluation-clients/*.png
$py pictures "$work" "$root/docs/evaluation-clients"
$py table "$work" "$(date -u +%Y-%m-%d)" "$("$bin" --version | cut -d' ' -f2)" "$three_times" \
    "$(($(date +%s) - t_start))" > "$work/table.md"
cat "$work/table.md"
# shellcheck source=scripts/lib/doc_section.sh
. "$root/scripts/lib/doc_section.sh"
if replace_doc_section "$root/docs/evaluation-clients.md" eval-clients "$work/table.md"; then
    echo "evaluation-clients: table written into docs/evaluation-clients.md, pictures into docs/evaluation-clients/"
fi
