#!/usr/bin/env bash
# `matremap remap` from the command line: help, usage errors, bad inputs, and two known answers — a model remapped
# to itself recovers its parameters, and black-box renders in another renderer's light units (here: ours x 2)
# recover them too once --match-irradiance brings them back. Ends with "N passed, N failed".
set -u
bin="${MR_BUILD:-build}/bin/matremap"
source "$(dirname "$0")/lib/cli_harness.sh"

# A JSON number field of the last output.
field() { sed -E "s/.*\"$1\": \\[?([-0-9.e+]+).*/\\1/" "$tmp/out"; }
# |a - b| <= tol
near() { awk -v a="$1" -v b="$2" -v t="$3" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(d <= t) }'; }

expect "remap --help" 0 "Usage: matremap remap" -- "$bin" remap --help
expect "missing --to" 1 "missing --to" -- "$bin" remap --from ggx
expect "no source" 1 "exactly one source" -- "$bin" remap --to ggx
expect "two sources" 1 "exactly one source" -- "$bin" remap --from ggx --from-images a.exr --to ward
expect "unknown strategy lists valid ones" 1 "valid: auto, single, two, three" -- \
    "$bin" remap --from ggx --to ward --strategy best
expect "unknown local method lists valid ones" 1 "unknown local method 'newton' \\(valid: auto, gradient, bobyqa\\)" -- \
    "$bin" remap --from ggx --to ward --local newton
expect "the local stage the fit ran is reported" 0 '"local_method": "gradient"' -- \
    "$bin" remap --from ggx alpha=0.2 f0=0.04 diffuse=0.3 --to ward --json
expect "the paper's strategies keep BOBYQA" 0 "strategy single, local bobyqa" -- \
    "$bin" remap --from ggx alpha=0.2 f0=0.04 diffuse=0.3 --to ward --strategy single
expect "bobyqa on request" 0 '"local_method": "bobyqa"' -- \
    "$bin" remap --from ggx alpha=0.2 f0=0.04 diffuse=0.3 --to ward --local bobyqa --json
expect "unknown target model" 2 "unknown BRDF model 'wrad'" -- "$bin" remap --from ggx --to wrad
expect "bad source parameter" 2 "no parameter 'roughness'" -- "$bin" remap --from ggx roughness=0.2 --to ward
expect "components only with images" 1 "go with --from-images" -- \
    "$bin" remap --from ggx --diffuse d.exr --specular s.exr --to ward
expect "threads out of range" 1 "--threads '-1': expected an integer in \\[0, 1024\\]" -- \
    "$bin" remap --from ggx --to ward --threads -1
expect "threads given are used, same answer" 0 '"outcome": "converged"' -- \
    "$bin" remap --from ggx alpha=0.2 f0=0.3 --to ggx --threads 2 --json
expect "missing source image names it" 2 "nope.exr" -- "$bin" remap --from-images "$tmp/nope.exr" --to ward

# Known answer 1: a model remapped to itself.
expect "ggx to ggx (json)" 0 '"outcome": "converged"' -- \
    "$bin" remap --from ggx alpha=0.2 f0=0.3,0.5,0.7 diffuse=0.2,0.1,0.05 --to ggx --size 64 --json
check "ggx to ggx recovers alpha" near "$(field alpha)" 0.2 1e-4
check "ggx to ggx recovers f0 (red)" near "$(sed -E 's/.*"f0": \[([-0-9.e+]+).*/\1/' "$tmp/out")" 0.3 1e-4

# Known answer 2: black-box renders twice too bright, with a Lambert reference in the same units.
"$bin" render gltf base_color=0.7,0.4,0.2 metallic=0 roughness=0.5 --size 64 --exposure 2 -o "$tmp/src.exr" 2>/dev/null
"$bin" render gltf base_color=0.7,0.4,0.2 metallic=0 roughness=0.5 --size 64 --exposure 2 \
    --component diffuse -o "$tmp/src_d.exr" 2>/dev/null
"$bin" render gltf base_color=0.7,0.4,0.2 metallic=0 roughness=0.5 --size 64 --exposure 2 \
    --component specular -o "$tmp/src_s.exr" 2>/dev/null
"$bin" render lambert albedo=0.5 --size 64 --exposure 2 -o "$tmp/ref.exr" 2>/dev/null
expect "images matched in irradiance" 0 '"irradiance_scale": 0.5' -- \
    "$bin" remap --from-images "$tmp/src.exr" --match-irradiance "$tmp/ref.exr" --to gltf --json
check "irradiance-matched fit recovers roughness" near "$(field roughness)" 0.5 1e-3
check "irradiance-matched fit recovers metallic" near "$(field metallic)" 0 1e-3
expect "two-stage with component images" 0 '"strategy": "two"' -- \
    "$bin" remap --from-images "$tmp/src.exr" --diffuse "$tmp/src_d.exr" --specular "$tmp/src_s.exr" \
    --match-irradiance "$tmp/ref.exr" --to ward --strategy two --json
expect "two-stage without components" 2 "needs the source's diffuse-only" -- \
    "$bin" remap --from-images "$tmp/src.exr" --to ward --strategy two
"$bin" render lambert --size 32 -o "$tmp/small.exr" 2>/dev/null
expect "size mismatch names both files" 2 "small.exr' is 32x32 but .*src.exr' is 64x64" -- \
    "$bin" remap --from-images "$tmp/src.exr" --match-irradiance "$tmp/small.exr" --to ward
