#!/usr/bin/env bash
# make paper: reproduces the paper's Appendix "A. Parametric Fits" and its figures 18 and 19 (Sztrajman et al. 2019,
# sections 5-7) with `matremap sweep`, `learn`, `convert`, `render` and `ssim`: sweeps and parametric fits of the five
# Appendix pairs under both fit lights, our curves beside the paper's printed ones, the Fig. 19 extrapolation test
# (SVR and parametric trained on specular <= 0.1, applied to a coloured texture beyond it), and the Fig. 18 chain
# Blender-Ward -> Mitsuba-Ward -> Mitsuba-GGX -> Cycles-GGX against a direct transform on a real texture set.
# docs/paper-reproduction.md explains every step and discusses the numbers; this script writes the plots and
# pictures into docs/paper/ and splices its tables into that document between <!-- NAME:begin/end --> markers.
#
# Usage: scripts/paper-appendix.sh [BUILD] [--keep]
#   BUILD   build directory (default build); everything else goes into BUILD/paper/
#   --keep  reuse the finished sweeps of a previous run (`matremap sweep --resume`); without it BUILD/paper/ starts
#           empty
# Environment: PAPER_THREADS (default 2), PAPER_SIZE (fit-scene side, default 128: twice the tool's default, so that
#   lobes down to alpha ~ 0.04 are resolved; docs/paper-reproduction.md says what 64 changes),
#   PAPER_ROUGHNESS (roughness values per sweep, default 30: the paper's section 5.2), PAPER_SPECULAR (specular
#   values per sweep, default 4: the parametric form is linear in it), PAPER_RENDER (picture side, default 256).
# Needs gnuplot and oiiotool (make deps). About 4-5 minutes on 2 cores (248-286 s measured: the 13 sweeps 100 s,
# the SVR of Fig. 19 75 s, the renders of the material sphere under the probe 60-85 s).
set -euo pipefail
build=build keep=
for arg in "$@"; do
    case $arg in
        --keep) keep=--keep ;;
        -*) echo "paper: error: unknown option '$arg' (usage: scripts/paper-appendix.sh [BUILD] [--keep])" >&2; exit 1 ;;
        *) build=$arg ;;
    esac
done
root=$(cd "$(dirname "$0")/.." && pwd)
bin="$root/$build/bin/matremap"
helpers="$root/scripts/paper"
cols_awk="$root/scripts/analyses/cols.awk"
svgmin="$root/scripts/analyses/svgmin.awk"
work="$root/$build/paper"
docs="$root/docs/paper"
doc="$root/docs/paper-reproduction.md"
assets="$root/../shared/assets"
threads=${PAPER_THREADS:-2}
size=${PAPER_SIZE:-128}
nr=${PAPER_ROUGHNESS:-30}
ns=${PAPER_SPECULAR:-4}
picture_size=${PAPER_RENDER:-256}
export LC_ALL=C
source "$root/scripts/lib/evaluation.sh"

die() { echo "paper: error: $*" >&2; exit 1; }
[ -x "$bin" ] || die "$bin is missing (run make first)"
command -v gnuplot >/dev/null || die "gnuplot is missing (make deps)"
command -v oiiotool >/dev/null || die "oiiotool is missing (make deps)"
[ -d "$assets/hdri" ] || die "$assets is missing (the shared test data: ../shared/assets beside the project)"
if [ "$keep" != "--keep" ]; then rm -rf "$work"; fi
mkdir -p "$work"/{sweeps,learn,plots,chain,direct,fig18,fig19} "$docs"
log="$work/log.txt"
: > "$log"
t_start=$SECONDS
step=0
say() { echo "$*" | tee -a "$log"; }
progress() { step=$((step + 1)); say "paper: [$step] $* ($((SECONDS - t_start)) s)"; }
cols() { local spec=$1; shift; awk -v cols="$spec" -f "$cols_awk" "$@"; }
svg() { awk -f "$svgmin" "$1" > "$2"; } # shrink a gnuplot SVG into docs/paper
mesh="$assets/paper/matsphere.obj"
env="$(env_file tabac)"

