"""matremap's Blender renderer server: renders requests of the renderer-server protocol (v1) with Cycles.

Run by the library (src/render/renderer_process.c), one process per worker:

    blender -b --factory-startup --python-exit-code 3 --python data/renderers/blender_server.py --

Requests are JSON lines on stdin; responses are lines on stdout that start with "@matremap " (docs: the
protocol's "Lines", "op render" and "op describe"). The scene (data/renderers/blender_scene.py, the same
pieces as scripts/cycles_fit_scene.py) is built once; a request changes only what differs from the last
one (material values, camera, sphere, lights, size, samples, seed, threads), and Cycles keeps its data
between renders (persistent data), so a request costs about one bpy.ops.render.render.

One render gives every component: the Combined pass (full), DiffDir x DiffCol (diffuse) and
GlossDir x GlossCol (specular), products taken in float. Blender writes them to a multilayer OpenEXR
(uncompressed) beside the request's output prefix, which this script reads itself and removes.

Blender's own chatter (C stdio: "Fra:1 ...", "Saved: ...") goes to /dev/null: only protocol lines reach
stdout, each written whole. Python warnings and tracebacks go to stderr (the library's log).
"""

import json
import math
import os
import struct
import sys
import time
import traceback

import bpy
import numpy as np

sys.dont_write_bytecode = True   # no __pycache__ beside the sources (or in an installed tree)
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_scene  # noqa: E402

COMPONENTS = ("full", "diffuse", "specular")
# matremap's parameters of each model rendered by values ('matremap models NAME'): channels, default.
MODELS = {
    "cycles-principled": {"base_color": (3, 0.8), "metallic": (1, 0.0), "specular": (1, 0.5),
                          "specular_tint": (1, 0.0), "roughness": (1, 0.5)},
    "lambert": {"albedo": (3, 0.5)},
}
# Component -> the passes whose product it is (None: the Combined pass itself).
PASSES = {"full": None, "diffuse": ("DiffDir", "DiffCol"), "specular": ("GlossDir", "GlossCol")}
MIN_SIZE = 4        # Blender renders at least 4 x 4 pixels (a smaller resolution is raised to 4)
MAX_SIZE = 16384


class RequestError(Exception):
    """A request that names a wrong value or file: answered with its one-line message."""


def fmt_float(v):
    """The shortest text that reads back as the same float32 (0.8, not 0.800000011920929; 180, not 1.8e+02)."""
    v = float(v)
    if not math.isfinite(v):
        return repr(v)
    if v == 0.0 or 1e-4 <= abs(v) < 1e7:
        return np.format_float_positional(np.float32(v), unique=True, trim="-")
    return np.format_float_scientific(np.float32(v), unique=True, trim="-")


# ---------------------------------------------------------------------------------------------
# Request fields.

def field(req, name, where="request"):
    if name not in req:
        raise RequestError("%s has no '%s'" % (where, name))
    return req[name]


def as_int(value, name, lo, hi=None):
    if isinstance(value, bool) or not isinstance(value, int):
        raise RequestError("'%s' must be an integer, got %s" % (name, json.dumps(value)))
    if value < lo or (hi is not None and value > hi):
        raise RequestError("'%s' must be in [%d, %s], got %d" % (name, lo, hi if hi is not None else "...", value))
    return value


def as_number(value, name):
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise RequestError("'%s' must be a number, got %s" % (name, json.dumps(value)))
    if not math.isfinite(value):
        raise RequestError("'%s' must be finite, got %s" % (name, value))
    return float(value)


def as_numbers(value, name, count, grey_ok=False):
    """`count` finite numbers from a list (or, with grey_ok or count 1, from one number)."""
    if not isinstance(value, list):
        if count == 1 or grey_ok:
            return [as_number(value, name)] * count
        raise RequestError("'%s' must be a list of %d numbers, got %s" % (name, count, json.dumps(value)))
    if len(value) != count:
        raise RequestError("'%s' takes %d value%s, got %d" % (name, count, "" if count == 1 else "s", len(value)))
    return [as_number(v, "%s[%d]" % (name, i)) for i, v in enumerate(value)]


def as_object(value, name):
    if not isinstance(value, dict):
        raise RequestError("'%s' must be an object, got %s" % (name, json.dumps(value)))
    return value


# ---------------------------------------------------------------------------------------------
# .blend materials.

