#!/usr/bin/env bash
# gltf-library.sh — lay out a library of spec-gloss glTF assets for `matremap gltf spec2metal DIR -o OUT` and its
# benchmark (scripts/bench.sh --only library): the spec-gloss variants of KhronosGroup/glTF-Sample-Models
# (2.0/*/glTF-pbrSpecularGlossiness) from a local copy, one folder per model.
#
# Usage: scripts/gltf-library.sh SOURCE DEST
#   SOURCE  a checkout of glTF-Sample-Models (a work tree), or its bare git directory (what `fetch` or
#           `git clone --bare` gives: the files are taken with `git archive` from HEAD), or "shared" for the
#           spec-gloss assets of ../shared/assets/specgloss (MR_SHARED) when no copy of the sample models is at hand
#   DEST    made if missing; DEST/NAME/... per model, and DEST/SOURCE.txt naming where they came from (the commit)
# Files a bare mirror lists but does not hold (its largest files may be absent) are reported, and a model missing
# any of them is left out (listed in SOURCE.txt). Prints the number of assets laid out.
set -eu
src=${1:?usage: scripts/gltf-library.sh SOURCE|shared DEST}
dest=${2:?usage: scripts/gltf-library.sh SOURCE|shared DEST}
root=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$dest"
note="$dest/SOURCE.txt"
count=0
if [ "$src" = shared ]; then
    shared=${MR_SHARED:-$root/../shared}/assets/specgloss
    [ -d "$shared" ] || { echo "gltf-library.sh: no $shared" >&2; exit 2; }
    for d in "$shared"/*/; do
        name=$(basename "$d")
        rm -rf "${dest:?}/$name"
        if [ -d "$d/glTF-pbrSpecularGlossiness" ]; then
            cp -r "$d/glTF-pbrSpecularGlossiness" "$dest/$name"
        else
            mkdir -p "$dest/$name" && cp -r "$d"/. "$dest/$name/"
        fi
        count=$((count + 1))
    done
    echo "../shared/assets/specgloss (see its MANIFEST.md): $count assets" >"$note"
elif [ -d "$src/2.0" ]; then
    commit=$(git -C "$src" rev-parse HEAD 2>/dev/null || echo "unknown commit")
    for d in "$src"/2.0/*/glTF-pbrSpecularGlossiness; do
        [ -d "$d" ] || continue
        name=$(basename "$(dirname "$d")")
        rm -rf "${dest:?}/$name" && cp -r "$d" "$dest/$name"
        count=$((count + 1))
    done
    echo "KhronosGroup/glTF-Sample-Models at $commit (work tree $src): $count assets" >"$note"
else
    git --git-dir="$src" rev-parse HEAD >/dev/null 2>&1 || { echo "gltf-library.sh: '$src' is neither a checkout" \
        "nor a git directory" >&2; exit 2; }
    commit=$(git --git-dir="$src" rev-parse HEAD)
    missing=()
    for name in $(git --git-dir="$src" ls-tree -d --name-only HEAD 2.0/ | sed 's|2.0/||'); do
        files=$(git --git-dir="$src" ls-tree -r --name-only HEAD "2.0/$name/glTF-pbrSpecularGlossiness/")
        [ -n "$files" ] || continue
        ok=1
        for f in $files; do git --git-dir="$src" cat-file -e "HEAD:$f" 2>/dev/null || { ok=0; missing+=("$f"); }; done
        [ "$ok" = 1 ] || continue
        rm -rf "${dest:?}/$name" && mkdir -p "$dest/$name"
        git --git-dir="$src" archive HEAD "2.0/$name/glTF-pbrSpecularGlossiness" |
            tar -x -C "$dest/$name" --strip-components=3
        count=$((count + 1))
    done
    {
        echo "KhronosGroup/glTF-Sample-Models at $commit (git directory $src): $count assets"
        [ "${#missing[@]}" = 0 ] || printf 'absent from the copy (model left out): %s\n' "${missing[@]}"
    } >"$note"
fi
cat "$note"