# ---- 1. Sweeps -----------------------------------------------------------------------------------------------------
# The five Appendix pairs, diffuse held at 0 on both sides (the paper's sweeps are specular only; the diffuse is
# carried by the ratio of the Lambertian lobes), nr roughness values x ns grey speculars, uniformly spaced as the
# paper's section 5.2 and over the authors' published Ward -> AS sweep's domain (roughness 0.005 .. 0.99, specular
# 0.02 .. 0.3; Blender Internal's slope stops at 0.4). Cycles' slider is swept so that alpha = roughness^2 covers
# the same 0.005 .. 0.99. Each pair under the frontal light (which the authors' data turns out to match) and 45
# degrees (the paper's section 4.1 and our default).
# pair: NAME SOURCE SRC_ROUGH SRC_SPEC TARGET TGT_ROUGH TGT_SPEC ROUGH_LO ROUGH_HI SQ_SRC SQ_TGT TITLE
pairs=(
    "ward_bward ward alpha specular blender-ward rms specular 0.005 0.4 0 0 Mitsuba_Ward_->_Blender_Internal_Ward"
    "cycles_as cycles-ggx roughness f0 as alpha f0 0.070710678 0.994987437 1 0 Cycles_GGX_->_Mitsuba_AS"
    "ggx_cycles ggx alpha f0 cycles-ggx roughness f0 0.005 0.99 0 1 Mitsuba_GGX_->_Cycles_GGX"
    "ward_ggx ward alpha specular ggx alpha f0 0.005 0.99 0 0 Mitsuba_Ward_->_Mitsuba_GGX"
    "ward_as ward alpha specular as alpha f0 0.005 0.99 0 0 Mitsuba_Ward_->_Mitsuba_AS"
)
# The paper's Appendix, in alpha units: roughness "c0 .. c4" and slope "c0 .. c5" (k = c0 + c1 e^(-c2 a) +
# c3 e^(-c4 a^2) + c5 / a). The Ward -> AS polynomial lacks the sign of its cubic term: '-' (pp2 reads it '+').
declare -A paper_poly paper_k
paper_poly[ward_bward]="0 1.01 -0.13 -0.41 0.24";     paper_k[ward_bward]="-43.4 43.6 0.0017 0.115 2.21 0"
paper_poly[cycles_as]="0 0.78 1.31 -1.86 0.61";       paper_k[cycles_as]="-0.067 1.43 0.692 -0.547 6.4 0.0002"
paper_poly[ggx_cycles]="0 0.98 0.09 -0.14 0.066";     paper_k[ggx_cycles]="1.05 -0.187 23.45 0.036 116.4 0"
paper_poly[ward_ggx]="0 1.135 -0.766 0.102 1.08";     paper_k[ward_ggx]="-944 944.82 0.00046 0.476 4.786 0"
paper_poly[ward_as]="0 1.04 -0.388 -0.332 0.25";      paper_k[ward_as]="-512.13 512.75 0.00057 0.398 3.12 0"
sweep_spec="0.02:0.3:$ns"

# sweep NAME LIGHT ARGS...: one resumable sweep into sweeps/NAME_LIGHT.csv, its summary line into the log. The
# target's diffuse is held at 0 (--hold), not only started there: fitted freely, AS spends a diffuse lobe of up to 1 %
# of F0 on imitating GGX's long tails, and the specular fit is then no longer the paper's two-stage one.
sweep() {
    local name=$1 light=$2; shift 2
    "$bin" sweep "$@" --hold diffuse --size "$size" --threads "$threads" --light "$light" \
        -o "$work/sweeps/${name}_$light.csv" \
        --resume 2>&1 | tee -a "$log" | sed 's/^/    /'
}
for p in "${pairs[@]}"; do
    read -r name src sr ss tgt tr ts lo hi sqs sqt title <<< "$p"
    for light in frontal 45; do
        progress "sweep ${title//_/ } (${light/#45/45°} light): $nr x $ns remaps at ${size}²"
        sweep "$name" "$light" --from "$src" diffuse=0 --to "$tgt" diffuse=0 --grid "$sr=$lo:$hi:$nr" "$ss=$sweep_spec"
    done