def output_node(mat):
    """The material's active output node for Cycles (target All or Cycles), or None."""
    outs = [n for n in mat.node_tree.nodes
            if n.bl_idname == "ShaderNodeOutputMaterial" and getattr(n, "target", "ALL") in ("ALL", "CYCLES")]
    for n in outs:
        if n.is_active_output:
            return n
    return outs[0] if outs else None


def socket_range(node, sock):
    """(min, max) of a float input: a group's interface range, else the socket type's soft range (Blender
    3.4's Python API does not expose a built-in node's per-socket range)."""
    if node.bl_idname == "ShaderNodeGroup" and node.node_tree is not None:
        for item in getattr(node.node_tree, "inputs", []):
            if item.identifier == sock.identifier and hasattr(item, "min_value"):
                return item.min_value, item.max_value
    prop = sock.bl_rna.properties["default_value"]
    return prop.soft_min, prop.soft_max


class BlendMaterial:
    """A material appended from a .blend file, its exposed inputs, and the file's values of them."""

    def __init__(self, path, name):
        if not os.path.isfile(path):
            raise RequestError("no such .blend file '%s'" % path)
        try:
            with bpy.data.libraries.load(path, link=False) as (data_from, data_to):
                present = list(data_from.materials)
                if name in present:
                    data_to.materials = [name]
        except (OSError, RuntimeError) as e:
            raise RequestError("cannot read '%s': %s" % (path, str(e).strip()))
        if name not in present:
            raise RequestError("no material '%s' in '%s' (it has: %s)"
                               % (name, path, ", ".join(present) if present else "no materials"))
        self.material = data_to.materials[0]
        self.where = "material '%s' in '%s'" % (name, path)
        out = output_node(self.material) if self.material.use_nodes and self.material.node_tree else None
        if out is None:
            problem = "has no Material Output node" if self.material.use_nodes else "does not use nodes"
            bpy.data.materials.remove(self.material)   # not kept: a later request loads the file again
            raise RequestError("%s %s" % (self.where, problem))
        self.material.use_fake_user = True
        self.params = self.exposed(out)     # path -> (socket, kind, min, max)
        self.file_values = {path: self.read(p[0]) for path, p in self.params.items()}

    @staticmethod
    def exposed(out):
        """Every enabled, visible, unlinked float or colour input of the nodes that feed the output's Surface,
        nearest first; path NODE.SOCKET (the socket's identifier when two enabled inputs share its name)."""
        params = {}
        seen = set()
        queue = [link.from_node for link in out.inputs["Surface"].links]
        while queue:
            node = queue.pop(0)
            if node.name in seen:
                continue
            seen.add(node.name)
            enabled = [s for s in node.inputs if s.enabled]
            names = [s.name for s in enabled]
            for sock in enabled:
                if sock.is_linked:
                    queue.extend(link.from_node for link in sock.links)
                    continue
                if sock.hide or sock.type not in ("VALUE", "RGBA"):
                    continue
                label = sock.identifier if names.count(sock.name) > 1 else sock.name
                kind = "float" if sock.type == "VALUE" else "color"
                lo, hi = socket_range(node, sock) if kind == "float" else (0.0, 1.0)
                params["%s.%s" % (node.name, label)] = (sock, kind, lo, hi)
        return params

    @staticmethod
    def read(sock):
        if sock.type == "VALUE":
            return [float(sock.default_value)]
        return [float(c) for c in sock.default_value[:3]]

    def apply(self, inputs):
        """The file's values, then the request's `inputs` (path -> list of numbers) over them."""
        values = dict(self.file_values)
        for path, given in as_object(inputs, "inputs").items():
            if path not in self.params:
                raise RequestError("no input '%s' in %s (its inputs: %s)"
                                   % (path, self.where, ", ".join(self.params) or "none"))
            kind = self.params[path][1]
            values[path] = as_numbers(given, path, 1 if kind == "float" else 3)
        for path, vals in values.items():
            sock = self.params[path][0]
            if sock.type == "VALUE":
                if sock.default_value != vals[0]:
                    sock.default_value = vals[0]
            elif tuple(sock.default_value[:3]) != tuple(vals):
                sock.default_value = tuple(vals) + (sock.default_value[3],)   # the file's alpha kept


# ---------------------------------------------------------------------------------------------
# The multilayer OpenEXR Blender writes (scanline, uncompressed, 32-bit float channels).

