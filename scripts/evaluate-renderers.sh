#!/usr/bin/env bash
# make evaluation-renderers: the node materials of data/blender/node_materials.blend (scripts/blender/
# make_node_materials.py) baked to glTF metal-rough by Blender's own glTF exporter and by matremap's remap, each
# rendered back beside the original in Cycles (Blender's glTF importer) and in three.js (data/renderers/three/
# server.mjs, when present): object SSIM per material, Cycles' noise floor, a contact sheet per material.
# Writes docs/evaluation-renderers.md and docs/images/renderers/NAME.png; renders and job files go to
# BUILD/evaluation-renderers/. About a minute on 2 cores at the defaults.
# Installs what it needs: Blender (scripts/install-deps.sh --bench); oiiotool and fonts-dejavu-core come with the
# base packages.
# Usage: scripts/evaluate-renderers.sh [BUILD]. Environment: RENDERERS_SIZE (512), RENDERERS_SAMPLES (64),
# RENDERERS_THREADS (2), RENDERERS_ROUTE (auto | standin | blender: how matremap gets the node material; auto takes
# `--from blender:` when `matremap remap --help` has it, else the --from-images stand-in), RENDERERS_THREE_SAMPLES
# (16), MATREMAP_BLENDER, MATREMAP_NODE.
set -euo pipefail
build=${1:-build}
root=$(cd "$(dirname "$0")/.." && pwd)
bin="$root/$build/bin/matremap"
export LC_ALL=C
if [ ! -x "$bin" ]; then
    echo "evaluation-renderers: $bin is missing (run make evaluation-renderers)" >&2
    exit 1
fi
"$root/scripts/install-deps.sh" --bench
three="$root/data/renderers/three"
if [ -f "$three/package-lock.json" ] && { [ ! -d "$three/node_modules" ] ||
        [ "$three/package-lock.json" -nt "$three/node_modules/.package-lock.json" ]; }; then
    (cd "$three" && npm ci --no-audit --no-fund --loglevel=error) >&2
fi
if [ ! -f "$root/data/blender/node_materials.blend" ]; then
    "${MATREMAP_BLENDER:-blender}" -b --factory-startup --python-exit-code 3 \
        --python "$root/scripts/blender/make_node_materials.py" -- -o "$root/data/blender/node_materials.blend" >&2
fi
cd "$root"
/usr/bin/python3 scripts/evaluate_renderers.py "$build"
