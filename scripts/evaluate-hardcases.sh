#!/usr/bin/env bash
# make evaluation-hardcases: the spec2metal methods on single texels chosen to be hard (docs/evaluation.md, "Hard
# cases"): dark, mid and bright dielectrics at the 8-bit dielectric F0 band (specular 40, 56 and 70/255, sRGB codes
# decoded to linear), saturated colours with F0 0.04, grey inputs, pure metals, partly metallic texels, each glossy
# (glossiness 0.9) and rough (0.3). Each texel is converted by every method `spec2metal` offers (mlp, weighted,
# mean and khronos in the default glTF convention, weighted and mean in the paper's), and the spec-gloss original
# (gltf-specgloss) and every conversion (gltf) are rendered on a sphere under both shared HDR maps by `matremap
# report` (256², one view, its default sampling, each map scaled to a mean luminance of 0.5, pictures and SSIM at
# the original's mid-grey exposure) and compared over the sphere's pixels (object SSIM, docs/metrics.md).
# The tables go into docs/evaluation.md between the eval-hardcases markers, two contact sheets (original | each
# method, studio map, glossy and rough) into docs/evaluation/, the reports into BUILD/evaluation-hardcases/.
#
# The script only calls the tools: whatever `spec2metal --method M` does when it runs is what is measured.
# Usage: scripts/evaluate-hardcases.sh [BUILD]
# Environment: EVAL_SIZE (render side, default 256), MR_SHARED, EVAL_ONLY (a smoke run: only the texels whose
#              names are listed, e.g. "dark-56 gold", and docs/ is left alone).
set -euo pipefail
build=${1:-build}
root=$(cd "$(dirname "$0")/.." && pwd)
bin="$root/$build/bin/matremap"
assets="${MR_SHARED:-$root/../shared}/assets"
work="$root/$build/evaluation-hardcases"
size=${EVAL_SIZE:-256}
only=${EVAL_ONLY:-}
pics="$root/docs/evaluation"
if [ -n "$only" ]; then pics="$work/pictures"; fi # a smoke run writes nothing into docs/
export LC_ALL=C
# shellcheck source=scripts/lib/evaluation.sh
. "$root/scripts/lib/evaluation.sh"

[ -x "$bin" ] || { echo "evaluation-hardcases: $bin is missing (run make first)" >&2; exit 1; }
[ -d "$assets/hdri" ] || { echo "evaluation-hardcases: no HDR maps in $assets (set MR_SHARED)" >&2; exit 1; }
command -v oiiotool >/dev/null || { echo "evaluation-hardcases: oiiotool is missing (make deps)" >&2; exit 1; }
rm -rf "$work"
mkdir -p "$work" "$pics"
t_start=$(date +%s)

envs=(studio tabac)
glosses=(glossy rough)
gloss_value() { case $1 in glossy) echo 0.9 ;; rough) echo 0.3 ;; esac; }
# METHOD/CONVENTION as spec2metal takes them, and the label the tables use.
methods=(mlp/gltf weighted/gltf mean/gltf khronos/gltf weighted/paper mean/paper)
method_label() { case $1 in */paper) echo "${1%/*} (paper)" ;; *) echo "${1%/*}" ;; esac; }

# ---- the texels: NAME, CATEGORY, DESCRIPTION, DIFFUSE R,G,B, SPECULAR R,G,B (linear) -----------------------------
# Colours given as 8-bit sRGB codes are decoded with the IEC 61966-2-1 curve, as a PNG texel is read.
texels="$work/texels.tsv"
python3 - > "$texels" <<'PY'
def lin(code):
    c = code / 255.0
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4
def rgb(*v): return ",".join("%.6g" % x for x in v)
def grey(v): return rgb(v, v, v)
rows = []
for level, code in (("dark", 12), ("mid", 118), ("bright", 230)):
    for spec in (40, 56, 70):
        rows.append(("%s-%d" % (level, spec), "dielectric, 8-bit F0",
                     "%s grey diffuse (sRGB %d/255), specular sRGB %d/255" % (level, code, spec),
                     grey(lin(code)), grey(lin(spec))))
for name, codes in (("red", (204, 20, 20)), ("green", (30, 170, 40)), ("blue", (25, 45, 200)),
                    ("yellow", (235, 200, 15))):
    rows.append((name, "saturated", "saturated %s diffuse (sRGB %d,%d,%d), specular 0.04" % ((name,) + codes),
                 rgb(*map(lin, codes)), grey(0.04)))
rows.append(("white-nospec", "grey", "white diffuse 1, specular 0", grey(1.0), grey(0.0)))
rows.append(("grey-nospec", "grey", "grey diffuse 0.5, specular 0", grey(0.5), grey(0.0)))
rows.append(("grey-half", "grey", "grey diffuse 0.25, grey specular 0.25", grey(0.25), grey(0.25)))
for name, f0 in (("gold", (1.0, 0.766, 0.336)), ("copper", (0.955, 0.638, 0.538)),
                 ("silver", (0.972, 0.960, 0.915)), ("iron", (0.562, 0.565, 0.578))):
    rows.append((name, "metal", "%s: diffuse 0, specular %s" % (name, rgb(*f0)), grey(0.0), rgb(*f0)))
