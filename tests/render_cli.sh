#!/usr/bin/env bash
# `matremap render` with environment lighting (--env ...) and parameters from texture maps (name=@MAP[:c]): known
# answers (a constant map renders like the constant; a grey environment map like its level), channel selection,
# and the errors a user meets (missing files named, a colour map for a scalar parameter, option misuse). Needs
# oiiotool. Ends with "N passed, N failed".
set -u
bin="${MR_BUILD:-build}/bin/matremap"
source "$(dirname "$0")/lib/cli_harness.sh"

# max |A - B| over all pixel values of two images (idiff's "Max error").
maxdiff() { idiff -v -fail 1e9 "$1" "$2" 2>&1 | sed -nE 's/.*Max error += ([-0-9.e+]+).*/\1/p'; }
below() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a != "" && a + 0 < b + 0) }'; }

oiiotool --pattern constant:color=0.25,0.5,0.75 16x8 3 -d float -o "$tmp/colour.exr"
oiiotool --pattern constant:color=0.2,0.7,0.4 16x8 3 -d float -o "$tmp/packed.exr"
oiiotool --pattern constant:color=1,1,1 32x16 3 -d float -o "$tmp/white_env.exr"

# A constant RGB map (all three channels read) renders exactly like the constant.
expect "RGB parameter from a map" 0 "wrote" -- "$bin" render ggx diffuse=@"$tmp/colour.exr" f0=0.04 alpha=0.3 \
    --size 64 -o "$tmp/map.exr"
expect "the same constant" 0 "wrote" -- "$bin" render ggx diffuse=0.25,0.5,0.75 f0=0.04 alpha=0.3 --size 64 \
    -o "$tmp/const.exr"
d=$(maxdiff "$tmp/map.exr" "$tmp/const.exr")
check "a constant RGB map renders like the constant (max diff $d)" below "$d" 1e-7
# A scalar parameter from one channel of a packed map: :g is 0.7.
expect "scalar parameter from channel g" 0 "wrote" -- "$bin" render gltf base_color=0.8,0.2,0.1 \
    metallic=@"$tmp/packed.exr":b roughness=@"$tmp/packed.exr":g --size 64 -o "$tmp/packed_render.exr"
"$bin" render gltf base_color=0.8,0.2,0.1 metallic=0.4 roughness=0.7 --size 64 -o "$tmp/packed_const.exr" 2>/dev/null
d=$(maxdiff "$tmp/packed_render.exr" "$tmp/packed_const.exr")
check "channels b and g read metallic 0.4 and roughness 0.7 (max diff $d)" below "$d" 1e-6
# A white Lambertian sphere under a uniform environment of radiance 1 shows radiance 1 (to the pattern's bias).
expect "uniform environment" 0 "shading samples" -- "$bin" render lambert albedo=1 --env "$tmp/white_env.exr" \
    --env-samples 4096 --size 32 -o "$tmp/furnace.exr"
centre=$(oiiotool "$tmp/furnace.exr" --cut 14,14,17,17 --printstats 2>/dev/null |
    sed -nE 's/.*Stats Avg: ([0-9.e+-]+).*/\1/p')
check "furnace: the centre pixels are 1 within 0.002 ($centre)" \
    awk -v v="$centre" 'BEGIN { exit !(v > 0.998 && v < 1.002) }'
expect "--env-scale 0.5 halves it" 0 "" -- "$bin" render lambert albedo=1 --env "$tmp/white_env.exr" \
    --env-samples 4096 --env-scale 0.5 --size 32 -o "$tmp/half.exr"
oiiotool "$tmp/furnace.exr" --mulc 0.5 -o "$tmp/furnace_half.exr"
d=$(maxdiff "$tmp/half.exr" "$tmp/furnace_half.exr")
check "--env-scale is linear (max diff $d)" below "$d" 1e-6
expect "a whole turn changes nothing" 0 "" -- "$bin" render lambert albedo=1 --env "$tmp/white_env.exr" \
    --env-samples 4096 --env-rotation 360 --size 32 -o "$tmp/turn.exr"
d=$(maxdiff "$tmp/turn.exr" "$tmp/furnace.exr")
check "--env-rotation 360 is bit-identical (max diff $d)" below "$d" 1e-30
# A GGX mirror (alpha 1e-4, f0 1, no diffuse) in the white furnace reflects 1 wherever it is seen head-on enough:
# with reflection samples the centre of the sphere (a 16x16 crop of 64x64) holds 1 within 2 %; the pattern alone
# misses the 2e-4 rad lobe there.
mirror=(ggx alpha=1e-4 f0=1,1,1 diffuse=0,0,0 --env "$tmp/white_env.exr" --size 64)
expect "a mirror in the furnace, 40 reflection samples" 0 "" -- "$bin" render "${mirror[@]}" \
    --env-reflection-samples 40 -o "$tmp/mirror40.exr"
