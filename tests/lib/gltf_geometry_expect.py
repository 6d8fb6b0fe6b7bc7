#!/usr/bin/env python3
"""Expected world-space geometry of a glTF asset, computed independently of the shim (plain JSON + struct).

Usage: gltf_geometry_expect.py FILE.gltf
Prints one line: "triangles T primitives P skipped S bbox x0 y0 z0 x1 y1 z1", where T counts the triangles of
every TRIANGLES/STRIP/FAN primitive reachable from the default scene (scene 0 if none) once per node that
instances its mesh, P those primitive instances, S the point/line primitive instances, and the box bounds the
POSITION data actually referenced (read from the buffers, transformed by the composed node matrices).
Used by tests/test_gltf.c (test_geometry_assets). Handles what the shared assets use: external or base64
buffers, float positions, byteStride, node matrix or TRS; not sparse accessors.
"""
import base64
import json
import math
import os
import struct
import sys


def mat_mul(a, b):  # column-major 4x4
    return [sum(a[k * 4 + r] * b[c * 4 + k] for k in range(4)) for c in range(4) for r in range(4)]


def node_matrix(n):
    if "matrix" in n:
        return list(map(float, n["matrix"]))
    t = n.get("translation", [0, 0, 0])
    x, y, z, w = n.get("rotation", [0, 0, 0, 1])
    s = n.get("scale", [1, 1, 1])
    r = [1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w),
         2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
         2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)]
    m = [0.0] * 16
    for c in range(3):
        for rr in range(3):
            m[c * 4 + rr] = r[c * 3 + rr] * s[c]
    m[12], m[13], m[14], m[15] = t[0], t[1], t[2], 1.0
    return m


def main():
    path = sys.argv[1]
    doc = json.load(open(path))
    base = os.path.dirname(path)
    buffers = []
    for b in doc.get("buffers", []):
        uri = b["uri"]
        if uri.startswith("data:"):
            buffers.append(base64.b64decode(uri.split(",", 1)[1]))
        else:
            from urllib.parse import unquote
            buffers.append(open(os.path.join(base, unquote(uri)), "rb").read())
    scene = doc.get("scene", 0)
    nodes = doc.get("nodes", [])
    tris = prims = skipped = 0
    lo = [math.inf] * 3
    hi = [-math.inf] * 3

    def positions(acc_index):
        a = doc["accessors"][acc_index]
        assert a["componentType"] == 5126 and a["type"] == "VEC3"
        v = doc["bufferViews"][a["bufferView"]]
        data = buffers[v["buffer"]]
        stride = v.get("byteStride", 12)
        start = v.get("byteOffset", 0) + a.get("byteOffset", 0)
        return [struct.unpack_from("<3f", data, start + i * stride) for i in range(a["count"])]

    def visit(i, parent):
        nonlocal tris, prims, skipped
        n = nodes[i]
        m = mat_mul(parent, node_matrix(n))
        if "mesh" in n:
            for p in doc["meshes"][n["mesh"]]["primitives"]:
                mode = p.get("mode", 4)
                pos = positions(p["attributes"]["POSITION"])
                count = doc["accessors"][p["indices"]]["count"] if "indices" in p else len(pos)
                if mode == 4:
                    tris += count // 3
                elif mode in (5, 6):
                    tris += max(count - 2, 0)
                else:
                    skipped += 1
                    continue
                prims += 1
                for q in pos:
                    w = [sum(m[k * 4 + r] * (list(q) + [1.0])[k] for k in range(4)) for r in range(3)]
                    for k in range(3):
                        lo[k] = min(lo[k], w[k])
                        hi[k] = max(hi[k], w[k])
        for c in n.get("children", []):
            visit(c, m)

    ident = [1.0 if r == c else 0.0 for c in range(4) for r in range(4)]
    for root in doc["scenes"][scene]["nodes"]:
        visit(root, ident)
    print("triangles %d primitives %d skipped %d bbox %.9g %.9g %.9g %.9g %.9g %.9g"
          % (tris, prims, skipped, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]))


main()
