#!/usr/bin/env bash
# Installs every Debian package matremap needs, and nothing that is already there.
# Idempotent: a second run does no network work. Usage: scripts/install-deps.sh [--bench]
#   --bench  also install what only the benchmarks use (hyperfine).
set -euo pipefail

packages=(
    build-essential pkg-config
    libopenexr-dev libopenimageio-dev openimageio-tools
    libtinygltf-dev nlohmann-json3-dev libstb-dev
    libnlopt-dev
    libpng-dev         # PNG read and write without OpenImageIO (src/io/png_io.c)
    libdeflate-dev     # PNG's zlib streams, compressed and inflated whole (src/io/png_deflate.c, png_palette.c)
    libsvm-dev         # epsilon-SVR training of learned transforms (src/learn/svr.c)
    libtinyobjloader-dev  # OBJ meshes, e.g. the paper's material-test sphere (src/io/obj_load.cpp)
    libexpat1-dev      # MaterialX documents read as export's input (src/doc/mtlx_read.c)
    gnuplot-nox
    jq                 # scripts/evaluate-svbrdf.sh reads the reports' summary.json
    fonts-dejavu-core  # labels on the demo's contact sheets (oiiotool --text)
    python3            # tests/gltf_validate.sh compares glTF JSON (tests/lib/gltf_json_compare.py)
    python3-numpy      # the independent transcriptions tests compare with (tests/*_reference.py); albedo tables
    locales            # tests/test_locale.c builds a decimal-comma locale (de_DE) with localedef from its data
    chromium           # tests/report_cli.sh opens a report page headless and checks its screenshot
    clang libclang-rt-14-dev libomp-14-dev  # make fuzz: libFuzzer targets with ASan+UBSan (clang's OpenMP runtime)
    openmpi-bin libopenmpi-dev  # optional: `mpirun -np N matremap sweep` (the MPI module; tests/sweep_mpi.sh)
    blender            # Cycles: the renderer server (data/renderers/blender_server.py, tests/blender_server.sh)
    python3-pytest     # the Python package's suite (tests/python.sh runs tests/python/test_*.py)
)
# node + npm run the independent SSIM implementation (ssim.js) and the Khronos glTF validator in the tests;
# the machine may already have a node of its own outside Debian's packages, which is fine.
command -v node >/dev/null 2>&1 || packages+=(nodejs)
command -v npm  >/dev/null 2>&1 || packages+=(npm)
if [ "${1:-}" = "--bench" ]; then
    packages+=(python3-numpy hyperfine)
fi

missing=()
for p in "${packages[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
        missing+=("$p")
    fi
done
if [ ${#missing[@]} -gt 0 ]; then
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    echo "install-deps: installing ${missing[*]}" >&2
    export DEBIAN_FRONTEND=noninteractive
    $sudo apt-get update -qq
    $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
fi

# The three.js renderer server's npm packages (data/renderers/three: three, playwright-core, pinned by its
# package-lock.json), installed once: nothing to do, and nothing said, when they are there.
three="$(cd "$(dirname "$0")/.." && pwd)/data/renderers/three"
if [ ! -f "$three/node_modules/three/package.json" ] || [ ! -f "$three/node_modules/playwright-core/package.json" ]
then
    echo "install-deps: npm ci in $three" >&2
    (cd "$three" && npm ci --no-audit --no-fund --loglevel=error) >&2
fi