done
# Figure 18 needs Blender-Ward -> Mitsuba-Ward (the chain's first hop) and Blender-Ward -> Cycles-GGX (the direct
# transform it is judged against); figure 19 Ward -> AS over a limited specular range, 0.01 .. 0.1. 45 degrees.
progress "sweep Blender Internal Ward -> Mitsuba Ward (45° light)"
sweep bward_ward 45 --from blender-ward diffuse=0 --to ward diffuse=0 --grid "rms=0.005:0.4:$nr" "specular=$sweep_spec"
progress "sweep Blender Internal Ward -> Cycles GGX (45° light)"
sweep bward_cycles 45 --from blender-ward diffuse=0 --to cycles-ggx diffuse=0 --grid "rms=0.005:0.4:$nr" \
    "specular=$sweep_spec"
progress "sweep Mitsuba Ward -> Mitsuba AS, specular 0.01 .. 0.1 only (45° light; figure 19)"
sweep ward_as_low 45 --from ward diffuse=0 --to as diffuse=0 --grid "alpha=0.005:0.99:$nr" "specular=0.01:0.1:$ns"

# ---- 2. Parametric fits, cross sections, comparison with the Appendix -----------------------------------------------
# learn NAME LIGHT [METHOD]: learn/NAME_LIGHT[_METHOD].mrt, its --json summary beside it, --plots into plots/.
learn() {
    local name=$1 light=$2 method=${3:-parametric} tag=${1}_$2
    [ "$method" = parametric ] || tag=${tag}_$method
    "$bin" learn "$work/sweeps/${name}_$light.csv" --method "$method" --threads "$threads" \
        -o "$work/learn/$tag.mrt" --plots "$work/plots/$tag" --json > "$work/learn/$tag.json" 2>> "$log"
}
# json_list FILE KEY: the numbers of a JSON array as words
json_list() { sed -n "s/.*\"$2\": \[\([^]]*\)\].*/\1/p" "$1" | tr -d ','; }
json_rmse() { sed -n 's/.*"validation_rmse": {\([^}]*\)}.*/\1/p' "$1" | sed 's/"[a-z_0-9]*": //g; s/,//g'; }
# pad6 WORDS: a slope's coefficients with c5 = 0 when the fit has no 1/alpha term
pad6() { set -- $1; if [ $# -lt 6 ]; then echo "$@" 0; else echo "$@"; fi; }

table="$work/appendix_table.md"
diffs="$work/appendix_curves.md"
: > "$table"
{
    echo -n "| pair | curve | ours, frontal, against the paper: max \\|Δ\\| on α ≤ 0.5 / on the domain (mean) "
    echo "| ours, 45°, against the paper: the same | ours, frontal against 45°: max \\|Δ\\| |"
    echo "|---|---|---:|---:|---:|"
} > "$diffs"
for p in "${pairs[@]}"; do
    read -r name src sr ss tgt tr ts lo hi sqs sqt title <<< "$p"
    progress "learn ${title//_/ } (parametric, both lights) and compare with the Appendix"
    for light in frontal 45; do learn "$name" "$light"; done
    # rows and per-roughness slopes in alpha units, light tagged 0 (frontal) or 45
    : > "$work/plots/${name}_rows.dat"
    : > "$work/plots/${name}_slopes.dat"
    for light in frontal 45; do
        tag=$([ "$light" = frontal ] && echo 0 || echo 45)
        # one point per roughness (the target roughness of its rows' mean: they differ in the 5th digit)
        cols "$sr,mean:$ss,to_$tr,mean:to_$ts" "$work/sweeps/${name}_$light.csv" |
            awk -v t="$tag" -v sqs="$sqs" -v sqt="$sqt" '
                function out() { if (n) { x = sqs ? a * a : a; y = sum / n; print t, x, sqt ? y * y : y } }
                $1 != a { out(); a = $1; sum = 0; n = 0 } { sum += $3; n++ } END { out() }' \
                >> "$work/plots/${name}_rows.dat"
        cols "$sr,mean:$ss,to_$tr,mean:to_$ts" "$work/sweeps/${name}_$light.csv" |
            awk -v sq_src="$sqs" -v sq_tgt="$sqt" -f "$helpers/slopes.awk" |
            awk -v t="$tag" '{ print t, $1, $2 }' >> "$work/plots/${name}_slopes.dat"
    done
    jf="$work/learn/${name}_frontal.json" j45="$work/learn/${name}_45.json"
    of=$(json_list "$jf" roughness) ok=$(pad6 "$(json_list "$jf" slope)")
    ff=$(json_list "$j45" roughness) fk=$(pad6 "$(json_list "$j45" slope)")
    pp=${paper_poly[$name]} pk=${paper_k[$name]}
    pp2="" ppl2=""
    if [ "$name" = ward_as ]; then pp2="0 1.04 -0.388 0.332 0.25"; ppl2="paper, cubic term read +"; fi
    alo=$(awk -v l="$lo" -v s="$sqs" 'BEGIN { print s ? l * l : l }')
    ahi=$(awk -v h="$hi" -v s="$sqs" 'BEGIN { print s ? h * h : h }')
    xl="source α ($src)" yl="target α ($tgt)"
    [ "$sqs" = 0 ] || xl="source α ($src: roughness²)"
    [ "$sqt" = 0 ] || yl="target α ($tgt: roughness²)"
    LC_ALL=C.UTF-8 gnuplot -e "out='$work/plots/${name}_compare.svg'; ttl='${title//_/ }: ours and the Appendix'" \
        -e "xl='$xl'; yl='$yl'; lo=$alo; hi=$ahi; pp='$pp'; pk='$pk'; pp2='$pp2'; ppl2='$ppl2'" \
        -e "of='$of'; ok='$ok'; ff='$ff'; fk='$fk'; sqs=$sqs; sqt=$sqt" \
        -e "dr='$work/plots/${name}_rows.dat'; dk='$work/plots/${name}_slopes.dat'" "$helpers/compare.gp"
    svg "$work/plots/${name}_compare.svg" "$docs/${name}_compare.svg"
    # the cross sections (learn --plots) stay in plots/; the reference pair's go into the docs
    if [ "$name" = ward_as ]; then
        for light in frontal 45; do
            svg "$work/plots/${name}_$light/specular.svg" "$docs/${name}_${light}_specular.svg"
        done
    fi
    # the coefficient table: the paper's row, then ours (a4 .. a1 of the polynomial, c0 .. c5 of k, held-out RMSE)
    heading="**${title//_/ }**"
    [ "$sqs$sqt" = 00 ] || heading+=" (our coefficients in Cycles' slider roughness r, α = r²; the paper's in α)"
    paper_row="paper (printed)"
    [ "$name" != ward_as ] || paper_row="paper (printed, cubic sign restored)"
    {
        echo "$heading"
        echo
        echo "| fit | a1 | a2 | a3 | a4 | c0 | c1 | c2 | c3 | c4 | c5 | held-out RMSE: roughness, specular |"
        echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"
        echo "$pp $pk" | awk -v n="$paper_row" \
            '{ printf "| %s |", n; for (i = 2; i <= 11; i++) printf " %.4g |", $i; print " – |" }'
        for light in frontal 45; do
            j="$work/learn/${name}_$light.json"
            echo "$(json_list "$j" roughness) $(pad6 "$(json_list "$j" slope)") $(json_rmse "$j")" |
                awk -v n="ours, ${light/#45/45°}" '{ printf "| %s |", n; for (i = 2; i <= 11; i++) printf " %.4g |", $i;
                                           printf " %.2g, %.2g |\n", $12, $13 }'
        done
        echo
    } >> "$table"
    # curve differences over the domain, in alpha units: ours (each light) against the paper, and frontal vs 45
    awk -v lo="$alo" -v hi="$ahi" -v pp="$pp" -v pk="$pk" -v of="$of" -v ok="$ok" -v ff="$ff" -v fk="$fk" \
        -v sqs="$sqs" -v sqt="$sqt" -v title="${title//_/ }" -f "$helpers/curves.awk" >> "$diffs"
done

# ---- 3. Figure 19: SVR and parametric beyond their training range ---------------------------------------------------
# The texture: "scratched gold" made from a real map, the FloppyDisk's spec-gloss texture (CC-BY-SA 4.0, ../shared/
# assets MANIFEST.md): the 512² window at (1200, 1300) of its 2048² map (the metal hub and the grimy shell around it),
# filtered to picture_size, its red channel v (8-bit code / 255) giving the Ward specular 0.6 v (1, 0.766, 0.336)
# (gold's colour) and its glossiness g the Ward alpha 0.42 - 0.4 g; 60 scratches (straight lines from a seeded
# Park-Miller generator, so any awk draws the same) set alpha to at least 0.3 and dim the specular by 30 %. Diffuse 0
# (a metal).
progress "figure 19: the scratched-gold texture"
f19="$work/fig19"
unassoc=(--iconfig oiio:UnassociatedAlpha 1)
floppy="$assets/specgloss/FloppyDisk-sketchfab/textures"
ps=$picture_size
oiiotool "${unassoc[@]}" "$floppy/material_0_specularGlossiness.png" --cut 512x512+1200+1300 \
    --resize:filter=triangle "${ps}x$ps" -d float -o "$f19/crop.exr"
lines=$(awk -v n=60 -v s="$ps" 'function r() { x = (16807 * x) % 2147483647; return x / 2147483647 }
    BEGIN { x = 19
            for (i = 0; i < n; i++) {
                a = r() * s; b = r() * s; t = (r() - 0.5) * 1.2 + 0.6; l = s * (0.08 + 0.35 * r())
                printf " --line:color=1,1,1 %d,%d,%d,%d", a, b, a + l * cos(t), b + l * sin(t) } }')
# shellcheck disable=SC2086 # $lines is a list of oiiotool arguments
oiiotool --pattern constant:color=0,0,0 "${ps}x$ps" 3 $lines -d float -o "$f19/scratches.exr"
oiiotool "$f19/crop.exr" --ch R,R,R --mulc 0.6 --mulc 1,0.766,0.336 "$f19/scratches.exr" --mulc -0.3 --addc 1 --mul \
    -d float -o "$f19/ward_specular.exr"
oiiotool "$f19/crop.exr" --ch A --mulc -0.4 --addc 0.42 "$f19/scratches.exr" --ch R --mulc 0.3 --max \
    -d float -o "$f19/ward_alpha.exr"
progress "figure 19: learn Ward -> AS on specular <= 0.1 (parametric, then SVR: a minute or two)"
learn ward_as_low 45
learn ward_as_low 45 svr
# fig19_tag METHOD: the transform of a Fig. 19 method: parametric and svr trained on specular <= 0.1; "full", the
# parametric fit of section 2 (specular 0.02 .. 0.3, 45 degrees), shows what the model change alone costs.
fig19_tag() {
    case $1 in parametric) echo ward_as_low_45 ;; svr) echo ward_as_low_45_svr ;; full) echo ward_as_45 ;; esac
}
for m in parametric svr full; do
    tag=$(fig19_tag "$m")
    [ "$m" = full ] || svg "$work/plots/$tag/specular.svg" "$docs/fig19_${m}_specular.svg"
    "$bin" convert --from ward --to as "specular=$f19/ward_specular.exr" "alpha=$f19/ward_alpha.exr" diffuse=0 \
        --transform "$work/learn/$tag.mrt" --threads "$threads" -o "$f19/${m}_" --json > "$f19/${m}_convert.json" \
        2>> "$log"
