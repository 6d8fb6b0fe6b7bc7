#!/usr/bin/env bash
# evaluate-renderer-fits.sh — fits through real renderers beside fits through the built-in model (docs/renderers.md,
# docs/performance.md "Renderers in the loop"); `make evaluation-renderer-fits`.
#
#   A. Cycles Principled -> glTF: the source rendered by Blender 3.4 (`--from-renderer blender`) against the source
#      rendered by matremap's model of it (cycles-principled); both fits' glTF values rendered at 512^2 and compared
#      over the sphere with Blender's own 512^2 render of the source.
#   B. glTF -> three.js: the target fitted through three.js (`--to-renderer three`) against the values as they are
#      (what a built-in fit of glTF to glTF returns); both rendered by three.js at 512^2 and compared over the sphere
#      with matremap's glTF render of the source: what a web viewer shows of each.
# Prints a markdown table per pair (values, object SSIM at 512^2, renders, seconds), Cycles' noise floor at the fit's
# sample count (two seeds apart), and a sweep through Blender on 1 process and on 2 MPI ranks.
# Usage: scripts/evaluate-renderer-fits.sh [BUILD_DIR]  (default build). Needs Blender, three.js's npm packages and
# Chromium (scripts/install-deps.sh); mpirun for the MPI row (skipped without it).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build}
bin="$build/bin/matremap"
[ -x "$bin" ] || { echo "evaluate-renderer-fits: $bin is missing (make)" >&2; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
py=/usr/bin/python3
field() { "$py" -c 'import json,sys; d=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))' "$@"; }
values() { # the glTF values of a remap's JSON as name=value words
    "$py" -c '
import json, sys
v = json.load(open(sys.argv[1]))["values"]
print(" ".join("%s=%s" % (k, ",".join("%.6g" % x for x in (x if isinstance(x, list) else [x]))) for k, x in v.items()))' "$1"
}
short() { # base colour, metallic, roughness of a values line
    "$py" -c '
import sys
d = dict(w.split("=") for w in sys.argv[1].split())
print("(%s), %s, %s" % (", ".join("%.3f" % float(c) for c in d["base_color"].split(",")), "%.3f" % float(d["metallic"]),
      "%.3f" % float(d["roughness"])))' "$1"
}
ssim_over() { "$bin" ssim "$1" "$2" --mask "$3" | head -n 1; }
ms() { "$py" -c 'import sys; print("%.0f" % (1e3 * float(sys.argv[1])))' "$1"; }

echo "$("$bin" --version 2>/dev/null | head -n 1), $(blender --version 2>/dev/null | head -n 1), $(date -u +%Y-%m-%d)"
echo
echo "### A. Cycles Principled (Blender 3.4) -> glTF"
echo
echo "| source (cycles-principled) | fit through | glTF base colour, metallic, roughness | object SSIM vs Cycles at 512² | renders (Blender) | seconds |"
echo "|---|---|---|---|---|---|"
sources_a=("base_color=0.8,0.2,0.1 roughness=0.4"
           "base_color=0.1,0.2,0.7 roughness=0.15"
           "base_color=0.95,0.7,0.3 metallic=1 roughness=0.35"
           "base_color=0.5,0.5,0.5 roughness=0.8 specular=0.7")
k=0
for src in "${sources_a[@]}"; do
    k=$((k + 1))
    # shellcheck disable=SC2086
    "$bin" render cycles-principled $src --renderer blender --size 512 -o "$tmp/a$k.exr" --mask "$tmp/m.exr" 2>/dev/null
    for route in blender builtin; do
        opt=()
        [ "$route" = blender ] && opt=(--from-renderer blender)
        # shellcheck disable=SC2086
        "$bin" remap --from cycles-principled $src "${opt[@]}" --to gltf --json >"$tmp/r.json"
        v=$(values "$tmp/r.json")
        # shellcheck disable=SC2086
        "$bin" render gltf $v --size 512 -o "$tmp/t.exr" 2>/dev/null
        renders=$(field "$tmp/r.json" 'd["renderers"]["source"].get("renders", 0)')
        echo "| $src | $([ $route = blender ] && echo "Blender's render" || echo "the built-in model") | $(short "$v") |" \
             "$(ssim_over "$tmp/a$k.exr" "$tmp/t.exr" "$tmp/m.exr") | $renders |" \
             "$(field "$tmp/r.json" '"%.2f" % d["seconds"]') |"
    done
done

echo
echo "### B. glTF -> three.js (what a web viewer shows)"
echo
echo "| source (gltf) | target values | base colour, metallic, roughness | object SSIM, three.js at 512² vs the source | renders (three.js) | seconds |"
echo "|---|---|---|---|---|---|"
sources_b=("base_color=0.8,0.1,0.1 metallic=0 roughness=0.3"
           "base_color=0.95,0.7,0.3 metallic=1 roughness=0.6"
           "base_color=0.95,0.64,0.54 metallic=1 roughness=0.2"
           "base_color=0.6,0.6,0.6 metallic=0.5 roughness=0.45")
k=0
for src in "${sources_b[@]}"; do
    k=$((k + 1))
    # shellcheck disable=SC2086
    "$bin" render gltf $src --size 512 -o "$tmp/b$k.exr" --mask "$tmp/m.exr" 2>/dev/null
    # shellcheck disable=SC2086
    "$bin" remap --from gltf $src --to gltf --to-renderer three --json >"$tmp/r.json"
    fitted=$(values "$tmp/r.json")
    for route in as-is three; do
        if [ "$route" = as-is ]; then v="$src specular=1 specular_color=1,1,1 ior=1.5"; else v=$fitted; fi
        # shellcheck disable=SC2086
        "$bin" render gltf $v --renderer three --size 512 -o "$tmp/t.exr" 2>/dev/null
        if [ "$route" = as-is ]; then
            echo "| $src | as they are | $(short "$v") | $(ssim_over "$tmp/b$k.exr" "$tmp/t.exr" "$tmp/m.exr") | — | — |"
        else
            echo "| | fitted through three.js | $(short "$v") | $(ssim_over "$tmp/b$k.exr" "$tmp/t.exr" "$tmp/m.exr") |" \
                 "$(field "$tmp/r.json" 'd["renderers"]["target"].get("renders", 0)') |" \
                 "$(field "$tmp/r.json" '"%.2f" % d["seconds"]') |"
        fi
    done
done

echo
echo "### Cycles' noise floor at the fit scene's 64², two seeds apart"
echo
echo "| samples | object SSIM | object relative RMSE |"
echo "|---|---|---|"
for n in 64 256 1024; do
    for s in 0 1; do
        "$bin" render cycles-principled base_color=0.8,0.2,0.1 roughness=0.4 --renderer blender --samples "$n" \
            --seed "$s" --size 64 -o "$tmp/n$s.exr" --mask "$tmp/m64.exr" 2>/dev/null
    done
    "$bin" ssim "$tmp/n0.exr" "$tmp/n1.exr" --mask "$tmp/m64.exr" --json >"$tmp/n.json"
    echo "| $n | $(field "$tmp/n.json" '"%.5f" % d["object_ssim"]') | $(field "$tmp/n.json" '"%.4f" % d["object_relative_rmse"]') |"
done

echo
echo "### A sweep through Blender (cycles-principled -> gltf, 40 random samples, 256 samples per pixel)"
echo
echo "| processes | seconds | rows/s | Blender renders | Blender processes |"
echo "|---|---|---|---|---|"
args=(--from cycles-principled --to gltf --random 40 --seed 11 --from-renderer blender)
"$bin" sweep "${args[@]}" --threads 2 -o "$tmp/s1.csv" --json >"$tmp/s1.json" 2>/dev/null
echo "| 1 process, 2 threads | $(field "$tmp/s1.json" '"%.1f" % d["seconds"]') |" \
     "$(field "$tmp/s1.json" '"%.2f" % (d["computed"] / d["seconds"])') |" \
     "$(field "$tmp/s1.json" 'd["renderers"]["renders"]') | $(field "$tmp/s1.json" 'd["renderers"]["process_starts"]') |"
if command -v mpirun >/dev/null; then
    mpi=(mpirun --oversubscribe -np 2)
    [ "$(id -u)" -eq 0 ] && mpi+=(--allow-run-as-root)
    "${mpi[@]}" "$bin" sweep "${args[@]}" -o "$tmp/s2.csv" --json >"$tmp/s2.json" 2>/dev/null
    echo "| 2 MPI ranks, 1 thread each (each its own Blender) | $(field "$tmp/s2.json" '"%.1f" % d["seconds"]') |" \
         "$(field "$tmp/s2.json" '"%.2f" % (d["computed"] / d["seconds"])') | rank 0: $(field "$tmp/s2.json" 'd["renderers"]["renders"]') |" \
         "rank 0: $(field "$tmp/s2.json" 'd["renderers"]["process_starts"]') |"
    check=$(cmp -s <(grep -v '^#' "$tmp/s1.csv" | rev | cut -d, -f2- | rev) \
                  <(grep -v '^#' "$tmp/s2.csv" | rev | cut -d, -f2- | rev) && echo "the same rows" || echo "DIFFERENT rows")
    echo
    echo "The MPI file and the single process's: $check (the seconds column aside)."
fi
