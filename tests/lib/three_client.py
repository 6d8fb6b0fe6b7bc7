"""A small client of matremap's three.js renderer server (data/renderers/three/server.mjs; protocol in
docs/renderers.md) for tests/three_server.sh, and the comparison with `matremap render` that docs/renderers.md
reports. Run with /usr/bin/python3 (numpy).

  three_client.py compare MATREMAP WORK SIZE SAMPLES MODEL name=v[,v,v] ...
      renders MODEL in the fit scene with the server and with `matremap render`, prints
      "rel_rmse R max_alpha_diff A lit N" (relative RMSE over the pixels either covers).
  three_client.py bench SIZE [REPEATS]
      seconds to the ready line, then per request (median over REPEATS after a first) for s = 1, 4, 8.
  three_client.py session MATREMAP WORK
      tests/three_server.sh's checks, one "ok    NAME" or "FAIL  NAME" line each.
"""
import json
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
SERVER = os.path.join(HERE, "..", "..", "data", "renderers", "three", "server.mjs")

# matremap's fit scene (matremap render --help): unit sphere at the origin, camera at distance 4 with a 35-degree
# field of view, a 10 W/sr point light at distance 3, 45 degrees from the view direction.
FIT_SCENE = {
    "camera": {"position": [0, 0, 4], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 35.0},
    "sphere": {"center": [0, 0, 0], "radius": 1.0},
    "lights": [{"position": [3 * 0.5 ** 0.5, 0, 3 * 0.5 ** 0.5], "intensity": [10, 10, 10]}],
}


class Server:
    """The server as a child process: request() sends one JSON line and returns the '@matremap' answer lines."""

    def __init__(self, stderr=None):
        self.proc = subprocess.Popen([os.environ.get("MATREMAP_NODE", "node"), SERVER], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=stderr, text=True, bufsize=1)
        self.ready = self.answer()

    def answer(self):
        while True:
            line = self.proc.stdout.readline()
            if not line:
                raise RuntimeError("the server closed its stdout")
            if line.startswith("@matremap "):
                return line.rstrip("\n")

    def send(self, text):
        self.proc.stdin.write(text + "\n")
        self.proc.stdin.flush()
        return self.answer()

    def request(self, **fields):
        return self.send(json.dumps(fields))

    def close(self, timeout=30):
        self.proc.stdin.close()
        return self.proc.wait(timeout)


def render_request(rid, size, samples, model, values, output, components=("full",)):
    return dict(op="render", id=rid, size=size, samples=samples, seed=0, threads=1, **FIT_SCENE,
                material={"model": model, "values": values}, components=list(components), output=output)


def read_f32(path, size):
    """An answer's RGBA image, top row first: (size, size, 4)."""
    return np.fromfile(path, dtype="<f4").reshape(size, size, 4)


def read_exr(path, channels):
    """An image through `oiiotool --dumpdata` (no EXR reader in numpy): (height, width, channels), top row first."""
    text = subprocess.run(["oiiotool", "--dumpdata", path], check=True, capture_output=True, text=True).stdout
    rows = [line.split(":", 1) for line in text.splitlines() if line.strip().startswith("Pixel (")]
    coords = [tuple(int(v) for v in key.strip()[7:-1].split(",")) for key, _ in rows]
    width, height = max(c[0] for c in coords) + 1, max(c[1] for c in coords) + 1
    image = np.zeros((height, width, channels))
    for (x, y), (_, vals) in zip(coords, rows):
        image[y, x] = [float(v) for v in vals.split()[:channels]]
    return image


def matremap_render(matremap, work, size, edge_samples, model, params, name):
    out, mask = os.path.join(work, name + ".exr"), os.path.join(work, name + "_mask.exr")
    subprocess.run([matremap, "render", model, *params, "--size", str(size), "--edge-samples", str(edge_samples),
                    "-o", out, "--mask", mask], check=True, capture_output=True)
    return read_exr(out, 3), read_exr(mask, 1)[:, :, 0]


def parse_values(params):
    values = {}
    for p in params:
        name, v = p.split("=", 1)
        nums = [float(x) for x in v.split(",")]
        values[name] = nums[0] if len(nums) == 1 else nums
    return values


def compare(three_rgba, ref_rgb, ref_alpha):
    """Relative RMSE of RGB over the pixels either covers, and the largest |alpha - coverage|."""
    covered = (three_rgba[:, :, 3] > 0) | (ref_alpha > 0)
    diff = three_rgba[:, :, :3][covered] - ref_rgb[covered]
    rel = np.sqrt(np.mean(diff ** 2)) / np.sqrt(np.mean(ref_rgb[covered] ** 2))
    return rel, float(np.max(np.abs(three_rgba[:, :, 3] - ref_alpha))), int(covered.sum())


