#!/usr/bin/env bash
# Holds from the command line (issue 28): --hold NAME=VALUE sets and holds a target parameter in remap, sweep and
# convert --direct; every fitting command prints the holds it used, the caller's and the target model's default ones
# (text and --json), the sweep's header records them and learn reads them back; bad hold lists name the parameter and
# the value. A Ward texture set converts into openpbr and blender-principled by --direct, its outcomes counted. Ties
# (--tie, the default metalness tie from a glTF source) are said, recorded in the sweep header and kept by the fits.
# Ends with "N passed, N failed".
set -u
bin="${MR_BUILD:-build}/bin/matremap"
source "$(dirname "$0")/lib/cli_harness.sh"

# ---- remap -------------------------------------------------------------------------------------------------------
expect "remap --hold NAME=VALUE: held at the value, said with the model's default holds" 0 \
    "held: base_metalness=0 \(--hold\); base_weight=1, base_diffuse_roughness=0, specular_weight=1, specular_color=1, specular_ior=1.5, coat_weight=0, .* \(default for openpbr\)" -- \
    "$bin" remap --from ward diffuse=0.5 specular=0.05 alpha=0.1 --to openpbr --size 32 --hold base_metalness=0
check "... the fit keeps it" grep -q "^openpbr .* base_metalness=0 " "$tmp/out"
check "... and converges" grep -q "^outcome: converged" "$tmp/out"
expect "remap --hold: an RGB value and a bare name" 0 \
    "held: specular_color=0.9,1,1, specular_roughness=0.3 \(--hold\)" -- "$bin" remap --from ward --to openpbr \
    --size 16 --hold specular_color=0.9,1,1,specular_roughness
expect "remap --json: the holds with their values and why" 0 \
    '"held": \[\{"name": "base_weight", "value": 1, "by": "default"\}, \{"name": "base_metalness", "value": 0, "by": "--hold"\}' \
    -- "$bin" remap --from ward diffuse=0.5 specular=0.05 alpha=0.1 --to openpbr --size 16 --hold base_metalness=0 --json
expect "remap: a model without holds prints none" 0 "" -- "$bin" remap --from ward --to ward --size 16
check "... no held line" bash -c "! grep -q '^held:' '$tmp/out'"
expect "remap --json: no holds, an empty list" 0 '"held": \[\][,}]' -- "$bin" remap --from ward --to ward --size 16 --json

# Bad lists: a usage error naming the parameter and the value.
expect "--hold: an unknown parameter, the valid ones listed" 1 \
    "remap: --hold: 'metalness' is not a parameter of 'openpbr' \(valid: base_weight, " -- \
    "$bin" remap --from ward --to openpbr --hold metalness=0
expect "--hold: not a number" 1 "--hold: parameter 'base_metalness' of model 'openpbr': 'x' is not a number" -- \
    "$bin" remap --from ward --to openpbr --hold base_metalness=x
expect "--hold: out of range" 1 "--hold: parameter 'specular_ior' of model 'openpbr': 7 is outside \[1, 3\]" -- \
    "$bin" remap --from ward --to openpbr --hold specular_ior=7
expect "--hold: two channels of three" 1 "'specular_color' of model 'openpbr' takes 3 values \(or one for all\), got 2" \
    -- "$bin" remap --from ward --to openpbr --hold specular_color=1,0.5
expect "--hold: no value after =" 1 "parameter 'coat_weight' of model 'openpbr': 'coat_weight=' holds no value" -- \
    "$bin" remap --from ward --to openpbr --hold coat_weight=
expect "--hold: an empty name" 1 "hold list 'coat_weight,,base_metalness': an empty parameter name" -- \
    "$bin" remap --from ward --to openpbr --hold coat_weight,,base_metalness

# ---- convert --direct: a small Ward texture set into the layered models -------------------------------------------
oiiotool --pattern fill:top=0.05:bottom=0.3 4x4 1 -d float -o "$tmp/alpha.exr" >/dev/null 2>&1
oiiotool --pattern fill:left=0.03,0.03,0.03:right=0.2,0.2,0.2 4x4 3 -d uint8 -o "$tmp/spec.png" >/dev/null 2>&1
oiiotool --pattern fill:topleft=0.6,0.3,0.1:topright=0.1,0.4,0.6:bottomleft=0.3,0.3,0.3:bottomright=0.7,0.7,0.2 \
    4x4 3 -d uint8 -o "$tmp/diff.png" >/dev/null 2>&1
