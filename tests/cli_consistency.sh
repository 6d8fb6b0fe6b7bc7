#!/usr/bin/env bash
# What every command shares (issue 26): outputs in folders that do not exist yet are made (nested) before any work,
# and a folder that cannot be made is exit 2 naming it; one -o PREFIX rule; `help CMD` = `CMD --help`; a hint when
# a value that looks like a file lacks its '@'; render takes a glTF asset as report does; --json on every command
# that prints results; one wording for unknown options; every message starts "matremap CMD: ". Ends with
# "N passed, N failed".
set -u
bin="${MR_BUILD:-build}/bin/matremap"
bin=$(cd "$(dirname "$bin")" && pwd)/$(basename "$bin")
shared="${MR_SHARED:-$(cd "$(dirname "$0")/../.." && pwd)/shared}"
source "$(dirname "$0")/lib/cli_harness.sh"

json() { # EXPRESSION over d, the JSON object in $tmp/out
    python3 -c "import json, sys; d = json.load(open(sys.argv[1])); print($1)" "$tmp/out" 2>/dev/null
}
duck="$shared/assets/specgloss/Duck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Duck.gltf"
bottle="$shared/assets/metalrough/WaterBottle/glTF/WaterBottle.gltf"
studio="$shared/assets/hdri/studio_small_03_1k.hdr"

# ---- inputs the file-writing commands need (made in $tmp/in) ----------------------------------------------------
mkdir -p "$tmp/in"
oiiotool --pattern constant:color=0.1 16x16 1 -d float -o "$tmp/in/rough.exr" >/dev/null 2>&1
"$bin" render lambert --size 16 -o "$tmp/in/a.exr" 2>/dev/null
"$bin" sweep --from ward diffuse=0 --to ggx diffuse=0 --grid alpha=0.03:0.4:4:log specular=0.03:0.25:3 --size 16 \
    --threads 2 -o "$tmp/in/wg.csv" 2>/dev/null
"$bin" learn "$tmp/in/wg.csv" -o "$tmp/in/wg.mrt" >/dev/null 2>&1
"$bin" sweep --from ggx-metallic alpha=0.2 --to ggx-metallic alpha=0.2 --hold alpha --random 20 --size 16 \
    --threads 2 -o "$tmp/in/on.csv" 2>/dev/null
for k in 0 1; do
    "$bin" sweep --from ward diffuse=0 --to ggx diffuse=0 --grid alpha=0.03:0.4:4:log --size 16 --threads 2 \
        --shard $k/2 -o "$tmp/in/s$k.csv" 2>/dev/null
done
check "the inputs are made" test -s "$tmp/in/rough.exr" -a -s "$tmp/in/wg.mrt" -a -s "$tmp/in/on.csv" \
    -a -s "$tmp/in/s1.csv"