# Tolerances of the session, measured (docs/renderers.md): lambert at 64^2 with 4 x 4 sub-pixels differs from
# `matremap render --edge-samples 4` by a relative RMSE of 0.0018 (interior pixels average 16 sub-pixel positions
# where matremap shades the centre; the tessellated silhouette), and its alpha from matremap's coverage by at most
# one sub-pixel of 16 (0.0625); a smooth-enough dielectric gltf (roughness 0.5) by 0.0031.
LAMBERT_REL_RMSE = 0.005
GLTF_DIELECTRIC_REL_RMSE = 0.01


def session(matremap, work):
    results = []

    def check(name, ok):
        results.append(ok)
        print(f"{'ok   ' if ok else 'FAIL '} {name}", flush=True)

    log = open(os.path.join(work, "server.log"), "w")
    server = Server(stderr=log)
    check(f"ready line: {server.ready}", server.ready.startswith("@matremap ready three 0.187.0 ")
          and set(server.ready.split()[4:]) == {"components=full", "models=gltf,lambert"})

    # lambert against matremap's renderer, and alpha against its coverage mask (the same 4 x 4 sub-pixels).
    lam = render_request(1, 64, 16, "lambert", {"albedo": [0.8, 0.2, 0.1]}, os.path.join(work, "lambert"))
    answer = server.request(**lam)
    check(f"lambert render answered: {answer}", answer.startswith("@matremap ok 1 "))
    three = read_f32(os.path.join(work, "lambert.full.f32"), 64)
    ref, cover = matremap_render(matremap, work, 64, 4, "lambert", ["albedo=0.8,0.2,0.1"], "lambert_ref")
    rel, dalpha, _ = compare(three, ref, cover)
    check(f"lambert matches matremap render (relative RMSE {rel:.4f} < {LAMBERT_REL_RMSE})", rel < LAMBERT_REL_RMSE)
    alpha = three[:, :, 3]
    check(f"alpha is matremap's coverage within one sub-pixel of 16 (max difference {dalpha:.4f})",
          dalpha <= 1 / 16 + 1e-6)
    check("alpha is k/16: 1 inside, 0 in the corners, partial only on the silhouette",
          np.allclose(alpha * 16, np.round(alpha * 16), atol=1e-5) and alpha[32, 32] == 1 and alpha[0, 0] == 0
          and 0 < np.count_nonzero((alpha > 0) & (alpha < 1)) < 400)
    check("RGB is zero where alpha is", bool(np.all(three[:, :, :3][alpha == 0] == 0)))

    # gltf: deterministic (the same request twice, another in between), and close to matremap for a dielectric.
    values = {"base_color": [0.8, 0.2, 0.1], "metallic": 0, "roughness": 0.5}
    outs = []
    for rid, v in ((2, values), (3, dict(values, metallic=1, roughness=0.2)), (4, values)):
        out = os.path.join(work, f"gltf{rid}")
        answer = server.request(**render_request(rid, 64, 16, "gltf", v, out))
        check(f"gltf render {rid} answered: {answer}", answer.startswith(f"@matremap ok {rid} "))
        outs.append(open(out + ".full.f32", "rb").read())
    check("gltf: the same request twice gives the same bytes", outs[0] == outs[2] and outs[0] != outs[1])
    ref, cover = matremap_render(matremap, work, 64, 4, "gltf", ["base_color=0.8,0.2,0.1", "metallic=0",
                                                                  "roughness=0.5"], "gltf_ref")
    rel, _, _ = compare(read_f32(os.path.join(work, "gltf2.full.f32"), 64), ref, cover)
    check(f"gltf dielectric (roughness 0.5) near matremap's gltf (relative RMSE {rel:.4f} < "
          f"{GLTF_DIELECTRIC_REL_RMSE})", rel < GLTF_DIELECTRIC_REL_RMSE)

    # Errors: one line naming the value, and the server keeps serving.
    def request_text(rid, **changes):
        r = render_request(rid, 16, 1, "gltf", {}, os.path.join(work, f"e{rid}"))
        r.update(changes)
        return json.dumps(r)

    errors = [
        (request_text(10, material={"model": "phong", "values": {}}),
         '@matremap error 10 unknown model "phong" (three renders: gltf, lambert)'),
        (request_text(11, material={"model": "gltf", "values": {"shine": 1}}),
         "@matremap error 11 model gltf has no parameter 'shine' (it has: base_color, metallic, roughness, "
         "specular, specular_color, ior)"),
        (request_text(12, material={"model": "gltf", "values": {"base_color": [0.1, 0.2]}}),
         "@matremap error 12 gltf base_color takes 1 or 3 values, not 2"),
        (request_text(13, material={"model": "gltf", "values": {"metallic": [0, 1, 0]}}),
         "@matremap error 13 gltf metallic takes 1 value, not 3"),
        (request_text(14, lights=[{"position": ["X", 0, 3], "intensity": 10}]).replace('"X"', "1e999"),
         "@matremap error 14 lights[0].position must be 3 finite numbers, not [Infinity,0,3]"),
        (request_text(21, material={"model": "gltf", "values": {"roughness": "X"}}).replace('"X"', "-1e999"),
         "@matremap error 21 gltf roughness must be a finite number, not -Infinity"),
        (request_text(15, material={"model": "gltf", "values": {"roughness": "0.5"}}),
         '@matremap error 15 gltf roughness must be a finite number, not "0.5"'),
        (request_text(16, components=["full", "diffuse"]),
         '@matremap error 16 component "diffuse" is not supported by three (components=full)'),
        (request_text(17, material={"model": "gltf", "values": {"roughness": 2}}),
         "@matremap error 17 gltf roughness 2 is outside [0.01, 1]"),
        (request_text(22, camera={"position": [0, 0, 4], "target": [0, 0, 0], "up": [0, 0, 1], "fov_y": 35}),
         "@matremap error 22 camera: position equals target, or up is parallel to the view direction"),
        ('{"op": "render", "id": 18, "size": ', None),
        (json.dumps({"op": "describe", "id": 19}), '@matremap error 19 unknown op "describe" (three answers: '
                                                    'render, quit)'),
    ]
    for text, expected in errors:
        answer = server.send(text)
        if expected is None:
            ok = answer.startswith("@matremap error -1 malformed JSON request: ")
        else:
            ok = answer == expected
        check(f"error answered: {answer}", ok)
    wrote = [f for f in os.listdir(work) if f.startswith("e")]
    check("no output written for a refused request", wrote == [])
    answer = server.request(**render_request(20, 16, 1, "lambert", {}, os.path.join(work, "after")))
    check(f"still serving after the errors: {answer}", answer.startswith("@matremap ok 20 "))
    code = server.close()
    check(f"stdin at EOF: exit {code}", code == 0)
    server = Server(stderr=log)
    server.proc.stdin.write('{"op": "quit"}\n')
    server.proc.stdin.flush()
    code = server.proc.wait(30)
    check(f'{{"op": "quit"}}: exit {code}', code == 0)
    return all(results)


