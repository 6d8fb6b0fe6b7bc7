#!/usr/bin/env bash
# make-corpus.sh — the fuzz targets' seed corpora, from the project's own data, tests' kind of inputs and the
# real assets of ../shared/assets, made small (a seed is read thousands of times a second; libFuzzer's inputs
# grow from it). Usage: tests/fuzz/make-corpus.sh BUILD OUT   (BUILD: a normal build with bin/matremap; OUT gets
# one folder per target). Idempotent: a folder that exists is left as it is (delete OUT to remake it).
set -euo pipefail
build=$1
out=$2
root=$(cd "$(dirname "$0")/../.." && pwd)
shared=${MR_SHARED:-$root/../shared}
assets=$shared/assets
bin=$build/bin/matremap
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

need() { [ ! -d "$out/$1" ] && mkdir -p "$out/$1"; }
made() { echo "fuzz corpus: $1: $(ls "$out/$1" | wc -l) seeds" >&2; }

# Small images of every kind the readers take, from the assets' textures and maps.
small_pngs=()
for f in "$assets"/metalrough/TextureSettingsTest/glTF/*.png "$assets"/specgloss/Duck-pbrSpecularGlossiness/*/*.png \
         "$assets"/metalrough/WaterBottle/glTF/WaterBottle_emissive.png; do
    [ -f "$f" ] && small_pngs+=("$f")
