#!/usr/bin/env bash
# The readers never trust a file (issue 16, parts 2 and 4): every malformed or lying input that
# tests/lib/hostile_inputs.py makes (glTF JSON nested 50000 deep, accessor counts of 2^30, URIs naming a folder, a FIFO
# or /dev/zero, material extensions that are not objects, factors of the wrong type, length or range, PNG/JPEG/HDR
# headers claiming 16000 x 16000 over a few bytes, corrupt deflate data, EXR data windows out of range...) goes
# through the command a user would run on it, and each must end with exit 2 and exactly one line on stderr (nothing
# that libpng, libjpeg, OpenEXR, OpenImageIO or tinygltf prints of their own), naming the file and the field or
# value, within seconds, with the input unchanged and nothing written. Copies of the inputs are kept in
# tests/fuzz/regressions/. Needs python3 and oiiotool. Ends with "N passed, N failed".
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
build="${MR_BUILD:-$root/build}"
bin="$build/bin/matremap"
source "$(dirname "$0")/lib/cli_harness.sh"

oiiotool --pattern constant:color=0.5,0.2,0.1 64x64 3 -o "$tmp/base.jpg"
oiiotool --pattern checker 16x16 3 -d uint8 -o "$tmp/ref.png"
python3 "$root/tests/lib/hostile_inputs.py" "$tmp/in" "$tmp/base.jpg"
in=$tmp/in
# What glTF URIs name that git cannot keep: a folder and a FIFO beside the assets.
mkdir "$in/gltf/textures"
mkfifo "$in/gltf/fifo.png"

# refuse NAME FILE PATTERN -- command...: exit 2 within 60 s (timeout: a hang fails, exit 124) with PATTERN in the
# output; stderr exactly one line, naming FILE; stdout empty; FILE unchanged (a FIFO is not read to compare it);
# nothing written into $tmp/o, the command's output folder.
refuse() {
    local name=$1 file=$2 pattern=$3
    shift 4
    rm -rf "$tmp/o"
    mkdir "$tmp/o"
    local before=""
    [ -f "$file" ] && before=$(md5sum <"$file")
    expect "$name" 2 "$pattern" -- timeout 60 "$@"
    check "$name: one line on stderr naming the file, none on stdout" \
        test "$(wc -l <"$tmp/err")" -eq 1 -a ! -s "$tmp/out" -a "$(grep -cF -- "$file" "$tmp/err")" -eq 1
    local after=""
    [ -f "$file" ] && after=$(md5sum <"$file")
    check "$name: input unchanged, nothing written" test "$after" = "$before" -a -z "$(ls -A "$tmp/o")"
}
gltf() { refuse "gltf spec2metal $1" "$in/gltf/$1" "$2" -- "$bin" gltf spec2metal "$in/gltf/$1" -o "$tmp/o/o.gltf"; }
report() { refuse "report $1" "$in/gltf/$1" "$2" -- "$bin" report "$in/gltf/$1" -o "$tmp/o/report"; }
image() {
    refuse "ssim $1" "$in/$1" "$2" -- "$bin" ssim "$in/$1" "$tmp/ref.png" --map "$tmp/o/map.png"
}

# ---- glTF: the JSON ---------------------------------------------------------------------------------------------
gltf json-arrays-50000-deep.gltf "nests deeper than 128 levels \(at byte 163\)"
gltf json-objects-50000-deep.gltf "nests deeper than 128 levels \(at byte [0-9]+\)"
gltf json-arrays-50000-deep.glb "nests deeper than 128 levels \(at byte 183\)"
report json-arrays-50000-deep.gltf "nests deeper than 128 levels"

# ---- glTF: sizes taken from the file, checked against the bytes that hold them --------------------------------------
report accessor-count-2e30.gltf "POSITION: accessor 0: count 1073741824 .* runs past the end of buffer view 0"
report accessor-count-2e62-stride-overflow.gltf "accessor 0: count 4611686018427387904 .*byteStride 12"
report accessor-offset-2e63.gltf "accessor 0: .*byteOffset 9223372036854775808 runs past"
report bufferview-past-buffer.gltf "buffer view 0 \(byteOffset 0, byteLength 1000000\) exceeds buffer 0 \(36 bytes\)"
report sparse-count-2e30.gltf "accessor 0: sparse.count 1073741824 out of range"
report zero-accessor-instanced-4096-times.gltf "accessor 0: count 1048576 takes the scene past the limit of 16777216"
gltf image-bufferview-past-buffer.glb "image 0: buffer view 0 \(byteOffset 0, byteLength 1048576\) runs past the end"
gltf glb-buffer-bytelength-0.glb "malformed"

