"""Blender's own glTF exporter as the peer of a remap: export each material of a .blend on a UV sphere with Blender's
bundled io_scene_gltf2 (bpy.ops.export_scene.gltf) and read back the metal-rough values it wrote.

    blender -b --factory-startup --python-exit-code 3 --python scripts/blender/export_gltf.py -- \
        --blend data/blender/node_materials.blend --out-dir DIR [--materials A,B,...]

For every material NAME (default: all of the file's materials, sorted) it writes DIR/NAME/exporter.gltf (one
embedded .gltf: a UV sphere, 64 segments x 32 rings, smooth, with the material; no camera, no light) and prints one
JSON line on stdout:

    {"material": NAME, "gltf": PATH, "written": {...the material object the exporter wrote...},
     "values": {"base_color": [r, g, b], "metallic": m, "roughness": r, "specular": s, "specular_color": [...],
                "ior": i}}

"values" are the material's effective glTF metal-rough values: what the file says, the glTF 2.0 defaults for what
it leaves out (baseColorFactor 1,1,1, metallicFactor 1, roughnessFactor 1 (glTF 2.0 section 5.22),
KHR_materials_specular 1 / 1,1,1, KHR_materials_ior 1.5), and "textured": true when the exporter wrote a texture.
Exit codes: 0 ok, 1 usage, 2 bad input, 3 Blender failure.
"""

import argparse
import json
import os
import sys

import bpy


def fail(msg, code=2):
    sys.stderr.write("export_gltf: %s\n" % msg)
    sys.stderr.flush()
    os._exit(code)


class UsageParser(argparse.ArgumentParser):
    def error(self, message):
        self.print_usage(sys.stderr)
        fail("usage: %s" % message, 1)


def effective_values(m):
    pbr = m.get("pbrMetallicRoughness", {})
    ext = m.get("extensions", {})
    spec = ext.get("KHR_materials_specular", {})
    ior = ext.get("KHR_materials_ior", {})
    textured = any(k.endswith("Texture") for k in pbr) or any(k.endswith("Texture") for k in spec) or \
        any(k.endswith("Texture") for k in m)
    return {
        "base_color": list(pbr.get("baseColorFactor", [1.0, 1.0, 1.0, 1.0])[:3]),
        "metallic": pbr.get("metallicFactor", 1.0),
        "roughness": pbr.get("roughnessFactor", 1.0),
        "specular": spec.get("specularFactor", 1.0),
        "specular_color": list(spec.get("specularColorFactor", [1.0, 1.0, 1.0])),
        "ior": ior.get("ior", 1.5),
        "textured": textured,
    }


def export_one(mat, out_dir):
    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob, do_unlink=True)
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=1.0, location=(0.0, 0.0, 0.0))
    ob = bpy.context.active_object
    ob.name = "Sphere"
    bpy.ops.object.shade_smooth()
    ob.data.materials.clear()
    ob.data.materials.append(mat)
    d = os.path.join(out_dir, mat.name)
    os.makedirs(d, exist_ok=True)
    path = os.path.join(d, "exporter.gltf")
    bpy.ops.export_scene.gltf(filepath=path, export_format="GLTF_EMBEDDED", use_selection=False,
                              export_cameras=False, export_lights=False, export_apply=True,
                              export_materials="EXPORT", export_yup=True)
    if not os.path.isfile(path):
        fail("Blender's glTF exporter did not write '%s'" % path, 3)
    with open(path) as f:
        doc = json.load(f)
    mats = doc.get("materials", [])
    written = mats[0] if mats else {}
    print(json.dumps({"material": mat.name, "gltf": path, "written": written,
                      "values": effective_values(written)}), flush=True)


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = UsageParser(prog="export_gltf.py", description="Export .blend materials with Blender's glTF exporter.")
    p.add_argument("--blend", required=True)
    p.add_argument("--out-dir", required=True)
    p.add_argument("--materials", default="", help="comma-separated names (default: all)")
    a = p.parse_args(argv)
    if not os.path.isfile(a.blend):
        fail("no file '%s'" % a.blend)
    os.makedirs(a.out_dir, exist_ok=True)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    with bpy.data.libraries.load(os.path.abspath(a.blend), link=False) as (src, dst):
        names = sorted(src.materials)
        want = [n for n in a.materials.split(",") if n] or names
        missing = [n for n in want if n not in names]
        if missing:
            fail("no material '%s' in '%s' (it has: %s)" % (missing[0], a.blend, ", ".join(names)))
        dst.materials = want
    for mat in dst.materials:
        mat.use_fake_user = True
        export_one(mat, os.path.abspath(a.out_dir))


try:
    main()
except SystemExit as e:
    os._exit(e.code if isinstance(e.code, int) else 1)
except Exception as e:  # noqa: BLE001
    import traceback
    traceback.print_exc()
    fail("internal error: %s" % e, 3)