done

# render NAME OUT MODEL PARAMS...: the paper's material sphere under the Tabac Plant probe (scaled to a mean luminance
# of 0.5, as docs/evaluation.md), the paper's camera, picture_size², linear EXR; the coverage mask once.
env_scale=$(oiiotool --stats "$env" 2>/dev/null |
            awk '/Stats Avg/ { print 0.5 / (0.2126 * $3 + 0.7152 * $4 + 0.0722 * $5); exit }')
mask="$work/mask.exr"
render() {
    local out=$1; shift
    local extra=()
    [ -f "$mask" ] || extra=(--mask "$mask")
    "$bin" render "$@" --mesh "$mesh" --camera paper --env "$env" --env-scale "$env_scale" --size "$ps" \
        --threads "$threads" "${extra[@]}" -o "$out" 2>> "$log"
}
# exposure_of EXR: the exposure that brings the object's mean luminance to 0.18 (mid grey)
exposure_of() {
    local l c
    l=$(oiiotool --stats "$1" 2>/dev/null | awk '/Stats Avg/ { print 0.2126 * $3 + 0.7152 * $4 + 0.0722 * $5; exit }')
    c=$(oiiotool --stats "$mask" 2>/dev/null | awk '/Stats Avg/ { print $3; exit }')
    awk -v l="$l" -v c="$c" 'BEGIN { print 0.18 * c / l }'
}
# ssim_of A B EXPOSURE MAP: object SSIM of B against A
ssim_of() {
    "$bin" ssim "$1" "$2" --mask "$mask" --exposure "$3" --map "$4" --json |
        sed -n 's/.*"object_ssim": \([0-9.e-]*\).*/\1/p'
}
display() { oiiotool "$1" --mulc "$2" --colorconvert linear sRGB --ch R,G,B -d uint8 -o "$3"; }
# flag_counts CONVERT.json: "TEXELS EXTRAPOLATED" from `matremap convert --json`
flag_counts() { sed -n 's/.*"texels": \([0-9]*\).*"extrapolated_or_unconverged": \([0-9]*\).*/\1 \2/p' "$1"; }

