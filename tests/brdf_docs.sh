#!/usr/bin/env bash
# docs/brdfs.md is generated from the doc blocks of src/brdf/*.c: fail when it no longer matches them.
# Ends with "N passed, N failed" for scripts/run-tests.sh.
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
if "$root/scripts/gen-brdf-docs.sh" --check; then
    echo "ok    docs/brdfs.md matches the model doc blocks"
    echo "1 passed, 0 failed"
else
    echo "FAIL  docs/brdfs.md is stale: run scripts/gen-brdf-docs.sh"
    echo "0 passed, 1 failed"
    exit 1
fi
