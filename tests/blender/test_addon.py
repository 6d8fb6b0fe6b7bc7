"""Headless test of the matremap Blender add-on (docs/blender-addon.md), run by tests/blender_addon.sh as
    blender -b --factory-startup --python tests/blender/test_addon.py -- ZIP ASSET.gltf OUTDIR MATREMAP_BIN
Installs and enables the zip, imports a spec-gloss glTF with Blender's importer, renders it in Cycles (before),
runs the spec-gloss -> Principled operator, checks the node tree it reports, renders again (after) and compares the
two with `matremap ssim --mask` (object SSIM); then remaps a Principled to gltf and back. Prints "N passed, M failed".
"""

import math
import os
import subprocess
import sys
import time

import bpy
import numpy
from mathutils import Vector

if not hasattr(numpy, "bool"):  # Blender 3.4's glTF importer still uses numpy.bool (removed in numpy 1.24)
    numpy.bool = bool

ZIP, ASSET, OUT, MATREMAP = sys.argv[sys.argv.index("--") + 1:][:4]
SIZE, SAMPLES = 128, 32
# Avocado, mlp, 128x128, 32 samples: 0.989 measured (the flat grey control: 0.672); docs/blender-addon.md
SSIM_MIN = float(os.environ.get("MR_ADDON_SSIM_MIN", "0.95"))
passed = failed = 0
T0 = time.time()


def check(ok, what):
    global passed, failed
    if ok:
        passed += 1
        print("ok   %s" % what)
    else:
        failed += 1
        print("FAIL %s" % what)
    return ok


def finish():
    print("addon test took %.1f s" % (time.time() - T0))
    print("%d passed, %d failed" % (passed, failed))
    sys.stdout.flush()
    os._exit(0 if failed == 0 else 1)


def link_from(sock):
    return sock.links[0].from_node if sock.is_linked else None


# --- install and enable the zip -------------------------------------------------------------------------------
bpy.ops.preferences.addon_install(filepath=ZIP, overwrite=True)
bpy.ops.preferences.addon_enable(module="matremap_addon")
check(hasattr(bpy.ops.matremap, "convert_specgloss") and hasattr(bpy.types.Scene, "matremap"),
      "the zip installs and registers its operators")
import matremap_addon  # noqa: E402  (installed above)
from matremap_addon import package  # noqa: E402
mr = matremap_addon.load_package()
if not check(mr is not None, "the add-on loads matremap: %s" % (package.where() or package.error())):
    finish()

# --- the scene: the asset, a camera fitted to it, a sun, a black world ----------------------------------------
for ob in list(bpy.data.objects):
    bpy.data.objects.remove(ob, do_unlink=True)
for m in list(bpy.data.materials):
    bpy.data.materials.remove(m)
bpy.ops.import_scene.gltf(filepath=ASSET)
meshes = [o for o in bpy.data.objects if o.type == "MESH"]
pts = [o.matrix_world @ Vector(c) for o in meshes for c in o.bound_box]
lo = Vector([min(p[i] for p in pts) for i in range(3)])
hi = Vector([max(p[i] for p in pts) for i in range(3)])
center, radius = (lo + hi) / 2, (hi - lo).length / 2
scene = bpy.context.scene
cam = bpy.data.objects.new("Cam", bpy.data.cameras.new("Cam"))
scene.collection.objects.link(cam)
cam.data.lens = 50
view = Vector((0.4, -1.0, 0.35)).normalized()
cam.location = center + view * (radius / math.sin(cam.data.angle / 2) * 1.05)
cam.rotation_euler = (-view).to_track_quat("-Z", "Y").to_euler()
cam.data.clip_start, cam.data.clip_end = radius * 0.01, radius * 100
scene.camera = cam
sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
sun.data.energy = 3.0
sun.rotation_euler = (math.radians(45), 0, math.radians(30))
scene.collection.objects.link(sun)
world = bpy.data.worlds.new("W")
world.use_nodes = True
world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.3
world.node_tree.nodes["Background"].inputs["Color"].default_value = (1, 1, 1, 1)
scene.world = world
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = SAMPLES
scene.cycles.use_denoising = False
scene.cycles.use_adaptive_sampling = False
scene.cycles.seed = 1
scene.cycles.max_bounces = 4
scene.render.resolution_x = scene.render.resolution_y = SIZE
scene.render.resolution_percentage = 100
scene.render.film_transparent = True
scene.render.threads_mode = "FIXED"
scene.render.threads = 2
scene.view_settings.view_transform = "Standard"
scene.render.image_settings.file_format = "OPEN_EXR"
scene.render.image_settings.color_mode = "RGBA"
scene.render.image_settings.color_depth = "32"