# ---- A. missing output folders: made, nested, before any work ---------------------------------------------------
# Each command writes into a/b/c/... of an empty folder; then the same with a regular file where a folder must be:
# exit 2 naming that file, and nothing written.
run_cmd() { # NAME OUT: the command NAME writing under folder OUT (the file(s) it writes echoed by `outputs`)
    local o=$2
    case $1 in
    render) "$bin" render gltf --size 16 -o "$o/a/b/c/x.png" --mask "$o/m/n/mask.png" ;;
    ssim) "$bin" ssim "$tmp/in/a.exr" "$tmp/in/a.exr" --map "$o/a/b/c/map.png" ;;
    remap) "$bin" remap --from ggx alpha=0.2 --to ward --size 16 --images "$o/a/b/c/fit" ;;
    spec2metal) "$bin" spec2metal --diffuse 0.5 --specular 0.04 --glossiness 0.5 --method weighted -o "$o/a/b/c/s" ;;
    metal2spec) "$bin" metal2spec --basecolor 0.5 --metallic 0 --roughness 0.5 -o "$o/a/b/c/m" --flags "$o/f/g/f.png" ;;
    convert) "$bin" convert --from ward --to ggx alpha=@"$tmp/in/rough.exr" --transform "$tmp/in/wg.mrt" \
        -o "$o/a/b/c/ggx_" ;;
    sweep) "$bin" sweep --from ward diffuse=0 --to ggx diffuse=0 --grid alpha=0.03:0.4:2:log --size 16 --threads 1 \
        -o "$o/a/b/c/s.csv" ;;
    sweep_merge) "$bin" sweep merge "$tmp/in/s0.csv" "$tmp/in/s1.csv" -o "$o/a/b/c/m.csv" ;;
    learn) "$bin" learn "$tmp/in/wg.csv" -o "$o/a/b/c/t.mrt" --plots "$o/p/q/plots" ;;
    train) "$bin" train "$tmp/in/on.csv" -o "$o/a/b/c/n.mlp" --hidden 4 --epochs 3 --loss-curve "$o/l/m/curve" ;;
    dataset) "$bin" dataset -o "$o/a/b/c/pairs.csv" --samples 4 --size 16 --threads 1 ;;
    report) "$bin" report -o "$o/a/b/c/report" --size 32 gltf -- ggx ;;
    gltf) "$bin" gltf spec2metal "$duck" -o "$o/a/b/c/duck.gltf" --method weighted ;;
    export) "$bin" export "$bottle" -o "$o/a/b/c/b.mtlx" --to gltf ;;
    esac
}
outputs() { # NAME: the files it wrote, under its folder
    case $1 in
    render) echo a/b/c/x.png m/n/mask.png ;;
    ssim) echo a/b/c/map.png ;;
    remap) echo a/b/c/fit_source.png a/b/c/fit_target.png a/b/c/fit_ssim.png ;;
    spec2metal) echo a/b/c/s_basecolor.png a/b/c/s_metallic.png a/b/c/s_roughness.png ;;
    metal2spec) echo a/b/c/m_diffuse.png a/b/c/m_specular.png f/g/f.png ;;
    convert) echo a/b/c/ggx_alpha.exr a/b/c/ggx_f0.exr a/b/c/ggx_flags.png ;;
    sweep) echo a/b/c/s.csv ;;
    sweep_merge) echo a/b/c/m.csv ;;
    learn) echo a/b/c/t.mrt p/q/plots/rows.csv ;;
    train) echo a/b/c/n.mlp l/m/curve.csv ;;
    dataset) echo a/b/c/pairs.csv ;;
    report) echo a/b/c/report/index.html ;;
    gltf) echo a/b/c/duck.gltf ;;
    export) echo a/b/c/b.mtlx a/b/c/b_image0.png a/b/c/b_image1.png ;;
    esac
}
all_written() { # FOLDER NAME
    local f
    for f in $(outputs "$2"); do [ -s "$1/$f" ] || { echo "      missing $1/$f"; return 1; }; done
}
for name in render ssim remap spec2metal metal2spec convert sweep sweep_merge learn train dataset report gltf \
    export; do
    d="$tmp/A/$name"
    mkdir -p "$d"
    expect "$name: outputs in missing nested folders" 0 "" -- run_cmd "$name" "$d"
    check "$name: ... are written there" all_written "$d" "$name"
    b="$tmp/B/$name"
    mkdir -p "$b" && touch "$b/a" "$b/p" "$b/l" "$b/m" "$b/f"
    refuses "$name: a regular file where a folder must be: exit 2 naming it" "cannot create the folder '$b/[a-z]'" \
        "$b" -- run_cmd "$name" "$b"
done
# Before any work: the message is the first thing the command says (no render, no sweep row, no "wrote").
touch "$tmp/file"
expect "sweep: the folder is refused before any row" 2 "^matremap sweep: error: output '$tmp/file/s.csv': cannot" -- \
    "$bin" sweep --from ward --to ggx --random 5 --size 16 -o "$tmp/file/s.csv"
check "... its only line" test "$(wc -l <"$tmp/err")" -eq 1
expect "gltf: the folder is refused before the conversion" 2 "^matremap gltf: error: output '$tmp/file/d.gltf'" -- \
    "$bin" gltf spec2metal "$duck" -o "$tmp/file/d.gltf"
check "... its only line" test "$(wc -l <"$tmp/err")" -eq 1
# A run that fails after making folders leaves none of them (when empty).
expect "render: a bad value after the folders are planned" 2 "not a number" -- \
    "$bin" render gltf metallic=abc --size 16 -o "$tmp/gone/a/x.png"
