#!/usr/bin/env bash
# make evaluation-svbrdf: real texture sets expressed as Ward SVBRDFs (Mitsuba's `ward`), remapped by every learned
# method into GGX, Beckmann, Ashikhmin-Shirley and Cycles' Principled BSDF, rendered on the paper's material-test
# sphere under the Tabac Plant probe turned through 360° (the paper's Fig. 23), each remap compared with its Ward
# source by object SSIM (issue 15, item 5; docs/evaluation-svbrdf.md says what and why).
#
#   1. sets      Ward maps (diffuse, specular, alpha) made from ../shared/assets at SET_SIZE² (oiiotool, metal2spec)
#   2. sweeps    ward -> TARGET uniform remaps in the fit scene, with the frontal and the 45° light
#   3. learn     one transform per sweep and method (parametric where its shape applies, svr, mlp)
#   4. convert   every set through every transform (matremap convert), out-of-domain texels counted
#   5. report    per set, one `matremap report --mesh matsphere.obj --camera paper` with the Ward source and every
#                remap, ROTATIONS views of the probe (one render plan per view shared by every material)
#   6. plots     1 - object SSIM against the rotation angle per set x target (gnuplot SVG), the summary table
#                (mean over the angles per method x target x light) and a contact sheet per set (index.html)
# Outputs under BUILD/evaluation-svbrdf/; the table is spliced into docs/evaluation-svbrdf.md between the
# eval-svbrdf markers and the plots copied into docs/evaluation-svbrdf/ (unless EVAL_SMOKE is set).
#
# Usage: scripts/evaluate-svbrdf.sh [BUILD]. Environment (defaults in brackets):
#   SETS [floppy waterbottle]       texture sets: floppy, waterbottle, avocado (the set the settings were tuned on)
#   TARGETS [ggx beckmann as cycles-principled]   LIGHTS [frontal 45]
#   METHODS [parametric svr mlp direct]   direct: `convert --direct`, the reference (no sweep, no learning)
#   SET_SIZE [512]  RENDER_SIZE [192]  ROTATIONS [12]  ENV_SAMPLES [256]
#   DIRECT_TARGETS [ggx beckmann as]   targets --direct runs for
#   SVR_ARGS []   e.g. "--svr-c 1000 --svr-epsilon 0.001": hyper-parameters held instead of searched
#   MR_SHARED [../shared]   EVAL_SMOKE (non-empty: docs/ left alone)
set -euo pipefail
build=${1:-build}
root=$(cd "$(dirname "$0")/.." && pwd)
bin="$root/$build/bin/matremap"
assets="${MR_SHARED:-$root/../shared}/assets"
work="$root/$build/evaluation-svbrdf"
sets=${SETS:-floppy waterbottle}
targets=${TARGETS:-ggx beckmann as cycles-principled}
lights=${LIGHTS:-frontal 45}
methods=${METHODS:-parametric svr mlp direct}
set_size=${SET_SIZE:-512}
render_size=${RENDER_SIZE:-192}
rotations=${ROTATIONS:-12}
env_samples=${ENV_SAMPLES:-256}
svr_args=${SVR_ARGS:-}
# --direct into Cycles' Principled BSDF fits three nonlinear parameters by multi-start per distinct value: tens of
# minutes for a set, beyond this evaluation's budget; it is the reference for the microfacet targets.
direct_targets=${DIRECT_TARGETS:-ggx beckmann as}
smoke=${EVAL_SMOKE:-}
mesh="$assets/paper/matsphere.obj"
probe="$assets/hdri/tabac_plant_vogl.hdr"
docs="$root/docs/evaluation-svbrdf"
export LC_ALL=C
[ -x "$bin" ] || { echo "evaluation-svbrdf: $bin is missing (run make first)" >&2; exit 1; }
for f in "$mesh" "$probe"; do [ -f "$f" ] || { echo "evaluation-svbrdf: $f is missing" >&2; exit 1; }; done
command -v oiiotool >/dev/null || { echo "evaluation-svbrdf: oiiotool is missing (scripts/install-deps.sh)" >&2; exit 1; }
command -v gnuplot >/dev/null || { echo "evaluation-svbrdf: gnuplot is missing (scripts/install-deps.sh)" >&2; exit 1; }
command -v jq >/dev/null || { echo "evaluation-svbrdf: jq is missing (scripts/install-deps.sh)" >&2; exit 1; }
# shellcheck source=scripts/lib/doc_section.sh
. "$root/scripts/lib/doc_section.sh"
rm -rf "$work"
mkdir -p "$work"/{sets,sweeps,transforms,convert,reports,plots,logs}
started=$(date +%s)
stage() { echo "== $(($(date +%s) - started)) s: $*"; }
# Seconds each stage took, for the doc.
declare -A stage_seconds=()
stage_t0=$started
stage_end() { local now; now=$(date +%s); stage_seconds[$1]=$((now - stage_t0)); stage_t0=$now; }

