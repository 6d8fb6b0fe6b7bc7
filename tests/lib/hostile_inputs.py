#!/usr/bin/env python3
"""hostile_inputs.py OUT_DIR [BASE.jpg] — writes the malformed and lying files the readers must refuse by name
(tests/hostile_cli.sh runs them through the CLI; copies live in tests/fuzz/regressions/<target>/, which
test_fuzz_inputs replays through the fuzz targets). One folder per reader: OUT_DIR/gltf, png, jpeg, exr, hdr, other (GIF, BMP, WebP).
Each file is small and says in its name what it claims; the comment beside each says what it once did.

Every file is made here from scratch (a PNG, an uncompressed EXR and a flat Radiance HDR are simple enough to write
by hand), except the JPEGs, which are cut and patched from BASE.jpg (any small baseline JPEG, e.g. one oiiotool
wrote); without it no JPEG is written. Folders and FIFOs that glTF URIs name are the test's to make (they cannot be
kept in git): the assets that name them are written here."""
import base64
import json
import os
import struct
import sys
import zlib


# ---- PNG ---------------------------------------------------------------------------------------------------------

def png_chunk(tag, data):
    return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)


def png(width, height, idat, colour=2, depth=8, interlace=0):
    return (b"\x89PNG\r\n\x1a\n" + png_chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, depth, colour, 0, 0,
                                                                  interlace)) +
            png_chunk(b"IDAT", idat) + png_chunk(b"IEND", b""))


def png_rgb(width, height):
    rows = b"".join(b"\x00" + bytes((x * 7 + y * 13) & 255 for x in range(width * 3)) for y in range(height))
    return png(width, height, zlib.compress(rows))


