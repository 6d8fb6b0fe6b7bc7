"""Renders glTF assets with Blender Cycles as a user sees them: Blender's own glTF importer, an HDR map as the
world, a fixed camera, film transparent (alpha = the object's coverage). make evaluation-viewers
(scripts/evaluate-viewers.sh; docs/evaluation.md, "What viewers show").

Usage: blender -b --factory-startup --python-exit-code 3 --python blender_render.py -- JOBS.json
JOBS.json: {"threads": 2, "jobs": [{"gltf": ABS, "env": ABS.hdr, "out": ABS.exr, "size": 384, "samples": 256,
            "seed": 0, "envMean": 0.5, "view": {"azimuth": deg, "elevation": deg, "fov": deg, "margin": 1.05}}]}
Jobs with the same gltf in a row share one import. Each render is a linear RGBA float EXR (alpha = coverage);
one JSON line per job on stdout: {"out", "seconds", "import_seconds", "materials": [node types per material]}.

The scene, the same as three_page.js's in glTF's axes (Blender's importer turns glTF's +Y up into +Z up):
- the world is the equirectangular map (Environment Texture, default mapping), its strength set so that the
  map's mean luminance, weighted by solid angle, is envMean; no other light;
- the camera looks at the centre of the box around every mesh vertex (world space) from the direction
  (azimuth, elevation) (azimuth 0 = glTF's +Z, 90 = +X), at the distance where the box's bounding sphere, times
  margin, just fits the vertical field of view;
- Cycles on the CPU: `samples` paths per pixel, the given seed, no adaptive sampling, no denoising, no clamping,
  Blender's default bounces, box pixel filter; the importer's materials as it makes them.
"""
import json
import math
import os
import sys
import time

import bpy
import numpy
from mathutils import Vector

# Blender 3.4's glTF add-on still uses numpy.bool, which numpy 1.24 removed.
if not hasattr(numpy, "bool"):
    numpy.bool = bool


def mean_luminance(path):
    image = bpy.data.images.load(path, check_existing=True)
    w, h = image.size
    px = numpy.empty(w * h * 4, numpy.float32)
    image.pixels.foreach_get(px)
    px = px.reshape(h, w, 4).astype(numpy.float64)
    lum = 0.2126 * px[..., 0] + 0.7152 * px[..., 1] + 0.0722 * px[..., 2]
    # Blender's rows run bottom to top; the weights are symmetric about the equator anyway.
    weights = numpy.cos(((numpy.arange(h) + 0.5) / h - 0.5) * math.pi)
    return float((lum.sum(axis=1) * weights).sum() / (weights.sum() * w)), image


def set_world(scene, env, env_mean):
    mean, image = mean_luminance(env)
    if scene.world is not None and scene.world.name.startswith("viewer-env"):
        bpy.data.worlds.remove(scene.world)
    world = bpy.data.worlds.new("viewer-env")
    world.use_nodes = True
    nodes = world.node_tree.nodes
    nodes.clear()
    tex = nodes.new("ShaderNodeTexEnvironment")
    tex.image = image
    background = nodes.new("ShaderNodeBackground")
    background.inputs["Strength"].default_value = env_mean / mean
    output = nodes.new("ShaderNodeOutputWorld")
    world.node_tree.links.new(background.inputs["Color"], tex.outputs["Color"])
    world.node_tree.links.new(output.inputs["Surface"], background.outputs["Background"])
    scene.world = world
    return env_mean / mean


def mesh_bounds():
    lo = Vector((math.inf,) * 3)
    hi = Vector((-math.inf,) * 3)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    for obj in bpy.context.scene.objects:
        if obj.type != "MESH":
            continue
        mesh = obj.evaluated_get(depsgraph).to_mesh()
        n = len(mesh.vertices)
        if n:
            co = numpy.empty(n * 3, numpy.float64)
            mesh.vertices.foreach_get("co", co)
            co = co.reshape(n, 3)
            m = numpy.array(obj.matrix_world)
            world = co @ m[:3, :3].T + m[:3, 3]
            lo = Vector(numpy.minimum(numpy.array(lo), world.min(axis=0)))
            hi = Vector(numpy.maximum(numpy.array(hi), world.max(axis=0)))
        obj.evaluated_get(depsgraph).to_mesh_clear()
    return lo, hi


