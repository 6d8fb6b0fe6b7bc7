#!/usr/bin/env python3
"""gltf_kitchen_sink.py OUT.gltf — writes a small, valid glTF holding what the material shim must pass through
untouched (tests/gltf_validate.sh): extras and extensions on the asset, nodes, meshes, samplers, skins and
materials, asset.minVersion, a property outside the schema (a validator warning, not an error),
an unknown material extension with a transformed texture, KHR_lights_punctual, KHR_materials_emissive_strength,
a camera, a skin, an animation, morph targets, a sparse accessor, named samplers, data-URI buffer and image."""
import base64
import json
import struct
import sys
import zlib


def png_1x1():
    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 1, 1, 8, 2, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(b"\x00\xff\x80\x00")) + chunk(b"IEND", b""))


positions = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)       # 36 bytes
uvs = struct.pack("<6f", 0, 0, 1, 0, 0, 1)                       # 24 bytes
times = struct.pack("<2f", 0, 1)                                 # 8 bytes
rotations = struct.pack("<8f", 0, 0, 0, 1, 0, 0.7071068, 0, 0.7071068)  # 32 bytes
ibm = struct.pack("<16f", *[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1])  # 64 bytes
joints = struct.pack("<12B", *([0, 0, 0, 0] * 3))               # 12 bytes
weights = struct.pack("<12f", *([1, 0, 0, 0] * 3))               # 48 bytes
sparse_idx = struct.pack("<H2x", 1)                              # 4 bytes
sparse_val = struct.pack("<3f", 0, 0, 0.5)                       # 12 bytes
blob = positions + uvs + times + rotations + ibm + joints + weights + sparse_idx + sparse_val
offsets = {}
o = 0
for name, part in [("pos", positions), ("uv", uvs), ("t", times), ("r", rotations), ("ibm", ibm),
                   ("j", joints), ("w", weights), ("si", sparse_idx), ("sv", sparse_val)]:
    offsets[name] = (o, len(part))
    o += len(part)


def view(part, **extra):
    off, n = offsets[part]
    v = {"buffer": 0, "byteOffset": off, "byteLength": n}
    v.update(extra)
    return v


gltf = {
    "asset": {"version": "2.0", "minVersion": "2.0", "generator": "matremap kitchen sink", "copyright": "CC0",
              "extras": {"note": "asset extras"}},
    "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_materials_clearcoat",
                       "KHR_texture_transform"],
    "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "color": [1, 0.5, 0.25],
                                                       "intensity": 3.5, "name": "bulb"}]}},
    "extras": {"pipeline": {"stage": 2, "tags": ["a", "b"]}},
    "scene": 0,
    "scenes": [{"name": "main", "nodes": [0, 2, 3], "extras": {"s": 1}}],
    "nodes": [
        {"name": "triangle", "mesh": 0, "skin": 0, "translation": [1, 2, 3], "children": [1],
         "extras": {"id": 42}, "xNotInTheSchema": [1, 2]},
        {"name": "joint", "rotation": [0, 0, 0, 1]},
        {"name": "camera", "camera": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 5, 1]},
        {"name": "light", "extensions": {"KHR_lights_punctual": {"light": 0}}},
    ],
    "cameras": [{"type": "perspective", "name": "cam",
                 "perspective": {"yfov": 0.8, "znear": 0.1, "zfar": 100, "aspectRatio": 1.5}}],
    "meshes": [{"name": "tri", "weights": [0.25],
                "primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1, "JOINTS_0": 5, "WEIGHTS_0": 6},
                                "material": 0, "targets": [{"POSITION": 7}], "extras": {"p": True}}],
                "extras": {"m": "mesh"}}],
    "skins": [{"name": "skin", "joints": [1], "inverseBindMatrices": 4, "extras": {"rig": "a"}}],
    "animations": [{"name": "spin",
                    "channels": [{"sampler": 0, "target": {"node": 1, "path": "rotation"}}],
                    "samplers": [{"input": 2, "output": 3, "interpolation": "STEP"}]}],
    "accessors": [
        {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
        {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"},
        {"bufferView": 2, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0], "max": [1]},
        {"bufferView": 3, "componentType": 5126, "count": 2, "type": "VEC4"},
        {"bufferView": 4, "componentType": 5126, "count": 1, "type": "MAT4"},
        {"bufferView": 5, "componentType": 5121, "count": 3, "type": "VEC4"},
        {"bufferView": 6, "componentType": 5126, "count": 3, "type": "VEC4"},
        {"componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [0, 0, 0.5],
         "sparse": {"count": 1, "indices": {"bufferView": 7, "componentType": 5123},
                    "values": {"bufferView": 8}}},
    ],
    "bufferViews": [view("pos", target=34962, name="positions"), view("uv", target=34962), view("t"), view("r"),
                    view("ibm"), view("j", target=34962), view("w", target=34962), view("si"), view("sv")],
    "buffers": [{"byteLength": len(blob),
                 "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
    "images": [{"name": "pixel", "uri": "data:image/png;base64," + base64.b64encode(png_1x1()).decode()}],
    "samplers": [{"name": "nearest clamp", "magFilter": 9728, "minFilter": 9728, "wrapS": 33071, "wrapT": 33648,
                  "extras": {"sampler": "extras"}}],
    "textures": [{"name": "tex", "source": 0, "sampler": 0, "extras": {"t": 1}}],
    "materials": [{
        "name": "sink",
        "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.25, 0.125, 1], "metallicFactor": 0.5,
                                 "baseColorTexture": {"index": 0, "extras": {"ti": "extras"}}},
        "emissiveFactor": [1, 1, 1],
        "emissiveTexture": {"index": 0, "texCoord": 0},
        "extensions": {
            "KHR_materials_emissive_strength": {"emissiveStrength": 4},
            "KHR_materials_clearcoat": {
                "clearcoatFactor": 0.5,
                "clearcoatTexture": {"index": 0, "extensions": {"KHR_texture_transform": {"scale": [2, 2]}}}},
        },
        "extras": {"author": "test"},
    }],
}
with open(sys.argv[1], "w", encoding="utf-8") as f:
    json.dump(gltf, f, indent=1)
