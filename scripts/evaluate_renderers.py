#!/usr/bin/python3
"""make evaluation-renderers (via scripts/evaluate-renderers.sh): node materials of data/blender/node_materials.blend
baked to glTF metal-rough two ways and rendered back beside the original (issue 29, item 6).

Per material NAME:
  1. Blender's own glTF exporter (scripts/blender/export_gltf.py) writes BUILD/.../NAME/exporter.gltf; the values
     it wrote are read back.
  2. matremap's remap to gltf (remap_step below): `matremap remap --from blender:BLEND:NAME --to gltf --json` when
     the binary has it, else the stand-in: the node material rendered by Cycles in the fit scene at 64^2
     (scripts/blender/render_back.py) and `matremap remap --from-images FULL.exr --to gltf --json`. Its values go
     into NAME/matremap.gltf (the exporter's file with the material replaced).
  3. Render-back in Cycles at SIZE^2 (scripts/blender/render_back.py, the fit scene of scripts/cycles_fit_scene.py):
     the original node material (seeds 0 and 1: the noise floor), and each .gltf as Blender's glTF importer builds
     it; in three.js (data/renderers/three/server.mjs, op render, model gltf; skipped with a line when absent).
  4. Object SSIM and relative RMSE against the original (`matremap ssim ORIG X --mask COVERAGE --json`), a contact
     sheet per material (docs/images/renderers/NAME.png), the page docs/evaluation-renderers.md.
Environment: RENDERERS_SIZE (512), RENDERERS_SAMPLES (64), RENDERERS_THREADS (2), RENDERERS_ROUTE (auto |
standin | blender), RENDERERS_THREE_SAMPLES (16), MATREMAP_BLENDER (blender), MATREMAP_NODE (node),
MATREMAP_THREE_SERVER (the three.js server script, default data/renderers/three/server.mjs).
Usage: scripts/evaluate_renderers.py BUILD (run from the repository root by scripts/evaluate-renderers.sh).
"""

import json
import os
import shutil
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BUILD = os.path.join(ROOT, sys.argv[1] if len(sys.argv) > 1 else "build")
BIN = os.path.join(BUILD, "bin", "matremap")
BLEND = os.path.join(ROOT, "data", "blender", "node_materials.blend")
BLEND_REL = "data/blender/node_materials.blend"
WORK = os.path.join(BUILD, "evaluation-renderers")
DOC = os.path.join(ROOT, "docs", "evaluation-renderers.md")
IMAGES = os.path.join(ROOT, "docs", "images", "renderers")
THREE_SERVER = (os.environ.get("MATREMAP_THREE_SERVER")
                or os.path.join(ROOT, "data", "renderers", "three", "server.mjs"))
FONT = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"
SIZE = int(os.environ.get("RENDERERS_SIZE", "512"))
SAMPLES = int(os.environ.get("RENDERERS_SAMPLES", "64"))
THREADS = int(os.environ.get("RENDERERS_THREADS", "2"))
ROUTE = os.environ.get("RENDERERS_ROUTE", "auto")
THREE_SAMPLES = int(os.environ.get("RENDERERS_THREE_SAMPLES", "16"))
STANDIN_SIZE, STANDIN_SAMPLES = 64, 512
BLENDER = os.environ.get("MATREMAP_BLENDER", "blender")
NODE = os.environ.get("MATREMAP_NODE", "node")
# Remaps with KHR_materials_specular's colour fitted (`--free specular_color`, metallic held at 0: a dielectric whose
# Fresnel-less Glossy lobe outshines glTF's 4 % dielectric): expected specular_color = the lobe's reflectance / 0.04.
FREED = ["--free", "specular_color", "--hold", "metallic=0"]
DIAGNOSTIC_HOLDS = {"ConstantMixGlossy": FREED,   # 0.3 x white Glossy, no Fresnel: 7.5 expected
                    "DiffuseGlossyAdd": FREED}    # a 0.08 grey Glossy added: 2 expected
# The fit scene of protocol v1 (notes: the library's fit scene, light at 45 degrees).
S45 = 2.1213203435596424
FIT_SCENE = {"camera": {"position": [0, 0, 4], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 35.0},
             "sphere": {"center": [0, 0, 0], "radius": 1.0},
             "lights": [{"position": [S45, 0, S45], "intensity": [10, 10, 10]}]}