for row in rows: print("\t".join(row))
PY
# Partly metallic texels: metal-rough ones through metal2spec (the default glTF convention), so they lie on the
# metallic manifold, and one off it (a coloured diffuse under a coloured specular, as rusty or lacquered metal).
mixed() { # NAME BASE METALLIC
    local line diffuse specular
    line=$("$bin" metal2spec --basecolor "$2" --metallic "$3" --roughness 0.5 2>/dev/null | tail -n 1)
    diffuse=$(echo "$line" | sed -E 's/.*diffuse=([^ ]*).*/\1/')
    specular=$(echo "$line" | sed -E 's/.*specular=([^ ]*).*/\1/')
    printf '%s\tmixed\tbase colour %s, metallic %s (metal2spec)\t%s\t%s\n' "$1" "$2" "$3" "$diffuse" "$specular"
}
mixed half-gold 0.9,0.6,0.3 0.5 >> "$texels"
mixed grey-m30 0.5,0.5,0.5 0.3 >> "$texels"
printf 'rust\tmixed\tcoloured diffuse under a coloured specular (off the manifold)\t0.25,0.08,0.03\t0.35,0.25,0.15\n' \
    >> "$texels"
if [ -n "$only" ]; then
    awk -F'\t' -v only=" $only " 'index(only, " " $1 " ")' "$texels" > "$texels.tmp" && mv "$texels.tmp" "$texels"
fi
[ -s "$texels" ] || { echo "evaluation-hardcases: no texel matches EVAL_ONLY='$only'" >&2; exit 1; }

# ---- convert, render, compare ---------------------------------------------------------------------------------
conversions="$work/conversions.tsv" # case, method, base colour, metallic, roughness
results="$work/results.tsv"         # case, env, method, object ssim, whole-frame ssim
: > "$conversions"
: > "$results"
cases=0
while IFS=$'\t' read -r name category description diffuse specular; do
    for gloss in "${glosses[@]}"; do
        case_name="$name-$gloss"
        g=$(gloss_value "$gloss")
        args=(--label "spec-gloss original" gltf-specgloss "diffuse=$diffuse" "specular=$specular" "glossiness=$g")
        for method in "${methods[@]}"; do
            label=$(method_label "$method")
            line=$("$bin" spec2metal --diffuse "$diffuse" --specular "$specular" --glossiness "$g" \
                   --method "${method%/*}" --convention "${method#*/}" 2>/dev/null | tail -n 1)
            base=$(echo "$line" | sed -E 's/.*basecolor=([^ ]*).*/\1/')
            metallic=$(echo "$line" | sed -E 's/.*metallic=([^ ]*).*/\1/')
            roughness=$(echo "$line" | sed -E 's/.*roughness=([^ ]*).*/\1/')
            printf '%s\t%s\t%s\t%s\t%s\n' "$case_name" "$label" "$base" "$metallic" "$roughness" >> "$conversions"
            args+=(-- --label "$label" gltf "base_color=$base" "metallic=$metallic" "roughness=$roughness")
        done
        for e in "${envs[@]}"; do
            mkdir -p "$work/$case_name"
            "$bin" report -o "$work/$case_name/$e" --env "$(env_file "$e")" --rotations 1 --size "$size" \
                --title "$description, glossiness $g" "${args[@]}" >/dev/null
            python3 - "$work/$case_name/$e/summary.json" "$case_name" "$e" >> "$results" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
for m in d["materials"][1:]:
    print("%s\t%s\t%s\t%.6f\t%.6f" % (sys.argv[2], sys.argv[3], m["label"], m["object_ssim"][0], m["ssim"][0]))
PY
        done
        cases=$((cases + 1))
        echo "== $case_name ($cases)"
    done
done < "$texels"

# ---- contact sheets: per roughness, studio map, a row per texel: the original and each method ------------------
cell=96
for gloss in "${glosses[@]}"; do
    images=()
    rows=0
    while IFS=$'\t' read -r name _; do
        for k in $(seq 0 "${#methods[@]}"); do
            if [ "$k" = 0 ]; then text=$name; elif [ "$rows" = 0 ]; then text=$(method_label "${methods[$((k - 1))]}")
            else text=""; fi
            images+=("$work/$name-$gloss/studio/view0_material$k.png" --resize "${cell}x$cell")
            if [ -n "$text" ]; then images+=(--text:x=3:y=11:size=10:color=1,1,1:font=DejaVuSans "$text"); fi
        done
        rows=$((rows + 1))
    done < "$texels"
    oiiotool "${images[@]}" --mosaic:pad=2 "$((${#methods[@]} + 1))x$rows" -o "$pics/hardcases_$gloss.png"