def render(name):
    path = os.path.join(OUT, name + ".exr")
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    return path


def write_mask(exr, path):
    img = bpy.data.images.load(exr)
    px = numpy.empty(img.size[0] * img.size[1] * 4, dtype=numpy.float32)
    img.pixels.foreach_get(px)
    a = px.reshape(-1, 4)[:, 3]
    m = bpy.data.images.new("mask", img.size[0], img.size[1], alpha=False, float_buffer=True)
    m.pixels.foreach_set((numpy.repeat(a, 4).reshape(-1, 4) * numpy.array([1, 1, 1, 0], dtype=numpy.float32)
                         + numpy.array([0, 0, 0, 1], dtype=numpy.float32)).ravel())
    # one channel (`matremap ssim --mask` takes coverage, not colour): a grey 8-bit PNG, Blender's one-channel
    # format (0 and 1 exact; the view transform sRGB-encodes the partial coverage of edge pixels)
    settings = scene.render.image_settings
    settings.file_format, settings.color_mode, settings.color_depth = "PNG", "BW", "8"
    m.save_render(path, scene=scene)
    settings.file_format, settings.color_mode, settings.color_depth = "OPEN_EXR", "RGBA", "32"
    return float(a.mean())


def ssim(a, b, mask):
    out = subprocess.run([MATREMAP, "ssim", a, b, "--mask", mask], capture_output=True, text=True)
    if out.returncode != 0:
        print("matremap ssim failed: %s" % out.stderr.strip())
        return float("nan")
    return float(out.stdout.split()[-1])


old_mats = {m.name for o in meshes for m in o.data.materials if m}
scene.cycles.seed = 2
before2 = render("before_seed2")  # the same scene with other samples: the noise floor of the comparison
scene.cycles.seed = 1
before = render("before")
coverage = write_mask(before, os.path.join(OUT, "mask.png"))
check(coverage > 0.05, "the asset covers %.0f%% of the frame" % (100 * coverage))

