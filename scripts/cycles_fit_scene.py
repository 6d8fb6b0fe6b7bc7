"""Render matremap's fit scene with Blender Cycles (the "Cycles peer").

Run inside Blender (3.4; also meant to work with later 3.x):

    blender -b --factory-startup --python scripts/cycles_fit_scene.py -- \
        --size 256 --samples 16 --light 45 --material principled \
        --base-color 0.8,0.2,0.1 --metallic 0 --specular 0.5 --roughness 0.4 \
        --specular-tint 0 --distribution GGX --component full -o out.exr

The scene is built from data/renderers/blender_scene.py, which the renderer server
(data/renderers/blender_server.py) builds its scene from too.

The fit scene (matremap's definition; see docs/cycles-peer.md):
  * right-handed world, +y up (Blender's axes used as they are: the camera looks along -z);
  * unit sphere at the origin: by default a Geometry Nodes point of radius 1, which Cycles (3.1+)
    ray-traces as an exact sphere; --geometry icosphere uses a smooth-shaded icosphere mesh instead
    (7 subdivisions, 81 920 triangles, silhouette at most 0.008 px inside the true one at 256^2);
  * perspective camera at (0, 0, 4) looking at the origin, up +y, vertical FOV 35 degrees, N x N pixels;
  * white point light of radiant intensity 10 W/sr at distance 3: "45" at (3 sin45, 0, 3 cos45),
    "frontal" at (0, 0, 3); radius 0 (hard shadows);
  * black world, no other light, direct lighting only.

Cycles' point light of "Power" P watts (radius 0) has radiant intensity I = P / (4 pi) W/sr, with no
extra factor of pi (measured to 1e-6 with the exact sphere, see docs/cycles-peer.md), so I = 10 W/sr is P = 40 pi = 125.66 W.

Output: a 32-bit float linear RGB OpenEXR (no alpha). --component diffuse|specular writes the
product of the Cycles passes DiffDir x DiffCol (resp. GlossDir x GlossCol), composited in float;
"full" writes the Combined pass.  Prints one JSON line
    {"render_seconds": ..., "total_seconds": ..., "size": ..., "samples": ...}
on stdout (also written to --timing-json).  render_seconds covers bpy.ops.render.render
(scene sync, BVH build, path tracing, compositing and writing the EXR); total_seconds is wall time
since the Blender process started (start-up + scene building + render), measured from /proc.

Extra (calibration): --check-lambert ALBEDO compares the written image with the analytic Lambert
sphere (L = albedo/pi * I * cos(theta_l) / d^2, box-filtered over each pixel by 8x8 supersampling)
and prints a second JSON line; use it with --material diffuse --base-color a,a,a.
--silhouette-check prints the mesh's silhouette error against a perfect sphere (in pixels).
"""

import argparse
import json
import math
import os
import sys
import time

import bpy

T_SCRIPT_START = time.time()

# The scene's pieces are shared with the renderer server (data/renderers/blender_scene.py).
sys.dont_write_bytecode = True   # no __pycache__ beside the sources (or in an installed tree)
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data", "renderers"))
import blender_scene  # noqa: E402

ICO_SUBDIVISIONS = blender_scene.ICO_SUBDIVISIONS

# Radiant intensity of the fit-scene light, W/sr, and Cycles' conversion (measured in Blender
# 3.4.1: a point light of Power P watts and radius 0 has I = P / (4 pi) W/sr).
FIT_INTENSITY = 10.0
LIGHT_DISTANCE = 3.0
CAMERA_Z = 4.0
FOV_DEG = 35.0


def process_start_time():
    """Wall-clock time at which this process started (Linux /proc), or None."""
    try:
        with open("/proc/self/stat") as f:
            stat = f.read()
        # Field 22 (starttime, in clock ticks since boot); skip the "(comm)" field safely.
        fields = stat[stat.rindex(")") + 2:].split()
        start_ticks = int(fields[19])
        with open("/proc/uptime") as f:
            uptime = float(f.read().split()[0])
        hz = os.sysconf("SC_CLK_TCK")
        return time.time() - (uptime - start_ticks / hz)
    except (OSError, ValueError, IndexError):
        return None


