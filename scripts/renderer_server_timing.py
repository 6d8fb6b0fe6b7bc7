"""Times a renderer server of matremap's renderer-server protocol (v1): start-up to its ready line, then the fit
scene's cycles-principled sphere at SIZE^2 for each sample count, the material changed between requests (as a fit
does), REPEATS requests per count. Prints one line per count: the first request's wall time and the median over
the others of the wall time (request written to answer read) and of the server's own SECONDS.

Usage: /usr/bin/python3 scripts/renderer_server_timing.py [--size 64] [--samples 16,64,256] [--repeats 12]
           [--threads 1] [-- SERVER COMMAND...]
The default command is the Blender server: blender -b --factory-startup --python-exit-code 3
--python data/renderers/blender_server.py -- (docs/cycles-peer.md, "The renderer server")."""

import argparse
import os
import statistics
import sys
import tempfile
import time

sys.dont_write_bytecode = True
root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(root, "tests", "lib"))
from renderer_client import RendererServer, fit_scene_request  # noqa: E402


def main():
    argv = sys.argv[1:]
    command = None
    if "--" in argv:
        command = argv[argv.index("--") + 1:]
        argv = argv[:argv.index("--")]
    p = argparse.ArgumentParser(description="Times a matremap renderer server (see the module's docstring).")
    p.add_argument("--size", type=int, default=64)
    p.add_argument("--samples", default="16,64,256")
    p.add_argument("--repeats", type=int, default=12)
    p.add_argument("--threads", type=int, default=1)
    a = p.parse_args(argv)
    if not command:
        command = [os.environ.get("MATREMAP_BLENDER", "blender"), "-b", "--factory-startup", "--python-exit-code",
                   "3", "--python", os.path.join(root, "data", "renderers", "blender_server.py"), "--"]
    with tempfile.TemporaryDirectory(prefix="matremap-timing-") as tmp:
        t0 = time.monotonic()
        server = RendererServer(command, os.path.join(tmp, "server.log"))
        print("ready after %.3f s: %s" % (time.monotonic() - t0, server.ready))
        rid = 0
        for spp in (int(s) for s in a.samples.split(",")):
            walls, own = [], []
            for k in range(a.repeats):
                rid += 1
                req = fit_scene_request(id=rid, size=a.size, samples=spp, threads=a.threads,
                                        output=os.path.join(tmp, "r"))
                req["material"]["values"].update(metallic=0.05 * k, roughness=0.2 + 0.05 * k)
                t = time.monotonic()
                _, final = server.request(req)
                walls.append(time.monotonic() - t)
                if not final.startswith("ok "):
                    sys.exit("renderer_server_timing: %s" % final)
                own.append(float(final.split()[2]))
            print("%d^2 at %d spp, %d threads: first %.3f s; median of the next %d: wall %.4f s, server %.4f s"
                  % (a.size, spp, a.threads, walls[0], len(walls) - 1, statistics.median(walls[1:]),
                     statistics.median(own[1:])))
        print("exit status at EOF: %s" % server.close())


main()