# --- operator (a) ---------------------------------------------------------------------------------------------
t = time.time()
METHOD = os.environ.get("MR_ADDON_METHOD", "mlp")
res = bpy.ops.matremap.convert_specgloss(scope="ALL", method=METHOD, mode="NEW", suffix="_metalrough")
t_convert = time.time() - t
print("convert_specgloss: %s in %.1f s: %s" % (res, t_convert, scene.matremap.last_report))
check(res == {"FINISHED"}, "convert_specgloss finishes")
report = bpy.data.texts.get("matremap report")
check(report is not None and "_metalrough" in report.as_string(), "the report text block names the new material")
for name in sorted(old_mats):
    new = bpy.data.materials.get(name + "_metalrough")
    if not check(new is not None, "%s -> %s_metalrough exists" % (name, name)):
        continue
    if not any(n.type == "TEX_IMAGE" for n in bpy.data.materials[name].node_tree.nodes):
        p = new.node_tree.nodes.get("matremap Principled")
        check(p is not None and not p.inputs["Base Color"].is_linked, "%s: constants, no images" % name)
        continue
    check(all(new in [s.material for s in o.material_slots] for o in meshes if name in o.data.materials),
          "%s_metalrough takes the object's slot" % name)
    check(bpy.data.materials[name].use_fake_user, "the spec-gloss %s is kept" % name)
    nodes = new.node_tree.nodes
    check(not any(n.type in ("BSDF_DIFFUSE", "BSDF_GLOSSY") for n in nodes), "no Diffuse/Glossy BSDF left")
    p = nodes.get("matremap Principled")
    if not check(p is not None and p.type == "BSDF_PRINCIPLED", "a Principled BSDF"):
        continue
    out = next(n for n in nodes if n.type == "OUTPUT_MATERIAL" and n.is_active_output)
    check(link_from(out.inputs["Surface"]) == p, "the Principled feeds the material output")
    bc = link_from(p.inputs["Base Color"])
    check(bc is not None and bc.type == "TEX_IMAGE" and bc.image.name == name + "_metalrough_baseColor"
          and bc.image.packed_file is not None and bc.image.colorspace_settings.name == "sRGB",
          "Base Color <- the packed sRGB image %s_metalrough_baseColor" % name)
    sep_r, sep_m = link_from(p.inputs["Roughness"]), link_from(p.inputs["Metallic"])
    check(sep_r is not None and sep_r == sep_m and p.inputs["Roughness"].links[0].from_socket == sep_r.outputs[1]
          and p.inputs["Metallic"].links[0].from_socket == sep_r.outputs[2], "Roughness <- G, Metallic <- B")
    mrn = link_from(sep_r.inputs[0]) if sep_r else None
    check(mrn is not None and mrn.type == "TEX_IMAGE" and mrn.image.name == name + "_metalrough_metallicRoughness"
          and mrn.image.colorspace_settings.name == "Non-Color", "... of the Non-Color metallicRoughness image")
    if any(n.type == "NORMAL_MAP" for n in bpy.data.materials[name].node_tree.nodes):
        nm = link_from(p.inputs["Normal"])
        check(nm is not None and nm.type == "NORMAL_MAP", "the normal map kept")
    if mrn is not None:  # the image holds the roughness the operator reported
        w, h = mrn.image.size
        px = numpy.empty(w * h * 4, dtype=numpy.float32)
        mrn.image.pixels.foreach_get(px)
        g_mean = float(px.reshape(-1, 4)[:, 1].mean())
        line = [l for l in report.as_string().splitlines() if "roughness" in l and "spec2metal" in l][0]
        rep = float(line.split("roughness ")[1].split("mean ")[1].split(")")[0])
        check(abs(g_mean - rep) < 2.0 / 255, "metallicRoughness G mean %.4f = reported roughness mean %.4f"
              % (g_mean, rep))
after = render("after")
s_after = ssim(before, after, os.path.join(OUT, "mask.png"))

# the control: every converted material set to a flat grey Principled
for m in bpy.data.materials:
    p = m.node_tree.nodes.get("matremap Principled") if m.use_nodes else None
    if p is not None:
        for sock in ("Base Color", "Roughness", "Metallic"):
            for l in list(p.inputs[sock].links):
                m.node_tree.links.remove(l)
        p.inputs["Base Color"].default_value = (0.5, 0.5, 0.5, 1)
grey = render("grey")
s_grey = ssim(before, grey, os.path.join(OUT, "mask.png"))
s_noise = ssim(before, before2, os.path.join(OUT, "mask.png"))
print("object SSIM vs the imported spec-gloss render: converted %.4f, flat grey control %.4f, the same render with "
      "another seed %.4f (threshold %.2f)" % (s_after, s_grey, s_noise, SSIM_MIN))
check(s_after >= SSIM_MIN, "converted object SSIM %.4f >= %.2f" % (s_after, SSIM_MIN))
check(s_after > s_grey + 0.02, "converted beats the flat grey control (%.4f > %.4f)" % (s_after, s_grey))