def png_inputs():
    good = png_rgb(16, 16)
    rows = b"".join(b"\x00" + bytes(48) for _ in range(16))
    z = zlib.compress(rows)
    # Corrupt deflate data under a right CRC: only the decoder can tell (libpng printed "libpng error: ..." once).
    bad = bytearray(z)
    bad[2] ^= 0xff  # the first block's header: an invalid block type or code
    return {
        # A few bytes claiming 10^10 pixels: refused by the maximum dimension before any allocation.
        "ihdr-100000x100000.png": png(100000, 100000, zlib.compress(b"\x00" * 64)),
        # Within the maximum dimension, but its 20-odd bytes of IDAT cannot inflate to 16000 x 16000 pixels: libpng
        # allocated 768 MB of rows first.
        "ihdr-16000x16000-idat-tiny.png": png(16000, 16000, zlib.compress(b"\x00" * 64)),
        # The same claim, interlaced (Adam7: the path that always went to libpng).
        "ihdr-16000x16000-interlaced.png": png(16000, 16000, zlib.compress(b"\x00" * 64), interlace=1),
        "idat-corrupt-deflate.png": png(16, 16, bytes(bad)),
        "truncated-in-idat.png": good[:len(good) // 2],
        "ihdr-zero-width.png": png(0, 16, z),
        "ihdr-colour-type-5.png": png(16, 16, z, colour=5),
        "no-idat.png": b"\x89PNG\r\n\x1a\n" + png_chunk(b"IHDR", struct.pack(">IIBBBBB", 16, 16, 8, 2, 0, 0, 0)) +
                       png_chunk(b"IEND", b""),
        # A paletted 16000 x 16000 image: glTF conversions take paletted PNGs apart themselves (png_palette.c).
        "palette-16000x16000.png": b"\x89PNG\r\n\x1a\n" +
                                   png_chunk(b"IHDR", struct.pack(">IIBBBBB", 16000, 16000, 8, 3, 0, 0, 0)) +
                                   png_chunk(b"PLTE", b"\x00\x00\x00\xff\xff\xff") +
                                   png_chunk(b"IDAT", zlib.compress(b"\x00" * 64)) + png_chunk(b"IEND", b""),
    }


# ---- EXR (single part, scanline, uncompressed, half RGB) ----------------------------------------------------------

def exr_attr(name, kind, value):
    return name + b"\0" + kind + b"\0" + struct.pack("<i", len(value)) + value


def exr(width, height, window=None, tiles=None):
    """A valid EXR of width x height half RGB pixels; `window` (x0, y0, x1, y1) overrides the data window written
    in the header (the offsets and pixels stay those of width x height); `tiles` adds a tiledesc attribute."""
    x0, y0, x1, y1 = window or (0, 0, width - 1, height - 1)
    chlist = b"".join(c + b"\0" + struct.pack("<iB3xii", 1, 0, 1, 1) for c in (b"B", b"G", b"R")) + b"\0"
    header = (b"\x76\x2f\x31\x01" + struct.pack("<i", 2 | (0x200 if tiles else 0)) +
              exr_attr(b"channels", b"chlist", chlist) +
              exr_attr(b"compression", b"compression", b"\0") +
              exr_attr(b"dataWindow", b"box2i", struct.pack("<4i", x0, y0, x1, y1)) +
              exr_attr(b"displayWindow", b"box2i", struct.pack("<4i", 0, 0, width - 1, height - 1)) +
              exr_attr(b"lineOrder", b"lineOrder", b"\0") +
              exr_attr(b"pixelAspectRatio", b"float", struct.pack("<f", 1.0)) +
              exr_attr(b"screenWindowCenter", b"v2f", struct.pack("<2f", 0, 0)) +
              exr_attr(b"screenWindowWidth", b"float", struct.pack("<f", 1.0)) +
              (exr_attr(b"tiles", b"tiledesc", struct.pack("<IIB", *tiles)) if tiles else b"") + b"\0")
    half_one = struct.pack("<e", 0.5)
    line = half_one * width * 3
    start = len(header) + 8 * height
    chunks, offsets = b"", []
    for y in range(height):
        offsets.append(start + len(chunks))
        chunks += struct.pack("<ii", y, len(line)) + line
    return header + b"".join(struct.pack("<Q", o) for o in offsets) + chunks


def exr_inputs():
    good = exr(16, 16)
    return {
        "data-window-2e30.exr": exr(16, 16, (0, 0, 2 ** 30, 2 ** 30)),
        "data-window-16000x16000.exr": exr(16, 16, (0, 0, 15999, 15999)),
        "data-window-origin-2e31.exr": exr(16, 16, (2 ** 31 - 16, 2 ** 31 - 16, 2 ** 31 - 1, 2 ** 31 - 1)),
        "data-window-negative-origin.exr": exr(16, 16, (-2 ** 31, -2 ** 31, -2 ** 31 + 15, -2 ** 31 + 15)),
        "data-window-inverted.exr": exr(16, 16, (15, 15, 0, 0)),
        "data-window-width-wraps.exr": exr(16, 16, (-2 ** 31, 0, 2 ** 31 - 1, 15)),
        "tiles-2e30.exr": exr(16, 16, tiles=(2 ** 30, 2 ** 30, 0)),
        "truncated.exr": good[:len(good) // 2],
    }


# ---- Radiance HDR -------------------------------------------------------------------------------------------------

def hdr(width, height, size_line=None, rows=None):
    head = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + (size_line or b"-Y %d +X %d" % (height, width)) + b"\n"
    pixel = bytes((128, 64, 32, 129))  # flat RGBE (width < 8 is never run-length encoded)
    return head + pixel * width * (height if rows is None else rows)


def hdr_inputs():
    return {
        "header-100000x100000.hdr": hdr(4, 4, b"-Y 100000 +X 100000", rows=4),
        "header-16000x16000-4-pixels.hdr": hdr(4, 4, b"-Y 16000 +X 16000", rows=1),
        "header-negative-height.hdr": hdr(4, 4, b"-Y -5 +X 4"),
        "header-no-size.hdr": hdr(4, 4, b"-Y +X"),
        "truncated-rows.hdr": hdr(4, 4, rows=2),
    }


# ---- GIF, BMP, WebP: the sizes their headers declare ---------------------------------------------------------------

def other_inputs():
    # OpenImageIO's readers allocate the declared picture when they open the file: the GIF below (its screen is what
    # fuzz_gltf found inside a .glb) took 2 GB and 3 s before it failed.
    gif = b"GIF89a" + struct.pack("<HHBBB", 28941, 16316, 0, 0, 0) + b";"
    dib = struct.pack("<IiiHHIIiiII", 40, 100000, -100000, 1, 8, 1, 0, 2835, 2835, 0, 0)  # RLE8, top-down
    bmp = b"BM" + struct.pack("<IHHI", 14 + len(dib) + 6, 0, 0, 14 + len(dib)) + dib + b"\x00\x01\x00\x00\x00\x01"
    vp8x = b"VP8X" + struct.pack("<I", 10) + b"\x00\x00\x00\x00" + (1 << 20).to_bytes(3, "little") * 2
    webp = b"RIFF" + struct.pack("<I", 4 + len(vp8x)) + b"WEBP" + vp8x
    return {"screen-28941x16316.gif": gif, "dib-100000x100000-rle8.bmp": bmp, "canvas-1048577x1048577.webp": webp}


# ---- JPEG (patched from a base file) ------------------------------------------------------------------------------

def jpeg_inputs(base):
    sof = max(base.find(b"\xff\xc0"), base.find(b"\xff\xc2"))
    if sof < 0:
        raise SystemExit("hostile_inputs.py: the base JPEG has no SOF0/SOF2 marker")
    big = bytearray(base)
    struct.pack_into(">HH", big, sof + 5, 16000, 16000)  # height, width
    huge = bytearray(base)
    struct.pack_into(">HH", huge, sof + 5, 65000, 65000)
    zero = bytearray(base)
    struct.pack_into(">HH", zero, sof + 5, 0, 16)
    return {
        # 16000 x 16000 claimed over a few hundred bytes: libjpeg decoded 3 GB of grey rows before it said so.
        "sof-16000x16000.jpg": bytes(big),
        "sof-65000x65000.jpg": bytes(huge),
        "sof-zero-height.jpg": bytes(zero),
        "truncated-in-header.jpg": base[:sof + 4],
        "truncated-in-scan.jpg": base[:len(base) * 3 // 4],
    }


# ---- glTF ---------------------------------------------------------------------------------------------------------

POSITIONS = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)


def data_uri(data, mime="application/octet-stream"):
    return "data:%s;base64,%s" % (mime, base64.b64encode(data).decode())


def triangle_asset(accessor=None, view=None, extra=None):
    """One triangle (36 bytes of positions in a data-URI buffer) with its accessor and view overridable."""
    a = {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}
    v = {"buffer": 0, "byteLength": 36}
    a.update(accessor or {})
    v.update(view or {})
    d = {"asset": {"version": "2.0"},
         "buffers": [{"byteLength": 36, "uri": data_uri(POSITIONS)}],
         "bufferViews": [v], "accessors": [a],
         "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
         "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0}
    d.update(extra or {})
    return d


def material_asset(material, textures=0):
    """`material` as the only material of a triangle's asset (so that `report` reads it), with `textures` textures
    of one 1x1 PNG."""
    d = triangle_asset()
    d["meshes"][0]["primitives"][0]["material"] = 0
    d["materials"] = [material]
    if textures:
        d["images"] = [{"uri": data_uri(png_rgb(1, 1), "image/png")}]
        d["textures"] = [{"source": 0}] * textures
        d["extensionsUsed"] = ["KHR_materials_pbrSpecularGlossiness"]
    return d


def glb(doc, bin_chunk=b""):
    j = json.dumps(doc).encode() if not isinstance(doc, bytes) else doc
    j += b" " * (-len(j) % 4)
    body = struct.pack("<I4s", len(j), b"JSON") + j
    if bin_chunk:
        bin_chunk += b"\0" * (-len(bin_chunk) % 4)
        body += struct.pack("<I4s", len(bin_chunk), b"BIN\0") + bin_chunk
    return struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body


def gltf_inputs():
    sg = "KHR_materials_pbrSpecularGlossiness"
    deep = 50000
    out = {}
    # JSON nested tens of thousands deep: tinygltf and nlohmann/json recursed until the stack ran out (SIGSEGV).
    out["json-arrays-50000-deep.gltf"] = ('{"asset":{"version":"2.0"},"extras":' + "[" * deep + "]" * deep +
                                          "}").encode()
    out["json-objects-50000-deep.gltf"] = ('{"asset":{"version":"2.0"},"extras":' + '{"a":' * deep + "0" +
                                           "}" * deep + "}").encode()
    out["json-arrays-50000-deep.glb"] = glb(out["json-arrays-50000-deep.gltf"])
    # Sizes from the file: a count of 2^30 made `report` allocate 24 GiB before checking it against 36 bytes.
    out["accessor-count-2e30.gltf"] = json.dumps(triangle_asset({"count": 2 ** 30})).encode()
    out["accessor-count-2e62-stride-overflow.gltf"] = json.dumps(
        triangle_asset({"count": 2 ** 62}, {"byteStride": 12})).encode()
    out["accessor-offset-2e63.gltf"] = json.dumps(triangle_asset({"byteOffset": 2 ** 63})).encode()
    out["bufferview-past-buffer.gltf"] = json.dumps(triangle_asset(view={"byteLength": 1000000})).encode()
    out["sparse-count-2e30.gltf"] = json.dumps(triangle_asset(
        {"sparse": {"count": 2 ** 30, "indices": {"bufferView": 0, "componentType": 5125},
                    "values": {"bufferView": 0}}})).encode()
    # Instancing multiplies what the bytes hold: 2^20 zeros (an accessor without a buffer view) under 4096 nodes.
    out["zero-accessor-instanced-4096-times.gltf"] = json.dumps(
        {**triangle_asset(extra={"nodes": [{"children": list(range(1, 4097))}] + [{"mesh": 0}] * 4096}),
         "accessors": [{"componentType": 5126, "count": 2 ** 20, "type": "VEC3"}]}).encode()
    # An image in a buffer view longer than its buffer: tinygltf handed &data[offset] and the view's length over
    # unchecked (a read past the buffer).
    png1 = png_rgb(1, 1)
    out["image-bufferview-past-buffer.glb"] = glb(
        {"asset": {"version": "2.0"}, "buffers": [{"byteLength": len(png1)}],
         "bufferViews": [{"buffer": 0, "byteLength": 1 << 20}],
         "images": [{"bufferView": 0, "mimeType": "image/png"}]}, png1)
    # A GLB buffer of byteLength 0 over a BIN chunk: tinygltf threw std::out_of_range (exit 3).
    out["glb-buffer-bytelength-0.glb"] = glb({"asset": {"version": "2.0"}, "buffers": [{"byteLength": 0}]}, b"1234")
    # URIs naming what is no file: a folder (2^63-byte allocation, exit 3), a FIFO (a hang), a device.
    for kind, uri in (("folder", "textures/"), ("fifo", "fifo.png"), ("dev-zero", "../" * 16 + "dev/zero")):
        out["image-uri-%s.gltf" % kind] = json.dumps(material_asset(
            {"name": "M", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}, 0) |
            {"images": [{"uri": uri}], "textures": [{"source": 0}]}).encode()
        out["buffer-uri-%s.gltf" % kind] = json.dumps(
            {"asset": {"version": "2.0"}, "buffers": [{"byteLength": 64, "uri": uri}]}).encode()
    # An embedded image that does not decode: errors named a scratch file (./.matremap-gltf-XXXX/image0.png).
    half = png_rgb(16, 16)[:60]
    out["embedded-image-truncated.gltf"] = json.dumps(material_asset(
        {"name": "Cut", "extensions": {sg: {"diffuseTexture": {"index": 0}}}}, 1) |
        {"images": [{"uri": data_uri(half, "image/png")}]}).encode()
    big = png_inputs()["ihdr-100000x100000.png"]
    asset = material_asset({"name": "Big", "extensions": {sg: {"diffuseTexture": {"index": 0}}}}, 1)
    asset["buffers"].insert(0, {"byteLength": len(big)})  # the GLB's BIN chunk: buffer 0
    asset["bufferViews"] = [{"buffer": 0, "byteLength": len(big)}, {"buffer": 1, "byteLength": 36}]
    asset["accessors"][0]["bufferView"] = 1
    asset["images"] = [{"bufferView": 0, "mimeType": "image/png"}]
    out["embedded-image-ihdr-100000.glb"] = glb(asset, big)
    # Material fields tinygltf parses, or drops, without a word: "left as it is", exit 0, before.
    bad = {
        "extension-number": {"extensions": {sg: 5}},
        "extension-array": {"extensions": {sg: [1, 2]}},
        "extensions-string": {"extensions": "KHR_materials_pbrSpecularGlossiness"},
        "specgloss-diffusefactor-string": {"extensions": {sg: {"diffuseFactor": [1, 1, "x", 1]}}},
        "specgloss-specularfactor-length-2": {"extensions": {sg: {"specularFactor": [1, 1]}}},
        "specgloss-glossiness-1e999": {"extensions": {sg: {"glossinessFactor": "1e999"}}},
        "specgloss-texture-index-7": {"extensions": {sg: {"diffuseTexture": {"index": 7}}}},
        "specgloss-texture-no-index": {"extensions": {sg: {"diffuseTexture": {"texCoord": 0}}}},
        "specgloss-texture-texcoord-negative": {"extensions": {sg: {"diffuseTexture": {"index": 0, "texCoord": -1}}}},
        "texture-transform-not-object": {"extensions": {sg: {"diffuseTexture": {
            "index": 0, "extensions": {"KHR_texture_transform": 3}}}}},
        "metallic-factor-string": {"pbrMetallicRoughness": {"metallicFactor": "high"}},
        "metallic-factor-2": {"pbrMetallicRoughness": {"metallicFactor": 2}},
        "basecolor-factor-length-3": {"pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1]}},
        "basecolor-texture-index-7": {"pbrMetallicRoughness": {"baseColorTexture": {"index": 7}}},
        "emissive-factor-negative": {"emissiveFactor": [0, -1, 0]},
        "alpha-mode-unknown": {"alphaMode": "GLASS"},
        "ior-below-1": {"extensions": {"KHR_materials_ior": {"ior": 0.5}}},
    }
    for name, fields in bad.items():
        text = json.dumps(material_asset({"name": "Hostile", **fields}, 1))
        out["material-%s.gltf" % name] = text.replace('"1e999"', "1e999").encode()
    # The same extension hidden behind an escaped key: JSON means "materials", so it is checked all the same.
    out["material-extension-number-escaped-key.gltf"] = out["material-extension-number.gltf"].replace(
        b'"materials"', b'"materi\\u0061ls"')
    out["texture-source-9.gltf"] = json.dumps(material_asset({"name": "M"}, 1) |
                                              {"textures": [{"source": 9}]}).encode()
    return out


def main():
    if len(sys.argv) not in (2, 3):
        raise SystemExit(__doc__)
    root = sys.argv[1]
    sets = {"png": png_inputs(), "exr": exr_inputs(), "hdr": hdr_inputs(), "gltf": gltf_inputs(),
            "other": other_inputs()}
    if len(sys.argv) == 3:
        with open(sys.argv[2], "rb") as f:
            sets["jpeg"] = jpeg_inputs(f.read())
    for target, files in sets.items():
        os.makedirs(os.path.join(root, target), exist_ok=True)
        for name, data in files.items():
            with open(os.path.join(root, target, name), "wb") as f:
                f.write(data)


if __name__ == "__main__":
    main()