# ---- 1. texture sets ---------------------------------------------------------------------------------------------
# Resampling: a box filter in linear values (colour maps sRGB-decoded first), so every texel of the working set is the
# mean of the source texels it covers and no value leaves its range (a Lanczos filter rings below 0).
shrink="--resize:filter=box ${set_size}x${set_size}"
make_set() {
    local name=$1 d="$work/sets/$1"
    mkdir -p "$d"
    case $name in
    floppy | avocado)
        # Spec-gloss (KHR_materials_pbrSpecularGlossiness): rho_s = F0 (the specular colour x specularFactor),
        # rho_d = diffuse colour x diffuseFactor x (1 - max F0) (the extension's c_diff), alpha = (1 - g)^2 with
        # g = glossiness x glossinessFactor: the GGX alpha of the extension's roughness 1 - g, taken as Ward's RMS
        # slope (the two distributions agree near the peak; the ward -> ggx sweeps give alpha' ~ 0.97 alpha there).
        local src dif sg df sf gf
        if [ "$name" = floppy ]; then
            src="$assets/specgloss/FloppyDisk-sketchfab/textures"
            dif="$src/material_0_diffuse.png" sg="$src/material_0_specularGlossiness.png"
            df=0.93 sf=0.89 gf=0.91 # scene.gltf's factors
        else
            src="$assets/specgloss/Avocado-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness"
            dif="$src/Avocado_diffuse.png" sg="$src/Avocado_specularGlossiness.png"
            df=1 sf=1 gf=1
        fi
        # shellcheck disable=SC2086
        oiiotool "$sg" --ch R,G,B --colorconvert sRGB linear $shrink --mulc "$sf" --clamp:min=0 -d float \
            -o "$d/specular.exr"
        oiiotool "$d/specular.exr" --maxchan --mulc -1 --addc 1 --ch 0,0,0 -d float -o "$d/one_minus_max_f0.exr"
        # shellcheck disable=SC2086
        oiiotool "$dif" --ch R,G,B --colorconvert sRGB linear $shrink --mulc "$df" "$d/one_minus_max_f0.exr" --mul \
            --clamp:min=0 -d float -o "$d/diffuse.exr"
        # shellcheck disable=SC2086
        oiiotool "$sg" --ch A $shrink --mulc "$gf" --mulc -1 --addc 1 --clamp:min=0 --powc 2 --clamp:min=0.001 \
            -d float -o "$d/alpha.exr"
        rm -f "$d/one_minus_max_f0.exr"
        ;;
    waterbottle)
        # Metal-rough (glTF core): the paper's Eq. 2 (matremap metal2spec, F0 0.04 for dielectrics, its paper
        # convention: diffuse = base (1 - metallic) as it is), then rho_d = diffuse, rho_s = specular, alpha =
        # roughness^2 (glTF's GGX alpha, as above). Roughness is the packed texture's G channel.
        local src="$assets/metalrough/WaterBottle/glTF"
        "$bin" metal2spec --basecolor "$src/WaterBottle_baseColor.png" \
            --metallic-roughness "$src/WaterBottle_occlusionRoughnessMetallic.png" --convention paper \
            --format exr -o "$d/full" >"$work/logs/metal2spec.log"
        # shellcheck disable=SC2086
        oiiotool "$d/full_diffuse.exr" --ch R,G,B $shrink --clamp:min=0 -d float -o "$d/diffuse.exr"
        # shellcheck disable=SC2086
        oiiotool "$d/full_specular.exr" --ch R,G,B $shrink --clamp:min=0 -d float -o "$d/specular.exr"
        # shellcheck disable=SC2086
        oiiotool "$d/full_glossiness.exr" --ch 0 $shrink --mulc -1 --addc 1 --clamp:min=0 --powc 2 \
            --clamp:min=0.001 -d float -o "$d/alpha.exr"
        rm -f "$d"/full_*
        ;;
    *) echo "evaluation-svbrdf: unknown set '$name' (floppy, waterbottle, avocado)" >&2; exit 1 ;;
    esac
}
stage "texture sets: $sets at ${set_size}²"
for s in $sets; do make_set "$s"; done
stage_end sets