# --- operator (b): a Principled to gltf and back --------------------------------------------------------------
mat = bpy.data.materials.new("RemapMe")
mat.use_nodes = True
p = next(n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
orig = {"Base Color": (0.6, 0.3, 0.2), "Metallic": 0.3, "Roughness": 0.45}
p.inputs["Base Color"].default_value = orig["Base Color"] + (1.0,)
p.inputs["Metallic"].default_value = orig["Metallic"]
p.inputs["Roughness"].default_value = orig["Roughness"]
ob = meshes[0]
ob.data.materials.clear()
ob.data.materials.append(mat)
bpy.context.view_layer.objects.active = ob
res = bpy.ops.matremap.remap_principled(model="gltf", direction="TO", size=32)
print("remap TO gltf: %s: %s" % (res, scene.matremap.last_report))
check(res == {"FINISHED"} and "matremap:gltf:base_color" in mat, "Principled -> gltf stores the glTF values")
if "matremap:gltf:base_color" in mat:
    print("  gltf values: %s" % {k: tuple(v) if hasattr(v, "__len__") else round(v, 4)
                                 for k, v in mat.items() if k.startswith("matremap:gltf:")})
p.inputs["Base Color"].default_value = (0.1, 0.1, 0.1, 1.0)
p.inputs["Metallic"].default_value = 0.9
p.inputs["Roughness"].default_value = 0.9
res = bpy.ops.matremap.remap_principled(model="gltf", direction="FROM", size=32)
print("remap FROM gltf: %s: %s" % (res, scene.matremap.last_report))
back_bc = tuple(p.inputs["Base Color"].default_value)[:3]
back_m, back_r = p.inputs["Metallic"].default_value, p.inputs["Roughness"].default_value
err = max(max(abs(a - b) for a, b in zip(back_bc, orig["Base Color"])), abs(back_m - orig["Metallic"]),
          abs(back_r - orig["Roughness"]))
print("  back: base (%.4f, %.4f, %.4f) metallic %.4f roughness %.4f: max error %.4f"
      % (back_bc + (back_m, back_r, err)))
check(res == {"FINISHED"} and err < 0.02, "Principled -> gltf -> Principled within 0.02 (max error %.4f)" % err)
bpy.context.view_layer.objects.active = ob
res = bpy.ops.matremap.remap_principled(model="ward", direction="FROM", size=32)
print("remap FROM ward: %s: %s" % (res, scene.matremap.last_report))
check(res == {"FINISHED"} and "the model's default" in scene.matremap.last_report
      and tuple(p.inputs["Base Color"].default_value)[:3] != back_bc,
      "ward (its defaults, flagged as such) -> Principled sets the Principled")

# --- operator (a) in place, on the active object only: the Duck (specularFactor 0: no metal-rough texel holds it) --
duck = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(ASSET))),
                    "Duck-pbrSpecularGlossiness", "glTF-pbrSpecularGlossiness", "Duck.gltf")
if os.path.isfile(duck):
    before_objs = set(bpy.data.objects)
    bpy.ops.import_scene.gltf(filepath=duck)
    dob = next(o for o in bpy.data.objects if o not in before_objs and o.type == "MESH")
    dmat = dob.active_material
    dname = dmat.name
    bpy.context.view_layer.objects.active = dob
    tex_dir = os.path.join(OUT, "textures")
    res = bpy.ops.matremap.convert_specgloss(scope="ACTIVE", method="weighted", mode="REPLACE", save_dir=tex_dir)
    print("convert_specgloss (Duck, replace): %s: %s" % (res, scene.matremap.last_report))
    nodes = dmat.node_tree.nodes
    check(res == {"FINISHED"} and dob.active_material == dmat and dmat.name == dname
          and nodes.get("matremap Principled") is not None
          and not any(n.type in ("BSDF_DIFFUSE", "BSDF_GLOSSY") for n in nodes),
          "REPLACE rewrites the active material '%s' in place" % dname)
    saved = sorted(os.listdir(tex_dir)) if os.path.isdir(tex_dir) else []
    check(saved == ["%s_baseColor.png" % bpy.path.clean_name(dname),
                    "%s_metallicRoughness.png" % bpy.path.clean_name(dname)]
          and bpy.data.images[dname + "_baseColor"].packed_file is None,
          "Save textures to: the PNGs written there, not packed (%s)" % ", ".join(saved))
    check("not reproduced by metal-rough" in scene.matremap.last_report,
          "the Duck's zero specular is flagged (metal-rough keeps F0 >= 0.04)")
    check(bpy.data.materials.get(name + "_metalrough") is not None, "the Avocado's material untouched by ACTIVE")
else:
    print("Duck asset missing: the REPLACE check skipped")

