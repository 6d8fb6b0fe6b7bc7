"""Matremap's fit scene in a running Blender, for scripts that render many materials in one process
(scripts/blender/export_gltf.py, scripts/blender/render_back.py).

The scene code is scripts/cycles_fit_scene.py's (build_scene, make_sphere, ...): that file is a script whose last
statement runs main(), so it is loaded here by parsing it and executing every top-level statement except that
final try/main block. (When the scene code moves to data/renderers/blender_scene.py, import it from there instead.)

On top of the fit scene this adds: RGBA output with a transparent film (alpha = the sphere's coverage, the object
mask of the object SSIM), swapping the sphere's material, materials appended from a .blend or built by Blender's
glTF importer, and one render to a 32-bit float RGBA EXR.
"""

import ast
import os
import types

import bpy
import numpy

# Blender 3.4's glTF importer still uses numpy.bool, which numpy 1.24 removed (as scripts/viewers/blender_render.py).
if not hasattr(numpy, "bool"):
    numpy.bool = bool

HERE = os.path.dirname(os.path.abspath(__file__))
FIT_SCENE_PY = os.path.join(os.path.dirname(HERE), "cycles_fit_scene.py")


def load_fit_scene():
    with open(FIT_SCENE_PY) as f:
        tree = ast.parse(f.read(), FIT_SCENE_PY)
    keep = [st for st in tree.body if not isinstance(st, ast.Try)]  # the final `try: main() except ...`
    mod = types.ModuleType("cycles_fit_scene")
    mod.__file__ = FIT_SCENE_PY
    exec(compile(ast.Module(body=keep, type_ignores=[]), FIT_SCENE_PY, "exec"), mod.__dict__)
    return mod


fs = load_fit_scene()


def fit_args(size, samples, threads=0, seed=0, light="45"):
    """The options cycles_fit_scene.build_scene reads (its own defaults for the rest)."""
    return fs.parse_args(["--size", str(size), "--samples", str(samples), "--threads", str(threads),
                          "--seed", str(seed), "--light", light, "--material", "principled", "-o", "unused.exr"])


def setup(size, samples, threads=0, seed=0, light="45"):
    """Builds the fit scene (clearing everything in the file) and returns (scene, sphere)."""
    scene, sphere, _power = fs.build_scene(fit_args(size, samples, threads, seed, light))
    scene.render.film_transparent = True
    scene.render.image_settings.color_mode = "RGBA"
    return scene, sphere


def set_size(scene, size, samples, seed=0):
    scene.render.resolution_x = size
    scene.render.resolution_y = size
    scene.cycles.samples = samples
    scene.cycles.seed = seed


def set_material(sphere, mat):
    """Puts mat on the fit sphere (its mesh slot and, for the point sphere, the Set Material node)."""
    sphere.data.materials.clear()
    sphere.data.materials.append(mat)
    for mod in sphere.modifiers:
        if mod.type == "NODES" and mod.node_group is not None:
            for n in mod.node_group.nodes:
                if n.bl_idname == "GeometryNodeSetMaterial":
                    n.inputs["Material"].default_value = mat


def append_material(blend, name):
    """The material NAME of the .blend file (appended once; a ValueError names what the file has)."""
    blend = os.path.abspath(blend)
    with bpy.data.libraries.load(blend, link=False) as (src, dst):
        if name not in src.materials:
            raise ValueError("no material '%s' in '%s' (it has: %s)" % (name, blend, ", ".join(src.materials)))
        dst.materials = [name]
    mat = dst.materials[0]
    mat.use_fake_user = True
    return mat


def import_gltf_material(path, label):
    """Imports a .gltf with Blender's glTF importer, keeps the material it built for the first mesh and deletes
    the imported objects. The material is renamed LABEL."""
    before_obj = set(bpy.data.objects)
    before_mat = set(bpy.data.materials)
    bpy.ops.import_scene.gltf(filepath=os.path.abspath(path))
    new_objs = [o for o in bpy.data.objects if o not in before_obj]
    new_mats = [m for m in bpy.data.materials if m not in before_mat]
    mat = None
    for o in new_objs:
        if o.type == "MESH" and o.data.materials and o.data.materials[0] is not None:
            mat = o.data.materials[0]
            break
    if mat is None and new_mats:
        mat = new_mats[0]
    if mat is None:
        raise ValueError("Blender's glTF importer built no material from '%s'" % path)
    mat.use_fake_user = True
    mat.name = label
    for o in new_objs:
        bpy.data.objects.remove(o, do_unlink=True)
    return mat


def render(scene, path):
    """Renders to PATH: a 32-bit float linear RGBA EXR (A = coverage), written under a temporary name first."""
    path = os.path.abspath(path)
    tmp = "%s.tmp-%d.exr" % (path[:-4], os.getpid())
    scene.render.filepath = tmp
    bpy.ops.render.render(write_still=True)
    if not os.path.isfile(tmp):
        raise RuntimeError("Blender did not write '%s'" % tmp)
    os.replace(tmp, path)