# ---- 2. sweeps ---------------------------------------------------------------------------------------------------
# ggx, beckmann, as: a 2-D grid of grey specular x roughness with the diffuse held at 0 in both models (the
# parametric form's data; the diffuse is carried by the Lambertian lobes' ratio; a free target diffuse would soak up
# the weak lobes of the lowest speculars). Specular on a log axis down to 0.0005: spec-gloss F0 maps reach 0.002. cycles-principled cannot hold a coloured or large specular
# with a free diffuse in one lobe (its dielectric F0 is 0.08 specular <= 0.08; more needs metallic, which takes the
# base colour from the diffuse): a 3-D grey grid adds the diffuse, and every Principled parameter but specular_tint
# (held at 0) is fitted.
sweep_args() {
    case $1 in
    cycles-principled)
        echo "--from ward --to cycles-principled specular_tint=0 --hold specular_tint"
        echo "--grid alpha=0.005:1:10:log specular=0.0005:0.6:5:log diffuse=0:0.8:4"
        ;;
    *)
        echo "--from ward diffuse=0 --to $1 diffuse=0 --hold diffuse"
        echo "--grid alpha=0.005:1:16:log specular=0.0005:0.6:8:log"
        ;;
    esac
}
for t in $targets; do
    for l in $lights; do
        stage "sweep ward -> $t, light $l"
        # shellcheck disable=SC2046
        "$bin" sweep $(sweep_args "$t") --light "$l" --threads 2 -o "$work/sweeps/ward_${t}_$l.csv" \
            2>"$work/logs/sweep_${t}_$l.log" >/dev/null
        tail -n 1 "$work/logs/sweep_${t}_$l.log"
    done
done
stage_end sweeps

# ---- 3. transforms -----------------------------------------------------------------------------------------------
has_direct=0
"$bin" convert --help 2>&1 | grep -q -- '--direct' && has_direct=1
declare -A learn_note=()
for t in $targets; do
    for l in $lights; do
        for m in $methods; do
            key="${t}_${l}_$m"
            if [ "$m" = direct ]; then
                [ "$has_direct" = 1 ] || learn_note[$key]="not yet in this build (convert --direct)"
                continue
            fi
            extra=()
            # shellcheck disable=SC2206
            [ "$m" = svr ] && extra=($svr_args)
            stage "learn $m: ward -> $t, light $l"
            if ! "$bin" learn "$work/sweeps/ward_${t}_$l.csv" --method "$m" --threads 2 "${extra[@]}" \
                -o "$work/transforms/$key.mrt" >"$work/logs/learn_$key.log" 2>&1; then
                learn_note[$key]=$(grep -m1 'error' "$work/logs/learn_$key.log" | sed 's/^matremap learn: error: //')
                echo "   not applicable: ${learn_note[$key]}"
            fi
        done
    done