done
[ ${#small_pngs[@]} -gt 0 ] || { echo "fuzz corpus: no PNG under $assets" >&2; exit 2; }

if need png; then
    i=0
    for f in "${small_pngs[@]}"; do
        i=$((i + 1))
        oiiotool "$f" --resize 24x24 -o "$out/png/rgb$i.png"
        oiiotool "$f" --resize 16x16 --ch R -o "$out/png/grey$i.png"
        oiiotool "$f" --resize 16x16 -d uint16 -o "$out/png/rgb16_$i.png"
        oiiotool "$f" --resize 12x12 --ch R,G,B,A=1 -o "$out/png/rgba$i.png"
    done
    # Interlaced and palette PNGs come from Python's zlib (the project's tests make the same kinds).
    python3 - "$out/png" <<'PY'
import struct, sys, zlib
def chunk(t, d): return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xffffffff)
def png(path, w, h, ctype, depth, rows, extra=b"", interlace=0):
    ihdr = struct.pack(">IIBBBBB", w, h, depth, ctype, 0, 0, interlace)
    raw = b"".join(b"\x00" + r for r in rows)
    body = chunk(b"IHDR", ihdr) + extra + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")
    open(path, "wb").write(b"\x89PNG\r\n\x1a\n" + body)
out = sys.argv[1]
png(out + "/palette.png", 8, 8, 3, 8, [bytes((x + y) % 4 for x in range(8)) for y in range(8)],
    chunk(b"PLTE", bytes([255,0,0, 0,255,0, 0,0,255, 255,255,255])) + chunk(b"tRNS", bytes([255, 128])))
png(out + "/palette2bit.png", 8, 4, 3, 2, [bytes([0x1b, 0xe4]) for y in range(4)], chunk(b"PLTE", bytes(range(12))))
png(out + "/grey_alpha.png", 4, 4, 4, 8, [bytes(range(8)) for y in range(4)])
png(out + "/gamma.png", 4, 4, 2, 8, [bytes(range(12)) for y in range(4)], chunk(b"gAMA", struct.pack(">I", 45455)))
PY
    made png
fi

if need jpeg; then
    i=0
    for f in "${small_pngs[@]}"; do
        i=$((i + 1))
        oiiotool "$f" --resize 24x24 --ch R,G,B -o "$out/jpeg/rgb$i.jpg"
        oiiotool "$f" --resize 16x16 --ch R -o "$out/jpeg/grey$i.jpg"
        oiiotool "$f" --resize 17x9 --ch R,G,B --attrib "Compression" "jpeg:50" -o "$out/jpeg/odd$i.jpg"
    done
    made jpeg
fi

if need exr; then
    f=${small_pngs[0]}
    for c in none rle zip zips piz pxr24 b44 b44a dwaa dwab; do
        oiiotool "$f" --resize 16x16 -d half --compression "$c" -o "$out/exr/half_$c.exr"
        oiiotool "$f" --resize 16x16 -d float --compression "$c" -o "$out/exr/float_$c.exr"
    done
    oiiotool "$f" --resize 32x32 -d half --tile 16 16 -o "$out/exr/tiled.exr"
    oiiotool "$f" --resize 16x16 --ch R -d float -o "$out/exr/grey.exr"
    oiiotool "$f" --resize 16x16 --ch R,G,B,A=1 -d half -o "$out/exr/rgba.exr"
    oiiotool "$f" --resize 37x23 --tile 8 8 -d half -o "$out/exr/tiled_odd.exr"
    oiiotool "$f" --resize 37x23 -d half -otex:resize=0 "$out/exr/mipmap.exr"
    oiiotool "$f" --resize 16x16 --attrib oiio:subimagename a "$f" --resize 16x16 --ch R,G \
        --attrib oiio:subimagename b --siappend -o "$out/exr/multipart.exr"
    made exr
fi

if need hdr; then
    for f in "$assets"/hdri/*.hdr "$root"/data/demo/*.hdr; do
        [ -f "$f" ] || continue
        n=$(basename "$f" .hdr)
        oiiotool "$f" --resize 32x16 -o "$out/hdr/$n.hdr"   # RLE rows (8 <= width < 32768)
        oiiotool "$f" --resize 6x3 -o "$out/hdr/${n}_flat.hdr"  # too narrow for RLE: flat RGBE
    done
    made hdr
fi

if need gltf; then
    # The assets as self-contained files: their real JSON and buffers, their images shrunk to 8x8 and embedded
    # (.glb chunk, and data URIs in a .gltf), so that the loader reaches every part without other files.
    oiiotool "${small_pngs[0]}" --resize 8x8 -o "$tmp/tiny.png"
    for g in "$assets"/specgloss/*/*/*.gltf "$assets"/specgloss/*/*.gltf "$assets"/metalrough/*/glTF/*.gltf; do
        [ -f "$g" ] || continue
        python3 - "$g" "$tmp/tiny.png" "$out/gltf" <<'PY'
import base64, json, os, struct, sys
src, tiny_path, out = sys.argv[1:4]
doc = json.load(open(src))
base = os.path.dirname(src)
tiny = open(tiny_path, "rb").read()
name = os.path.splitext(os.path.basename(src))[0]
blob = bytearray()
def add(data):
    while len(blob) % 4: blob.append(0)
    off = len(blob); blob.extend(data); return off
views = doc.get("bufferViews", [])
offsets = []
for b in doc.get("buffers", []):
    uri = b.get("uri", "")
    if uri.startswith("data:"):
        data = base64.b64decode(uri.split(",", 1)[1])
    else:
        data = open(os.path.join(base, uri), "rb").read()
    offsets.append(add(data))
for v in views:
    v["byteOffset"] = v.get("byteOffset", 0) + offsets[v.get("buffer", 0)]
    v["buffer"] = 0
for im in doc.get("images", []):
    im.pop("uri", None)
    views.append({"buffer": 0, "byteOffset": add(tiny), "byteLength": len(tiny)})
    im["bufferView"] = len(views) - 1
    im["mimeType"] = "image/png"
doc["bufferViews"] = views
doc["buffers"] = [{"byteLength": len(blob)}]
js = json.dumps(doc, separators=(",", ":")).encode()
js += b" " * (-len(js) % 4)
while len(blob) % 4: blob.append(0)
if len(js) + len(blob) > 16384: sys.exit(0)   # libFuzzer mutates whole inputs: small seeds run faster
glb = struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(js) + 8 + len(blob))
glb += struct.pack("<I4s", len(js), b"JSON") + js + struct.pack("<I4s", len(blob), b"BIN\0") + bytes(blob)
open(os.path.join(out, name + ".glb"), "wb").write(glb)
# The same as a .gltf with the buffer as a data URI (images stay in views of it).
data_uri = "data:application/octet-stream;base64," + base64.b64encode(bytes(blob)).decode()
doc["buffers"] = [{"byteLength": len(blob), "uri": data_uri}]
open(os.path.join(out, name + ".gltf"), "w").write(json.dumps(doc))
PY
    done
    # Small hand-made assets: materials only (every spec-gloss and metal-rough field, texture transforms), and
    # one triangle whose buffer and image are data URIs.
    python3 - "$tmp/tiny.png" "$out/gltf" <<'PY'
import base64, json, struct, sys
tiny = base64.b64encode(open(sys.argv[1], "rb").read()).decode()
out = sys.argv[2]
tex = {"index": 0, "texCoord": 0, "extensions": {"KHR_texture_transform": {"offset": [0.5, 0], "scale": [2, 2],
       "rotation": 0.3}}}
materials = [
    {"name": "sg", "extensions": {"KHR_materials_pbrSpecularGlossiness": {"diffuseFactor": [0.8, 0.2, 0.1, 1],
     "specularFactor": [0.04, 0.04, 0.04], "glossinessFactor": 0.6, "diffuseTexture": tex,
     "specularGlossinessTexture": {"index": 0}}}, "alphaMode": "MASK", "alphaCutoff": 0.3, "doubleSided": True},
    {"name": "mr", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.5], "metallicFactor": 0.2,
     "roughnessFactor": 0.7, "baseColorTexture": {"index": 0}, "metallicRoughnessTexture": {"index": 0}},
     "normalTexture": {"index": 0, "scale": 0.5}, "occlusionTexture": {"index": 0, "strength": 0.3},
     "emissiveTexture": {"index": 0}, "emissiveFactor": [0.1, 0, 0], "alphaMode": "BLEND"},
]
doc = {"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_materials_pbrSpecularGlossiness",
       "KHR_texture_transform"], "materials": materials, "textures": [{"source": 0, "sampler": 0}],
       "samplers": [{"magFilter": 9729, "minFilter": 9987, "wrapS": 33648, "wrapT": 33071}],
       "images": [{"uri": "data:image/png;base64," + tiny}]}
open(out + "/materials.gltf", "w").write(json.dumps(doc))
positions = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
uvs = struct.pack("<6f", 0, 0, 1, 0, 0, 1)
indices = struct.pack("<3H", 0, 1, 2) + b"\0\0"
blob = positions + uvs + indices
doc.update({"buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64," +
            base64.b64encode(blob).decode()}],
            "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 24},
                            {"buffer": 0, "byteOffset": 60, "byteLength": 6}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                           "min": [0, 0, 0], "max": [1, 1, 0]},
                          {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"},
                          {"bufferView": 2, "componentType": 5123, "count": 3, "type": "SCALAR"}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2,
                                        "material": 0}]}],
            "nodes": [{"mesh": 0, "translation": [1, 2, 3], "children": [1]},
                      {"mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}],
            "scenes": [{"nodes": [0]}], "scene": 0})
open(out + "/triangle.gltf", "w").write(json.dumps(doc))
PY
    made gltf
fi

if need obj; then
    head -n 3000 "$assets/paper/matsphere.obj" > "$out/obj/matsphere_part.obj"
    printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1 4/3/1\n' \
        > "$out/obj/quad.obj"
    printf 'o a\ng b\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf -1 -2 -3\nf 1//1 2//1 4//1\nvn 0 0 1\n' \
        > "$out/obj/groups.obj"
    made obj
fi

if need sweep || need mrt || need mlp; then
    mkdir -p "$out/sweep" "$out/mrt" "$out/mlp"
    "$bin" sweep --from ward diffuse=0 --to ggx diffuse=0 --grid alpha=0.03:0.4:5:log specular=0.03:0.25:2 \
        --size 16 -o "$tmp/wg.csv" >/dev/null 2>&1
    "$bin" sweep --from gltf-specgloss --to gltf --random 12 --size 16 -o "$tmp/sm.csv" >/dev/null 2>&1
    cp "$tmp/wg.csv" "$out/sweep/ward_ggx.csv"
    "$bin" sweep --from ward --to ggx --random 4 --size 16 --shard 0/1 -o "$tmp/shard.csv" >/dev/null 2>&1
    cp "$tmp/shard.csv" "$out/sweep/shard_0_of_1.csv"
    cp "$tmp/sm.csv" "$out/sweep/specgloss_gltf.csv"
    for m in parametric svr mlp; do
        "$bin" learn "$tmp/wg.csv" --method "$m" -o "$out/mrt/ward_ggx_$m.mrt" >/dev/null 2>&1
    done
    "$bin" sweep --from ggx --to ggx-metallic --random 12 --size 16 -o "$tmp/gm.csv" >/dev/null 2>&1
    cp "$tmp/gm.csv" "$out/sweep/ggx_metallic.csv"
    "$bin" train "$tmp/gm.csv" --hidden 4 --epochs 3 -o "$tmp/tiny.mlp" >/dev/null 2>&1
    cp "$tmp/tiny.mlp" "$out/mlp/tiny.mlp"
    # The shipped network (6x300x4, 60 kB) is left to the tests: whole inputs are mutated, and a 16-unit one has
    # every part of the grammar at a tenth of the size.
    "$bin" train "$tmp/gm.csv" --hidden 16 --epochs 2 --form plain -o "$tmp/plain.mlp" >/dev/null 2>&1
    cp "$tmp/plain.mlp" "$out/mlp/plain16.mlp"
    made sweep; made mrt; made mlp
fi

if need cli_value; then
    # First byte: the model (index into `matremap models`' order, modulo their count); then arguments, one a line.
    i=0
    for text in 'alpha=0.1' 'specular=0.2,0.3,0.4' 'diffuse=0.5\nalpha=0.05:0.5:10:log' 'roughness=1e-3' \
                'alpha,specular' 'gltf' 'paper' '0x1p-3' '-0' 'nan' 'inf' '1e400' 'alpha=0.1:0.2:3' \
                'base_color=0.2,0.3,0.4\nmetallic=1\nroughness=0.5' 'f0=0.04\nalpha=0.3'; do
        for m in 0 1 2 3 4 5 6 7 8 9 10 11; do
            i=$((i + 1))
            { printf "\\x$(printf %02x $m)"; printf -- "$text"; } > "$out/cli_value/seed$i"
        done
    done
    made cli_value
fi

if need mtlx; then
    # MaterialX's own examples (tests/data/materialx, Apache-2.0: kept with their notice there), and documents of
    # our own writer: maps with extract, multiply, texcoord and wraps (WaterBottle, TextureSettingsTest to gltf_pbr,
    # copied: no remap), and a uniform one.
    cp "$root"/tests/data/materialx/*.mtlx "$out/mtlx/"
    printf '{"asset": {"version": "2.0"}, "materials": [{"name": "Gold", "pbrMetallicRoughness": {"baseColorFactor":
        [1.0, 0.77, 0.34, 1], "metallicFactor": 1.0, "roughnessFactor": 0.3}}]}' > "$tmp/uniform.gltf"
    "$bin" export "$tmp/uniform.gltf" -o "$out/mtlx/uniform_gltf_pbr.mtlx" --to gltf >/dev/null 2>&1 || true
    for g in "$assets/metalrough/WaterBottle/glTF/WaterBottle.gltf" \
             "$assets/metalrough/TextureSettingsTest/glTF/TextureSettingsTest.gltf"; do
        [ -f "$g" ] || continue
        n=$(basename "$g" .gltf)
        "$bin" export "$g" -o "$tmp/mtlx_$n/$n.mtlx" --to gltf >/dev/null 2>&1 && cp "$tmp/mtlx_$n/$n.mtlx" "$out/mtlx/"
    done
    made mtlx
fi