check "... leaves no folder" test ! -e "$tmp/gone"

# ---- C. one -o PREFIX rule: '_' unless PREFIX ends in '/', '_', '-' or '.' ---------------------------------------
P="$tmp/prefix"
mkdir -p "$P"
expect "convert -o pfx/ggx writes pfx/ggx_alpha.exr" 0 "" -- "$bin" convert --from ward --to ggx \
    alpha=@"$tmp/in/rough.exr" --transform "$tmp/in/wg.mrt" -o "$P/pfx/ggx"
check "... pfx/ggx_alpha.exr, pfx/ggx_flags.png" test -s "$P/pfx/ggx_alpha.exr" -a -s "$P/pfx/ggx_flags.png"
expect "convert -o out/ggx_ writes out/ggx_alpha.exr" 0 "" -- "$bin" convert --from ward --to ggx \
    alpha="$tmp/in/rough.exr" --transform "$tmp/in/wg.mrt" -o "$P/out/ggx_"
check "... out/ggx_alpha.exr" test -s "$P/out/ggx_alpha.exr" -a ! -e "$P/out/ggx__alpha.exr"
expect "convert -o dir/ writes dir/alpha.exr" 0 "" -- "$bin" convert --from ward --to ggx \
    alpha="$tmp/in/rough.exr" --transform "$tmp/in/wg.mrt" -o "$P/dir/"
check "... dir/alpha.exr" test -s "$P/dir/alpha.exr"
expect "spec2metal -o avocado writes avocado_basecolor.png" 0 "" -- "$bin" spec2metal --diffuse 0.5 --specular 0.04 \
    --glossiness 0.5 --method weighted -o "$P/avocado"
check "... avocado_basecolor.png" test -s "$P/avocado_basecolor.png"
expect "spec2metal -o sm/ writes sm/basecolor.png" 0 "" -- "$bin" spec2metal --diffuse 0.5 --specular 0.04 \
    --glossiness 0.5 --method weighted -o "$P/sm/"
check "... sm/basecolor.png" test -s "$P/sm/basecolor.png" -a ! -e "$P/sm/_basecolor.png"
expect "metal2spec -o gold- writes gold-diffuse.png" 0 "" -- "$bin" metal2spec --basecolor 0.9,0.6,0.2 --metallic 1 \
    --roughness 0.3 -o "$P/gold-"
check "... gold-diffuse.png" test -s "$P/gold-diffuse.png"
expect "remap --images r/ writes r/source.png" 0 "" -- "$bin" remap --from ggx alpha=0.2 --to ward --size 16 \
    --images "$P/r/"
check "... r/source.png, r/target.png, r/ssim.png" test -s "$P/r/source.png" -a -s "$P/r/target.png" \
    -a -s "$P/r/ssim.png"
expect "remap --images fit writes fit_source.png" 0 "" -- "$bin" remap --from ggx alpha=0.2 --to ward --size 16 \
    --images "$P/fit"
check "... fit_source.png" test -s "$P/fit_source.png"

# ---- B. hints, help, render of a glTF asset ----------------------------------------------------------------------
expect "render: a file without '@' gets a hint" 2 \
    "'avocado_basecolor.png' is not a number; did you mean base_color=@avocado_basecolor.png\?" -- \
    "$bin" render gltf base_color=avocado_basecolor.png -o "$tmp/h.png"
expect "... an existing file too, a channel kept" 2 "did you mean roughness=@$tmp/in/rough.exr:g\?" -- \
    "$bin" render gltf roughness="$tmp/in/rough.exr:g" -o "$tmp/h.png"
expect "report: the same hint" 2 "did you mean diffuse=@d.png\?" -- "$bin" report -o "$tmp/hr" lambert diffuse=d.png
expect "a plain bad number gets no hint" 2 "'abc' is not a number$" -- "$bin" render gltf metallic=abc -o "$tmp/h.png"
expect "help alone is the general help" 0 "^Commands:" -- "$bin" help
check "... the same as --help" cmp -s <("$bin" help) <("$bin" --help)
for cmd in models render ssim remap sweep dataset train learn convert spec2metal metal2spec gltf report export; do
    check "help $cmd prints exactly '$cmd --help'" cmp -s <("$bin" help $cmd) <("$bin" $cmd --help)