done
stage_end learn

# ---- 4. conversions ----------------------------------------------------------------------------------------------
declare -A extrapolated=()
ward_maps() { echo "diffuse=@$1/diffuse.exr specular=@$1/specular.exr alpha=@$1/alpha.exr"; }
for s in $sets; do
    mkdir -p "$work/convert/$s"
    for t in $targets; do
        for l in $lights; do
            for m in $methods; do
                key="${t}_${l}_$m" prefix="$work/convert/$s/${key}_"
                how=()
                if [ "$m" = direct ]; then
                    [ "$has_direct" = 1 ] || continue
                    case " $direct_targets " in *" $t "*) ;; *) continue ;; esac
                    how=(--direct --light "$l")
                else
                    [ -f "$work/transforms/$key.mrt" ] || continue
                    how=(--transform "$work/transforms/$key.mrt")
                fi
                # shellcheck disable=SC2046
                "$bin" convert --from ward --to "$t" $(ward_maps "$work/sets/$s") "${how[@]}" --threads 2 --json \
                    -o "$prefix" >"$work/logs/convert_${s}_$key.json" 2>"$work/logs/convert_${s}_$key.log"
                extrapolated[${s}_$key]=$(jq -r '(.flags.extrapolated_or_unconverged // 0) as $e
                    | (.texels // ((.width // 0) * (.height // 0))) as $n
                    | if $n > 0 then 100 * $e / $n else 0 end' "$work/logs/convert_${s}_$key.json" 2>/dev/null \
                    || echo 0)
            done
        done
    done
done
stage_end convert

# ---- 5. reports --------------------------------------------------------------------------------------------------
# The material groups of one set's report: the Ward source, then every remap as TARGET name=@map ...
declare -a labels=()
report_args() {
    local s=$1 d="$work/convert/$1"
    labels=()
    # shellcheck disable=SC2046
    args=(--label "ward (source)" ward $(ward_maps "$work/sets/$s"))
    for t in $targets; do
        for l in $lights; do
            for m in $methods; do
                local key="${t}_${l}_$m" maps=()
                for f in "$d/${key}_"*.exr; do
                    [ -f "$f" ] || continue
                    local p=${f##*/}
                    p=${p#"${key}_"}
                    maps+=("${p%.exr}=@$f")
                done
                [ ${#maps[@]} -gt 0 ] || continue
                args+=(-- --label "$t $m $l" "$t" "${maps[@]}")
                labels+=("$t $m $l")
            done
        done
    done
}
for s in $sets; do
    report_args "$s"
    stage "report $s: $((${#labels[@]} + 1)) materials x $rotations views at ${render_size}²"
    "$bin" report -o "$work/reports/$s" --mesh "$mesh" --camera paper --env "$probe" --rotations "$rotations" \
        --size "$render_size" --env-samples "$env_samples" --threads 2 --title "$s: Ward remapped (matsphere, Tabac)" \
        "${args[@]}" >"$work/logs/report_$s.txt" 2>"$work/logs/report_$s.log"
    tail -n 1 "$work/logs/report_$s.txt"
done
stage_end reports

# ---- 6. plots, table, contact sheets -----------------------------------------------------------------------------
step=$(awk -v n="$rotations" 'BEGIN { print 360 / n }')
# One data file per set x target: angle, then 1 - object SSIM of each method x light in columns (NaN where absent).
stage "plots and tables"
for s in $sets; do
    json="$work/reports/$s/index.html"
    json="$work/reports/$s/summary.json"
    for t in $targets; do
        dat="$work/plots/${s}_$t.dat" cols=() titles=()
        for m in $methods; do for l in $lights; do cols+=("$t $m $l"); titles+=("$m, $l"); done; done
        {
            printf '# angle'
            for c in "${cols[@]}"; do printf ' "%s"' "$c"; done
            echo
            for ((v = 0; v < rotations; v++)); do
                printf '%s' "$(awk -v v="$v" -v st="$step" 'BEGIN { print v * st }')"
                for c in "${cols[@]}"; do
                    jq -r --arg l "$c" --argjson v "$v" '[.materials[] | select(.label == $l)
                        | 1 - .object_ssim[$v]] | if length > 0 then .[0] | tostring else "NaN" end' "$json" |
                        tr '\n' ' ' | sed 's/^/ /'
                done
                echo
            done
        } >"$dat"
        # gnuplot: one line per method x light; colour by light (frontal red, 45° blue, as the paper's Fig. 23),
        # dash and point by method.
        plot=""
        i=2
        for m in $methods; do
            for l in $lights; do
                if [ "$(awk -v c="$i" 'NR > 1 && $c != "NaN" { n++ } END { print n + 0 }' "$dat")" -gt 0 ]; then
                    colour=$([ "$l" = frontal ] && echo "#c0392b" || echo "#2c6fbb")
                    dash=1 pt=7
                    case $m in svr) dash=2 pt=5 ;; mlp) dash=3 pt=9 ;; direct) dash=4 pt=13 ;; esac
                    plot+="${plot:+, }'$dat' using 1:$i with linespoints lc rgb '$colour' dt $dash pt $pt ps 0.6 "
                    plot+="title '$m, $l'"
                fi
                i=$((i + 1))
            done
        done
        [ -n "$plot" ] || continue
        gnuplot <<EOF
set terminal svg size 560,340 dynamic font "DejaVu Sans,11"
set output '$work/plots/${s}_$t.svg'
set title "$s: ward -> $t (matsphere, Tabac Plant)"
set xlabel "environment rotation (degrees)"
set ylabel "1 - object SSIM"
set xrange [0:360]
set xtics 0,60,360
set key outside right top
set grid ytics lc rgb "#dddddd"
set datafile missing "NaN"
plot $plot
EOF
    done
done

# The summary table: mean of 1 - object SSIM over the angles per set x target x method x light.
table="$work/table.md"
{
    echo "Measured by \`make evaluation-svbrdf\` on $(date -u +%Y-%m-%d), matremap $("$bin" --version | cut -d' ' -f2):"
    echo "sets at ${set_size}², rendered on matsphere.obj (paper camera) at ${render_size}² under the Tabac Plant probe"
    echo "turned in $rotations steps of ${step}° ($env_samples fixed directions + 40 about each mirror direction);"
    echo "**mean 1 − object SSIM over the $rotations angles** (lower is better; the best per set × target in bold);"
    echo "in brackets the share of texels outside the transform's training domain (flagged extrapolated)."
    echo
    header="| set | target | method |"
    rule="|---|---|---|"
    for l in $lights; do header+=" light $l |"; rule+="---:|"; done
    echo "$header"
    echo "$rule"
    for s in $sets; do
        json="$work/reports/$s/summary.json"
        for t in $targets; do
            best=$(jq -r --arg t "$t " '[.materials[] | select(.label | startswith($t)) | 1 - .mean_object_ssim]
                | min // empty' "$json")
            for m in $methods; do
                row="| $s | $t | $m |"
                for l in $lights; do
                    key="${t}_${l}_$m"
                    e=$(jq -r --arg lab "$t $m $l" '[.materials[] | select(.label == $lab) | 1 - .mean_object_ssim]
                        | .[0] // empty' "$json")
                    if [ -z "$e" ]; then
                        note=${learn_note[$key]:-not run}
                        [ -n "${learn_note[$key]:-}" ] && note="n/a"
                        row+=" $note |"
                    else
                        cell=$(awk -v e="$e" 'BEGIN { printf "%.4f", e }')
                        [ "$e" = "$best" ] && cell="**$cell**"
                        x=${extrapolated[${s}_$key]:-0}
                        row+=" $cell ($(awk -v x="$x" 'BEGIN { printf "%.1f", x }') %) |"
                    fi
                done
                echo "$row"
            done
        done
    done
    echo
    echo "Not applicable (the tool's own message):"
    echo
    for key in $(printf '%s\n' "${!learn_note[@]}" | sort); do
        echo "- \`${key//_/ }\`: ${learn_note[$key]}"
    done
    echo
    echo -n "Stage times (s, wall clock, 2 cores):"
    for k in sets sweeps learn convert reports; do echo -n " $k ${stage_seconds[$k]:-0},"; done
    echo " plots and tables $(($(date +%s) - stage_t0)); total $(($(date +%s) - started))."
} >"$table"

# Contact sheets: per set, the source and every remap at four angles, with each picture's object SSIM.
sheet="$work/index.html"
{
    echo '<!doctype html><html><head><meta charset="utf-8"><title>matremap: SVBRDF evaluation</title><style>'
    echo 'body{font-family:sans-serif;margin:1em} td{text-align:center;font-size:12px;padding:2px} img{width:128px}'
    echo 'th{font-size:12px;text-align:left}</style></head><body><h1>SVBRDF evaluation: Ward remapped</h1>'
    echo "<p>Each set's Ward source and every remap on the paper's material-test sphere under the Tabac Plant probe;"
    echo "object SSIM against the source under each picture. Full reports (every angle, SSIM maps, maps):"
    for s in $sets; do echo "<a href=\"reports/$s/index.html\">$s</a>"; done
    echo "; plots in <a href=\"plots/\">plots/</a>; <a href=\"table.md\">table.md</a>.</p>"
    quarter=$((rotations / 4))
    [ "$quarter" -gt 0 ] || quarter=1
    for s in $sets; do
        json="$work/reports/$s/summary.json"
        echo "<h2>$s</h2><table><tr><th>material</th>"
        for ((v = 0; v < rotations; v += quarter)); do
            echo "<th>$(awk -v v="$v" -v st="$step" 'BEGIN { print v * st }')°</th>"
        done
        echo "<th>mean SSIM</th></tr>"
        n=$(jq '.materials | length' "$json")
        for ((k = 0; k < n; k++)); do
            echo "<tr><th>$(jq -r --argjson k "$k" '.materials[$k].label' "$json")</th>"
            for ((v = 0; v < rotations; v += quarter)); do
                ssim=$(jq -r --argjson k "$k" --argjson v "$v" '(.materials[$k].object_ssim // [])[$v] // 1
                    | . * 10000 | round / 10000' \
                    "$json")
                echo "<td><img src=\"reports/$s/view${v}_material$k.png\"><br>$ssim</td>"
            done
            echo "<td>$(jq -r --argjson k "$k" '.materials[$k].mean_object_ssim // 1
                | . * 10000 | round / 10000' "$json")</td></tr>"
        done
        echo "</table>"
    done
    echo "</body></html>"
} >"$sheet"

if [ -z "$smoke" ]; then
    mkdir -p "$docs"
    # Small SVGs in docs/: gnuplot's output shrunk by make analyses' minifier (what it draws unchanged).
    for f in "$work"/plots/*.svg; do
        [ -f "$f" ] && awk -f "$root/scripts/analyses/svgmin.awk" "$f" >"$docs/${f##*/}"
    done
    replace_doc_section "$root/docs/evaluation-svbrdf.md" eval-svbrdf "$table" ||
        echo "evaluation-svbrdf: docs/evaluation-svbrdf.md has no eval-svbrdf markers: table left in $table" >&2
fi
stage "done: $sheet, $table"
cat "$table"