# --- Blender 4.1+'s importer tree (glTF-Blender-IO #2127), rebuilt by hand from the Avocado's images: ----------
# a Principled with IOR 1000, Specular Tint <- specGloss colour, Roughness <- alpha of a copy holding 1 - gloss.
# Same texels in, so the same images must come out as from the 3.4 tree.
dimg, simg = (next((i for i in bpy.data.images if i.name.startswith(n)), None)
              for n in ("Avocado_diffuse", "Avocado_specularGlossiness"))
if dimg is None or simg is None:
    print("not the Avocado: the 4.1+ tree check skipped")
    finish()
rimg = simg.copy()
px = numpy.empty(rimg.size[0] * rimg.size[1] * 4, dtype=numpy.float32)
rimg.pixels.foreach_get(px)
px = px.reshape(-1, 4)
px[:, 3] = 1.0 - px[:, 3]
rimg.pixels.foreach_set(px.ravel())
v2 = bpy.data.materials.new("SpecGlossV2")
v2.use_nodes = True
t2 = v2.node_tree
p2 = next(n for n in t2.nodes if n.type == "BSDF_PRINCIPLED")
p2.inputs["IOR"].default_value = 1000.0
for img, out, to in ((dimg, "Color", "Base Color"), (simg, "Color", "Specular Tint"), (rimg, "Alpha", "Roughness")):
    tn = t2.nodes.new("ShaderNodeTexImage")
    tn.image = img
    t2.links.new(tn.outputs[out], p2.inputs[to])
vob = bpy.data.objects.new("V2", bpy.data.meshes.new("V2"))
scene.collection.objects.link(vob)
vob.data.materials.append(v2)
bpy.context.view_layer.objects.active = vob
res = bpy.ops.matremap.convert_specgloss(scope="ACTIVE", method=METHOD, mode="NEW")
print("convert_specgloss (4.1+ tree): %s: %s" % (res, scene.matremap.last_report))
n2 = bpy.data.materials.get("SpecGlossV2_metalrough")
ok = res == {"FINISHED"} and n2 is not None
if ok:
    q = n2.node_tree.nodes.get("matremap Principled")
    ok = (q is not None and abs(q.inputs["IOR"].default_value - 1.5) < 1e-6 and not q.inputs["Specular Tint"].is_linked
          and link_from(q.inputs["Base Color"]).image.name == "SpecGlossV2_metalrough_baseColor"
          and link_from(link_from(q.inputs["Roughness"]).inputs[0]).image.name
          == "SpecGlossV2_metalrough_metallicRoughness"
          and len(n2.node_tree.nodes) == 5)  # the output, the Principled, 2 images, Separate: the old ones gone
check(ok, "the 4.1+ importer's spec-gloss Principled is converted in place of its inputs (IOR 1.5, tint unlinked)")
for suffix in ("_baseColor", "_metallicRoughness"):
    a, b = bpy.data.images.get(name + "_metalrough" + suffix), bpy.data.images.get("SpecGlossV2_metalrough" + suffix)
    if a is None or b is None:
        check(False, "images %s to compare" % suffix)
        continue
    pa, pb = (numpy.empty(i.size[0] * i.size[1] * 4, dtype=numpy.float32) for i in (a, b))
    a.pixels.foreach_get(pa)
    b.pixels.foreach_get(pb)
    d = float(numpy.abs(pa - pb).max())
    check(d <= 1.5 / 255, "%s from the 4.1+ tree = from the 3.4 tree (max difference %.4f)" % (suffix, d))

# --- the panel draws (a stand-in layout takes every call) and the model chooser lists matremap's models ---------
class AnyLayout:
    def __getattr__(self, name):
        return self

    def __call__(self, *args, **kwargs):
        return self

    def __setattr__(self, name, value):
        pass


try:
    matremap_addon.MATERIAL_PT_matremap.draw(type("P", (), {"layout": AnyLayout()})(), bpy.context)
    drew = True
except Exception as exc:
    drew = False
    print("panel draw: %s" % exc)
check(drew, "the panel draws")
names = [i[0] for i in matremap_addon.model_items(None, bpy.context)]
check("gltf" in names and "ward" in names and "cycles-principled" not in names,
      "the model chooser lists matremap.models() (%d: %s ...)" % (len(names), ", ".join(names[:4])))
finish()