def set_camera(scene, view):
    lo, hi = mesh_bounds()
    centre = (lo + hi) / 2
    radius = (hi - lo).length / 2
    az = math.radians(view["azimuth"])
    el = math.radians(view["elevation"])
    # glTF direction (sin az cos el, sin el, cos az cos el) in Blender's axes (x, -z, y).
    d = Vector((math.sin(az) * math.cos(el), -math.cos(az) * math.cos(el), math.sin(el)))
    distance = view["margin"] * radius / math.sin(math.radians(view["fov"]) / 2)
    cam_data = bpy.data.cameras.new("viewer-camera")
    cam_data.sensor_fit = "VERTICAL"
    cam_data.angle = math.radians(view["fov"])
    cam_data.clip_start = 0.01 * distance
    cam_data.clip_end = 10 * distance
    cam = bpy.data.objects.new("viewer-camera", cam_data)
    scene.collection.objects.link(cam)
    cam.location = centre + d * distance
    cam.rotation_mode = "QUATERNION"
    cam.rotation_quaternion = (-d).to_track_quat("-Z", "Y")
    scene.camera = cam


def material_summary():
    out = []
    for mat in bpy.data.materials:
        if mat.users and mat.node_tree:
            kinds = sorted({n.bl_idname for n in mat.node_tree.nodes if "Bsdf" in n.bl_idname})
            out.append("%s: %s" % (mat.name, "+".join(kinds)))
    return out


def import_asset(path):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    started = time.time()
    bpy.ops.import_scene.gltf(filepath=path)
    for obj in list(bpy.context.scene.objects):
        if obj.type in ("CAMERA", "LIGHT"):
            bpy.data.objects.remove(obj, do_unlink=True)
    return time.time() - started


def render(scene, job, threads):
    scene.render.engine = "CYCLES"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.samples = job["samples"]
    cycles.use_adaptive_sampling = False
    cycles.use_denoising = False
    cycles.seed = job.get("seed", 0)
    cycles.sample_clamp_direct = 0.0
    cycles.sample_clamp_indirect = 0.0
    cycles.pixel_filter_type = "BOX"
    scene.render.film_transparent = True
    scene.render.resolution_x = scene.render.resolution_y = job["size"]
    scene.render.resolution_percentage = 100
    scene.render.threads_mode = "FIXED"
    scene.render.threads = threads
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    settings = scene.render.image_settings
    settings.file_format = "OPEN_EXR"
    settings.color_mode = "RGBA"
    settings.color_depth = "32"
    settings.exr_codec = "ZIP"
    scene.render.use_file_extension = False
    scene.render.filepath = job["out"] + ".tmp"
    started = time.time()
    bpy.ops.render.render(write_still=True)
    return time.time() - started


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if len(argv) != 1:
        print("usage: blender -b --python blender_render.py -- JOBS.json", file=sys.stderr)
        os._exit(1)
    spec = json.load(open(argv[0]))
    threads = spec.get("threads", 2)
    current, view, import_seconds = None, None, 0.0
    for job in spec["jobs"]:
        if job["gltf"] != current:
            import_seconds = import_asset(job["gltf"])
            current, view = job["gltf"], job["view"]
            set_camera(bpy.context.scene, view)
        elif job["view"] != view:
            print("blender_render: the jobs of one asset must share one view", file=sys.stderr)
            os._exit(1)
        scene = bpy.context.scene
        scale = set_world(scene, job["env"], job.get("envMean", 0.5))
        seconds = render(scene, job, threads)
        os.replace(job["out"] + ".tmp", job["out"])
        print(json.dumps({"out": job["out"], "seconds": round(seconds, 3), "import_seconds": round(import_seconds, 3),
                          "env_scale": scale, "materials": material_summary()}), flush=True)


main()