progress "figure 19: renders (source Ward; AS by parametric, SVR and the full-range parametric)"
render "$f19/ward.exr" ward diffuse=0 "specular=@$f19/ward_specular.exr" "alpha=@$f19/ward_alpha.exr"
for m in parametric svr full; do
    render "$f19/$m.exr" as diffuse=0 "f0=@$f19/${m}_f0.exr" "alpha=@$f19/${m}_alpha.exr"
done
e19=$(exposure_of "$f19/ward.exr")
fig19="$work/fig19_table.md"
{
    echo -n "| transform | texels flagged extrapolated | angle between input and output specular RGB: mean / "
    echo -n "95th percentile (≤) / max | mean \\|Δ(r/g)\\| / (r/g) | mean \\|Δ(b/g)\\| / (b/g) "
    echo "| object SSIM against the Ward source |"
    echo "|---|---:|---:|---:|---:|---:|"
    for m in parametric svr full; do
        read -r n ex <<< "$(flag_counts "$f19/${m}_convert.json")"
        chroma=$(paste <(oiiotool --dumpdata "$f19/ward_specular.exr") <(oiiotool --dumpdata "$f19/${m}_f0.exr") |
                 awk -f "$helpers/chroma.awk")
        s=$(ssim_of "$f19/ward.exr" "$f19/$m.exr" "$e19" "$f19/ssim_$m.png")
        case $m in
            parametric) label="parametric, specular ≤ 0.1" ;;
            svr) label="SVR, specular ≤ 0.1" ;;
            full) label="parametric, specular 0.02-0.3 (section 2's fit)" ;;
        esac
        echo "$chroma" | awk -v m="$label" -v n="$n" -v ex="$ex" -v s="$s" \
            '{ printf "| %s | %.1f %% | %.3g° / %.2f° / %.3g° | %.3g | %.3g | %.4f |\n",
                      m, 100 * ex / n, $4, $6, $8, $10, $12, s }'
    done
} > "$fig19"
for n in ward parametric svr; do display "$f19/$n.exr" "$e19" "$f19/$n.png"; done
oiiotool "$f19/ward.png" "$f19/parametric.png" "$f19/svr.png" --mosaic:pad=4 3x1 -o "$docs/fig19_renders.jpg"
oiiotool "$f19/ward_specular.exr" --colorconvert linear sRGB -d uint8 -o "$f19/specular.png"
oiiotool "$f19/parametric_f0.exr" --colorconvert linear sRGB -d uint8 -o "$f19/parametric_f0.png"
oiiotool "$f19/svr_f0.exr" --colorconvert linear sRGB -d uint8 -o "$f19/svr_f0.png"
oiiotool "$f19/specular.png" "$f19/parametric_f0.png" "$f19/svr_f0.png" --mosaic:pad=4 3x1 -o "$docs/fig19_maps.jpg"