def read_multilayer_exr(path):
    """{pass name: (h, w, channels) float32 array, rows from the top} of an uncompressed scanline EXR."""
    with open(path, "rb") as f:
        data = f.read()
    if struct.unpack_from("<i", data, 0)[0] != 20000630:
        raise RequestError("'%s' is not an OpenEXR file" % path)
    flags = struct.unpack_from("<I", data, 4)[0]
    if flags & 0x1a00:  # tiled, deep, multi-part (0x400, long names, is fine)
        raise RequestError("'%s' is tiled, deep or multi-part: not the scanline EXR Blender writes" % path)
    pos = 8
    header = {}
    while data[pos] != 0:
        end = data.index(b"\0", pos)
        name = data[pos:end].decode()
        tend = data.index(b"\0", end + 1)
        size = struct.unpack_from("<i", data, tend + 1)[0]
        header[name] = data[tend + 5:tend + 5 + size]
        pos = tend + 5 + size
    pos += 1
    if header.get("compression") != b"\0":
        raise RequestError("'%s' is compressed; expected an uncompressed EXR" % path)
    x0, y0, x1, y1 = struct.unpack("<4i", header["dataWindow"])
    w, h = x1 - x0 + 1, y1 - y0 + 1
    channels = []
    chl, cpos = header["channels"], 0
    while chl[cpos] != 0:
        end = chl.index(b"\0", cpos)
        ptype = struct.unpack_from("<i", chl, end + 1)[0]
        if ptype != 2:
            raise RequestError("'%s': channel %s is not 32-bit float" % (path, chl[cpos:end].decode()))
        channels.append(chl[cpos:end].decode())
        cpos = end + 17
    offsets = struct.unpack_from("<%dQ" % h, data, pos)
    image = np.empty((h, len(channels), w), dtype=np.float32)
    for off in offsets:
        y, size = struct.unpack_from("<ii", data, off)
        if size != 4 * w * len(channels):
            raise RequestError("'%s': scanline %d has %d bytes, expected %d" % (path, y, size, 4 * w * len(channels)))
        image[y - y0] = np.frombuffer(data, dtype="<f4", count=w * len(channels), offset=off + 8).reshape(-1, w)
    passes = {}
    for i, cname in enumerate(channels):
        parts = cname.split(".")
        passes.setdefault(parts[-2] if len(parts) >= 2 else "", {})[parts[-1]] = image[:, i, :]
    out = {}
    for name, chans in passes.items():
        keys = [k for k in "RGBA" if k in chans] or sorted(chans)
        out[name] = np.stack([chans[k] for k in keys], axis=-1)
    return out   # OpenEXR's line 0 is the top of the image


# ---------------------------------------------------------------------------------------------
# The server.