def fail(msg, code=2):
    sys.stderr.write("cycles_fit_scene: %s\n" % msg)
    sys.stderr.flush()
    os._exit(code)  # immediate exit with this code: no Blender exit handler can change it


def parse_triple(text):
    try:
        vals = [float(v) for v in text.split(",")]
    except ValueError:
        vals = []
    if len(vals) == 1:
        vals = vals * 3
    if len(vals) != 3 or not all(math.isfinite(v) and v >= 0.0 for v in vals):
        raise argparse.ArgumentTypeError("expected r,g,b (three numbers >= 0), got '%s'" % text)
    return vals


class UsageParser(argparse.ArgumentParser):
    """argparse with matremap's exit codes: usage errors exit 1 (argparse's default is 2)."""

    def error(self, message):
        self.print_usage(sys.stderr)
        fail("usage: %s" % message, 1)


def parse_args(argv):
    p = UsageParser(prog="cycles_fit_scene.py",
                    description="Render matremap's fit scene with Cycles. Exit codes: 0 ok, "
                                "1 usage, 2 bad input, 3 Blender/internal failure.")
    p.add_argument("--size", type=int, default=256, help="image is SIZE x SIZE (default 256)")
    p.add_argument("--samples", type=int, default=16, help="samples per pixel (default 16)")
    p.add_argument("--light", choices=["45", "frontal"], default="45")
    p.add_argument("--material", choices=["principled", "diffuse", "glossy"], default="principled",
                   help="Principled BSDF, Diffuse BSDF (roughness 0: Lambert), or Glossy BSDF (colour "
                        "--base-color, --roughness, --distribution; matremap's cycles-ggx at f0 = 1 when the "
                        "colour is white)")
    p.add_argument("--base-color", type=parse_triple, default=[0.8, 0.8, 0.8],
                   help="linear r,g,b (or one value for grey)")
    p.add_argument("--metallic", type=float, default=0.0)
    p.add_argument("--specular", type=float, default=0.5)
    p.add_argument("--roughness", type=float, default=0.5)
    p.add_argument("--specular-tint", type=float, default=0.0)
    p.add_argument("--distribution", choices=["GGX", "MULTI_GGX"], default="GGX")
    p.add_argument("--component", choices=["full", "diffuse", "specular"], default="full")
    p.add_argument("--geometry", choices=["points", "icosphere"], default="points",
                   help="sphere as a Geometry Nodes point of radius 1, which Cycles ray-traces as an "
                        "exact sphere (default), or as a smooth icosphere mesh (81 920 triangles)")
    p.add_argument("-o", "--output", required=True, help="output .exr path")
    p.add_argument("--threads", type=int, default=0, help="CPU threads (default 0 = all cores)")
    p.add_argument("--seed", type=int, default=0, help="Cycles sampling seed (default 0)")
    p.add_argument("--timing-json", help="also write the timing JSON here")
    p.add_argument("--light-power", type=float, default=None,
                   help="override the Blender light Power in W (calibration only)")
    p.add_argument("--check-lambert", type=float, default=None, metavar="ALBEDO",
                   help="compare the output with the analytic Lambert sphere of this albedo")
    p.add_argument("--silhouette-check", action="store_true",
                   help="measure the mesh silhouette against a perfect sphere")
    a = p.parse_args(argv)
    if a.size < 1 or a.size > 16384:
        p.error("--size must be in [1, 16384], got %d" % a.size)
    if a.samples < 1:
        p.error("--samples must be >= 1, got %d" % a.samples)
    if a.threads < 0:
        p.error("--threads must be >= 0, got %d" % a.threads)
    for name in ("metallic", "specular", "roughness", "specular_tint"):
        v = getattr(a, name)
        if not math.isfinite(v) or v < 0.0:
            p.error("--%s must be a finite number >= 0, got %g" % (name.replace("_", "-"), v))
    for name in ("metallic", "roughness", "specular_tint"):
        if getattr(a, name) > 1.0:
            p.error("--%s must be in [0, 1], got %g" % (name.replace("_", "-"), getattr(a, name)))
    if a.material == "diffuse" and a.component == "specular":
        p.error("--material diffuse has no specular component")
    if a.material == "glossy" and a.component == "diffuse":
        p.error("--material glossy has no diffuse component")
    return a


