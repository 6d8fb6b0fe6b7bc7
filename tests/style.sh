#!/usr/bin/env bash
# House style (docs/style.md, "House style, enforced by a script"): in every tracked C, C++ and header file —
# no tabs, no trailing whitespace, LF line endings, lines of at most 120 characters, and a final newline.
# Ends with "N passed, N failed".
set -u
cd "${MR_ROOT:-$(dirname "$0")/..}"
passed=0
failed=0
check() { # NAME PATTERN-DESCRIPTION COMMAND...
    local name=$1; shift
    local hits
    hits=$("$@")
    if [ -n "$hits" ]; then
        echo "FAIL  $name:"; echo "$hits" | head -10 | sed 's/^/      /'; failed=$((failed + 1))
    else
        echo "ok    $name"; passed=$((passed + 1))
    fi
}
mapfile -t files < <(git ls-files 'src/*' 'tests/*' 'nn/*' 'gltf/*' | grep -E '\.(c|h|cpp|hpp)$')
check "no tabs" grep -nP '\t' "${files[@]}"
check "no trailing whitespace" grep -nP ' +$' "${files[@]}"
check "LF line endings" grep -nlP '\r' "${files[@]}"
check "lines of at most 120 characters" awk 'length > 120 { print FILENAME ":" FNR ": " length " characters" }' "${files[@]}"
check "final newline" bash -c 'for f in "$@"; do [ -z "$(tail -c 1 "$f")" ] || echo "$f"; done' _ "${files[@]}"
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