# ---- 4. Figure 18: the chain against a direct transform -------------------------------------------------------------
# A real SVBRDF as Blender Internal Ward parameters: the FloppyDisk's spec-gloss set, filtered to 512²: diffuse =
# its diffuse albedo (sRGB-decoded) / pi (Blender Internal's Lambert has no 1/pi), specular = its specular colour
# (sRGB-decoded), rms = (1 - glossiness)², the spec-gloss model's GGX alpha (Ward's alpha matches GGX's for glossy
# lobes), clamped into Blender's [0.001, 0.4].
progress "figure 18: the FloppyDisk set as Blender Internal Ward maps"
f18="$work/fig18"
oiiotool "${unassoc[@]}" "$floppy/material_0_diffuse.png" --ch R,G,B --resize:filter=triangle 512x512 \
    --colorconvert sRGB linear --mulc 0.318309886 -d float -o "$f18/bward_diffuse.exr"
oiiotool "${unassoc[@]}" "$floppy/material_0_specularGlossiness.png" --resize:filter=triangle 512x512 -d float \
    -o "$f18/sg.exr"
oiiotool "$f18/sg.exr" --ch R,G,B --colorconvert sRGB linear -d float -o "$f18/bward_specular.exr"
oiiotool "$f18/sg.exr" --ch A --mulc -1 --addc 1 --powc 2 --clamp:min=0.001:max=0.4 -d float -o "$f18/bward_rms.exr"
progress "figure 18: learn Blender-Ward -> Mitsuba-Ward and Blender-Ward -> Cycles-GGX; convert by chain and direct"
learn bward_ward 45
learn bward_cycles 45
cp "$work/learn/bward_ward_45.mrt" "$work/learn/ward_ggx_45.mrt" "$work/learn/ggx_cycles_45.mrt" "$work/chain/"
cp "$work/learn/bward_cycles_45.mrt" "$work/direct/"
maps=("diffuse=$f18/bward_diffuse.exr" "specular=$f18/bward_specular.exr" "rms=$f18/bward_rms.exr")
"$bin" convert --from blender-ward --to cycles-ggx "${maps[@]}" --transforms "$work/chain" --via ward,ggx \
    --threads "$threads" -o "$f18/chain_" --json > "$f18/chain_convert.json" 2>> "$log"
