#!/usr/bin/env bash
# Renders matremap's fit scene with Blender Cycles (the "Cycles peer"); see docs/cycles-peer.md.
# Usage: scripts/cycles-render.sh [cycles_fit_scene.py options] -o OUT.exr
#   e.g. scripts/cycles-render.sh --size 256 --samples 16 --light 45 --material principled \
#            --base-color 0.8,0.3,0.1 --roughness 0.3 --distribution GGX --component full -o out.exr
# Options are passed through unchanged (scripts/cycles-render.sh --help lists them).
# stdout carries only the script's JSON lines (timing, and any --check-* results); Blender's own
# chatter goes to stderr. Exit codes: 0 ok, 1 usage, 2 bad input, 3 Blender failure; 127 no Blender.
# Set BLENDER=/path/to/blender to use another Blender (3.x; the Principled inputs are pre-4.0).
set -euo pipefail

blender="${BLENDER:-blender}"
if ! command -v "$blender" >/dev/null 2>&1; then
    echo "cycles-render: '$blender' not found; install with scripts/install-deps.sh" >&2
    exit 127
fi
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
script="$here/cycles_fit_scene.py"
if [ ! -f "$script" ]; then
    echo "cycles-render: missing $script" >&2
    exit 3
fi

# JSON lines (they start with '{') go to stdout, everything else Blender prints to stderr.
"$blender" -b --factory-startup --python-exit-code 3 --python "$script" -- "$@" \
    | awk '/^\{/ { print; fflush(); next } { print > "/dev/stderr" }'