# Renders that are not radiance are bad input (exit 2), named with the pixel: a NaN at (3, 5), an infinity in a
# component image, a negative value.
oiiotool --pattern constant:color=nan,nan,nan 1x1 3 -d float --pattern constant:color=0.2,0.2,0.2 64x64 3 -d float \
    --paste +3+5 -o "$tmp/nan.exr"
oiiotool --pattern constant:color=0.1,inf,0.1 1x1 3 -d float --pattern constant:color=0.2,0.2,0.2 64x64 3 -d float \
    --paste +10+2 -o "$tmp/inf.exr"
oiiotool --pattern constant:color=0.1,0.1,-0.3 1x1 3 -d float --pattern constant:color=0.2,0.2,0.2 64x64 3 -d float \
    --paste +0+63 -o "$tmp/negative.exr"
expect "a NaN pixel is bad input, named" 2 "nan.exr': pixel \(3, 5\), channel 0 holds nan" -- \
    "$bin" remap --from-images "$tmp/nan.exr" --to ward
expect "an infinite component pixel is bad input, named" 2 "inf.exr': pixel \(10, 2\), channel 1 holds inf" -- \
    "$bin" remap --from-images "$tmp/src.exr" --diffuse "$tmp/inf.exr" --specular "$tmp/src_s.exr" --to ward
expect "a negative pixel is bad input, named" 2 "negative.exr': pixel \(0, 63\), channel 2 holds -0.3" -- \
    "$bin" remap --from-images "$tmp/negative.exr" --to ward
expect "pictures written" 0 "" -- "$bin" remap --from as f0=0.9 alpha=0.05 --to ward --size 64 --images "$tmp/pic"
check "source, target and SSIM pictures exist" test -s "$tmp/pic_source.png" -a -s "$tmp/pic_target.png" \
    -a -s "$tmp/pic_ssim.png"
expect "Ward cannot follow a bright conductor" 0 "outcome: unreachable .*trimming" -- \
    "$bin" remap --from as f0=0.9 alpha=0.05 --to ward --size 64

# --images PREFIX writes PREFIX_source.png, _target.png and _ssim.png: none of them may be an input.
mkdir -p "$tmp/io"
"$bin" render lambert albedo=0.5 --size 32 -o "$tmp/io/r_source.png" 2>/dev/null
"$bin" render lambert albedo=0.5 --size 32 --component diffuse -o "$tmp/io/d.exr" 2>/dev/null
"$bin" render lambert albedo=0.5 --size 32 --component specular -o "$tmp/io/s.exr" 2>/dev/null
ln -s d.exr "$tmp/io/x_ssim.png"
refuses "remap --images over the --from-images render" \
    "output '$tmp/io/r_source.png' \(--images $tmp/io/r\) is the input --from-images $tmp/io/r_source.png" \
    "$tmp/io" -- "$bin" remap --from-images "$tmp/io/r_source.png" --images "$tmp/io/r" --to lambert
refuses "remap --images: a picture that links to --diffuse" "x_ssim.png' \(--images .*/x\) is the input --diffuse" \
    "$tmp/io" -- "$bin" remap --from-images "$tmp/io/r_source.png" --diffuse "$tmp/io/d.exr" \
    --specular "$tmp/io/s.exr" --images "$tmp/io/./x" --to lambert

# --method materialx: MaterialX's translation graph instead of a fit (src/remap/translate.h; known answers in
# tests/test_translate.c). Coated copper into glTF: the base colour becomes the coat colour; the fit-scene SSIM is
# printed as a fit's is.
expect "materialx: copper into gltf (json)" 0 '"graph": "NG_standard_surface_to_gltf_pbr"' -- \
    "$bin" remap --from standard-surface base_color=1 metalness=1 specular=0 coat=1 coat_color=0.9,0.4,0.25 \
    --to gltf --method materialx --json
check "materialx: base colour = coat colour" near "$(sed -E 's/.*"values": \{"base_color": \[([-0-9.e+]+), ([-0-9.e+]+).*/\2/' \
    "$tmp/out")" 0.4 1e-12
check "materialx: prints the fit scene's SSIM" near "$(field ssim)" 0.5 0.5
expect "materialx: plain output names the graph and what it drops" 0 "not carried: specular, specular_color" -- \
    "$bin" remap --from standard-surface --to usd-preview --method materialx
expect "materialx: no graph for the pair" 1 "--method materialx: no MaterialX translation graph from 'gltf' to \
'openpbr' \(graphs: standard-surface -> gltf, standard-surface -> usd-preview, openpbr -> standard-surface\)" -- \
    "$bin" remap --from gltf --to openpbr --method materialx
expect "materialx: no fit options" 1 "--hold, --tie, --strategy, --grid-points and name=value after --to go with --method fit" \
    -- "$bin" remap --from openpbr --to standard-surface --method materialx --hold coat
expect "materialx: needs a model source" 1 "give --from MODEL" -- \
    "$bin" remap --from-images "$tmp/nope.exr" --to gltf --method materialx
expect "unknown method" 1 "--method 'graph': expected fit or materialx" -- \
    "$bin" remap --from standard-surface --to gltf --method graph

finish
