#!/usr/bin/env bash
# CLI contract tests for `matremap`: help everywhere, exit codes (0 ok, 1 usage, 2 bad input), messages that
# name the bad value and list valid ones, render -> file, ssim identities. Ends with "N passed, N failed".
set -u
bin="${MR_BUILD:-build}/bin/matremap"
source "$(dirname "$0")/lib/cli_harness.sh"

expect "no arguments is a usage error" 1 "Usage" -- "$bin"
expect "top-level help" 0 "Commands:" -- "$bin" --help
expect "unknown command lists commands" 1 "valid:.*render" -- "$bin" frobnicate
for cmd in models render ssim remap sweep train spec2metal metal2spec report gltf; do
    expect "$cmd --help" 0 "Usage: matremap $cmd" -- "$bin" $cmd --help
done
expect "models lists ggx" 0 "^ggx " -- "$bin" models
expect "models lists every registered model in JSON" 0 '"name": "cycles-ggx"' -- "$bin" models --json
expect "models NAME shows ranges" 0 "roughness" -- "$bin" models gltf
expect "models unknown name lists valid ones" 2 "unknown BRDF model 'ggxx' \(valid: .*ggx" -- "$bin" models ggxx

expect "render gltf to EXR" 0 "wrote" -- "$bin" render gltf base_color=0.8,0.3,0.1 metallic=0 roughness=0.4 \
    --size 64 -o "$tmp/x.exr"
expect "ssim of an image with itself is 1" 0 "^1\.000000$" -- "$bin" ssim "$tmp/x.exr" "$tmp/x.exr"
expect "ssim --json has ssim and rmse" 0 '"ssim": 1, "rmse": 0' -- "$bin" ssim --json "$tmp/x.exr" "$tmp/x.exr"
expect "render specular component to PNG" 0 "" -- "$bin" render ggx alpha=0.2 --component specular \
    --light frontal --size 64 -o "$tmp/s.png"
expect "ssim between different renders is below 1" 0 "^0\.[0-9]+$" -- "$bin" ssim "$tmp/s.png" "$tmp/x.exr"
expect "ssim --map writes a picture" 0 "" -- "$bin" ssim "$tmp/s.png" "$tmp/x.exr" --map "$tmp/map.png"
if [ -s "$tmp/map.png" ]; then echo "ok    ssim map file exists"; passed=$((passed + 1));
else echo "FAIL  ssim map file missing"; failed=$((failed + 1)); fi

expect "unknown model" 2 "unknown BRDF model 'nope' \(valid:" -- "$bin" render nope -o "$tmp/y.exr"
expect "unknown parameter lists valid ones" 2 "no parameter 'rough' \(valid: .*roughness" -- \
    "$bin" render gltf rough=0.5 -o "$tmp/y.exr"
expect "out-of-range parameter" 2 "outside \[0, 1\]" -- "$bin" render gltf metallic=1.5 -o "$tmp/y.exr"
expect "malformed parameter" 2 "not a number" -- "$bin" render gltf metallic=abc -o "$tmp/y.exr"
expect "missing output" 1 "missing -o" -- "$bin" render gltf
expect "bad size" 1 "--size" -- "$bin" render gltf --size 0 -o "$tmp/y.exr"
expect "bad light" 1 "valid: 45, frontal" -- "$bin" render gltf --light 30 -o "$tmp/y.exr"
expect "unknown option" 1 "unknown option '--frob'" -- "$bin" render gltf --frob -o "$tmp/y.exr"
expect "unknown extension" 2 "y.xyz" -- "$bin" render gltf --size 32 -o "$tmp/y.xyz"
if ls "$tmp" | grep -q 'y\.'; then echo "FAIL  a failed render left a file behind"; failed=$((failed + 1));
else echo "ok    failed renders leave no file"; passed=$((passed + 1)); fi
touch "$tmp/plain"
expect "a folder that cannot be made (under a file)" 2 "cannot create the folder '$tmp/plain'" -- \
    "$bin" render gltf --size 32 -o "$tmp/plain/nodir/y.exr"
expect "ssim missing file names it" 2 "missing.exr" -- "$bin" ssim "$tmp/missing.exr" "$tmp/x.exr"
"$bin" render lambert --size 32 -o "$tmp/small.exr" 2>/dev/null
expect "ssim size mismatch names both files" 2 "small.exr' is 32x32 but .*x.exr' is 64x64" -- \
    "$bin" ssim "$tmp/small.exr" "$tmp/x.exr"
expect "ssim needs two images" 1 "two images" -- "$bin" ssim "$tmp/x.exr"

# ssim: --map never replaces an image it compares or the mask (by inode: spellings and links count).
mkdir -p "$tmp/io"
cp "$tmp/x.exr" "$tmp/io/a.exr"
"$bin" render lambert --size 64 -o "$tmp/io/b.exr" --mask "$tmp/io/mask.png" 2>/dev/null
ln "$tmp/io/b.exr" "$tmp/io/b_link.exr"
refuses "ssim --map over image A" "output '$tmp/io/./a.exr' \(--map\) is the input image A $tmp/io/a.exr; refusing" \
    "$tmp/io" -- "$bin" ssim "$tmp/io/a.exr" "$tmp/io/b.exr" --map "$tmp/io/./a.exr"
