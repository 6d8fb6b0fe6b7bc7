"""Render materials in matremap's fit scene with Cycles, many in one Blender process (docs/evaluation-renderers.md).

    blender -b --factory-startup --python-exit-code 3 --python scripts/blender/render_back.py -- \
        --jobs JOBS.json [--threads T]

JOBS.json is a list of renders, each
    {"output": "/abs/out.exr", "size": 512, "samples": 64, "seed": 0, "rgb": false,
     "material": {"blend": "/abs/file.blend", "name": "MATERIAL"}}      a node material of a .blend, as it is
  or "material": {"gltf": "/abs/file.gltf"}                               the material Blender's glTF importer builds
                                                                          (a Principled BSDF) from the file's first
                                                                          mesh
The scene is scripts/cycles_fit_scene.py's fit scene (point-primitive unit sphere, light at 45 degrees, 10 W/sr,
camera at (0, 0, 4), 35 degrees, direct light only, box filter of one pixel, Standard view) with a transparent film:
the output is a 32-bit float linear EXR, RGBA (A = the sphere's coverage) or RGB when "rgb" is true (what
`matremap remap --from-images` reads). Prints one JSON line per render: {"output": ..., "seconds": ...}.
Exit codes: 0 ok, 1 usage, 2 bad input, 3 Blender failure.
"""

import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fit_scene_lib as fsl  # noqa: E402


def fail(msg, code=2):
    sys.stderr.write("render_back: %s\n" % msg)
    sys.stderr.flush()
    os._exit(code)


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    jobs_path, threads = None, 0
    i = 0
    while i < len(argv):
        if argv[i] == "--jobs" and i + 1 < len(argv):
            jobs_path = argv[i + 1]
        elif argv[i] == "--threads" and i + 1 < len(argv):
            threads = int(argv[i + 1])
        else:
            fail("usage: render_back.py -- --jobs JOBS.json [--threads T] (unknown '%s')" % argv[i], 1)
        i += 2
    if jobs_path is None:
        fail("usage: render_back.py -- --jobs JOBS.json [--threads T]", 1)
    with open(jobs_path) as f:
        jobs = json.load(f)
    scene, sphere = fsl.setup(64, 16, threads)
    cache = {}
    for job in jobs:
        m = job["material"]
        key = json.dumps(m, sort_keys=True)
        if key not in cache:
            if "blend" in m:
                cache[key] = fsl.append_material(m["blend"], m["name"])
            elif "gltf" in m:
                cache[key] = fsl.import_gltf_material(m["gltf"], "gltf%d" % len(cache))
            else:
                fail("job %s: material needs 'blend' and 'name', or 'gltf'" % key)
        fsl.set_material(sphere, cache[key])
        fsl.set_size(scene, int(job["size"]), int(job["samples"]), int(job.get("seed", 0)))
        scene.render.image_settings.color_mode = "RGB" if job.get("rgb") else "RGBA"
        t0 = time.time()
        fsl.render(scene, job["output"])
        print(json.dumps({"output": job["output"], "seconds": round(time.time() - t0, 3)}), flush=True)


try:
    main()
except SystemExit as e:
    os._exit(e.code if isinstance(e.code, int) else 1)
except (ValueError, KeyError, OSError) as e:
    fail(str(e), 2)
except Exception as e:  # noqa: BLE001
    import traceback
    traceback.print_exc()
    fail("internal error: %s" % e, 3)