check "the Ward maps are made" test -s "$tmp/alpha.exr" -a -s "$tmp/spec.png" -a -s "$tmp/diff.png"
for target in openpbr blender-principled; do
    expect "convert --direct ward -> $target (13 and 11 parameters: more than 8 slots)" 0 \
        "ward -> $target by direct remaps, 4x4 = 16 texels" -- "$bin" convert --from ward --to "$target" \
        alpha="$tmp/alpha.exr" specular="$tmp/spec.png" diffuse="$tmp/diff.png" --direct --size 32 -o "$tmp/$target/"
    # 16 distinct values; measured: 12 converged, 2 at-bound, 2 unreachable into each (every one said, flagged red)
    check "... $target: the outcomes are counted, most converged" \
        grep -qE "outcomes: 1[2-6] converged, [0-9]+ under-resolved, [0-9]+ at-bound, [0-9]+ unreachable, 0 local" \
        "$tmp/err"
    check "... $target: the holds are said" grep -q "^matremap convert: --direct: held: .*(default for $target)" \
        "$tmp/err"
    check "... $target: every parameter written" test -s "$tmp/$target/base_color.exr" -a -s "$tmp/$target/flags.png"
done
# A glTF metal-rough set (measured: 16 of 16 converged into each).
oiiotool --pattern fill:top=0.2:bottom=0.8 4x4 1 -d float -o "$tmp/rough.exr" >/dev/null 2>&1
oiiotool --pattern fill:left=0:right=1 4x4 1 -d float -o "$tmp/metal.exr" >/dev/null 2>&1
for target in openpbr blender-principled; do
    expect "convert --direct gltf -> $target" 0 "gltf -> $target by direct remaps, 4x4 = 16 texels .*: 0 not converged" \
        -- "$bin" convert --from gltf --to "$target" base_color="$tmp/diff.png" metallic="$tmp/metal.exr" \
        roughness="$tmp/rough.exr" --direct --size 32 -o "$tmp/gltf_$target/"
done
check "... openpbr: its held parameters are written as their values" bash -c \
    "oiiotool --stats '$tmp/openpbr/specular_weight.exr' | grep -q 'Min: 1.000'"
expect "convert --direct --hold: set and held, said in --json" 0 \
    '"held": \[\{"name": "base_weight", "value": 1, "by": "default"\}, \{"name": "base_metalness", "value": 0, "by": "--hold"\}' -- \
    "$bin" convert --from ward --to openpbr \
    alpha=0.2 specular=0.05 diffuse=0.5 --direct --size 32 --hold base_metalness=0 --json
check "... the constant's answer holds it" grep -q '"base_metalness": 0,' "$tmp/out"
check "... --json counts every outcome" grep -q '"outcomes": {"converged": 1, "at-bound": 0' "$tmp/out"
expect "convert --hold without --direct" 1 "--hold goes with --direct" -- "$bin" convert --from ward --to openpbr \
    alpha=0.2 --transform x.mrt --hold base_metalness=0
expect "convert --direct --hold: a bad value names it" 1 "convert: --hold: parameter 'base_metalness' of model " -- \
    "$bin" convert --from ward --to openpbr alpha=0.2 --direct --hold base_metalness=-1

# ---- sweep -> learn: the holds recorded in the header and read back -----------------------------------------------
expect "sweep --hold NAME=VALUE: held, said" 0 \
    "matremap sweep: held: base_metalness=0 \(--hold\); base_weight=1, .* \(default for openpbr\)" -- \
    "$bin" sweep --from ward --to openpbr --random 12 --size 16 --threads 2 --hold base_metalness=0 -o "$tmp/s.csv"
check "... the header records the value and the hold" bash -c \
    "grep -q '^# to: openpbr .* base_metalness=0 ' '$tmp/s.csv' && grep -q '^# remap: .* held=base_metalness$' '$tmp/s.csv'"
check "... every row holds it" bash -c "awk -F, 'NR > 1 && !/^#/ && \$0 !~ /^index/' '$tmp/s.csv' | wc -l | grep -q 12"
expect "learn reads the sweep's holds" 0 "held: base_metalness=0 \(--hold\); base_weight=1, " -- \
    "$bin" learn "$tmp/s.csv" --method svr -o "$tmp/s.mrt"