def bench(size, repeats, work):
    import statistics
    import time
    t0 = time.time()
    server = Server(stderr=subprocess.DEVNULL)
    print(f"ready in {time.time() - t0:.2f} s")
    rid = 0
    for samples in (1, 16, 64):
        for model, values in (("gltf", {"base_color": [0.8, 0.2, 0.1], "metallic": 0}), ("lambert", {})):
            walls = []
            for k in range(repeats + 1):
                rid += 1
                if model == "gltf":
                    values["roughness"] = 0.3 + 0.05 * k
                t = time.time()
                answer = server.request(**render_request(rid, size, samples, model, values, os.path.join(work, "b")))
                walls.append(time.time() - t)
                if not answer.startswith("@matremap ok"):
                    sys.exit(answer)
            print(f"{size}^2 s={min(8, int(samples ** 0.5))} {model}: first {walls[0]:.4f} s, "
                  f"then median {statistics.median(walls[1:]):.4f} s")
    server.close()


def main(argv):
    if argv[:1] == ["bench"]:
        import tempfile
        with tempfile.TemporaryDirectory() as work:
            return bench(int(argv[1]), int(argv[2]) if len(argv) > 2 else 10, work)
    if argv[:1] == ["session"]:
        sys.exit(0 if session(argv[1], argv[2]) else 1)
    if argv[:1] != ["compare"]:
        sys.exit(__doc__)
    matremap, work, size, samples, model, params = argv[1], argv[2], int(argv[3]), int(argv[4]), argv[5], argv[6:]
    server = Server()
    answer = server.request(**render_request(1, size, samples, model, parse_values(params),
                                             os.path.join(work, "three")))
    server.close()
    if not answer.startswith("@matremap ok 1 "):
        sys.exit(answer)
    ss = min(8, max(1, int(samples ** 0.5)))
    ref, alpha = matremap_render(matremap, work, size, ss, model, params, "matremap")
    rel, dalpha, lit = compare(read_f32(os.path.join(work, "three.full.f32"), size), ref, alpha)
    print(f"rel_rmse {rel:.5f} max_alpha_diff {dalpha:.4f} lit {lit} seconds {answer.split()[3]}")


if __name__ == "__main__":
    main(sys.argv[1:])