# ---- glTF: URIs naming what is not a file (by name, before a byte is read) -------------------------------------------
gltf image-uri-folder.gltf "image 0 \('textures/'\): is a directory"
gltf buffer-uri-folder.gltf "buffer 0 \('textures/'\): is a directory"
gltf image-uri-fifo.gltf "image 0 \('fifo.png'\): is not a regular file \(a FIFO\)"
gltf buffer-uri-fifo.gltf "buffer 0 \('fifo.png'\): is not a regular file \(a FIFO\)"
gltf image-uri-dev-zero.gltf "image 0 \('(\.\./)+dev/zero'\): is not a regular file \(a character device\)"
gltf buffer-uri-dev-zero.gltf "buffer 0 \('(\.\./)+dev/zero'\): is not a regular file \(a character device\)"
report image-uri-folder.gltf "image 0 \('textures/'\): is a directory"

# ---- glTF: embedded images named by asset and index, never by a scratch file ----------------------------------------
gltf embedded-image-truncated.gltf "material 0 'Cut': glTF '[^']*': image 0: truncated PNG"
report embedded-image-truncated.gltf "material 'Cut': diffuseTexture: glTF '[^']*': image 0: truncated PNG"
gltf embedded-image-ihdr-100000.glb "image 0: 100000x100000 pixels exceeds the maximum dimension 16384"
check "no message names a scratch file" test "$(grep -c 'matremap-gltf' "$tmp/err")" -eq 0

# ---- glTF: materials as the schema has them (tinygltf drops or defaults what it cannot parse) ------------------------
sg=KHR_materials_pbrSpecularGlossiness
material() { gltf "material-$1.gltf" "material 0 \('Hostile'\): $2"; }
material extension-number "extensions.$sg is a number, not a JSON object"
material extension-array "extensions.$sg is an array, not a JSON object"
material extension-number-escaped-key "extensions.$sg is a number, not a JSON object"
material extensions-string "extensions is a string, not a JSON object"
material specgloss-diffusefactor-string "extensions.$sg.diffuseFactor\[2\] is a string, not a number"
material specgloss-specularfactor-length-2 "extensions.$sg.specularFactor has 2 values, expected 3"
material specgloss-texture-index-7 "extensions.$sg.diffuseTexture.index is 7: no such texture \(the asset has 1\)"
material specgloss-texture-no-index "extensions.$sg.diffuseTexture has no index"
material specgloss-texture-texcoord-negative \
    "extensions.$sg.diffuseTexture.texCoord is -1, expected a non-negative integer"
material texture-transform-not-object \
    "extensions.$sg.diffuseTexture.extensions.KHR_texture_transform is a number, not a JSON object"
material metallic-factor-string "pbrMetallicRoughness.metallicFactor is a string, not a number"
material metallic-factor-2 "pbrMetallicRoughness.metallicFactor is 2, expected within \[0, 1\]"
material basecolor-factor-length-3 "pbrMetallicRoughness.baseColorFactor has 3 values, expected 4"
material basecolor-texture-index-7 "pbrMetallicRoughness.baseColorTexture.index is 7: no such texture"
material emissive-factor-negative "emissiveFactor\[1\] is -1, expected within \[0, 1\]"
material alpha-mode-unknown "alphaMode is 'GLASS', expected OPAQUE, MASK or BLEND"
material ior-below-1 "extensions.KHR_materials_ior.ior is 0.5, expected at least 1"
gltf material-specgloss-glossiness-1e999.gltf "invalid JSON: .*number overflow parsing '1e999'"
gltf texture-source-9.gltf "texture 0: source 9: no such image \(the asset has 1\)"
report material-extension-number.gltf "extensions.$sg is a number, not a JSON object"

