#!/usr/bin/python3
"""A renderer server that misbehaves on purpose, for tests/renderer_faults.sh: it speaks the protocol of
docs/renderers.md as three.js's server would (the library starts it as MATREMAP_NODE with the server script as its
argument, which it ignores), and FAKE_MODE says how it fails:
  ok         renders a uniform grey sphere of the plan's coverage (alpha 1 inside the sphere's disc)
  truncated  writes half the floats
  nan        writes NaN in one pixel
  noready    exits before its ready line
  badready   prints a ready line of another renderer
  die        exits without answering each render
  error      answers every render with an error line
"""
import json
import math
import os
import struct
import sys

mode = os.environ.get("FAKE_MODE", "ok")
if mode == "noready":
    sys.stderr.write("fake renderer: cannot start (as asked)\n")
    sys.exit(1)
out = sys.stdout
out.write("chatter that is not an answer\n")
out.write("@matremap ready %s 0.0.1 components=full models=gltf,lambert\n" % ("blender" if mode == "badready" else "three"))
out.flush()


def coverage(size, req):
    """1 inside the sphere's projected disc (the camera looks at the sphere's centre)."""
    cam, cen, r = req["camera"]["position"], req["sphere"]["center"], req["sphere"]["radius"]
    d = math.dist(cam, cen)
    half = math.tan(math.radians(req["camera"]["fov_y"]) / 2.0)
    disc = math.tan(math.asin(min(r / d, 1.0))) / half * size / 2.0
    px = []
    for y in range(size):
        for x in range(size):
            inside = math.hypot(x + 0.5 - size / 2.0, y + 0.5 - size / 2.0) <= disc
            px.append(1.0 if inside else 0.0)
    return px


for line in sys.stdin:
    if not line.strip():
        continue
    req = json.loads(line)
    if req.get("op") == "quit":
        break
    rid = req.get("id", -1)
    if mode == "die":
        sys.exit(3)
    if mode == "error":
        out.write("@matremap error %d the fake renderer refuses (as asked)\n" % rid)
        out.flush()
        continue
    size = req["size"]
    alpha = coverage(size, req)
    values = []
    for a in alpha:
        values += [0.2 * a, 0.2 * a, 0.2 * a, a]
    if mode == "nan":
        values[(size // 2 * size + size // 2) * 4] = float("nan")
    if mode == "truncated":
        values = values[: len(values) // 2]
    for comp in req["components"]:
        with open("%s.%s.f32" % (req["output"], comp), "wb") as f:
            f.write(struct.pack("<%df" % len(values), *values))
    out.write("@matremap ok %d 0.001\n" % rid)
    out.flush()
