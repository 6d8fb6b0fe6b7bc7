#!/usr/bin/env bash
# One rule for encoded maps (issue 26): the same 8-bit PNG, a uniform Ward specular map of code 64, read by every
# command that reads maps. Ward's specular is a colour (range 0-10), so 8-bit maps of it are sRGB-decoded: code 64
# is 0.0513, and each command must give what the constant 0.0513 gives, not what the stored value 0.251 gives;
# FILE:linear gives the 0.251 answer; :srgb on a float file is a usage error naming the map; `models` shows the
# encoding of each parameter. Ends with "N passed, N failed".
set -u
bin="${MR_BUILD:-build}/bin/matremap"
source "$(dirname "$0")/lib/cli_harness.sh"

# code 64 of 255, stored as is (0.25098 in linear units), and the value its sRGB decode gives
oiiotool --pattern constant:color=0.250980392,0.250980392,0.250980392 8x8 3 -d uint8 -o "$tmp/spec.png" >/dev/null 2>&1
oiiotool --pattern constant:color=0.25,0.25,0.25 8x8 3 -d float -o "$tmp/spec.exr" >/dev/null 2>&1
check "the 8-bit map holds code 64" bash -c "oiiotool --stats '$tmp/spec.png' | grep -q 'Min: 64 64 64'"
srgb=$(awk 'BEGIN { printf "%.9g", ((64 / 255 + 0.055) / 1.055) ^ 2.4 }')  # 0.0512694585
linear=$(awk 'BEGIN { printf "%.9g", 64 / 255 }')                           # 0.250980392

# |a - b| <= tol for every pair of numbers in two lists
near() { # A-LIST B-LIST TOL
    awk -v a="$1" -v b="$2" -v t="$3" 'BEGIN { n = split(a, x, /[ ,]+/); m = split(b, y, /[ ,]+/); if (n != m) exit 1
        for (i = 1; i <= n; i++) { d = x[i] - y[i]; if (d < -t || d > t) exit 1 } }'
}
differs() { ! near "$@"; }
# two images equal within 1e-5 in every pixel
same_image() { oiiotool "$1" "$2" --fail 1e-5 --failpercent 0 --diff >/dev/null 2>&1; }
# the mean of each channel of an image, as "r g b"
means() { oiiotool --stats "$1" | sed -n 's/.*Stats Avg: *\([-0-9.e]*\) \([-0-9.e]*\) \([-0-9.e]*\).*/\1 \2 \3/p'; }

# ---- models: the rule per parameter ----
expect "models ward: an ENCODING column" 0 "ENCODING" -- "$bin" models ward
check "... specular is sRGB" grep -qE '^  specular +3 .* sRGB +specular reflectance' "$tmp/out"
check "... diffuse is sRGB" grep -qE '^  diffuse +3 .* sRGB ' "$tmp/out"
check "... alpha is linear" grep -qE '^  alpha +1 .* linear +Ward roughness' "$tmp/out"
check "... trim is linear" grep -qE '^  trim +1 .* linear ' "$tmp/out"
expect "models ggx: f0 sRGB, alpha linear" 0 "" -- "$bin" models ggx
check "... f0 sRGB" grep -qE '^  f0 +3 .* sRGB ' "$tmp/out"
check "... alpha linear" grep -qE '^  alpha +1 .* linear ' "$tmp/out"
expect "models gltf: base_color and specular_color sRGB, metallic, roughness linear" 0 "" -- "$bin" models gltf
check "... as glTF's textures" bash -c "grep -qE '^  base_color .* sRGB ' '$tmp/out' &&
    grep -qE '^  specular_color .* sRGB ' '$tmp/out' && grep -qE '^  metallic .* linear ' '$tmp/out' &&
    grep -qE '^  roughness .* linear ' '$tmp/out'"
expect "models --json: map_encoding per parameter" 0 \
    '"name": "specular", "channels": 3, .*"map_encoding": "sRGB"' -- "$bin" models ward --json
check "... alpha linear" grep -qE '"name": "alpha", [^}]*"map_encoding": "linear"' "$tmp/out"
expect "models --json (all)" 0 '"map_encoding": "linear"' -- "$bin" models --json
check "... every parameter has it" bash -c \
    "[ \$(grep -o '\"channels\"' '$tmp/out' | wc -l) -eq \$(grep -o '\"map_encoding\"' '$tmp/out' | wc -l) ]"

# ---- convert (--direct: one distinct value, one remap), NAME=FILE and NAME=@FILE ----
direct=(--direct --size 32 --tolerance 1e-6) # maps and constants alike remapped at their exact values
expect "convert: the constant 0.0513" 0 "^ggx " -- "$bin" convert --from ward --to ggx specular="$srgb" "${direct[@]}"
f0_srgb=$(sed -n 's/.* f0=\([^ ]*\).*/\1/p' "$tmp/out")
expect "convert: the constant 0.251" 0 "^ggx " -- "$bin" convert --from ward --to ggx specular="$linear" "${direct[@]}"
f0_linear=$(sed -n 's/.* f0=\([^ ]*\).*/\1/p' "$tmp/out")
check "the two constants give different f0 ($f0_srgb, $f0_linear)" differs "$f0_srgb" "$f0_linear" 0.05
expect "convert specular=spec.png" 0 "texels" -- "$bin" convert --from ward --to ggx specular="$tmp/spec.png" \
    "${direct[@]}" -o "$tmp/c1_"
