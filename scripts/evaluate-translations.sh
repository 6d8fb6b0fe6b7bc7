#!/usr/bin/env bash
# make evaluation-translations: MaterialX's closed-form translation graphs (matremap remap --method materialx,
# src/remap/translate.h) beside matremap's image-fitted remap, for 13 materials (MaterialX's examples and a few of
# ours) and the three pairs MaterialX has graphs for, rendered on the fit scene's sphere under both shared HDR maps
# and compared with the source's render by object SSIM (matremap ssim --mask). Tables into
# docs/evaluation-translations.md between its markers, one montage per pair into docs/evaluation-translations/,
# renders and results.json into BUILD/evaluation-translations/. About 5 minutes on 2 cores after make.
# Usage: scripts/evaluate-translations.sh [BUILD] [MATERIAL ...]   (a subset of materials, for trying things out)
# Environment: MR_SHARED (default ../shared: assets/hdri/studio_small_03_1k.hdr and tabac_plant_vogl.hdr).
set -euo pipefail
build=${1:-build}
shift || true
root=$(cd "$(dirname "$0")/.." && pwd)
export LC_ALL=C
if [ ! -x "$root/$build/bin/matremap" ]; then
    echo "evaluation-translations: $root/$build/bin/matremap is missing (run make evaluation-translations)" >&2
    exit 1
fi
command -v oiiotool >/dev/null || "$root/scripts/install-deps.sh"
# /usr/bin/python3: the system's (docs: the pyenv python3 on PATH lacks numpy; this script needs only the standard
# library, but stays on the one interpreter the project's scripts use).
exec /usr/bin/python3 "$root/scripts/translations/evaluate_translations.py" "$root" "$build" "$@"