def light_position(which):
    if which == "frontal":
        return (0.0, 0.0, LIGHT_DISTANCE)
    s = math.sin(math.radians(45.0))
    return (LIGHT_DISTANCE * s, 0.0, LIGHT_DISTANCE * s)


def make_material(args):
    if args.material == "diffuse":
        mat, bsdf = blender_scene.make_lambert_material("FitMaterial")
        blender_scene.set_color(bsdf.inputs["Color"], args.base_color)
    elif args.material == "glossy":
        mat, bsdf = blender_scene.make_glossy_material("FitMaterial", args.distribution)
        blender_scene.set_color(bsdf.inputs["Color"], args.base_color)
        bsdf.inputs["Roughness"].default_value = args.roughness
    else:
        mat, bsdf = blender_scene.make_principled_material("FitMaterial")
        bsdf.distribution = args.distribution
        blender_scene.set_principled(bsdf, args.base_color, args.metallic, args.specular, args.specular_tint,
                                     args.roughness)
    return mat


def build_scene(args):
    scene = bpy.context.scene
    blender_scene.clear_scene()
    blender_scene.make_black_world(scene)
    sphere = blender_scene.Sphere(scene, args.geometry, make_material(args)).object
    blender_scene.make_camera(scene, (0.0, 0.0, CAMERA_Z), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), FOV_DEG)
    blender_scene.make_point_light(scene, "FitLight", light_position(args.light), [FIT_INTENSITY] * 3,
                                           args.light_power)
    power = args.light_power if args.light_power is not None else FIT_INTENSITY * blender_scene.WATTS_PER_W_SR
    blender_scene.configure_render(scene, args.size, args.samples, args.seed, args.threads, False)

    r = scene.render
    r.use_persistent_data = False
    im = r.image_settings
    im.file_format = "OPEN_EXR"
    im.color_mode = "RGB"
    im.color_depth = "32"
    im.exr_codec = "ZIP"

    vl = scene.view_layers[0]
    if args.component != "full":
        kind = "diffuse" if args.component == "diffuse" else "glossy"
        setattr(vl, "use_pass_%s_direct" % kind, True)
        setattr(vl, "use_pass_%s_color" % kind, True)
        scene.use_nodes = True
        r.use_compositing = True
        tree = scene.node_tree
        for n in list(tree.nodes):
            tree.nodes.remove(n)
        rl = tree.nodes.new("CompositorNodeRLayers")
        rl.scene = scene
        rl.layer = vl.name
        mul = tree.nodes.new("CompositorNodeMixRGB")
        mul.blend_type = "MULTIPLY"
        mul.use_alpha = False
        mul.use_clamp = False
        mul.inputs[0].default_value = 1.0
        comp = tree.nodes.new("CompositorNodeComposite")
        comp.use_alpha = False
        prefix = "Diff" if kind == "diffuse" else "Gloss"
        tree.links.new(rl.outputs[prefix + "Dir"], mul.inputs[1])
        tree.links.new(rl.outputs[prefix + "Col"], mul.inputs[2])
        tree.links.new(mul.outputs[0], comp.inputs["Image"])
    return scene, sphere, power