done

# ---- tables -----------------------------------------------------------------------------------------------------
table="$work/tables.md"
python3 - "$texels" "$conversions" "$results" "$size" "$("$bin" --version | cut -d' ' -f2)" \
    "$(( $(date +%s) - t_start ))" > "$table" <<'PY'
import sys, collections, datetime
texels_path, conversions_path, results_path, size, version, seconds = sys.argv[1:7]
methods = ["mlp", "weighted", "mean", "khronos", "weighted (paper)", "mean (paper)"]
texels = [line.rstrip("\n").split("\t") for line in open(texels_path)]
category = {t[0]: t[1] for t in texels}
conv = {}
for line in open(conversions_path):
    case, method, base, metallic, rough = line.rstrip("\n").split("\t")
    conv[case, method] = (base, float(metallic))
ssim, frame = {}, {}
for line in open(results_path):
    case, env, method, obj, whole = line.rstrip("\n").split("\t")
    ssim[case, env, method] = float(obj)
    frame[case, env, method] = float(whole)
cases = [(t[0], g) for t in texels for g in ("glossy", "rough")]
def mean_of(case, method): return (ssim[case, "studio", method] + ssim[case, "tabac", method]) / 2
print("Measured by `make evaluation-hardcases` on %s, matremap %s: each texel as a %s² sphere under"
      % (datetime.datetime.utcnow().strftime("%Y-%m-%d"), version, size))
print("studio_small_03 and tabac_plant_vogl (each scaled to a mean luminance of 0.5), one view, `matremap report`'s")
print("sampling defaults (256 environment directions, 40 reflection samples), SSIM at the original's mid-grey")
print("exposure **over the sphere** (the pixels whose SSIM window touches it) against the spec-gloss original;")
print("glossy = glossiness 0.9 (roughness 0.1), rough = glossiness 0.3. Wall time %s s." % seconds)
print()
print("**Per method** (object SSIM, the mean of the two maps per case, then over the cases; worst = the lowest of")
print("any case under either map; wins = cases where the method's mean is the best, ties within 1e-4 counted for")
print("each):")
print()
cats = []
for t in texels:
    if t[1] not in cats: cats.append(t[1])
print("| method | " + " | ".join(cats) + " | all cases | worst (case, map) | wins | whole-frame SSIM (all) |")
print("|---|" + "---:|" * len(cats) + "---:|---|---:|---:|")
best = {c: max(mean_of(c[0] + "-" + c[1], m) for m in methods) for c in cases}
for m in methods:
    per_cat = []
    for cat in cats:
        vals = [mean_of(n + "-" + g, m) for n, g in cases if category[n] == cat]
        per_cat.append("%.4f" % (sum(vals) / len(vals)))
    allv = [mean_of(n + "-" + g, m) for n, g in cases]
    worst = min(((ssim[n + "-" + g, e, m], n + "-" + g, e) for n, g in cases for e in ("studio", "tabac")))
    wins = sum(1 for c in cases if mean_of(c[0] + "-" + c[1], m) >= best[c] - 1e-4)
    whole = [(frame[n + "-" + g, "studio", m] + frame[n + "-" + g, "tabac", m]) / 2 for n, g in cases]
    print("| %s | %s | %.4f | %.4f (%s, %s) | %d of %d | %.4f |" % (m, " | ".join(per_cat), sum(allv) / len(allv),
          worst[0], worst[1], worst[2], wins, len(cases), sum(whole) / len(whole)))
print()
print("**Per texel**: object SSIM studio / tabac / mean for each method, the best mean in bold; below each")
print("method's figures, the metallic it chose.")
print()
print("| texel | " + " | ".join(methods) + " |")
print("|---|" + "---|" * len(methods))
for n, g in cases:
    c = n + "-" + g
    cells = []
    for m in methods:
        mean = mean_of(c, m)
        text = "%.4f / %.4f / %s" % (ssim[c, "studio", m], ssim[c, "tabac", m],
                                      ("**%.4f**" if mean >= best[(n, g)] - 1e-4 else "%.4f") % mean)
        cells.append(text + "<br>m %.3g" % conv[c, m][1])
    print("| %s %s | %s |" % (n, g, " | ".join(cells)))
print()
print("Texels (linear values; 8-bit sRGB codes decoded as a PNG texel is read):")
print()
print("| texel | what | diffuse | specular |")
print("|---|---|---|---|")
for t in texels:
    print("| %s | %s | %s | %s |" % (t[0], t[2], t[3], t[4]))
PY
cat "$table"
if [ -z "$only" ] && splice_table "$root/docs/evaluation.md" eval-hardcases "$table"; then
    echo "evaluation-hardcases: tables written into docs/evaluation.md, contact sheets into docs/evaluation/"
fi
echo "evaluation-hardcases: $cases cases in $(( $(date +%s) - t_start )) s"