check "... gives the f0 of the sRGB-decoded value ($(means "$tmp/c1_f0.exr") vs $f0_srgb)" \
    near "$(means "$tmp/c1_f0.exr")" "$f0_srgb" 1e-4
expect "convert specular=@spec.png" 0 "texels" -- "$bin" convert --from ward --to ggx specular=@"$tmp/spec.png" \
    "${direct[@]}" -o "$tmp/c2_"
check "... the same" near "$(means "$tmp/c2_f0.exr")" "$f0_srgb" 1e-4
expect "convert specular=spec.png:linear" 0 "texels" -- "$bin" convert --from ward --to ggx \
    specular="$tmp/spec.png:linear" "${direct[@]}" -o "$tmp/c3_"
check "... gives the f0 of the stored value 0.251" near "$(means "$tmp/c3_f0.exr")" "$f0_linear" 1e-4
expect "convert specular=@spec.png:srgb (the rule made explicit)" 0 "texels" -- "$bin" convert --from ward --to ggx \
    specular=@"$tmp/spec.png:srgb" "${direct[@]}" -o "$tmp/c4_"
check "... as without it" near "$(means "$tmp/c4_f0.exr")" "$f0_srgb" 1e-4
expect "convert: a float map is linear" 0 "texels" -- "$bin" convert --from ward --to ggx specular="$tmp/spec.exr" \
    "${direct[@]}" -o "$tmp/c5_"
expect "convert: the constant 0.25" 0 "^ggx " -- "$bin" convert --from ward --to ggx specular=0.25 "${direct[@]}"
f0_quarter=$(sed -n 's/.* f0=\([^ ]*\).*/\1/p' "$tmp/out")
check "... the same f0" near "$(means "$tmp/c5_f0.exr")" "$f0_quarter" 1e-4
expect "convert: :srgb on a float file is a usage error naming the map" 1 \
    "specular=.*spec.exr:srgb.*floating-point" -- "$bin" convert --from ward --to ggx specular="$tmp/spec.exr:srgb" \
    "${direct[@]}" -o "$tmp/c6_"
check "... and writes nothing" test ! -e "$tmp/c6_f0.exr"
expect "convert: selectors in the wrong order" 1 "channel comes before the encoding: .*spec.png:g:linear" -- \
    "$bin" convert --from ward --to ggx alpha="$tmp/spec.png:linear:g" "${direct[@]}" -o "$tmp/c7_"
expect "convert --format png: outputs by the same rule" 0 "texels" -- "$bin" convert --from ward --to ggx \
    specular="$tmp/spec.png" "${direct[@]}" -o "$tmp/c8_" --format png
expect "... and read back as written" 0 "" -- "$bin" convert --from ggx --to ggx f0="$tmp/c8_f0.png" \
    "${direct[@]}" -o "$tmp/c9_" --json
check "... (f0 sRGB in the PNG)" near "$(means "$tmp/c9_f0.exr")" "$f0_srgb" 0.003

# ---- render (and report, through the same material reader) ----
expect "render specular=$srgb" 0 "" -- "$bin" render ward specular="$srgb" --size 64 -o "$tmp/r_srgb.exr"
expect "render specular=$linear" 0 "" -- "$bin" render ward specular="$linear" --size 64 -o "$tmp/r_linear.exr"
expect "render specular=@spec.png" 0 "" -- "$bin" render ward specular=@"$tmp/spec.png" --size 64 -o "$tmp/r_map.exr"
check "... equals the render of the decoded constant" \
    same_image "$tmp/r_map.exr" "$tmp/r_srgb.exr"
check "... not that of the stored value" bash -c "! oiiotool '$tmp/r_map.exr' '$tmp/r_linear.exr' --diff >/dev/null 2>&1"
expect "render specular=@spec.png:linear" 0 "" -- "$bin" render ward specular=@"$tmp/spec.png:linear" --size 64 \
    -o "$tmp/r_maplin.exr"
check "... equals the render of the stored value" \
    same_image "$tmp/r_maplin.exr" "$tmp/r_linear.exr"
expect "render alpha=@spec.png:g:srgb (channel, then encoding)" 0 "" -- "$bin" render ward \
    alpha=@"$tmp/spec.png:g:srgb" --size 64 -o "$tmp/r_alpha_map.exr"
expect "render alpha=$srgb" 0 "" -- "$bin" render ward alpha="$srgb" --size 64 -o "$tmp/r_alpha.exr"
check "... the same image" same_image "$tmp/r_alpha_map.exr" "$tmp/r_alpha.exr"
expect "render: :srgb on a float map is a usage error naming it" 1 "specular=@.*spec.exr:srgb.*floating-point" -- \
    "$bin" render ward specular=@"$tmp/spec.exr:srgb" --size 16 -o "$tmp/r_bad.exr"