"$bin" convert --from blender-ward --to cycles-ggx "${maps[@]}" --transforms "$work/direct" \
    --threads "$threads" -o "$f18/direct_" --json > "$f18/direct_convert.json" 2>> "$log"
# the reference: no regression, every distinct texel remapped by the optimiser in the transforms' own fit scene
progress "figure 18: convert --direct (every distinct texel remapped; a few minutes)"
"$bin" convert --from blender-ward --to cycles-ggx "${maps[@]}" --direct --size "$size" --light 45 \
    --threads "$threads" -o "$f18/ref_" --json > "$f18/ref_convert.json" 2>> "$log"
# the intermediate hops, for the pictures: Blender-Ward -> Mitsuba-Ward, then -> Mitsuba-GGX
"$bin" convert --from blender-ward --to ward "${maps[@]}" --transform "$work/learn/bward_ward_45.mrt" \
    --threads "$threads" -o "$f18/ward_" 2>> "$log" >/dev/null
"$bin" convert --from ward --to ggx "diffuse=$f18/ward_diffuse.exr" "specular=$f18/ward_specular.exr" \
    "alpha=$f18/ward_alpha.exr" --transform "$work/learn/ward_ggx_45.mrt" --threads "$threads" -o "$f18/ggx_" \
    2>> "$log" >/dev/null
progress "figure 18: renders (Blender-Ward, Mitsuba-Ward, Mitsuba-GGX, Cycles-GGX by chain and direct)"
render "$f18/bward.exr" blender-ward "diffuse=@${maps[0]#*=}" "specular=@${maps[1]#*=}" "rms=@${maps[2]#*=}"
render "$f18/ward.exr" ward "diffuse=@$f18/ward_diffuse.exr" "specular=@$f18/ward_specular.exr" \
    "alpha=@$f18/ward_alpha.exr"
render "$f18/ggx.exr" ggx "diffuse=@$f18/ggx_diffuse.exr" "f0=@$f18/ggx_f0.exr" "alpha=@$f18/ggx_alpha.exr"
for m in chain direct ref; do
    render "$f18/$m.exr" cycles-ggx "diffuse=@$f18/${m}_diffuse.exr" "f0=@$f18/${m}_f0.exr" \
        "roughness=@$f18/${m}_roughness.exr"
