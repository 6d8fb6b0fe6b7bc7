"""The checks of tests/blender_server.sh: drives data/renderers/blender_server.py through one session and prints
"ok    NAME" or "FAIL  NAME: why" per check (the shell test counts them).
Usage: blender_server_check.py MATREMAP BLENDER SERVER_SCRIPT TMPDIR TINY_BLEND"""

import json
import os
import re
import subprocess
import sys

import numpy as np

sys.dont_write_bytecode = True   # no __pycache__ beside the sources (or in an installed tree)
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from renderer_client import RendererServer, fit_scene_request, read_rgba, sphere_coverage, write_pfm  # noqa: E402

matremap, blender, script, tmp, blend = sys.argv[1:6]
SIZE = 64
# Tolerances against matremap's built-in renderer at 64^2, 64 spp, seed 0. Measured: object SSIM 0.9995 (full,
# diffuse), 0.99998 (specular); relative RMSE 0.013 / 0.014 / 0.017 (cycles-principled), 0.0096 (lambert): Cycles'
# 64 random samples per pixel against the built-in renderer's pixel centres and 4x4 silhouette rays.
MIN_SSIM = 0.998
MAX_REL_RMSE = 0.03
results = []
full = lam = None


def check(name, ok, why=""):
    results.append(bool(ok))
    print("ok    %s" % name if ok else "FAIL  %s: %s" % (name, why), flush=True)


def scene(**kw):
    return fit_scene_request(size=SIZE, **kw)


out_dir = os.path.join(tmp, "renders")
os.mkdir(out_dir)
COMMAND = [blender, "-b", "--factory-startup", "--python-exit-code", "3", "--python", script, "--"]
server = RendererServer(COMMAND, os.path.join(tmp, "server.log"))
check("ready line names blender, its version and the caps",
      re.fullmatch(r"ready blender \d+\.\d+\.\d+ components=full,diffuse,specular "
                   r"models=cycles-principled,lambert materials=blend", server.ready), server.ready)
next_id = [0]


def render(name, expect_files=True, **kw):
    """Renders; returns the output prefix, or None (a FAIL printed) when the server did not answer ok."""
    next_id[0] += 1
    rid = next_id[0]
    prefix = os.path.join(out_dir, "r%d" % rid)
    req = scene(id=rid, output=prefix, **kw)
    before = set(os.listdir(out_dir))
    _, final = server.request(req)
    if not re.fullmatch(r"ok %d \d+\.\d+" % rid, final):
        check(name, False, "answered: %s" % final)
        return None
    new = set(os.listdir(out_dir)) - before
    want = {"r%d.%s.f32" % (rid, c) for c in req["components"]}
    if new != want:
        check(name, False, "wrote %s, expected %s" % (sorted(new), sorted(want)))
        return None
    return prefix


def builtin(model, values, component, tag):
    """matremap render of the same material (linear EXR) and its coverage mask."""
    path = os.path.join(tmp, "%s.%s.exr" % (tag, component))
    mask = os.path.join(tmp, "mask.exr")
    subprocess.run([matremap, "render", model] + values + ["--size", str(SIZE), "--component", component,
                                                           "-o", path, "--mask", mask],
                   check=True, stderr=subprocess.DEVNULL)
    return path, mask


def compare(prefix, comp, ref, mask):
    pfm = "%s.%s.pfm" % (prefix, comp)
    write_pfm(pfm, read_rgba(prefix, comp, SIZE)[:, :, :3])
    res = subprocess.run([matremap, "ssim", ref, pfm, "--mask", mask, "--json"], check=True,
                         capture_output=True, text=True)
    os.remove(pfm)
    return json.loads(res.stdout)


def against_builtin(prefix, model, values, tag):
    for comp in ("full", "diffuse", "specular"):
        ref, mask = builtin(model, values, comp, tag)
        m = compare(prefix, comp, ref, mask)
        print("      %s %s: object SSIM %.5f, relative RMSE %.4f" % (tag, comp, m["object_ssim"],
                                                                   m["object_relative_rmse"]))
        if model == "lambert" and comp == "specular":
            check("%s specular is black" % tag, np.abs(read_rgba(prefix, comp, SIZE)[:, :, :3]).max() == 0.0)
            continue
        check("%s %s matches matremap render (object SSIM >= %g, relative RMSE <= %g)"
              % (tag, comp, MIN_SSIM, MAX_REL_RMSE),
              m["object_ssim"] >= MIN_SSIM and m["object_relative_rmse"] <= MAX_REL_RMSE, m)