expect "render: an RGB parameter still takes no channel" 1 "takes the whole image" -- \
    "$bin" render ward specular=@"$tmp/spec.png:g:linear" --size 16 -o "$tmp/r_bad.exr"
cp "$tmp/spec.png" "$tmp/odd.png:linear"
expect "render: a file named '...:linear' is read with an explicit encoding after it" 0 "" -- \
    "$bin" render ward specular=@"$tmp/odd.png:linear:srgb" --size 64 -o "$tmp/r_odd.exr"
check "... as the rule reads it" same_image "$tmp/r_odd.exr" "$tmp/r_srgb.exr"
expect "report reads maps by the rule" 0 "" -- "$bin" report -o "$tmp/rep" ward specular="$srgb" -- \
    ward specular=@"$tmp/spec.png" -- ward specular=@"$tmp/spec.png:linear"
rmse=$(sed -n 's/.*"mean_relative_rmse": \([-0-9.e]*\).*/\1/p' "$tmp/rep/summary.json" | tr '\n' ' ')
check "... the map renders as the constant, :linear does not (relative RMSE $rmse)" \
    awk -v r="$rmse" 'BEGIN { split(r, x, " "); exit !(x[1] < 1e-5 && x[2] > 0.1) }'
check "... and the thumbnail names the override" grep -q 'specular (.*spec.png:linear)' "$tmp/rep/summary.json"

# ---- spec2metal / metal2spec ----
s2m=(--method weighted --diffuse 0.3 --glossiness 0.5)
expect "spec2metal --specular $srgb" 0 "metallic=" -- "$bin" spec2metal "${s2m[@]}" --specular "$srgb"
metal_srgb=$(sed -n 's/.*metallic=\([^ ]*\).*/\1/p' "$tmp/out")
expect "spec2metal --specular $linear" 0 "metallic=" -- "$bin" spec2metal "${s2m[@]}" --specular "$linear"
metal_linear=$(sed -n 's/.*metallic=\([^ ]*\).*/\1/p' "$tmp/out")
json_mean() { sed -n "s/.*\"$1\": {\"min\": [^m]*\"mean\": \[*\([-0-9.e]*\).*/\1/p" "$tmp/out"; }
expect "spec2metal --specular spec.png" 0 '"metallic"' -- "$bin" spec2metal "${s2m[@]}" --specular "$tmp/spec.png" \
    -o "$tmp/s1" --format exr --json
check "... the metallic of the decoded value ($(json_mean metallic) vs $metal_srgb)" \
    near "$(json_mean metallic)" "$metal_srgb" 1e-5
expect "spec2metal --specular spec.png:linear" 0 '"metallic"' -- "$bin" spec2metal "${s2m[@]}" \
    --specular "$tmp/spec.png:linear" -o "$tmp/s2" --format exr --json
check "... the metallic of the stored value ($(json_mean metallic) vs $metal_linear)" \
    near "$(json_mean metallic)" "$metal_linear" 1e-5
check "... its input is the file without the selector" test -s "$tmp/s2_metallic.exr"
expect "spec2metal: :srgb on a float file is a usage error naming the option" 1 \
    "'--specular .*spec.exr:srgb'.*floating-point" -- "$bin" spec2metal "${s2m[@]}" --specular "$tmp/spec.exr:srgb" \
    -o "$tmp/s3"
oiiotool --pattern constant:color=0.5,0.5,0.5 8x8 3 -d uint8 -o "$tmp/half.png" >/dev/null 2>&1
expect "metal2spec --metallic half.png (linear, as the rule says)" 0 '"specular"' -- "$bin" metal2spec \
    --basecolor 0.8 --metallic "$tmp/half.png" --roughness 0.5 -o "$tmp/m1" --format exr --json
spec_map=$(json_mean specular)
expect "metal2spec --metallic 0.50196" 0 "specular=" -- "$bin" metal2spec --basecolor 0.8 --metallic 0.501960784 \
    --roughness 0.5
check "... the same" near "$spec_map" "$(sed -n 's/.*specular=\([^,]*\),.*/\1/p' "$tmp/out")" 1e-5
expect "metal2spec --metallic half.png:srgb" 0 '"specular"' -- "$bin" metal2spec --basecolor 0.8 \
    --metallic "$tmp/half.png:srgb" --roughness 0.5 -o "$tmp/m2" --format exr --json
check "... differs" differs "$(json_mean specular)" "$spec_map" 1e-3

# ---- help texts state the rule and the override ----
expect "convert --help states the rule" 0 "FILE:linear or FILE:srgb" -- "$bin" convert --help
check "... no longer 'colour maps are sRGB-decoded, everything else is read as it is'" \
    bash -c "! grep -q 'everything else is read as it is' '$tmp/out'"
expect "render --help states the override" 0 ":linear" -- "$bin" render --help
expect "spec2metal --help states the override" 0 "FILE:linear or FILE:srgb" -- "$bin" spec2metal --help
expect "metal2spec --help states the override" 0 "FILE:linear or FILE:srgb" -- "$bin" metal2spec --help
finish