# ---- PNG (png_deflate.c, libpng): IHDR against max_dimension and against what IDAT can inflate to -------------------
image png/ihdr-100000x100000.png "100000x100000 pixels exceeds the maximum dimension 16384"
image png/ihdr-16000x16000-idat-tiny.png "truncated PNG: IHDR claims 16000x16000 pixels .* IDAT chunks hold 12"
image png/ihdr-16000x16000-interlaced.png "truncated PNG: IHDR claims 16000x16000 pixels"
image png/palette-16000x16000.png "truncated PNG: IHDR claims 16000x16000 pixels"
image png/idat-corrupt-deflate.png "cannot decode PNG \(corrupt or truncated\?\): IDAT: invalid"
check "libpng's own 'libpng error' line is not printed" test "$(grep -c 'libpng error' "$tmp/err")" -eq 0
image png/truncated-in-idat.png "truncated PNG: chunk 'IDAT' at byte 33"
image png/ihdr-zero-width.png "corrupt PNG: IHDR gives 0x16 pixels"
image png/ihdr-colour-type-5.png "corrupt PNG: IHDR gives colour type 5"
image png/no-idat.png "IDAT chunks hold 0 compressed bytes"

# ---- JPEG, EXR, HDR through OpenImageIO: the spec checked before pixels, pixels read a band at a time ----------------
# (The EXR and JPEG patterns take OpenEXR's and libjpeg's words or those of a structure check before them.)
image jpeg/sof-16000x16000.jpg "decoded with errors .*premature end of data"
image jpeg/sof-65000x65000.jpg "65000x65000 pixels exceeds the maximum dimension 16384"
image jpeg/sof-zero-height.jpg "Empty JPEG image"
image jpeg/truncated-in-header.jpg "Premature end of JPEG file|corrupt JPEG"
image jpeg/truncated-in-scan.jpg "Premature end of JPEG file|corrupt JPEG"
image exr/data-window-2e30.exr "Invalid data window|data window|exceeds the maximum dimension|larger than the limit"
image exr/data-window-16000x16000.exr "Unexpected end of file|offset|truncated"
image exr/data-window-origin-2e31.exr "Invalid data window|data window"
image exr/data-window-negative-origin.exr "Invalid data window|data window"
image exr/data-window-inverted.exr "Invalid data window|data window"
image exr/data-window-width-wraps.exr "Invalid data window|data window|larger than the limit"
image exr/tiles-2e30.exr "[Tt]ile"
image exr/truncated.exr "Unexpected end of file|truncated|outside"
image hdr/header-100000x100000.hdr "100000x100000 pixels exceeds the maximum dimension 16384"
image hdr/header-16000x16000-4-pixels.hdr "cannot decode pixels .*scanline 0"
image hdr/header-negative-height.hdr "empty image \(4x-5"
image hdr/header-no-size.hdr "missing image size"
image hdr/truncated-rows.hdr "cannot decode pixels .*scanline 2"
# A JPEG is read whole (its header is rewritten in memory): one larger than 1 GiB is refused before (a sparse file).
printf '\377\330\377\340' >"$in/jpeg/sparse-1100M.jpg"
truncate -s 1100M "$in/jpeg/sparse-1100M.jpg"
image jpeg/sparse-1100M.jpg "1153433600 bytes, more than the 1073741824 a JPEG file may have"
# GIF, BMP and WebP: the declared picture refused before OpenImageIO's reader allocates it at open.
image other/screen-28941x16316.gif "its GIF header declares 28941 x 16316 pixels \(each side 1 to 16384\)"
image other/dib-100000x100000-rle8.bmp "its BMP header declares 100000 x 100000 pixels"
image other/canvas-1048577x1048577.webp "its WebP header declares 1048577 x 1048577 pixels"