# -- the fit scene by values, against the built-in renderer
p = render("cycles-principled render")
if p:
    full, diff, spec = (read_rgba(p, c, SIZE) for c in ("full", "diffuse", "specular"))
    against_builtin(p, "cycles-principled", ["base_color=0.8,0.2,0.1", "metallic=0", "specular=0.5",
                                             "specular_tint=0", "roughness=0.4"], "cycles-principled")
    err = np.abs(full[:, :, :3] - diff[:, :, :3] - spec[:, :, :3]).max() / full[:, :, :3].max()
    check("full = diffuse + specular (max error %.2g of the peak)" % err, err < 1e-5, err)
    cov = sphere_coverage(SIZE, [0, 0, 4], [0, 0, 0], [0, 1, 0], 35.0, [0, 0, 0], 1.0)
    a = full[:, :, 3]
    edge = (cov > 0) & (cov < 1)
    # Pixels whose 3x3 neighbourhood is wholly inside (outside) the sphere: 8x8 rays can miss a sliver.
    pad = np.pad(cov, 1, mode="edge")
    near = np.stack([pad[i:i + SIZE, j:j + SIZE] for i in range(3) for j in range(3)])
    check("alpha is 1 inside the sphere, 0 outside, in every component",
          (a[near.min(axis=0) == 1] == 1).all() and (a[near.max(axis=0) == 0] == 0).all()
          and all((c[:, :, 3] == a).all() for c in (diff, spec)), "alpha off")
    check("alpha on the silhouette is its coverage (mean error %.3f, total %.4f vs %.4f)"
          % (np.abs(a - cov)[edge].mean(), a.sum(), cov.sum()),
          np.abs(a - cov)[edge].mean() < 0.06 and abs(a.sum() - cov.sum()) < 0.002 * cov.sum())
    right, left = full[:, SIZE // 2:, 0].sum(), full[:, :SIZE // 2, 0].sum()
    check("the 45-degree light (+x) lights the image's right", right > 3 * left, (right, left))

p = render("lambert render", material={"model": "lambert", "values": {"albedo": [0.5, 0.5, 0.5]}})
if p:
    against_builtin(p, "lambert", ["albedo=0.5"], "lambert")
    lam = read_rgba(p, "full", SIZE)

# -- orientation, framing and light colour
p = render("light above", lights=[{"position": [0, 3, 0], "intensity": [10, 10, 10]}], components=["full"])
if p:
    img = read_rgba(p, "full", SIZE)[:, :, 0]
    check("rows run from the top (a light at +y lights the first rows)",
          img[:SIZE // 2].sum() > 10 * img[SIZE // 2:].sum(), (img[:SIZE // 2].sum(), img[SIZE // 2:].sum()))
c = np.array([1.0, 2.0, 3.0])
p = render("moved scene", components=["full"], sphere={"center": c.tolist(), "radius": 2.0},
           camera={"position": (c + [8, 0, 0]).tolist(), "target": c.tolist(), "up": [0, 1, 0], "fov_y": 35.0},
           lights=[{"position": (c + [4.242640687119285, 0, -4.242640687119285]).tolist(),
                    "intensity": [40, 40, 40]}])
if p and full is not None:
    moved = read_rgba(p, "full", SIZE)
    rel = np.sqrt(np.mean((moved - full) ** 2)) / full[:, :, :3][full[:, :, 3] > 0].mean()
    check("the fit scene turned, moved and scaled renders the same image (relative RMSE %.4f)" % rel, rel < 0.02)
p = render("coloured lights", material={"model": "lambert", "values": {"albedo": 0.5}}, components=["full"],
           lights=[{"position": [2.1213203435596424, 0, 2.1213203435596424], "intensity": [8, 4, 2]},
                   {"position": [-3, 0, 0], "intensity": [0, 0, 1]}])
if p and lam is not None:
    img = read_rgba(p, "full", SIZE)
    lit = (lam[:, :, 0] > 0.05 * lam[:, :, 0].max()) & (img[:, :, 2] > 0) & (lam[:, :, 3] == 1)
    r = img[:, :, 0][lit] / lam[:, :, 0][lit]
    check("intensity (8,4,2) is Power 4 pi 8 W of colour (1,0.5,0.25) (red %.4f of 10 W/sr's)" % r.mean(),
          abs(r.mean() - 0.8) < 0.004 and np.allclose(img[:, :, 1][lit], img[:, :, 0][lit] / 2, rtol=1e-3))
    check("a second light adds where the first does not reach", img[:, :SIZE // 4, 2].sum() > 0)

# -- a .blend material
ids = iter(range(100, 200))


def ask(req):
    req.setdefault("id", next(ids))
    others, final = server.request(req)
    return req["id"], others, final


rid, params, final = ask({"op": "describe", "material": {"blend": blend, "name": "TinyMat"}})
want = ["param %d color 0 1 0.6 0.3 0.2 Diffuse BSDF.Color" % rid,
        "param %d float 0 1 0 Diffuse BSDF.Roughness" % rid,
        "param %d color 0 1 0.5 0.5 0.5 Glossy BSDF.Color" % rid,
        "param %d float 0 1 0.3 Glossy BSDF.Roughness" % rid]
check("describe lists the .blend material's inputs with the file's values", params == want and
      re.fullmatch(r"ok %d \d+\.\d+" % rid, final), (params, final))
tiny = {"blend": blend, "name": "TinyMat"}
b1 = render(".blend material renders", material=tiny)
b2 = render(".blend material with an input override", material=dict(tiny, inputs={"Glossy BSDF.Color": [0, 0, 0]}))
b3 = render(".blend material again without overrides", material=tiny)
if b1 and b2 and b3 and lam is not None:
    f1, d1, s1 = (read_rgba(b1, c, SIZE) for c in ("full", "diffuse", "specular"))
    check(".blend render: diffuse and specular both lit, full = their sum",
          d1[:, :, :3].max() > 0 and s1[:, :, :3].max() > 0
          and np.abs(f1[:, :, :3] - d1[:, :, :3] - s1[:, :, :3]).max() < 1e-5 * f1.max())
    # Its Diffuse BSDF (roughness 0, colour 0.6,0.3,0.2) is Lambert: the lambert render of albedo 0.5, scaled.
    lit = lam[:, :, 0] > 0.05 * lam[:, :, 0].max()
    ratio = d1[:, :, :3][lit] / lam[:, :, :3][lit]
    check(".blend Diffuse BSDF = the lambert model's render x colour/0.5 (ratios %s)"
          % np.round(ratio.mean(axis=0), 4), np.allclose(ratio.mean(axis=0), [1.2, 0.6, 0.4], rtol=2e-3))
    s2 = read_rgba(b2, "specular", SIZE)
    check("the override Glossy BSDF.Color = 0 removes the specular", s2[:, :, :3].max() == 0.0)
    check("the file's values come back when a request does not override them",
          np.array_equal(read_rgba(b3, "full", SIZE), f1))

# -- errors: one line naming the value or file; the server keeps serving and writes nothing
missing = os.path.join(tmp, "missing.blend")
errors = [
    ("malformed JSON", "{not json", r"error -1 malformed JSON request .*"),
    ("missing .blend file", {"op": "describe", "material": {"blend": missing, "name": "TinyMat"}},
     r"error \d+ no such \.blend file '%s'" % re.escape(missing)),
    ("unknown material", {"op": "describe", "material": {"blend": blend, "name": "Nope"}},
     r"error \d+ no material 'Nope' in '%s' \(it has: (?=.*NoOutput)(?=.*TinyMat).*\)" % re.escape(blend)),
    ("material without nodes", {"op": "describe", "material": {"blend": blend, "name": "Other"}},
     r"error \d+ material 'Other' in '%s' does not use nodes" % re.escape(blend)),
    ("material without an output", {"op": "describe", "material": {"blend": blend, "name": "NoOutput"}},
     r"error \d+ material 'NoOutput' in '%s' has no Material Output node" % re.escape(blend)),
    ("unknown input path", scene(material=dict(tiny, inputs={"Glossy BSDF.Colour": [1, 1, 1]})),
     r"error \d+ no input 'Glossy BSDF\.Colour' in material 'TinyMat' in '%s' \(its inputs: Diffuse BSDF\.Color, "
     r"Diffuse BSDF\.Roughness, Glossy BSDF\.Color, Glossy BSDF\.Roughness\)" % re.escape(blend)),
    ("wrong value count (.blend input)", scene(material=dict(tiny, inputs={"Glossy BSDF.Color": [1, 1]})),
     r"error \d+ 'Glossy BSDF\.Color' takes 3 values, got 2"),
    ("wrong value count (model)", scene(material={"model": "lambert", "values": {"albedo": [1, 1]}}),
     r"error \d+ 'albedo' takes 3 values, got 2"),
    ("non-finite value", '{"op": "render", "id": 150, "size": 64, "samples": 4, "camera": {"position": [0,0,4], '
     '"target": [0,0,0], "up": [0,1,0], "fov_y": 35}, "sphere": {"center": [0,0,0], "radius": 1}, "lights": [], '
     '"material": {"model": "cycles-principled", "values": {"roughness": NaN}}, "components": ["full"], '
     '"output": "%s"}' % os.path.join(out_dir, "nan"), r"error 150 'roughness' must be finite, got nan"),
    ("non-finite .blend input", scene(material=dict(tiny, inputs={"Glossy BSDF.Roughness": [1e999]})),
     r"error \d+ 'Glossy BSDF\.Roughness\[0\]' must be finite, got inf"),
    ("unknown model", scene(material={"model": "phong", "values": {}}),
     r'error \d+ unknown model "phong" \(this server renders: cycles-principled, lambert\)'),
    ("unknown parameter", scene(material={"model": "cycles-principled", "values": {"albedo": 0.5}}),
     r"error \d+ model cycles-principled has no parameter 'albedo' \(its parameters: base_color, metallic, "
     r"specular, specular_tint, roughness\)"),
    ("component not supported", scene(components=["full", "transmission"]),
     r'error \d+ component "transmission" is not supported \(this server returns: full, diffuse, specular\)'),
    ("output folder missing", scene(output=os.path.join(tmp, "nowhere", "r")),
     r"error \d+ the folder of 'output' does not exist: '%s'" % re.escape(os.path.join(tmp, "nowhere"))),
    ("unknown op", {"op": "paint"}, r'error \d+ unknown op "paint" \(expected render, describe or quit\)'),
]
for name, req, pattern in errors:
    before = sorted(os.listdir(out_dir))
    if isinstance(req, dict):
        req["id"] = next(ids)
        if req["op"] == "render":
            req.setdefault("output", os.path.join(out_dir, "e%d" % req["id"]))
    _, final = server.request(req)
    check("error: %s" % name, re.fullmatch(pattern, final) and sorted(os.listdir(out_dir)) == before, final)
p = render("a render after the errors")
if p and full is not None:
    check("... is the first render again (fixed seed)", np.array_equal(read_rgba(p, "full", SIZE), full))
status = server.close()
check("EOF on stdin: the server exits with status 0", status == 0, status)
quitter = RendererServer(COMMAND, os.path.join(tmp, "quit.log"))
quitter.proc.stdin.write(b'{"op": "quit"}\n')
quitter.proc.stdin.flush()
try:
    status = quitter.proc.wait(30)
except subprocess.TimeoutExpired:
    quitter.proc.kill()
    status = None
check('{"op": "quit"}: the server exits with status 0', status == 0, status)
check("nothing but the outputs was written (no temporary EXR left)",
      all(re.fullmatch(r"r\d+\.(full|diffuse|specular)\.f32", f) for f in os.listdir(out_dir)),
      sorted(os.listdir(out_dir)))
print("      ready after %.2f s" % server.ready_seconds)
print("checks: %d passed, %d failed" % (sum(results), len(results) - sum(results)))