expect "... and without" 0 "" -- "$bin" render "${mirror[@]}" -o "$tmp/mirror0.exr"
centre_range() { oiiotool "$1" --cut 16x16+24+24 --printstats 2>/dev/null | sed -nE 's/.*Stats (Min|Max): ([-0-9.e+]+).*/\2/p' |
    paste -sd' ' | awk '{ m = $1; M = $1; for (i = 2; i <= NF; i++) { m = $i < m ? $i : m; M = $i > M ? $i : M }
    print m, M }'; }
read -r lo hi < <(centre_range "$tmp/mirror40.exr")
check "--env-reflection-samples 40: the mirror's centre holds 1 ($lo .. $hi)" awk -v a="$lo" -v b="$hi" \
    'BEGIN { exit !(a > 0.98 && b < 1.02) }'
read -r lo hi < <(centre_range "$tmp/mirror0.exr")
check "the pattern alone: far from 1 somewhere ($lo .. $hi)" awk -v a="$lo" -v b="$hi" 'BEGIN { exit !(a < 0.5 || b > 2) }'

# Coverage masks (--mask) and comparisons over them (ssim --mask; metrics.h).
expect "--mask writes the object's coverage" 0 "wrote" -- "$bin" render lambert albedo=0.5 --size 64 \
    -o "$tmp/lam.exr" --mask "$tmp/mask.exr"
"$bin" render ggx diffuse=0.2 f0=0.04 alpha=0.3 --size 64 -o "$tmp/ggx.exr" --mask "$tmp/mask2.exr" 2>/dev/null
"$bin" render ggx diffuse=0.2 f0=0.04 alpha=0.3 --size 64 -o "$tmp/ggx.png" --mask "$tmp/mask.png" 2>/dev/null
check "the mask is one channel of the render's size" test "$(oiiotool --info "$tmp/mask.exr" | grep -c '64 x   64, 1 channel')" = 1
# Its sum is the projected disc's area: radius tan(asin(1/4)) / tan(17.5°) x 32 pixels (render.h, the fit camera).
area=$(oiiotool "$tmp/mask.exr" --printstats 2>/dev/null | sed -nE 's/.*Stats Avg: ([0-9.e+-]+).*/\1/p')
check "its sum ($area x 64²) is the sphere's projected area within 0.5 %" awk -v a="${area:-0}" 'BEGIN {
    r = (0.25 / sqrt(1 - 0.0625)) / (sin(17.5 * 3.14159265358979 / 180) / cos(17.5 * 3.14159265358979 / 180)) * 32
    d = a * 4096 / (3.14159265358979 * r * r); exit !(d > 0.995 && d < 1.005) }'
check "the same mask for any material" below "$(maxdiff "$tmp/mask.exr" "$tmp/mask2.exr")" 1e-30
check "... and as an 8-bit PNG, within one code (linear, not sRGB)" below "$(maxdiff "$tmp/mask.exr" "$tmp/mask.png")" 0.0021
expect "ssim --mask of an image with itself is 1" 0 "^1\.000000$" -- "$bin" ssim "$tmp/lam.exr" "$tmp/lam.exr" \
    --mask "$tmp/mask.exr"
expect "ssim --mask --json adds the object's figures" 0 \
    '^\{"ssim": [0-9.e-]+, "rmse": [0-9.e-]+, "object_ssim": [0-9.e-]+, "object_rmse": [0-9.e-]+, "object_relative_rmse": [0-9.e-]+\}$' \
    -- "$bin" ssim --json "$tmp/lam.exr" "$tmp/ggx.exr" --mask "$tmp/mask.png"
read -r whole object < <(sed -E 's/.*"ssim": ([^,]*),.*"object_ssim": ([^,]*),.*/\1 \2/' "$tmp/out")
check "over the object the difference weighs more: SSIM $object < $whole" awk -v o="${object:-1}" -v w="${whole:-0}" \
    'BEGIN { exit !(o < w && w < 1) }'
oiiotool --pattern constant:color=1 64x64 1 -d float -o "$tmp/ones.exr"
check "a mask of ones gives the whole-frame SSIM" test "$("$bin" ssim "$tmp/lam.exr" "$tmp/ggx.exr" --mask "$tmp/ones.exr")" = \
    "$("$bin" ssim "$tmp/lam.exr" "$tmp/ggx.exr")"