# ---------------------------------------------------------------------------------------------
# Calibration helpers (Blender's Python has numpy when python3-numpy is installed).

def camera_rays(n, ss):
    """Directions of ss x ss stratified sub-pixel rays for an n x n image, rows from the top."""
    import numpy as np
    t = math.tan(math.radians(FOV_DEG) / 2.0)
    offs = (np.arange(ss) + 0.5) / ss
    u = (np.arange(n)[:, None] + offs[None, :]).reshape(-1) / n  # n*ss values in [0,1)
    x = (2.0 * u - 1.0) * t
    y = (1.0 - 2.0 * u) * t
    X, Y = np.meshgrid(x, y)  # Y varies along rows (top first)
    D = np.stack([X, Y, -np.ones_like(X)], axis=-1)
    return D / np.linalg.norm(D, axis=-1, keepdims=True)


def analytic_lambert(n, albedo, light, ss=8):
    import numpy as np
    D = camera_rays(n, ss)
    o = np.array([0.0, 0.0, CAMERA_Z])
    b = D @ o                      # ray o + t D, |o + tD|^2 = 1
    disc = b * b - (o @ o - 1.0)
    hit = disc > 0.0
    tt = -b - np.sqrt(np.where(hit, disc, 0.0))
    P = o + tt[..., None] * D
    Lv = np.array(light) - P
    d2 = np.sum(Lv * Lv, axis=-1)
    cos_l = np.sum(P * Lv, axis=-1) / np.sqrt(d2)   # normal = P on the unit sphere
    rad = np.where(hit & (cos_l > 0.0), albedo / math.pi * FIT_INTENSITY * np.maximum(cos_l, 0.0) / d2, 0.0)
    cover = hit.astype(np.float64)
    rad = rad.reshape(n, ss, n, ss).mean(axis=(1, 3))
    cover = cover.reshape(n, ss, n, ss).mean(axis=(1, 3))
    return rad, cover


def load_exr_rgb(path):
    """The EXR as an (n, n, 3) float array, rows from the top."""
    import numpy as np
    img = bpy.data.images.load(path, check_existing=False)
    w, h = img.size
    buf = np.empty(w * h * 4, dtype=np.float32)
    img.pixels.foreach_get(buf)
    bpy.data.images.remove(img)
    return buf.reshape(h, w, 4)[::-1, :, :3].astype(np.float64)  # Blender's rows are bottom-up


def check_lambert(path, args, power):
    import numpy as np
    n = args.size
    img = load_exr_rgb(path).mean(axis=2)
    ref, cover = analytic_lambert(n, args.check_lambert, light_position(args.light))
    inside = cover >= 1.0                       # pixels entirely on the sphere
    lit = inside & (ref > 0.05 * ref.max())     # and not in the dark part / terminator
    ratio_all = img.sum() / ref.sum()
    r = img[lit] / ref[lit]
    # Robust, noise-free power estimate: ratio over the lit interior pixels.
    k = float(img[lit].sum() / ref[lit].sum())
    # Radiant intensity this render actually had (the reference assumes FIT_INTENSITY).
    i_measured = k * FIT_INTENSITY
    return {
        "check": "lambert",
        "light": args.light,
        "albedo": args.check_lambert,
        "blender_power_W": power,
        "ratio_sum_all_pixels": float(ratio_all),
        "ratio_sum_lit_interior": k,
        "lit_interior_pixels": int(lit.sum()),
        "per_pixel_ratio_mean": float(r.mean()),
        "per_pixel_ratio_std": float(r.std()),
        "per_pixel_ratio_p01": float(np.percentile(r, 1)),
        "per_pixel_ratio_p99": float(np.percentile(r, 99)),
        "max_abs_err_over_max_radiance": float(np.abs(img - ref).max() / ref.max()),
        "rms_err_over_mean_lit_radiance": float(np.sqrt(np.mean((img - ref)[cover > 0] ** 2)) / ref[lit].mean()),
        "measured_I_W_per_sr": i_measured,
        "measured_W_per_W_per_sr": float(power / i_measured) if i_measured else None,
        "watts_for_10_W_per_sr": float(FIT_INTENSITY * power / i_measured) if i_measured else None,
    }


