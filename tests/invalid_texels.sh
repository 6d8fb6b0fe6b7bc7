#!/usr/bin/env bash
# One policy for parameter-map texels that hold no parameter value (docs/rendering.md, "Texels that are not
# parameter values"; docs/reliability.md): an 8x8 EXR with a NaN, an infinity and two negative texels goes through
# every command that reads parameter maps. render and report read NaN and infinities as 0 and clamp negatives to 0,
# say so in a note naming the map and the counts, and exit 0; the render equals that of the map with those texels
# replaced by hand, bit for bit. convert and spec2metal count them among their flagged inputs. Needs oiiotool.
# Ends with "N passed, N failed".
set -u
build=$(cd "${MR_BUILD:-build}" && pwd)
bin="$build/bin/matremap"
source "$(dirname "$0")/lib/cli_harness.sh"

# bad.exr: 0.5 grey but for (1, 1) = NaN in red, (3, 2) = +inf in green, (5, 6) and (6, 6) = -0.25 in blue;
# sane.exr: the same with those values replaced as the policy says (0).
make_map() { # out red_nan green_inf blue_negative
    oiiotool --pattern constant:color="$2",0.5,0.5 1x1 3 -d float \
        --pattern constant:color=0.5,0.5,0.5 8x8 3 -d float --paste +1+1 -o "$tmp/m1.exr" &&
        oiiotool --pattern constant:color=0.5,"$3",0.5 1x1 3 -d float "$tmp/m1.exr" --paste +3+2 -o "$tmp/m2.exr" &&
        oiiotool --pattern constant:color=0.5,0.5,"$4" 2x1 3 -d float "$tmp/m2.exr" --paste +5+6 -o "$1"
}
make_map "$tmp/bad.exr" nan inf -0.25 && make_map "$tmp/sane.exr" 0 0 0 ||
    { echo "FAIL  oiiotool could not make the maps"; echo "0 passed, 1 failed"; exit 1; }

# (1, 1) and (3, 2) are one texel each: 2 texels not finite.
note="note: base_color=@$tmp/bad.exr: 2 texels not finite, read as 0; 2 negative, clamped to 0"
expect "render: exit 0, the note names the map and the counts" 0 "matremap render: $note" -- \
    "$bin" render gltf base_color=@"$tmp/bad.exr" --size 64 -o "$tmp/bad_render.exr"
expect "render of the replaced map: no note" 0 "" -- \
    "$bin" render gltf base_color=@"$tmp/sane.exr" --size 64 -o "$tmp/sane_render.exr"
check "... and no note there" sh -c "! grep -q note '$tmp/err'"
check "render: the texels are read as the policy says (bit for bit the replaced map's render)" \
    cmp "$tmp/bad_render.exr" "$tmp/sane_render.exr"
expect "render, one channel of the map (metallic, blue: only the negatives)" 0 \
    "note: metallic=@$tmp/bad.exr: 2 negative, clamped to 0" -- \
    "$bin" render gltf metallic=@"$tmp/bad.exr":b --size 32 -o "$tmp/metallic.exr"
expect "render, one channel of the map (metallic, green: only the infinity)" 0 \
    "note: metallic=@$tmp/bad.exr: 1 texel not finite, read as 0$" -- \
    "$bin" render gltf metallic=@"$tmp/bad.exr":g --size 32 -o "$tmp/green.exr"

expect "report: exit 0, the note" 0 "matremap report: $note" -- \
    "$bin" report -o "$tmp/report" gltf base_color=@"$tmp/bad.exr"

expect "spec2metal: the texels are flagged and counted" 0 "flagged: 2 clamped input, 2 non-finite input" -- \
    "$bin" spec2metal --diffuse "$tmp/bad.exr" --specular 0.04 --glossiness 0.5 --method weighted -o "$tmp/sm_"
expect "convert: the texels are counted among its flagged inputs" 0 "4 clamped or non-finite inputs" -- \
    "$bin" convert --from ggx --to ward alpha="$tmp/bad.exr":r diffuse="$tmp/bad.exr" --direct --size 16 \
    -o "$tmp/cv_"
finish