done
e18=$(exposure_of "$f18/bward.exr")
fig18="$work/fig18_table.md"
{
    echo -n "| result | hops | texels flagged | object SSIM against Blender-Ward "
    echo "| against the direct transform | against \`--direct\` |"
    echo "|---|---:|---:|---:|---:|---:|"
    for m in ward ggx chain direct ref; do
        s=$(ssim_of "$f18/bward.exr" "$f18/$m.exr" "$e18" "$f18/ssim_$m.png")
        d=$(ssim_of "$f18/direct.exr" "$f18/$m.exr" "$e18" "$f18/ssim_direct_$m.png")
        r=$(ssim_of "$f18/ref.exr" "$f18/$m.exr" "$e18" "$f18/ssim_ref_$m.png")
        case $m in
            ward) label="Mitsuba-Ward (hop 1)"; hops=1; ex="–" ;;
            ggx) label="Mitsuba-GGX (hops 1-2)"; hops=2; ex="–" ;;
            ref) label="Cycles-GGX, \`--direct\` (per-texel remaps; flagged: not converged)"; hops="–"
                 ex=$(flag_counts "$f18/${m}_convert.json" | awk '{ printf "%.1f %%", 100 * $2 / $1 }') ;;
            *) label="Cycles-GGX, $m"; hops=$([ "$m" = chain ] && echo 3 || echo 1)
               ex=$(flag_counts "$f18/${m}_convert.json" | awk '{ printf "%.1f %%", 100 * $2 / $1 }') ;;
        esac
        echo "| $label | $hops | $ex | $(printf %.4f "$s") | $(printf %.4f "$d") | $(printf %.4f "$r") |"
    done
} > "$fig18"
params=$(paste <(oiiotool --dumpdata "$f18/chain_roughness.exr") <(oiiotool --dumpdata "$f18/direct_roughness.exr") \
               <(oiiotool --dumpdata "$f18/chain_f0.exr") <(oiiotool --dumpdata "$f18/direct_f0.exr") |
         awk -f "$helpers/params.awk")
echo "$params" | awk '{ printf "\nChain against direct, texel by texel (512² maps): Cycles roughness mean |Δ| %.4g " \
                             "(max %.4g), as alpha mean |Δ| %.4g; F0 mean relative |Δ| %.3g %% (max %.3g %%).\n",
                             $4, $6, $8, 100 * $10, 100 * $12 }' >> "$fig18"
for m in chain direct; do
    params=$(paste <(oiiotool --dumpdata "$f18/${m}_roughness.exr") <(oiiotool --dumpdata "$f18/ref_roughness.exr") \
                   <(oiiotool --dumpdata "$f18/${m}_f0.exr") <(oiiotool --dumpdata "$f18/ref_f0.exr") |
             awk -f "$helpers/params.awk")
    echo "$params" | awk -v m="$m" '{ printf "\nThe %s result against `--direct`, texel by texel: Cycles roughness mean " \
                                     "|Δ| %.4g (max %.4g); F0 mean relative |Δ| %.3g %% (max %.3g %%).\n",
                                     m == "chain" ? "chain'"'"'s" : "direct transform'"'"'s", $4, $6, 100 * $10, 100 * $12 }' \
        >> "$fig18"
done
for n in bward ward ggx chain direct; do display "$f18/$n.exr" "$e18" "$f18/$n.png"; done
oiiotool "$f18/bward.png" "$f18/ward.png" "$f18/ggx.png" "$f18/chain.png" "$f18/direct.png" "$f18/ssim_chain.png" \
    --ch R,G,B --mosaic:pad=4 6x1 --attrib Compression jpeg:85 -o "$docs/fig18_renders.jpg"

# ---- 5. Into the document -----------------------------------------------------------------------------------------
progress "tables into docs/paper-reproduction.md"
{
    echo "Run of $(date -u +%Y-%m-%d): $("$bin" --version 2>/dev/null | head -1), fit scene ${size}²," \
         "$nr roughness x $ns specular values per sweep, $threads threads, $(nproc) cores, $((SECONDS - t_start)) s."
    echo
    grep -h "is complete" "$log" | sed 's/^matremap sweep: /- /; s/ in [0-9.]* s (.*threads);/;/' |
        sed "s|$work/sweeps/||"
} > "$work/run.md"
if [ -f "$doc" ]; then
    # the run's line describes fresh sweeps: a --keep run (same sweeps, the same tables) leaves it as it is
    [ "$keep" = --keep ] || splice_table "$doc" run "$work/run.md" || true
    splice_table "$doc" appendix-coefficients "$table" || true
    splice_table "$doc" appendix-curves "$diffs" || true
    splice_table "$doc" fig19 "$fig19" || true
    splice_table "$doc" fig18 "$fig18" || true
fi
say "paper: done in $((SECONDS - t_start)) s: tables in $work/*.md (spliced into docs/paper-reproduction.md)," \
    "plots and pictures in docs/paper/"