refuses "ssim --map over a hard link of image B" "is the input image B $tmp/io/b.exr" "$tmp/io" -- \
    "$bin" ssim "$tmp/io/a.exr" "$tmp/io/b.exr" --map "$tmp/io/b_link.exr"
refuses "ssim --map over the mask" "is the input --mask" "$tmp/io" -- \
    "$bin" ssim "$tmp/io/a.exr" "$tmp/io/b.exr" --mask "$tmp/io/mask.png" --map "$tmp/io/mask.png"

# ssim: images are measurements, finite radiance >= 0; anything else is bad input (2) naming file, pixel, value.
oiiotool --pattern constant:color=nan,nan,nan 1x1 3 -d float --pattern constant:color=0.2,0.2,0.2 64x64 3 \
    -d float --paste +3+5 -o "$tmp/io/nan.exr"
oiiotool --pattern constant:color=0.1,inf,0.1 1x1 3 -d float --pattern constant:color=0.2,0.2,0.2 64x64 3 \
    -d float --paste +60+2 -o "$tmp/io/inf.exr"
oiiotool --pattern constant:color=0.1,0.1,-0.25 1x1 3 -d float --pattern constant:color=0.2,0.2,0.2 64x64 3 \
    -d float --paste +0+63 -o "$tmp/io/negative.exr"
expect "ssim of a NaN pixel: bad input, named" 2 "image '$tmp/io/nan.exr': pixel \(3, 5\), channel 0 holds nan" -- \
    "$bin" ssim "$tmp/io/a.exr" "$tmp/io/nan.exr"
expect "ssim of an infinite pixel: bad input, named" 2 "inf.exr': pixel \(60, 2\), channel 1 holds inf" -- \
    "$bin" ssim "$tmp/io/inf.exr" "$tmp/io/a.exr" --json
expect "ssim of negative radiance: bad input, named" 2 "negative.exr': pixel \(0, 63\), channel 2 holds -0.25" -- \
    "$bin" ssim "$tmp/io/a.exr" "$tmp/io/negative.exr" --map "$tmp/io/never.png"
check "... and no --map written" test ! -e "$tmp/io/never.png"

# OpenImageIO is a module loaded on first use: commands that need no image decoding never load it, and a
# missing module is a clear external failure (exit 3), not a crash.
expect "EXR output does not need the OpenImageIO module" 0 "wrote" -- env MR_OIIO_MODULE=/nonexistent/mod.so \
    "$bin" render lambert --size 32 -o "$tmp/lazy.exr"
expect "a missing OpenImageIO module is reported" 3 "cannot load the OpenImageIO module.*mod.so" -- \
    env MR_OIIO_MODULE=/nonexistent/mod.so "$bin" ssim "$tmp/x.exr" "$tmp/x.exr"

# So are the C++ libraries (tinygltf, tinyobjloader, libsvm; src/cxx_module.c): a remap never loads them, a glTF
# command without them is an external failure naming the module, and the tool itself links no C++ runtime (a
# sanitizer's runtime brings its own: not checked there). Not in a CXX_MODULE=0 build, which links them in.
if [ -e "$(dirname "$bin")/../lib/matremap/libmatremap-cxx.so" ]; then
    expect "a remap does not need the C++ module" 0 "outcome: converged" -- env MR_CXX_MODULE=/nonexistent/cxx.so \
        "$bin" remap --from ggx alpha=0.2 --to ward
    printf '{"asset": {"version": "2.0"}}\n' > "$tmp/empty.gltf"
    expect "a missing C++ module is reported" 3 "cannot load matremap's C\+\+ module libmatremap-cxx.so.*cxx.so" -- \
        env MR_CXX_MODULE=/nonexistent/cxx.so "$bin" gltf spec2metal "$tmp/empty.gltf" -o "$tmp/cxx/out.gltf"
    check "... and leaves no output" test ! -e "$tmp/cxx/out.gltf"
    modules="$(cd "$(dirname "$bin")/../lib/matremap" && pwd)"
    expect "a module of another kind in its place is named, with what it lacks" 3 \
        "libmatremap-oiio.so: not a matremap C\+\+ module \(no mr_cxx_module_table\)" -- \
        env MR_CXX_MODULE="$modules/libmatremap-oiio.so" "$bin" gltf spec2metal "$tmp/empty.gltf" -o "$tmp/cxx/out.gltf"
    expect "... and so for the OpenImageIO module" 3 \
        "libmatremap-cxx.so: not a matremap image module \(no mr_oiio_module_read\)" -- \
        env MR_OIIO_MODULE="$modules/libmatremap-cxx.so" "$bin" ssim "$tmp/x.exr" "$tmp/s.png"
    check "... and leaves no output" test ! -e "$tmp/cxx/out.gltf"
    if ! ldd "$bin" | grep -q 'libasan'; then
        check "the tool links no C++ runtime" sh -c "! ldd '$bin' | grep -q 'libstdc++'"
    fi
fi

finish