expect "--mask with --downsample" 1 "cannot be combined" -- "$bin" ssim "$tmp/lam.exr" "$tmp/ggx.exr" \
    --mask "$tmp/mask.exr" --downsample
oiiotool --pattern constant:color=1 32x16 1 -d float -o "$tmp/small_mask.exr"
expect "a mask of another size is refused, with both sizes" 2 "32x16x1; expected 64x64x1" -- "$bin" ssim \
    "$tmp/lam.exr" "$tmp/ggx.exr" --mask "$tmp/small_mask.exr"
expect "an RGB mask is refused, naming the file" 2 "white_env.exr.*1 channel" -- "$bin" ssim "$tmp/lam.exr" \
    "$tmp/ggx.exr" --mask "$tmp/white_env.exr"
expect "a missing mask is named" 2 "nomask.exr" -- "$bin" ssim "$tmp/lam.exr" "$tmp/ggx.exr" --mask "$tmp/nomask.exr"

# OBJ meshes (--mesh): a quad with UVs 0..1 under a red-over-blue map shows red above and blue below (the file's
# v = 1 is the map's top row), lit by the point light kept beside the camera; the paper's sphere with its camera
# covers most of the frame; a malformed file is named with its line.
printf 'v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n' >"$tmp/quad.obj"
oiiotool --create 16x16 3 --fill:color=1,0,0 16x8+0+0 --fill:color=0,0,1 16x8+0+8 -d float -o "$tmp/red_blue.exr"
expect "--mesh renders an OBJ quad" 0 "2 triangles, 4 vertices" -- "$bin" render lambert albedo=@"$tmp/red_blue.exr" \
    --mesh "$tmp/quad.obj" --size 32 -o "$tmp/quad.exr"
avg() { # the mean R and B of a crop
    oiiotool "$1" --cut "$2" --printstats 2>/dev/null |
        sed -nE 's/.*Stats Avg: ([-0-9.e+]+) ([-0-9.e+]+) ([-0-9.e+]+).*/\1 \3/p'
}
read -r top_r top_b < <(avg "$tmp/quad.exr" 32x8+0+4)
read -r bottom_r bottom_b < <(avg "$tmp/quad.exr" 32x8+0+20)
check "the map's top row lies at the file's v = 1: red above ($top_r, $top_b), blue below ($bottom_r, $bottom_b)" \
    awk -v a="$top_r" -v b="$top_b" -v c="$bottom_r" -v d="$bottom_b" \
    'BEGIN { exit !(a > 0.05 && b == 0 && c == 0 && d > 0.05) }'
matsphere="${MR_SHARED:-$(dirname "$0")/../../shared}/assets/paper/matsphere.obj"
expect "the paper's sphere with --camera paper" 0 "55742 triangles" -- "$bin" render ggx alpha=0.2 \
    --mesh "$matsphere" --camera paper --size 32 --mask "$tmp/matsphere_mask.exr" -o "$tmp/matsphere.exr"
covered=$(oiiotool "$tmp/matsphere_mask.exr" --printstats 2>/dev/null | sed -nE 's/.*Stats Avg: ([-0-9.e+]+).*/\1/p')
check "it fills 74 % of the frame as a radius 0.5 sphere at 1.5 with a 40-degree view ($covered)" \
    awk -v v="$covered" 'BEGIN { exit !(v > 0.70 && v < 0.78) }'
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n' >"$tmp/bad.obj"
expect "a malformed OBJ is named with its line" 2 "bad.obj', line 4: v index '4': out of range" -- "$bin" render ggx \
    --mesh "$tmp/bad.obj" -o "$tmp/e9.exr"
expect "a missing OBJ is named" 2 "nomesh.obj': cannot open" -- "$bin" render ggx --mesh "$tmp/nomesh.obj" \
    -o "$tmp/e10.exr"
expect "--camera takes auto or paper" 1 "expected auto or paper" -- "$bin" render ggx --camera side -o "$tmp/e11.exr"
check "no output after these failures" test ! -e "$tmp/e9.exr" -a ! -e "$tmp/e10.exr" -a ! -e "$tmp/e11.exr"

# Errors: the file or value named, nothing written.
expect "a missing map is named" 2 "nomap.png" -- "$bin" render ggx diffuse=@"$tmp/nomap.png" -o "$tmp/e1.exr"
expect "a missing environment is named" 2 "noenv.hdr" -- "$bin" render ggx --env "$tmp/noenv.hdr" -o "$tmp/e2.exr"
check "no output after a failure" test ! -e "$tmp/e1.exr" -a ! -e "$tmp/e2.exr"
expect "a colour map for a scalar needs a channel" 1 "pick a channel" -- "$bin" render ggx alpha=@"$tmp/colour.exr" \
    -o "$tmp/e3.exr"