def silhouette_check(sphere, n, geometry):
    """Largest deviation of the mesh silhouette from the perfect sphere's, in pixels."""
    if geometry == "points":
        return {"check": "silhouette", "mesh": "point primitive, radius 1 (exact sphere)", "size": n}
    from mathutils import Vector
    from mathutils.bvhtree import BVHTree
    dg = bpy.context.evaluated_depsgraph_get()
    bvh = BVHTree.FromObject(sphere, dg)
    o = Vector((0.0, 0.0, CAMERA_Z))
    t = math.tan(math.radians(FOV_DEG) / 2.0)
    px_per_unit = n / (2.0 * t)          # image-plane units (at focal distance 1) to pixels
    r_true = math.tan(math.asin(1.0 / CAMERA_Z))
    worst_in = worst_out = 0.0
    radii = []
    steps = 720
    for k in range(steps):
        phi = 2.0 * math.pi * (k + 0.5) / steps
        lo, hi = r_true * 0.99, r_true * 1.01
        for _ in range(40):
            mid = 0.5 * (lo + hi)
            d = Vector((mid * math.cos(phi), mid * math.sin(phi), -1.0)).normalized()
            if bvh.ray_cast(o, d)[0] is not None:
                lo = mid
            else:
                hi = mid
        radii.append(lo)
        dev = (lo - r_true) * px_per_unit
        worst_in = min(worst_in, dev)
        worst_out = max(worst_out, dev)
    mean_dev = (sum(radii) / len(radii) - r_true) * px_per_unit
    return {
        "check": "silhouette",
        "mesh": "icosphere, %d subdivisions, %d triangles" % (ICO_SUBDIVISIONS, len(sphere.data.polygons)),
        "size": n,
        "true_radius_px": r_true * px_per_unit,
        "mean_deviation_px": mean_dev,
        "max_inward_px": worst_in,
        "max_outward_px": worst_out,
    }


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    args = parse_args(argv)
    out = os.path.abspath(args.output)
    if not out.lower().endswith(".exr"):
        fail("output '%s' must end in .exr" % args.output)
    out_dir = os.path.dirname(out)
    if not os.path.isdir(out_dir):
        fail("output directory '%s' does not exist" % out_dir)
    t_proc = process_start_time()

    scene, sphere, power = build_scene(args)

    tmp = "%s.tmp-%d.exr" % (out[:-4], os.getpid())
    scene.render.filepath = tmp
    t0 = time.time()
    bpy.ops.render.render(write_still=True)
    t1 = time.time()
    if not os.path.isfile(tmp):
        fail("Blender did not write '%s'" % tmp, 3)
    os.replace(tmp, out)

    timing = {
        "render_seconds": round(t1 - t0, 4),
        "total_seconds": round(t1 - (t_proc if t_proc is not None else T_SCRIPT_START), 4),
        "size": args.size,
        "samples": args.samples,
    }
    line = json.dumps(timing)
    if args.timing_json:
        with open(args.timing_json, "w") as f:
            f.write(line + "\n")
    print(line, flush=True)

    if args.check_lambert is not None:
        print(json.dumps(check_lambert(out, args, power)), flush=True)
    if args.silhouette_check:
        print(json.dumps(silhouette_check(sphere, args.size, args.geometry)), flush=True)


try:
    main()
except SystemExit as e:  # argparse errors/--help: make Blender exit with the code too
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(e.code if isinstance(e.code, int) else 1)
except Exception as e:  # noqa: BLE001 - report any Blender/Python failure as one line
    import traceback
    traceback.print_exc()
    fail("internal error: %s" % e, 3)