class Server:
    def __init__(self, respond):
        self.respond = respond
        scene = self.scene = bpy.context.scene
        blender_scene.clear_scene()
        blender_scene.make_black_world(scene)
        self.principled, self.principled_bsdf = blender_scene.make_principled_material("MatremapPrincipled")
        self.lambert, self.lambert_bsdf = blender_scene.make_lambert_material("MatremapLambert")
        for mat in (self.principled, self.lambert):
            mat.use_fake_user = True
        self.sphere = blender_scene.Sphere(scene, "points", self.principled)
        self.camera = blender_scene.make_camera(scene, (0.0, 0.0, 4.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 35.0)
        self.lights = []
        blender_scene.configure_render(scene, 64, 16, 0, 0, True)
        r = scene.render
        r.use_persistent_data = True   # Cycles keeps its scene between renders
        im = r.image_settings
        im.file_format = "OPEN_EXR_MULTILAYER"
        im.color_mode = "RGBA"
        im.color_depth = "32"
        im.exr_codec = "NONE"
        vl = scene.view_layers[0]
        for attr, on in (("use_pass_z", False), ("use_pass_diffuse_direct", True), ("use_pass_diffuse_color", True),
                         ("use_pass_glossy_direct", True), ("use_pass_glossy_color", True)):
            setattr(vl, attr, on)
        self.blends = {}   # (path, name) -> BlendMaterial

    def ready_line(self):
        return "ready blender %s components=%s models=%s materials=blend" % (
            bpy.app.version_string.split()[0], ",".join(COMPONENTS), ",".join(MODELS))

    # -- requests

    def handle(self, line):
        """Answers one request line; returns False when the server should stop."""
        try:
            req = json.loads(line)
        except ValueError as e:
            self.respond("error -1 malformed JSON request (%s): %s" % (e, line.strip()[:200]))
            return True
        if not isinstance(req, dict):
            self.respond("error -1 a request must be a JSON object, got: %s" % line.strip()[:200])
            return True
        if req.get("op") == "quit":
            return False
        rid = req.get("id")
        if isinstance(rid, bool) or not isinstance(rid, int):
            self.respond("error -1 request without an integer 'id': %s" % line.strip()[:200])
            return True
        t0 = time.monotonic()
        try:
            op = req.get("op")
            if op == "render":
                self.render(req)
            elif op == "describe":
                self.describe(rid, req)
            else:
                raise RequestError("unknown op %s (expected render, describe or quit)" % json.dumps(op))
        except RequestError as e:
            self.respond("error %d %s" % (rid, " ".join(str(e).split())))
            return True
        except Exception as e:  # noqa: BLE001 - any failure answers the request and the server goes on
            traceback.print_exc(file=sys.stderr)
            sys.stderr.flush()
            self.respond("error %d internal error (%s): %s" % (rid, type(e).__name__, " ".join(str(e).split())))
            return True
        self.respond("ok %d %.4f" % (rid, time.monotonic() - t0))
        return True

    def blend(self, spec):
        path = field(spec, "blend", "material")
        if not isinstance(path, str) or not os.path.isabs(path):
            raise RequestError("material 'blend' must be an absolute path, got %s" % json.dumps(path))
        name = field(spec, "name", "material")
        if not isinstance(name, str):
            raise RequestError("material 'name' must be a string, got %s" % json.dumps(name))
        key = (os.path.realpath(path), name)
        if key not in self.blends:
            self.blends[key] = BlendMaterial(path, name)
        return self.blends[key]

    def describe(self, rid, req):
        spec = as_object(field(req, "material"), "material")
        blend = self.blend(spec)
        for path, (sock, kind, lo, hi) in blend.params.items():
            vals = " ".join(fmt_float(v) for v in blend.file_values[path])
            self.respond("param %d %s %s %s %s %s" % (rid, kind, fmt_float(lo), fmt_float(hi), vals, path))

    def material(self, spec):
        """The material a render request names, its values set; returns the Blender material."""
        spec = as_object(spec, "material")
        if "blend" in spec:
            blend = self.blend(spec)
            blend.apply(spec.get("inputs", {}))
            return blend.material
        model = field(spec, "model", "material")
        if model not in MODELS:
            raise RequestError("unknown model %s (this server renders: %s)" % (json.dumps(model), ", ".join(MODELS)))
        params = MODELS[model]
        given = as_object(spec.get("values", {}), "values")
        for name in given:
            if name not in params:
                raise RequestError("model %s has no parameter '%s' (its parameters: %s)"
                                   % (model, name, ", ".join(params)))
        v = {name: as_numbers(given[name], name, ch, grey_ok=True) if name in given else [default] * ch
             for name, (ch, default) in params.items()}
        if model == "lambert":
            blender_scene.set_color(self.lambert_bsdf.inputs["Color"], v["albedo"])
            return self.lambert
        blender_scene.set_principled(self.principled_bsdf, v["base_color"], v["metallic"][0], v["specular"][0],
                                     v["specular_tint"][0], v["roughness"][0])
        return self.principled

    def render(self, req):
        size = as_int(field(req, "size"), "size", MIN_SIZE, MAX_SIZE)
        samples = as_int(field(req, "samples"), "samples", 1, 1 << 24)
        seed = as_int(req.get("seed", 0), "seed", 0, (1 << 31) - 1)
        threads = as_int(req.get("threads", 0), "threads", 0, 1024)
        cam = as_object(field(req, "camera"), "camera")
        position = as_numbers(field(cam, "position", "camera"), "camera.position", 3)
        target = as_numbers(field(cam, "target", "camera"), "camera.target", 3)
        up = as_numbers(field(cam, "up", "camera"), "camera.up", 3)
        fov = as_number(field(cam, "fov_y", "camera"), "camera.fov_y")
        if not 0.0 < fov < 180.0:
            raise RequestError("'camera.fov_y' must be in (0, 180) degrees, got %s" % fmt_float(fov))
        try:
            blender_scene.look_at_matrix(position, target, up)
        except ValueError as e:
            raise RequestError(str(e))
        sph = as_object(field(req, "sphere"), "sphere")
        center = as_numbers(field(sph, "center", "sphere"), "sphere.center", 3)
        radius = as_number(field(sph, "radius", "sphere"), "sphere.radius")
        if radius <= 0.0:
            raise RequestError("'sphere.radius' must be > 0, got %s" % fmt_float(radius))
        lights_in = field(req, "lights")
        if not isinstance(lights_in, list):
            raise RequestError("'lights' must be a list, got %s" % json.dumps(lights_in))
        lights = []
        for i, light in enumerate(lights_in):
            light = as_object(light, "lights[%d]" % i)
            pos = as_numbers(field(light, "position", "lights[%d]" % i), "lights[%d].position" % i, 3)
            inten = as_numbers(field(light, "intensity", "lights[%d]" % i), "lights[%d].intensity" % i, 3,
                               grey_ok=True)
            if min(inten) < 0.0:
                raise RequestError("'lights[%d].intensity' must be >= 0, got %s" % (i, inten))
            lights.append((pos, inten))
        comps = field(req, "components")
        if not isinstance(comps, list) or not comps:
            raise RequestError("'components' must be a non-empty list, got %s" % json.dumps(comps))
        for c in comps:
            if c not in COMPONENTS:
                raise RequestError("component %s is not supported (this server returns: %s)"
                                   % (json.dumps(c), ", ".join(COMPONENTS)))
        output = self.output_prefix(field(req, "output"))
        material = self.material(field(req, "material"))

        # The scene: only what changed is touched (the setters compare before they write).
        scene = self.scene
        blender_scene.set_sampling(scene, size, samples, seed, threads)
        blender_scene.set_camera(self.camera, position, target, up, fov)
        self.sphere.place(center, radius)
        self.sphere.set_material(material)
        while len(self.lights) > len(lights):
            ob = self.lights.pop()
            data = ob.data
            bpy.data.objects.remove(ob, do_unlink=True)
            bpy.data.lights.remove(data)
        for i, (pos, inten) in enumerate(lights):
            if i < len(self.lights):
                blender_scene.set_point_light(self.lights[i], pos, inten)
            else:
                self.lights.append(blender_scene.make_point_light(scene, "MatremapLight%d" % i, pos, inten))

        tmp = output + ".render-tmp.exr"
        try:
            scene.render.filepath = tmp
            bpy.ops.render.render(write_still=True)
            if not os.path.isfile(tmp):
                raise RequestError("Blender did not write its render to '%s'" % tmp)
            passes = read_multilayer_exr(tmp)
        finally:
            if os.path.lexists(tmp):
                os.remove(tmp)
        combined = passes.get("Combined")
        if combined is None or combined.shape != (size, size, 4):
            raise RequestError("Blender's render has no %dx%d RGBA Combined pass" % (size, size))
        alpha = combined[:, :, 3:4]
        for comp in dict.fromkeys(comps):
            if PASSES[comp] is None:
                rgba = combined
            else:
                direct, color = (passes.get(p) for p in PASSES[comp])
                if direct is None or color is None:
                    raise RequestError("Blender's render lacks the %s and %s passes" % PASSES[comp])
                rgba = np.concatenate([direct[:, :, :3] * color[:, :, :3], alpha], axis=-1)
            np.ascontiguousarray(rgba, dtype="<f4").tofile("%s.%s.f32" % (output, comp))

    @staticmethod
    def output_prefix(output):
        if not isinstance(output, str) or not output:
            raise RequestError("'output' must be a path prefix, got %s" % json.dumps(output))
        if not os.path.isabs(output) or output.startswith("//") or output.endswith("/"):
            raise RequestError("'output' must be an absolute path prefix of files, got '%s'" % output)
        if "#" in output:
            raise RequestError("'output' must not contain '#' (Blender reads it as a frame number): '%s'" % output)
        folder = os.path.dirname(output)
        if not os.path.isdir(folder):
            raise RequestError("the folder of 'output' does not exist: '%s'" % folder)
        return output


def main():
    # Protocol lines go to the original stdout, whole; Blender's C-level chatter goes to /dev/null and any
    # Python print to stderr, so nothing can split a protocol line.
    out_fd = os.dup(1)
    null_fd = os.open(os.devnull, os.O_WRONLY)
    sys.stdout.flush()
    os.dup2(null_fd, 1)
    os.close(null_fd)
    sys.stdout = sys.stderr

    def respond(text):
        data = ("@matremap " + text.replace("\n", " ") + "\n").encode("utf-8", "replace")
        while data:
            data = data[os.write(out_fd, data):]

    server = Server(respond)
    respond(server.ready_line())
    while True:
        line = sys.stdin.readline()
        if not line:
            break          # EOF: Blender goes on to exit with status 0
        if not line.strip():
            continue
        if not server.handle(line):
            break


main()