expect "an RGB parameter takes no channel" 1 "takes the whole image" -- "$bin" render ggx \
    diffuse=@"$tmp/colour.exr":r -o "$tmp/e4.exr"
expect "an unknown parameter" 2 "no parameter 'shine'" -- "$bin" render ggx shine=@"$tmp/colour.exr" -o "$tmp/e5.exr"
expect "--env-samples 0" 1 "env-samples" -- "$bin" render ggx --env "$tmp/white_env.exr" --env-samples 0 \
    -o "$tmp/e6.exr"
expect "--env-rotation without --env" 1 "need --env" -- "$bin" render ggx --env-rotation 30 -o "$tmp/e7.exr"
expect "--env-reflection-samples without --env" 1 "need --env" -- "$bin" render ggx --env-reflection-samples 40 \
    -o "$tmp/e7.exr"
expect "--env-reflection-samples over the maximum" 1 "env-reflection-samples" -- "$bin" render ggx \
    --env "$tmp/white_env.exr" --env-reflection-samples 1025 -o "$tmp/e7.exr"
oiiotool --pattern constant:color=1,-1,1 8x4 3 -d float -o "$tmp/negative_env.exr"
expect "a negative environment value is named with its file" 2 \
    "image '$tmp/negative_env.exr': pixel \(0, 0\), channel 1 holds -1: expected finite radiance" -- "$bin" render ggx \
    --env "$tmp/negative_env.exr" -o "$tmp/e8.exr"
check "... and nothing is written" test ! -e "$tmp/e8.exr"

# ---- no output replaces an input (by device and inode: another spelling, a hard link, a symbolic link) -----------
mkdir -p "$tmp/io/sub"
oiiotool --pattern checker:width=4:height=4:color1=0.8,0.2,0.1:color2=0.1,0.3,0.8 16x16 3 -o "$tmp/io/t.png"
cp "$tmp/white_env.exr" "$tmp/io/env.exr"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' >"$tmp/io/tri.obj"
ln "$tmp/io/t.png" "$tmp/io/hard.png"
ln -s t.png "$tmp/io/soft.png"
abs_bin=$(realpath "$bin")
cd "$tmp/io"
refuses "render: -o ./t.png is the map base_color=@t.png" "output './t.png' is the input base_color=@t.png; refusing" \
    "$tmp/io" -- "$abs_bin" render gltf base_color=@t.png --size 16 -o ./t.png
cd "$OLDPWD"
refuses "render: -o through dir/.. is the map" "is the input base_color=@$tmp/io/t.png" "$tmp/io" -- \
    "$bin" render gltf base_color=@"$tmp/io/t.png" --size 16 -o "$tmp/io/sub/../t.png"
refuses "render: -o a hard link to the map" "output '$tmp/io/hard.png' is the input base_color=@" "$tmp/io" -- \
    "$bin" render gltf base_color=@"$tmp/io/t.png" --size 16 -o "$tmp/io/hard.png"
refuses "render: -o a symbolic link to a channel's map" "output '$tmp/io/soft.png' is the input roughness=@.*t.png:g" \
    "$tmp/io" -- "$bin" render gltf roughness=@"$tmp/io/t.png":g --size 16 -o "$tmp/io/soft.png"
refuses "render: -o the --env map" "output '$tmp/io/env.exr' is the input --env $tmp/io/env.exr" "$tmp/io" -- \
    "$bin" render gltf --env "$tmp/io/env.exr" --size 16 -o "$tmp/io/env.exr"
refuses "render: --mask over the --mesh" "output '$tmp/io/tri.obj' \(--mask\) is the input --mesh" "$tmp/io" -- \
    "$bin" render gltf --mesh "$tmp/io/tri.obj" --size 16 -o "$tmp/io/new.exr" --mask "$tmp/io/tri.obj"
refuses "render: --mask and -o are one file" "\(--mask\) is also the output '$tmp/io/sub/../m.png'" "$tmp/io" -- \
    "$bin" render gltf --size 16 -o "$tmp/io/sub/../m.png" --mask "$tmp/io/m.png"
expect "render: an output beside its input is fine" 0 "wrote" -- "$bin" render gltf base_color=@"$tmp/io/t.png" \
    --size 16 -o "$tmp/io/t2.png"

finish