done
check "help sweep merge prints exactly 'sweep merge --help'" cmp -s <("$bin" help sweep merge) \
    <("$bin" sweep merge --help)
expect "help of an unknown command is a usage error" 1 "unknown command 'frob' \(valid: .*render" -- \
    "$bin" help frob
expect "render --help shows the glTF form" 0 "matremap render ASSET.gltf\|ASSET.glb" -- "$bin" render --help
expect "render a glTF asset (metal-rough, textured) under --env" 0 "" -- "$bin" render "$bottle" --env "$studio" \
    --size 64 -o "$tmp/gltf/bottle.png" --json
check "... the asset's triangles, its material, lit pixels" test \
    "$(json '(d["asset"], d["triangles"], d["materials"], d["lit_pixels"] > 500)')" = "('$bottle', 4510, 1, True)"
check "... the picture is written" test -s "$tmp/gltf/bottle.png"
expect "render a glTF asset (spec-gloss) from a direction, with its mask" 0 "" -- "$bin" render "$duck" \
    --size 32 --camera-direction 1,0.5,1 --mask "$tmp/gltf/duck_mask.png" -o "$tmp/gltf/duck.exr" --json
check "... the asset is seen, both files written" test "$(json '(d["lit_pixels"] > 100, d["materials"])')" = \
    "(True, 1)" -a -s "$tmp/gltf/duck.exr" -a -s "$tmp/gltf/duck_mask.png"
expect "a glTF asset takes no name=value" 1 "takes no name=value" -- "$bin" render "$duck" metallic=1 -o "$tmp/x.png"
expect "--camera-direction is for glTF assets" 1 "--camera-direction" -- \
    "$bin" render gltf --camera-direction 1,0,0 -o "$tmp/x.png"
refuses "render: an output over a file of the asset" "is the input a file of asset" "$tmp/gltf" -- \
    "$bin" render "$duck" --size 16 -o "$(dirname "$duck")/DuckCM.png"

# ---- D. --json wherever results are printed ----------------------------------------------------------------------
J="$tmp/json"
mkdir -p "$J"
expect "render --json" 0 "" -- "$bin" render gltf --size 16 -o "$J/r.png" --mask "$J/m.png" --json
check "... outputs and pixels" test "$(json '(d["command"], d["outputs"], d["width"], d["lit_pixels"] > 0)')" = \
    "('render', ['$J/r.png', '$J/m.png'], 16, True)"
check "... nothing on stderr" test ! -s "$tmp/err"
expect "sweep --json" 0 "" -- "$bin" sweep --from ward diffuse=0 --to ggx diffuse=0 --grid alpha=0.03:0.4:3:log \
    --size 16 --threads 1 -o "$J/s.csv" --json
check "... samples computed, outcomes" test "$(json '(d["command"], d["samples"], d["computed"], \
sum(d["outcomes"].values()))')" = "('sweep', 3, 3, 3)"
expect "sweep --json on a finished file" 0 "" -- "$bin" sweep --from ward diffuse=0 --to ggx diffuse=0 \
    --grid alpha=0.03:0.4:3:log --size 16 --threads 1 -o "$J/s.csv" --resume --json
check "... nothing computed, all there" test "$(json '(d["computed"], d["already_done"])')" = "(0, 3)"
expect "sweep merge --json" 0 "" -- "$bin" sweep merge "$tmp/in/s1.csv" "$tmp/in/s0.csv" -o "$J/m.csv" --json
check "... samples and shards" test "$(json '(d["command"], d["samples"], d["shards"], d["output"])')" = \
    "('sweep merge', 4, 2, '$J/m.csv')"
expect "report --json" 0 "" -- "$bin" report -o "$J/rep" --size 32 gltf -- --label other ggx alpha=0.3 --json
check "... materials and figures" test "$(json '(d["command"], d["views"], [m["label"] for m in d["materials"]], \
d["materials"][0]["object_ssim"], 0 < d["materials"][1]["object_ssim"] < 1, d["page"])')" = \
    "('report', 1, ['gltf', 'other'], 1.0, True, '$J/rep/index.html')"
