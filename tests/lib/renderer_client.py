"""A small client of matremap's renderer-server protocol (v1) for tests: starts a server, waits for its ready line,
sends JSON requests and collects the "@matremap" lines about each; reads the raw RGBA float32 images it writes.
Not run by itself (tests/lib/ is outside run-tests.sh's glob); tests import it with sys.path."""

import json
import os
import select
import subprocess
import time

import numpy as np

PREFIX = "@matremap "


def fit_scene_request(**fields):
    """An op-render request of matremap's fit scene (camera at (0, 0, 4), 35 degrees; unit sphere; 10 W/sr at 45
    degrees; a cycles-principled material; every component), 64^2 at 64 spp, one thread; `fields` replace any."""
    req = {"op": "render", "id": 0, "size": 64, "samples": 64, "seed": 0, "threads": 1,
           "camera": {"position": [0, 0, 4], "target": [0, 0, 0], "up": [0, 1, 0], "fov_y": 35.0},
           "sphere": {"center": [0, 0, 0], "radius": 1.0},
           "lights": [{"position": [2.1213203435596424, 0, 2.1213203435596424], "intensity": [10, 10, 10]}],
           "material": {"model": "cycles-principled",
                        "values": {"base_color": [0.8, 0.2, 0.1], "metallic": 0, "specular": 0.5,
                                   "specular_tint": 0, "roughness": 0.4}},
           "components": ["full", "diffuse", "specular"]}
    req.update(fields)
    return req


class ServerError(Exception):
    pass


class RendererServer:
    def __init__(self, argv, log_path, timeout=120.0):
        self.log = open(log_path, "wb")
        self.proc = subprocess.Popen(argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self.log,
                                     bufsize=0)
        self.buffer = b""
        self.started = time.monotonic()
        line = self.next_line(timeout)
        if not line.startswith("ready "):
            raise ServerError("expected the ready line, got: %s" % line)
        self.ready = line
        self.ready_seconds = time.monotonic() - self.started

    def next_line(self, timeout):
        """The next protocol line (without its prefix); other stdout lines are skipped, as the library does."""
        deadline = time.monotonic() + timeout
        while True:
            while b"\n" in self.buffer:
                raw, self.buffer = self.buffer.split(b"\n", 1)
                text = raw.decode("utf-8", "replace")
                if text.startswith(PREFIX):
                    return text[len(PREFIX):]
            left = deadline - time.monotonic()
            if left <= 0:
                raise ServerError("no answer within %.0f s" % timeout)
            ready, _, _ = select.select([self.proc.stdout], [], [], left)
            if ready:
                chunk = os.read(self.proc.stdout.fileno(), 65536)
                if not chunk:
                    raise ServerError("the server closed its stdout (exit status %s)" % self.proc.wait())
                self.buffer += chunk

    def request(self, req, timeout=120.0):
        """Sends one request (a dict, or a raw line) and returns (other lines, final "ok"/"error" line)."""
        line = req if isinstance(req, str) else json.dumps(req)
        self.proc.stdin.write(line.encode() + b"\n")
        self.proc.stdin.flush()
        others = []
        while True:
            answer = self.next_line(timeout)
            if answer.startswith("ok ") or answer.startswith("error "):
                return others, answer
            others.append(answer)

    def close(self, timeout=30.0):
        """Closes stdin (EOF) and returns the exit status."""
        self.proc.stdin.close()
        try:
            return self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
            return None
        finally:
            self.log.close()


def read_rgba(prefix, component, size):
    """OUTPUT.COMPONENT.f32: size x size RGBA float32, rows from the top."""
    data = np.fromfile("%s.%s.f32" % (prefix, component), dtype="<f4")
    if data.size != size * size * 4:
        raise ServerError("%s.%s.f32 holds %d floats, expected %d" % (prefix, component, data.size, size * size * 4))
    return data.reshape(size, size, 4).astype(np.float64)


def write_pfm(path, rgb):
    """A colour PFM (what matremap's image reader, OpenImageIO, reads) of rows-from-the-top RGB."""
    rgb = np.asarray(rgb, dtype="<f4")
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (rgb.shape[1], rgb.shape[0]))
        f.write(np.ascontiguousarray(rgb[::-1, :, :3]).tobytes())   # PFM rows run bottom-up


def sphere_coverage(size, position, target, up, fov_y, center, radius, ss=8):
    """The fraction of each pixel (rows from the top) that the sphere covers, by ss x ss rays per pixel."""
    eye = np.asarray(position, float)
    fwd = np.asarray(target, float) - eye
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, np.asarray(up, float))
    right /= np.linalg.norm(right)
    upv = np.cross(right, fwd)
    t = np.tan(np.radians(fov_y) / 2.0)
    u = ((np.arange(size * ss) + 0.5) / (size * ss)) * 2.0 - 1.0
    x, y = np.meshgrid(u * t, -u * t)     # y falls along the rows: row 0 is the top
    d = x[..., None] * right + y[..., None] * upv + fwd
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    oc = eye - np.asarray(center, float)
    b = d @ oc
    disc = b * b - (oc @ oc - radius * radius)
    hit = (disc > 0.0) & (-b - np.sqrt(np.maximum(disc, 0.0)) > 0.0)
    return hit.reshape(size, ss, size, ss).mean(axis=(1, 3))
