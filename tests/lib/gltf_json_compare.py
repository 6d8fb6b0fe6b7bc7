#!/usr/bin/env python3
"""gltf_json_compare.py — compares two .gltf files' JSON semantically (tests/gltf_validate.sh).

Usage: gltf_json_compare.py ORIGINAL.gltf COPY.gltf
Ignores key order, int/float spelling (1 vs 1.0) and fields equal to glTF 2.0's defaults (the tinygltf writer
drops them): alphaMode "OPAQUE", alphaCutoff 0.5, doubleSided false, emissiveFactor [0,0,0], baseColorFactor
[1,1,1,1], metallicFactor 1, roughnessFactor 1, a textureInfo's texCoord 0, normalTexture.scale 1,
occlusionTexture.strength 1, sampler wrapS/wrapT 10497, byteOffset 0, accessor normalized false, primitive
mode 4, animation sampler interpolation "LINEAR", node matrix/rotation/scale/translation identity, empty
pbrMetallicRoughness objects. Everything else must be equal; each difference is printed as a JSON path.
Exit status 1 if any differ.
"""
import json
import sys

IDENTITY = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]
DEFAULTS = {
    "alphaMode": "OPAQUE", "alphaCutoff": 0.5, "doubleSided": False, "emissiveFactor": [0, 0, 0],
    "baseColorFactor": [1, 1, 1, 1], "metallicFactor": 1, "roughnessFactor": 1,
    "wrapS": 10497, "wrapT": 10497, "byteOffset": 0, "normalized": False, "mode": 4,
    "interpolation": "LINEAR", "matrix": IDENTITY, "rotation": [0, 0, 0, 1], "scale": [1, 1, 1],
    "translation": [0, 0, 0],
}
TEXTURE_INFOS = {"baseColorTexture", "metallicRoughnessTexture", "normalTexture", "occlusionTexture",
                 "emissiveTexture", "diffuseTexture", "specularGlossinessTexture", "specularTexture",
                 "specularColorTexture"}


def normalise(value, key=None, parent=None):
    if isinstance(value, dict):
        out = {}
        for k, v in value.items():
            if k in DEFAULTS and parent != "KHR_texture_transform" and v == DEFAULTS[k]:
                continue
            if key in TEXTURE_INFOS and k == "texCoord" and v == 0:
                continue
            if key == "normalTexture" and k == "scale" and v == 1:
                continue
            if key == "occlusionTexture" and k == "strength" and v == 1:
                continue
            n = normalise(v, k, key)
            if k == "pbrMetallicRoughness" and n == {}:
                continue
            out[k] = n
        return out
    if isinstance(value, list):
        return [normalise(v, key, parent) for v in value]
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    return float(value)


def diff(a, b, path, out):
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if k not in a:
                out.append(f"{path}/{k}: only in the copy: {json.dumps(b[k])[:80]}")
            elif k not in b:
                out.append(f"{path}/{k}: only in the original: {json.dumps(a[k])[:80]}")
            else:
                diff(a[k], b[k], f"{path}/{k}", out)
    elif isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        for i, (x, y) in enumerate(zip(a, b)):
            diff(x, y, f"{path}/{i}", out)
    elif a != b:
        out.append(f"{path}: {json.dumps(a)[:80]} != {json.dumps(b)[:80]}")


def main():
    with open(sys.argv[1], encoding="utf-8") as f:
        original = normalise(json.load(f))
    with open(sys.argv[2], encoding="utf-8") as f:
        copy = normalise(json.load(f))
    out = []
    diff(original, copy, "", out)
    for line in out:
        print(line)
    return 1 if out else 0


if __name__ == "__main__":
    sys.exit(main())