expect "export --json" 0 "" -- "$bin" export "$bottle" -o "$J/b.usda" --json
check "... command, format, routes and images" test "$(json '(d["command"], d["format"], \
[m["route"] for m in d["materials"]], len(d["images"]))')" = "('export', 'usda', ['maps'], 2)"
expect "dataset --json" 0 "" -- "$bin" dataset -o "$J/pairs.csv" --samples 6 --size 16 --threads 1 --json
check "... pairs and outcomes" test "$(json '(d["command"], d["pairs"], \
d["outcomes"]["converged"] + d["outcomes"]["unreachable"], sum(d["categories"].values()))')" = "('dataset', 6, 6, 6)"

# ---- E. one wording, one prefix --------------------------------------------------------------------------------
for cmd in models render ssim remap sweep "sweep merge" dataset train learn convert spec2metal metal2spec gltf \
    report export; do
    # shellcheck disable=SC2086 # "sweep merge" is two words
    expect "$cmd --bogus" 1 "^matremap $cmd: unknown option '--bogus'$" -- "$bin" $cmd --bogus
done
ln -s "$bin" "$tmp/spec2metal"
expect "spec2metal as a command of its own: the same prefix" 1 "^matremap spec2metal: unknown option '--bogus'" -- \
    "$tmp/spec2metal" --bogus
expect "spec2metal's summary line starts 'matremap spec2metal: '" 0 "^matremap spec2metal: 1x1 = 1 texel" -- \
    "$tmp/spec2metal" --diffuse 0.5 --specular 0.04 --glossiness 0.5 --method weighted
expect "metal2spec's summary line too" 0 "^matremap metal2spec: 1x1 = 1 texel" -- \
    "$bin" metal2spec --basecolor 0.5 --metallic 0 --roughness 0.5
# Every line on stderr of failing commands starts "matremap CMD: " (or is the --help hint).
prefixed() { ! grep -vE "^(matremap [a-z0-9 ]+: |Try 'matremap )" "$tmp/err"; }
expect "a bad map: every line prefixed" 2 "" -- "$bin" spec2metal --diffuse "$tmp/nope.png" --specular 0.04 \
    --glossiness 0.5 -o "$tmp/p"
check "... prefixed" prefixed
expect "a bad value: every line prefixed" 1 "" -- "$bin" metal2spec --basecolor 2 --metallic 0 --roughness 0.5
check "... prefixed" prefixed
# The note on a converted constant names the hop, the transform and the parameter (a chain: blender-ward -> ward
# -> ggx, as convert --help's example; Blender's diffuse has no 1/pi, so ward's diffuse leaves its range).
mkdir -p "$tmp/chain"
"$bin" sweep --from blender-ward diffuse=0 --to ward diffuse=0 --grid rms=0.03:0.4:4:log specular=0.03:0.25:3 \
    --size 16 --threads 2 -o "$tmp/in/bw.csv" 2>/dev/null
"$bin" learn "$tmp/in/bw.csv" -o "$tmp/chain/bw_ward.mrt" >/dev/null 2>&1
cp "$tmp/in/wg.mrt" "$tmp/chain/ward_ggx.mrt"
expect "convert: the clamp note names the hop and the parameter" 0 \
    "note: hop 1 of 2 \($tmp/chain/+bw_ward.mrt, blender-ward -> ward\): clamped into its range: diffuse 1,1,1" -- \
    "$bin" convert --from blender-ward --to ggx specular=0.1 rms=0.2 --transforms "$tmp/chain/" --via ward
check "... once" test "$(grep -c "clamped" "$tmp/err")" -eq 1
expect "convert: extrapolation names the parameter and the domain" 0 \
    "hop 2 of 2 \(.*ward_ggx.mrt, ward -> ggx\): extrapolated, outside its training domain: specular 0.9,0.9,0.9 \(tr" \
    -- \
    "$bin" convert --from blender-ward --to ggx specular=0.9 rms=0.2 diffuse=0.1 --transforms "$tmp/chain" --via ward

finish