check "... no 'constant in every row' note for what the sweep held" bash -c \
    "! grep -q 'target base_metalness is' '$tmp/out'"
expect "learn --json: the holds" 0 '"held": \[\{"name": "base_weight", "value": 1, "by": "default"\}, \{"name": "base_metalness", "value": 0, "by": "--hold"\}' \
    -- "$bin" learn "$tmp/s.csv" --method svr -o "$tmp/s2.mrt" --json
expect "sweep --hold: a bad name" 1 "sweep: --hold: 'metal' is not a parameter of 'openpbr'" -- \
    "$bin" sweep --from ward --to openpbr --random 2 --hold metal=0 -o "$tmp/bad.csv"

# ---- ties (docs/remap.md, "Ties"): a metalness the source states is held at its value ------------------------------
expect "remap gltf -> openpbr: base_metalness tied to metallic by default, said" 0 \
    "^tied: base_metalness=metallic, specular_color=specular_color, specular_ior=ior \(default for gltf -> openpbr\)" -- "$bin" remap --from gltf \
    base_color=0.9 metallic=1 roughness=0.9 ior=1.7 --to openpbr --size 16
check "... the fit keeps the source's metalness and IOR" grep -q "^openpbr .* base_metalness=1 .* specular_ior=1.7 " \
    "$tmp/out"
check "... the tied IOR is not said held at the default 1.5" bash -c "! grep -q '^held: .*specular_ior' '$tmp/out'"
expect "remap --tie none: fitted, no tied line" 0 "" -- "$bin" remap --from gltf base_color=0.9 metallic=1 \
    roughness=0.9 --to openpbr --size 16 --tie none
check "... no tied line" bash -c "! grep -q '^tied:' '$tmp/out'"
expect "remap --hold on the tied parameter: the hold wins, it is not tied" 0 "held: base_metalness=0.25 \(--hold\)" -- \
    "$bin" remap --from gltf metallic=1 roughness=0.5 --to openpbr --size 16 --hold base_metalness=0.25
check "... only the IOR and specular colour tied, the held value kept" bash -c \
    "grep -q '^tied: specular_color=specular_color, specular_ior=ior (default' '$tmp/out' && grep -q '^openpbr .* base_metalness=0.25 ' '$tmp/out'"
expect "remap --tie given, in --json" 0 '"tied": \[\{"name": "metalness", "source": "metallic", "by": "--tie"\}\]' -- \
    "$bin" remap --from gltf metallic=0.5 --to standard-surface --size 16 --tie metalness=metallic --json
expect "remap ward -> openpbr: Ward has no metalness, nothing tied" 0 '"tied": \[\]' -- \
    "$bin" remap --from ward --to openpbr --size 16 --json
expect "--tie: a channel mismatch named" 1 "--tie: tie list 'base_color=metallic': base_color has 3 channel" -- \
    "$bin" remap --from gltf --to openpbr --tie base_color=metallic
expect "--tie: an unknown target parameter" 1 "'metal' is not a parameter of 'openpbr' a fit can tie" -- \
    "$bin" remap --from gltf --to openpbr --tie metal=metallic
expect "--tie without --from" 1 "--tie needs --from MODEL" -- \
    "$bin" remap --from-images "$tmp/none.exr" --to openpbr --tie none
expect "sweep gltf -> openpbr: the tie said and recorded in the header" 0 \
    "matremap sweep: tied: base_metalness=metallic, specular_color=specular_color, specular_ior=ior \(default for gltf -> openpbr\)" -- \
    "$bin" sweep --from gltf \
    --to openpbr --grid metallic=0:1:2 --size 16 -o "$tmp/tied.csv"
check "... the header's remap line: the ties" \
    grep -q "^# remap: .* tied=base_metalness:metallic,specular_color:specular_color,specular_ior:ior$" "$tmp/tied.csv"
expect "convert --direct gltf -> blender-principled: tied, said" 0 \
    "tied: metallic=metallic, ior=ior, specular_tint=specular_color \(default for gltf -> blender-principled\)" -- "$bin" convert --from gltf \
    --to blender-principled base_color=0.5 metallic=0.3 roughness=0.6 --direct --size 16
check "... the converted metallic is the source's" grep -q " metallic=0.3 " "$tmp/out"
finish