# A JPEG that lies about its size costs what it holds, not what it claims: time and memory measured.
start=$(date +%s%N)
"$bin" ssim "$in/jpeg/sof-16000x16000.jpg" "$tmp/ref.png" >/dev/null 2>&1
elapsed_ms=$((($(date +%s%N) - start) / 1000000))
check "a JPEG claiming 16000x16000 is refused within 10 s (took ${elapsed_ms} ms)" test "$elapsed_ms" -lt 10000
if [ -x /usr/bin/time ]; then
    /usr/bin/time -f "%M" -o "$tmp/peak" "$bin" ssim "$in/hdr/header-16000x16000-4-pixels.hdr" "$tmp/ref.png" \
        >/dev/null 2>&1
    peak=$(tail -1 "$tmp/peak")
    check "an HDR header claiming 16000x16000 costs less than 1 GB (peak ${peak} KB; 3 GB before)" \
        test "${peak:-9999999}" -lt 1000000
fi

# ---- any input file: a folder, a FIFO, a device is refused by name -------------------------------------------------
mkdir "$tmp/folder.png"
mkfifo "$tmp/fifo.exr"
refuse "ssim of a folder" "$tmp/folder.png" "image '[^']*folder.png': is a directory" -- \
    "$bin" ssim "$tmp/folder.png" "$tmp/ref.png"
refuse "ssim of a FIFO (no hang)" "$tmp/fifo.exr" "image '[^']*fifo.exr': is not a regular file \(a FIFO\)" -- \
    "$bin" ssim "$tmp/fifo.exr" "$tmp/ref.png"
expect "ssim of /dev/zero" 2 "image '/dev/zero': is not a regular file \(a character device\)" -- \
    timeout 60 "$bin" ssim /dev/zero "$tmp/ref.png"
mkfifo "$tmp/fifo.hdr" "$tmp/fifo.obj"
refuse "report --env FIFO (no hang)" "$tmp/fifo.hdr" "image '[^']*fifo.hdr': is not a regular file \(a FIFO\)" -- \
    "$bin" report --env "$tmp/fifo.hdr" -o "$tmp/o/report" ggx alpha=0.3
env_map="${MR_SHARED:-$root/../shared}/assets/hdri/studio_small_03_1k.hdr"
if [ -f "$env_map" ]; then
    refuse "report --mesh FIFO (no hang)" "$tmp/fifo.obj" "OBJ '[^']*fifo.obj': cannot read: is not a regular file" \
        -- "$bin" report --mesh "$tmp/fifo.obj" --env "$env_map" -o "$tmp/o/report" ggx alpha=0.3
fi
mkfifo "$tmp/fifo.gltf"
refuse "a glTF that is a FIFO" "$tmp/fifo.gltf" "glTF '[^']*fifo.gltf': is not a regular file \(a FIFO\)" -- \
    "$bin" gltf spec2metal "$tmp/fifo.gltf" -o "$tmp/o/o.gltf"

# The text readers too: sweep files (learn, train, sweep merge), transforms (convert), networks (spec2metal).
mkfifo "$tmp/fifo.csv" "$tmp/fifo.mrt" "$tmp/fifo.mlp"
refuse "train of a FIFO (no hang)" "$tmp/fifo.csv" "fifo.csv: is not a regular file \(a FIFO\)" -- \
    "$bin" train "$tmp/fifo.csv" -o "$tmp/o/x.mlp"
refuse "learn of a FIFO (no hang)" "$tmp/fifo.csv" "fifo.csv: is not a regular file \(a FIFO\)" -- \
    "$bin" learn "$tmp/fifo.csv" -o "$tmp/o/x.mrt"
refuse "sweep merge of a FIFO (no hang)" "$tmp/fifo.csv" "shard file '[^']*fifo.csv': is not a regular file \(a FIFO\)" -- \
    "$bin" sweep merge "$tmp/fifo.csv" -o "$tmp/o/m.csv"
refuse "convert --transform of a FIFO (no hang)" "$tmp/fifo.mrt" \
    "transform '[^']*fifo.mrt': is not a regular file \(a FIFO\)" -- \
    "$bin" convert --from ward --to ggx alpha=0.1 --transform "$tmp/fifo.mrt" -o "$tmp/o/cv"
refuse "spec2metal --weights of a FIFO (no hang)" "$tmp/fifo.mlp" "weights '[^']*fifo.mlp': is not a regular file" -- \
    "$bin" spec2metal --diffuse "$tmp/ref.png" --specular "$tmp/ref.png" --glossiness 0.5 --method mlp \
    --weights "$tmp/fifo.mlp" -o "$tmp/o/s2m"

finish