def log(msg):
    sys.stderr.write("evaluation-renderers: %s\n" % msg)
    sys.stderr.flush()


def run(cmd, **kw):
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kw)
    if r.returncode != 0:
        log("failed (exit %d): %s\n%s" % (r.returncode, " ".join(cmd), r.stderr[-3000:]))
        sys.exit(3)
    return r.stdout


def blender(script, args):
    """Runs a scripts/blender/ script in Blender; returns its JSON lines (stdout lines that start with '{')."""
    cmd = [BLENDER, "-b", "--factory-startup", "--python-exit-code", "3",
           "--python", os.path.join(ROOT, "scripts", "blender", script), "--"] + args
    return [json.loads(line) for line in run(cmd).splitlines() if line.startswith("{")]


def render_jobs(jobs, path):
    with open(path, "w") as f:
        json.dump(jobs, f, indent=1)
    return blender("render_back.py", ["--jobs", path, "--threads", str(THREADS)])


def help_text():
    r = subprocess.run([BIN, "remap", "--help"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    return r.stdout


def remap_route():
    """'blender' when this matremap takes `--from blender:FILE.blend:MATERIAL`, else 'standin'."""
    if ROUTE in ("standin", "blender"):
        return ROUTE
    return "blender" if "blender:" in help_text() else "standin"


def remap_step(name, d, route, to_renderer=None, target_args=()):
    """THE remap of node material NAME to glTF metal-rough. Returns (values, command line, result JSON).

    route 'blender': `matremap remap --from blender:BLEND:NAME --to gltf [--to-renderer R] --json` (the source
    rendered by Blender through data/renderers/blender_server.py). TARGET_ARGS (name=value) follow `--to gltf`.
    route 'standin' (until that exists): the Cycles render d/source64.exr of the node material (made beforehand by
    render_back.py at 64^2, STANDIN_SAMPLES samples) fitted by `matremap remap --from-images`."""
    if route == "blender":
        cmd = [BIN, "remap", "--from", "blender:%s:%s" % (BLEND_REL, name), "--to", "gltf"] + list(target_args)
        if to_renderer:
            cmd += ["--to-renderer", to_renderer]
        cmd += ["--json"]
        out = run(cmd, cwd=ROOT)
    else:
        src = os.path.join(d, "source64.exr")
        cmd = [BIN, "remap", "--from-images", src, "--to", "gltf"] + list(target_args) + ["--json"]
        out = run(cmd, cwd=ROOT)
        cmd[3] = os.path.relpath(src, ROOT)
    res = json.loads(out)
    return res["values"], " ".join(os.path.relpath(c, ROOT) if c == BIN else c for c in cmd), res


def write_gltf_with(src_gltf, dst_gltf, values, name):
    """A copy of src_gltf whose first material holds glTF metal-rough VALUES (extensions only when not default)."""
    with open(src_gltf) as f:
        doc = json.load(f)
    m = {"name": name, "doubleSided": True, "pbrMetallicRoughness": {
        "baseColorFactor": [float(c) for c in values["base_color"][:3]] + [1.0],
        "metallicFactor": float(values["metallic"]), "roughnessFactor": float(values["roughness"])}}
    ext = {}
    spec, spec_col = values.get("specular", 1.0), values.get("specular_color", [1.0, 1.0, 1.0])
    if spec != 1.0 or list(spec_col) != [1.0, 1.0, 1.0]:
        ext["KHR_materials_specular"] = {"specularFactor": float(spec), "specularColorFactor": list(spec_col)}
    if values.get("ior", 1.5) != 1.5:
        ext["KHR_materials_ior"] = {"ior": float(values["ior"])}
    if ext:
        m["extensions"] = ext
        doc["extensionsUsed"] = sorted(set(doc.get("extensionsUsed", [])) | set(ext))
    doc["materials"] = [m]
    with open(dst_gltf + ".tmp", "w") as f:
        json.dump(doc, f)
    os.replace(dst_gltf + ".tmp", dst_gltf)


# ---- three.js (protocol29 v1, op render, model gltf) ---------------------------------------------------------------

class Three:
    """The three.js renderer server, when data/renderers/three/server.mjs is there; else .why says why not."""

    def __init__(self):
        self.proc, self.why, self.version, self.next_id = None, None, None, 1
        if not os.path.isfile(THREE_SERVER):
            self.why = "%s is not on this branch yet" % os.path.relpath(THREE_SERVER, ROOT)
            return
        if shutil.which(NODE) is None:
            self.why = "'%s' is not installed" % NODE
            return
        self.log = open(os.path.join(WORK, "three-server.log"), "w")
        self.proc = subprocess.Popen([NODE, THREE_SERVER], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=self.log, text=True, cwd=ROOT)
        line = self._line()
        if line is None or line[1] != "ready":
            self.close()
            self.why = "the server did not say ready (see %s)" % os.path.relpath(self.log.name, ROOT)
            return
        self.version = line[3] if len(line) > 3 else "?"
        caps = " ".join(line[4:])
        if "gltf" not in caps:
            self.close()
            self.why = "the server's models do not include gltf (%s)" % caps
            return

    def _line(self):
        while True:
            raw = self.proc.stdout.readline()
            if not raw:
                return None
            if raw.startswith("@matremap "):
                return raw.rstrip("\n").split(" ")

    def render(self, values, out_prefix, size):
        """Renders glTF VALUES; returns (RGBA rows top first as a float32 numpy array, seconds) or raises."""
        import numpy as np
        rid = self.next_id
        self.next_id += 1
        req = dict(FIT_SCENE, op="render", id=rid, size=size, samples=THREE_SAMPLES, seed=0, threads=THREADS,
                   material={"model": "gltf", "values": values}, components=["full"], output=out_prefix)
        self.proc.stdin.write(json.dumps(req) + "\n")
        self.proc.stdin.flush()
        line = self._line()
        if line is None:
            raise RuntimeError("the three.js server ended (see %s)" % self.log.name)
        if line[1] != "ok" or line[2] != str(rid):
            raise RuntimeError("three.js server: %s" % " ".join(line[1:]))
        px = np.fromfile(out_prefix + ".full.f32", dtype="<f4")
        if px.size != size * size * 4:
            raise RuntimeError("%s.full.f32 holds %d floats, not %d" % (out_prefix, px.size, size * size * 4))
        return px.reshape(size, size, 4), float(line[3])

    def close(self):
        if self.proc is not None:
            try:
                self.proc.stdin.write('{"op": "quit"}\n')
                self.proc.stdin.close()
                self.proc.wait(timeout=30)
            except (OSError, subprocess.TimeoutExpired):
                self.proc.kill()
            self.proc = None


def write_pfm(path, rgb):
    """rgb: (n, n, 3) rows from the top; PFM stores rows from the bottom, little-endian (scale -1)."""
    import numpy as np
    n = rgb.shape[0]
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (rgb.shape[1], n))
        f.write(np.ascontiguousarray(rgb[::-1].astype("<f4")).tobytes())


# ---- metrics and pictures ------------------------------------------------------------------------------------------

def ssim(a, b, mask):
    r = json.loads(run([BIN, "ssim", a, b, "--mask", mask, "--json"]))
    return r["object_ssim"], r["object_relative_rmse"]


def mean_rgb(path):
    """The image's mean linear R, G, B (oiiotool --stats): over a black background, the object's summed radiance."""
    for line in run(["oiiotool", "--stats", path]).splitlines():
        if "Stats Avg:" in line:
            return [float(v) for v in line.split(":")[1].split()[:3]]
    log("oiiotool --stats printed no average for %s" % path)
    sys.exit(3)


def contact_sheet(tiles, out_png):
    """tiles: [(image path, label)]; one row of 256^2 tiles, sRGB, labelled."""
    cmd = ["oiiotool"]
    for path, label in tiles:
        cmd += ["-i", path, "--ch", "R,G,B", "--resize", "256x256", "--colorconvert", "linear", "sRGB"]
        if os.path.isfile(FONT):
            cmd += ["--text:x=6:y=20:size=15:color=1,1,1:font=%s" % FONT, label]
    cmd += ["--mosaic:pad=4", "%dx1" % len(tiles), "-d", "uint8", "-o", out_png]
    run(cmd)


def fmt_vals(v):
    c = v["base_color"]
    s = "base (%.3f, %.3f, %.3f), metallic %.3f, roughness %.3f" % (c[0], c[1], c[2], v["metallic"], v["roughness"])
    if v.get("specular", 1.0) != 1.0:
        s += ", specular %.3f" % v["specular"]
    if list(v.get("specular_color", [1, 1, 1])) != [1, 1, 1]:
        s += ", specular_color (%.3f, %.3f, %.3f)" % tuple(v["specular_color"])
    if v.get("ior", 1.5) != 1.5:
        s += ", ior %.3f" % v["ior"]
    return s


def written_desc(w):
    pbr = w.get("pbrMetallicRoughness", {})
    if not pbr and not w.get("extensions"):
        return "nothing (empty pbrMetallicRoughness: glTF defaults, white metal of roughness 1)"
    keys = sorted(pbr) + sorted(w.get("extensions", {}))
    missing = [k for k in ("baseColorFactor", "metallicFactor", "roughnessFactor") if k not in pbr]
    return "%s%s" % (", ".join(keys), "; left out: " + ", ".join(missing) if missing else "")


def main():
    t0 = time.time()
    if not os.path.isfile(BLEND):
        log("%s is missing (make it with scripts/blender/make_node_materials.py)" % BLEND)
        sys.exit(2)
    shutil.rmtree(WORK, ignore_errors=True)
    os.makedirs(WORK)
    os.makedirs(IMAGES, exist_ok=True)
    route = remap_route()
    log("remap route: %s" % route)
    times = {}

    # 1. Blender's glTF exporter.
    t = time.time()
    exported = {r["material"]: r for r in blender("export_gltf.py", ["--blend", BLEND, "--out-dir", WORK])}
    names = sorted(exported)
    times["export"] = time.time() - t

    three = Three()
    if three.why:
        log("three.js render-back skipped: %s" % three.why)
    # The bakes: (key, column title); the fit targeted at three.js only with the real route and the server.
    bakes = [("exporter", "Blender exporter"),
             ("matremap", "matremap" + (" (via --from-images)" if route == "standin" else ""))]
    if route == "blender" and not three.why and "--to-renderer" in help_text():
        bakes.append(("matremap-three", "matremap --to-renderer three"))

    # 2. matremap's remap (stand-in: the 64^2 source renders first).
    t = time.time()
    if route == "standin":
        render_jobs([{"output": os.path.join(WORK, n, "source64.exr"), "size": STANDIN_SIZE,
                      "samples": STANDIN_SAMPLES, "seed": 0, "rgb": True,
                      "material": {"blend": BLEND, "name": n}} for n in names],
                    os.path.join(WORK, "jobs-source.json"))
    times["source"] = time.time() - t
    baked = {n: {"exporter": {"values": exported[n]["values"], "gltf": exported[n]["gltf"]}} for n in names}
    t = time.time()
    for n in names:
        d = os.path.join(WORK, n)
        for key, _title in bakes[1:]:
            t1 = time.time()
            values, cmdline, res = remap_step(n, d, route, "three" if key == "matremap-three" else None)
            g = os.path.join(d, key + ".gltf")
            write_gltf_with(exported[n]["gltf"], g, values, n)
            baked[n][key] = {"values": values, "cmd": cmdline, "result": res, "seconds": time.time() - t1, "gltf": g}
    diagnostics = {}
    for n, args in DIAGNOSTIC_HOLDS.items():
        if n in names:
            values, cmdline, res = remap_step(n, os.path.join(WORK, n), route, None, args)
            diagnostics[n] = {"values": values, "cmd": cmdline, "result": res, "holds": args}
    times["remap"] = time.time() - t

    # 3. Cycles render-back at SIZE^2: the original (two seeds) and every bake through Blender's glTF importer.
    t = time.time()
    jobs = []
    for n in names:
        d = os.path.join(WORK, n)
        common = {"size": SIZE, "samples": SAMPLES}
        jobs += [dict(common, output=os.path.join(d, "original.exr"), seed=0, material={"blend": BLEND, "name": n}),
                 dict(common, output=os.path.join(d, "original-seed1.exr"), seed=1,
                      material={"blend": BLEND, "name": n})]
        jobs += [dict(common, output=os.path.join(d, key + "-cycles.exr"), seed=0,
                      material={"gltf": baked[n][key]["gltf"]}) for key, _title in bakes]
    render_jobs(jobs, os.path.join(WORK, "jobs-back.json"))
    times["cycles"] = time.time() - t
    times["cycles_renders"] = len(jobs)

    # three.js render-back of every bake's values, when the server is there.
    t = time.time()
    if not three.why:
        for n in names:
            d = os.path.join(WORK, n)
            for key, _title in bakes:
                vals = baked[n][key]["values"]
                v = {k: vals[k] for k in ("base_color", "metallic", "roughness", "specular", "specular_color", "ior")}
                px, _sec = three.render(v, os.path.join(d, key + "-three"), SIZE)
                write_pfm(os.path.join(d, key + "-three.pfm"), px[:, :, :3])
        for n in sorted(diagnostics):
            d = os.path.join(WORK, n)
            px, _sec = three.render(diagnostics[n]["values"], os.path.join(d, "diagnostic-three"), SIZE)
            write_pfm(os.path.join(d, "diagnostic-three.pfm"), px[:, :, :3])
        three.close()
    times["three"] = time.time() - t

    # 4. Metrics and pictures.
    rows = {}
    for n in names:
        d = os.path.join(WORK, n)
        orig, mask = os.path.join(d, "original.exr"), os.path.join(d, "coverage.exr")
        run(["oiiotool", orig, "--ch", "A", "-o", mask])
        r = {"noise": ssim(orig, os.path.join(d, "original-seed1.exr"), mask)}
        m0 = mean_rgb(orig)
        ratio = {}
        tiles = [(orig, "original (Cycles nodes)")]
        for key, title in bakes:
            r[key + "-cycles"] = ssim(orig, os.path.join(d, key + "-cycles.exr"), mask)
            ratio[key + "-cycles"] = [b / a if a > 0 else float("nan")
                                      for a, b in zip(m0, mean_rgb(os.path.join(d, key + "-cycles.exr")))]
            tiles.append((os.path.join(d, key + "-cycles.exr"), title.split(" (")[0] + ", Cycles"))
        if not three.why:
            for key, title in bakes:
                r[key + "-three"] = ssim(orig, os.path.join(d, key + "-three.pfm"), mask)
                ratio[key + "-three"] = [b / a if a > 0 else float("nan")
                                         for a, b in zip(m0, mean_rgb(os.path.join(d, key + "-three.pfm")))]
                tiles.append((os.path.join(d, key + "-three.pfm"), title.split(" (")[0] + ", three.js"))
        contact_sheet(tiles, os.path.join(IMAGES, n + ".png"))
        r["ratio"] = ratio
        rows[n] = r
        if n in diagnostics and not three.why:
            diagnostics[n]["three"] = ssim(orig, os.path.join(d, "diagnostic-three.pfm"), mask)
    times["total"] = time.time() - t0

    write_doc(names, exported, baked, bakes, rows, route, three, times, diagnostics)
    with open(os.path.join(WORK, "results.json"), "w") as f:
        json.dump({"route": route, "values": {n: {k: baked[n][k]["values"] for k, _ in bakes} for n in names},
                   "metrics": rows, "times": times}, f, indent=1)
    log("wrote %s and %d contact sheets in %s (%.0f s)" % (os.path.relpath(DOC, ROOT), len(names),
                                                            os.path.relpath(IMAGES, ROOT), times["total"]))


def blender_version():
    out = subprocess.run([BLENDER, "--version"], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True).stdout
    return out.splitlines()[0].strip() if out else "?"


def write_doc(names, exported, baked, bakes, rows, route, three, times, diagnostics):
    L = []
    L.append("# Node materials baked to glTF: Blender's exporter and matremap, rendered back")
    L.append("")
    L.append("Generated by `make evaluation-renderers` (scripts/evaluate-renderers.sh, scripts/evaluate_renderers.py);"
             " do not edit by hand.")
    L.append("")
    L.append("`%s` (made by `blender -b --factory-startup --python scripts/blender/make_node_materials.py -- -o %s`)"
             " holds uniform node materials that glTF metal-rough cannot state directly: Diffuse and Glossy BSDFs "
             "added or mixed, a Layer Weight-driven mix, a Fresnel-less tinted Glossy metal, a Principled BSDF whose "
             "base colour comes through a ColorRamp (the script's docstring lists every value), and a control, "
             "ControlPrincipled, a plain Principled BSDF the exporter does state (it checks the export, import and "
             "render path itself). Each is baked to glTF metal-rough:" % (BLEND_REL, BLEND_REL))
    L.append("")
    L.append("- **Blender exporter**: %s's bundled glTF exporter (io_scene_gltf2, `bpy.ops.export_scene.gltf`) "
             "on a UV sphere (scripts/blender/export_gltf.py); the values are what it wrote, with glTF 2.0's "
             "defaults for what it left out (base colour 1, metallic 1, roughness 1)." % blender_version())
    if route == "standin":
        L.append("- **matremap (via --from-images)**: the node material rendered by Cycles in the fit scene at %d² "
                 "(%d samples, scripts/blender/render_back.py) and fitted by `matremap remap --from-images FULL.exr "
                 "--to gltf --json`: a stand-in until `--from blender:FILE.blend:MATERIAL` is on this branch (the "
                 "script takes that route by itself once `matremap remap --help` mentions `blender:`)."
                 % (STANDIN_SIZE, STANDIN_SAMPLES))
    else:
        L.append("- **matremap**: `matremap remap --from blender:%s:NAME --to gltf --json` (the source rendered by "
                 "Blender through data/renderers/blender_server.py, the target by the built-in glTF model)."
                 % BLEND_REL)
        if any(k == "matremap-three" for k, _ in bakes):
            L.append("- **matremap --to-renderer three**: the same with the target rendered by three.js.")
    L.append("")
    L.append("Every bake is rendered back in the fit scene (unit sphere, point light of 10 W/sr at 45°, camera at "
             "(0, 0, 4), 35°; scripts/cycles_fit_scene.py's scene) at %d² beside the original node material: in "
             "Cycles (%d samples, seed 0) as Blender's glTF importer builds the material (a Principled BSDF, GGX, "
             "Specular 0.5), and in three.js (data/renderers/three/server.mjs, op render, model gltf) when that "
             "server is present. Object SSIM and relative RMSE are over the sphere's pixels against the original "
             "(`matremap ssim ORIGINAL X --mask COVERAGE --json`: object_ssim, object_relative_rmse; the RMSE is "
             "linear and dominated by the highlight's few pixels, the SSIM is on display values)." % (SIZE, SAMPLES))
    L.append("")
    if three.why:
        L.append("three.js render-back: **skipped** (%s)." % three.why)
    else:
        L.append("three.js render-back: three %s, %d samples (sub-pixel grid)." % (three.version, THREE_SAMPLES))
    L.append("")
    L.append("## What each bake wrote")
    L.append("")
    L.append("| material | what Blender's exporter wrote | %s |" % " | ".join(title for _k, title in bakes))
    L.append("|---|---|%s" % ("---|" * len(bakes)))
    for n in names:
        cells = [fmt_vals(baked[n]["exporter"]["values"])]
        for key, _title in bakes[1:]:
            res = baked[n][key]["result"]
            cells.append("%s (%s, fit's relative RMSE %.3f, %.2f s)" % (
                fmt_vals(baked[n][key]["values"]), res.get("outcome", "?"), res.get("relative_rmse", float("nan")),
                baked[n][key]["seconds"]))
        L.append("| %s | %s | %s |" % (n, written_desc(exported[n]["written"]), " | ".join(cells)))
    L.append("")
    L.append("## Rendered back against the original (object SSIM / relative RMSE)")
    L.append("")
    cols = [("noise", "Cycles noise floor (seed 0 vs 1)")] + [(k + "-cycles", t + ", Cycles") for k, t in bakes]
    if not three.why:
        cols += [(k + "-three", t + ", three.js") for k, t in bakes]
    L.append("| material | %s |" % " | ".join(t for _k, t in cols))
    L.append("|---|%s" % ("---|" * len(cols)))
    for n in names:
        L.append("| %s | %s |" % (n, " | ".join("%.4f / %.3f" % rows[n][k] for k, _t in cols)))
    L.append("")
    L.append("The noise floor compares two Cycles renders of the original with seeds 0 and 1 at %d samples: "
             "differences of that size are Monte Carlo noise." % SAMPLES)
    L.append("")
    L.append("The SSIM sees luma only. Colour: each bake's total radiance per channel over the original's "
             "(R, G, B; 1 = the same; a wrong hue shows as unequal ratios):")
    L.append("")
    L.append("| material | %s |" % " | ".join(t for _k, t in cols[1:]))
    L.append("|---|%s" % ("---|" * (len(cols) - 1)))
    for n in names:
        L.append("| %s | %s |" % (n, " | ".join("%.2f, %.2f, %.2f" % tuple(rows[n]["ratio"][k]) for k, _t in cols[1:])))
    L.append("")
    if diagnostics:
        L.append("Where the source's specular is a Fresnel-less lobe stronger than glTF's 4 %% dielectric "
                 "reflectance, the default fit (KHR_materials_specular's specular_color held at 1) buys the missing "
                 "reflection with metallic, which tints it with the base colour: the unequal ratios above. Freeing "
                 "KHR_materials_specular's colour factor (`--free specular_color`, metallic held at 0) lets the fit "
                 "find the lobe's reflectance / 0.04 itself (7.5 and 2 expected; engines without the extension show "
                 "the core values only; not rendered back in Cycles here%s):" % (
                     "" if three.why else ", rendered back in three.js"))
        L.append("")
        L.append("| material | options | values | fit's relative RMSE (default hold) |%s" % (
            "" if three.why else " three.js object SSIM / relative RMSE (default hold) |"))
        L.append("|---|---|---|---|%s" % ("" if three.why else "---|"))
        for n in sorted(diagnostics):
            g = diagnostics[n]
            extra = ""
            if not three.why:
                extra = " %.4f / %.3f (%.4f / %.3f) |" % (g["three"] + rows[n]["matremap-three"])
            L.append("| %s | `%s` | %s | %.4f (%.4f) |%s" % (
                n, " ".join(g["holds"]), fmt_vals(g["values"]), g["result"].get("relative_rmse", float("nan")),
                baked[n]["matremap"]["result"].get("relative_rmse", float("nan")), extra))
        L.append("")
    L.append("## Pictures")
    L.append("")
    L.append("Each sheet (sRGB, exposure 1): the original node material in Cycles, then every bake's glTF through "
             "Blender's glTF importer into Cycles%s." % ("" if three.why else ", then every bake in three.js"))
    L.append("")
    for n in names:
        L.append("**%s**" % n)
        L.append("")
        L.append("![%s](images/renderers/%s.png)" % (n, n))
        L.append("")
    L.append("## Commands and cost")
    L.append("")
    L.append("```sh")
    L.append("make evaluation-renderers   # = scripts/evaluate-renderers.sh build")
    rel = os.path.relpath(WORK, ROOT)
    for n in names:
        for key, _title in bakes[1:]:
            L.append(baked[n][key]["cmd"].replace(rel, "build/evaluation-renderers"))
    for n in sorted(diagnostics):
        L.append(diagnostics[n]["cmd"].replace(rel, "build/evaluation-renderers"))
    L.append("```")
    L.append("")
    L.append("Wall time on this machine (%d Cycles threads): Blender's exporter %.1f s, stand-in source renders "
             "%.1f s, remaps %.1f s, Cycles render-back %.1f s (%d renders at %d², %d samples, one Blender), "
             "three.js %.1f s, total %.1f s." % (
                 THREADS, times["export"], times["source"], times["remap"], times["cycles"], times["cycles_renders"],
                 SIZE, SAMPLES, times["three"], times["total"]))
    L.append("")
    with open(DOC + ".tmp", "w") as f:
        f.write("\n".join(L))
    os.replace(DOC + ".tmp", DOC)


if __name__ == "__main__":
    main()
