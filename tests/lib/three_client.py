"""A small client of matremap's three.js renderer server (data/renderers/three/server.mjs; protocol in
docs/renderers.md) for tests/three_server.sh, and the comparison with `matremap render` that docs/renderers.md
reports. Run with /usr/bin/python3 (numpy).

  three_client.py compare MATREMAP WORK SIZE SAMPLES MODEL name=v[,v,v] ...
      renders MODEL in the fit scene with the server and with `matremap render`, prints
      "rel_rmse R max_alpha_diff A lit N" (relative RMSE over the pixels both cover fully or partly).
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


def main(argv):
    if argv[0] != "compare":
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
