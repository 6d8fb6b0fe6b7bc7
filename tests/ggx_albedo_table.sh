#!/usr/bin/env bash
# ggx_albedo_table.sh — src/brdf/ggx_albedo_tables.h, the directional-albedo table of the layered models (openpbr,
# blender-principled, standard-surface), against a fresh computation: scripts/gen-ggx-albedo.c built with
# -DGEN_CHECK recomputes a sample of the committed entries (every 29th dielectric, every 7th white one) with the
# library's own lobe and compares them to 2e-6, so the table cannot drift from the code (make tables rewrites it).
# Needs only a C compiler. Ends with "N passed, N failed" for scripts/run-tests.sh.
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
if ! ${CC:-cc} -std=c11 -O2 -Wall -Wextra -Werror -DGEN_CHECK -I"$root/src" "$root/scripts/gen-ggx-albedo.c" -lm \
    -o "$tmp/check"; then
    echo "FAIL  scripts/gen-ggx-albedo.c -DGEN_CHECK does not build against src/brdf/ggx_albedo_tables.h"
    echo "0 passed, 1 failed"
    exit 1
fi
if "$tmp/check"; then
    echo "1 passed, 0 failed"
else
    echo "0 passed, 1 failed"
    exit 1
fi
