#!/usr/bin/python3
"""make evaluation-translations: MaterialX's closed-form translation graphs beside matremap's image-fitted remap.

For every material of MATERIALS and every pair with a MaterialX graph (standard-surface -> gltf, standard-surface ->
usd-preview, openpbr -> standard-surface) this computes
  - the graph's translation:  matremap remap --from SRC ... --to DST --method materialx --json
  - the fit:                  matremap remap --from SRC ... --to DST --json   (the default fit scene, 64^2, point lit)
renders source, translation and fit on the fit scene's sphere under both shared HDR maps (matremap render --env,
256 pattern directions + 64 around the mirror direction, 192^2), and compares each with the source's render over
the object: matremap ssim A B --mask M --exposure E (the library's SSIM restricted to the windows that touch the
sphere, docs/metrics.md), E fixed per map (a white Lambert sphere's mean radiance on the object times E is 0.5).

Writes BUILD/evaluation-translations/ (renders, results.json), one montage per pair into
docs/evaluation-translations/ and the tables between the markers of docs/evaluation-translations.md.
Usage: evaluate_translations.py ROOT BUILD [MATERIAL ...]   (names: a subset, for trying things out)
"""
import concurrent.futures
import datetime
import json
import os
import subprocess
import sys
import time

SIZE = 192
CELL = 128  # montage cell side
ENV_ARGS = ["--env-samples", "256", "--env-reflection-samples", "64"]
MAPS = [("studio", "studio_small_03_1k.hdr"), ("tabac", "tabac_plant_vogl.hdr")]
PAIRS = [("standard-surface", "gltf"), ("standard-surface", "usd-preview"), ("openpbr", "standard-surface")]

MX = "MaterialX resources/Materials/Examples/"
# name: (origin, standard-surface values, openpbr values). Values not named keep the model's defaults.
# SS-origin materials: the OpenPBR values are what MaterialX's own NG_standard_surface_to_open_pbr_surface
# (libraries/bxdf/translation/standard_surface_to_open_pbr.mtlx) makes of them, worked by hand: base colour times
# mix(1, coat_color, coat); specular_weight 1 for a metal; coat_weight 0 when coat x metalness > 0 (the coat's
# colour then lives in the base colour); coat_darkening = coat_affect_roughness (0 by default).
# OpenPBR-origin materials: the Standard Surface values are the same inputs by name (base_weight -> base,
# base_metalness -> metalness, specular_weight -> specular, coat_weight -> coat ...).
# Roughness 0 in an example becomes the models' floor 0.01; lobes outside the models here (subsurface, thin film,
# anisotropy, sheen) are left out and named.
MATERIALS = [
    ("gold", MX + "StandardSurface/standard_surface_gold.mtlx",
     "base_color=0.944,0.776,0.373 specular_color=0.998,0.981,0.751 specular_roughness=0.02 metalness=1",
     "base_color=0.944,0.776,0.373 base_metalness=1 specular_color=0.998,0.981,0.751 specular_roughness=0.02 "
     "coat_ior=1.5 coat_darkening=0"),
    ("copper", MX + "StandardSurface/standard_surface_copper.mtlx (a white metal under a coloured coat)",
     "base_color=1 specular=0 specular_roughness=0.25 metalness=1 coat=1 coat_color=0.96467984,0.37626296,0.25818297 "
     "coat_roughness=0.2",
     "base_color=0.96467984,0.37626296,0.25818297 base_metalness=1 specular_roughness=0.25 coat_weight=0 "
     "coat_color=0.96467984,0.37626296,0.25818297 coat_roughness=0.2 coat_ior=1.5 coat_darkening=0"),
    ("chrome", MX + "StandardSurface/standard_surface_chrome.mtlx (roughness 0 -> 0.01)",
     "base_color=1 specular_color=1 specular_roughness=0.01 metalness=1",
     "base_color=1 base_metalness=1 specular_roughness=0.01 coat_ior=1.5 coat_darkening=0"),
    ("aluminium", MX + "OpenPbr/open_pbr_aluminum_brushed.mtlx (anisotropy 0.9 left out)",
     "base_color=0.912,0.914,0.920 metalness=1 specular_color=0.970,0.979,0.988 specular_roughness=0.2",
     "base_color=0.912,0.914,0.920 base_metalness=1 specular_color=0.970,0.979,0.988 specular_roughness=0.2"),
    ("rough-copper", "this evaluation's: a rough metal with a strong edge tint (specular_color far from 1)",
     "base_color=0.95,0.64,0.54 metalness=1 specular_color=1,0.75,0.6 specular_roughness=0.45",
     "base_color=0.95,0.64,0.54 base_metalness=1 specular_color=1,0.75,0.6 specular_roughness=0.45"),
    ("plastic", MX + "StandardSurface/standard_surface_plastic.mtlx (saturated blue)",
     "base_color=0.10470402,0.24188282,0.81800002 specular_roughness=0.32467532",
     "base_color=0.10470402,0.24188282,0.81800002 specular_roughness=0.32467532 coat_ior=1.5 coat_darkening=0"),
    ("greysphere", MX + "StandardSurface/standard_surface_greysphere.mtlx (rough)",
     "base_color=0.18 specular_roughness=0.7",
     "base_color=0.18 specular_roughness=0.7 coat_ior=1.5 coat_darkening=0"),
    ("jade", MX + "StandardSurface/standard_surface_jade.mtlx (specular_IOR 2.418; subsurface 0.4, anisotropy left out)",
     "base=0.5 base_color=0.0603,0.4398,0.1916 specular_roughness=0.25 specular_ior=2.418",
     "base_weight=0.5 base_color=0.0603,0.4398,0.1916 specular_roughness=0.25 specular_ior=2.418 coat_ior=1.5 "
     "coat_darkening=0"),
    ("ketchup", MX + "OpenPbr/open_pbr_ketchup.mtlx (ior 1.3, roughness 0 -> 0.01; subsurface left out)",
     "base_color=0.164,0.006,0.002 specular_roughness=0.01 specular_ior=1.3",
     "base_color=0.164,0.006,0.002 specular_roughness=0.01 specular_ior=1.3"),
    ("carpaint-ss", MX + "StandardSurface/standard_surface_carpaint.mtlx (coat roughness 0 -> 0.01; anisotropy left out)",
     "base=0.5 base_color=0.1037792,0.59212029,0.85064936 specular_roughness=0.4 coat=1 coat_roughness=0.01",
     "base_weight=0.5 base_color=0.1037792,0.59212029,0.85064936 specular_roughness=0.4 coat_weight=1 "
     "coat_roughness=0.01 coat_ior=1.5 coat_darkening=0"),
    ("carpaint-openpbr", MX + "OpenPbr/open_pbr_carpaint.mtlx",
     "base_color=0.1,0.6,0.9 specular_ior=1.6 specular_roughness=0.3 coat=1 coat_roughness=0.02 coat_ior=1.6",
     "base_color=0.1,0.6,0.9 specular_ior=1.6 specular_roughness=0.3 coat_weight=1 coat_roughness=0.02 coat_ior=1.6"),
    ("pearl", MX + "OpenPbr/open_pbr_pearl.mtlx (subsurface and thin film left out)",
     "base_color=0.8,0.75,0.7 specular_roughness=0.35 coat=1 coat_roughness=0.15 coat_ior=1.68",
     "base_color=0.8,0.75,0.7 specular_roughness=0.35 coat_weight=1 coat_roughness=0.15 coat_ior=1.68"),
    ("red-lacquer", "this evaluation's: a coloured, darkening coat over a light rough base",
     "base_color=0.8 specular_roughness=0.5 coat=1 coat_color=0.8,0.15,0.1 coat_roughness=0.05 coat_ior=1.5",
     "base_color=0.8 specular_roughness=0.5 coat_weight=1 coat_color=0.8,0.15,0.1 coat_roughness=0.05 coat_ior=1.5 "
     "coat_darkening=1"),
]


METHODS = ("materialx", "fit", "fit-ior")


def source_ior(vals):
    """The source's specular IOR (its specular_ior=, else the models' default 1.5)."""
    for v in vals:
        if v.startswith("specular_ior="):
            return float(v.split("=")[1])
    return 1.5


def run(cmd):
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        raise RuntimeError("%s: exit %d: %s" % (" ".join(cmd), p.returncode, p.stderr.strip()))
    return p.stdout


def words(values):
    out = []
    for name, v in values.items():
        out.append("%s=%s" % (name, ",".join("%.9g" % x for x in v) if isinstance(v, list) else "%.9g" % v))
    return out


def object_mean(path, mask):
    """Mean radiance over the object: the image's mean over its mask's mean (oiiotool --printstats)."""
    def avg(p):
        for line in run(["oiiotool", p, "--printstats"]).splitlines():
            if "Stats Avg:" in line:
                return [float(x) for x in line.split(":")[1].split() if not x.startswith("(")][:3]
        raise RuntimeError("no stats for " + p)
    a, m = avg(path), avg(mask)[0]
    return sum(a) / len(a) / m


def main():
    root, build = sys.argv[1], sys.argv[2]
    only = set(sys.argv[3:])
    mats = [m for m in MATERIALS if not only or m[0] in only]
    bin_ = os.path.join(root, build, "bin", "matremap")
    shared = os.environ.get("MR_SHARED", os.path.join(root, "..", "shared"))
    hdri = os.path.join(shared, "assets", "hdri")
    work = os.path.join(root, build, "evaluation-translations")
    os.makedirs(work, exist_ok=True)
    t0 = time.time()

    # Exposure per map: a white Lambert sphere's mean radiance on the object times E is 0.5.
    exposure = {}
    mask = os.path.join(work, "mask.exr")
    for key, f in MAPS:
        white = os.path.join(work, "white_%s.exr" % key)
        run([bin_, "render", "lambert", "albedo=1", "--env", os.path.join(hdri, f), "--size", str(SIZE)] + ENV_ARGS
            + ["--mask", mask, "-o", white])
        exposure[key] = 0.5 / object_mean(white, mask)

    # Translations and fits (fits run two at a time: the machine has 2 cores).
    jobs = {}
    with concurrent.futures.ThreadPoolExecutor(max_workers=2) as pool:
        for name, _, ss, op in mats:
            for src, dst in PAIRS:
                vals = (ss if src == "standard-surface" else op).split()
                base = [bin_, "remap", "--from", src] + vals + ["--to", dst, "--json"]
                jobs[(name, src, dst, "materialx")] = pool.submit(run, base + ["--method", "materialx"])
                jobs[(name, src, dst, "fit")] = pool.submit(run, base)
                ior = source_ior(vals)
                if ior != 1.5:  # the fit with the IOR held at 1.5 (a hold wins over the default IOR tie)
                    given = ["--hold", "%s=1.5" % ("specular_ior" if dst == "standard-surface" else "ior")]
                    cmd = [bin_, "remap", "--from", src] + vals + ["--to", dst] + given + ["--json"]
                    jobs[(name, src, dst, "fit-ior")] = pool.submit(run, cmd)
        results = {k: json.loads(f.result()) for k, f in jobs.items()}
    for name, _, _, _ in mats:
        for src, dst in PAIRS:
            results.setdefault((name, src, dst, "fit-ior"), results[(name, src, dst, "fit")])
    print("evaluation-translations: %d translations and fits, %.0f s" % (len(jobs), time.time() - t0), file=sys.stderr)

    # Renders: source (per source model), graph and fit (per pair), under each map; PNGs for the montages.
    def render(model, vals, stem):
        out = {}
        for key, f in MAPS:
            exr = os.path.join(work, "%s_%s.exr" % (stem, key))
            png = os.path.join(work, "%s_%s.png" % (stem, key))
            run([bin_, "render", model] + vals + ["--env", os.path.join(hdri, f), "--size", str(SIZE)] + ENV_ARGS
                + ["-o", exr])
            run(["oiiotool", exr, "--mulc", "%.9g" % exposure[key], "--tocolorspace", "sRGB", "--resize",
                 "%dx%d" % (CELL, CELL), "-d", "uint8", "-o", png])
            out[key] = (exr, png)
        return out

    tasks = {}
    with concurrent.futures.ThreadPoolExecutor(max_workers=2) as pool:
        for name, _, ss, op in mats:
            tasks[(name, "standard-surface", "source")] = pool.submit(render, "standard-surface", ss.split(),
                                                                      "%s_ss_source" % name)
            tasks[(name, "openpbr", "source")] = pool.submit(render, "openpbr", op.split(), "%s_openpbr_source" % name)
            for src, dst in PAIRS:
                for method in METHODS:
                    r = results[(name, src, dst, method)]
                    if method == "fit-ior" and r is results[(name, src, dst, "fit")]:
                        continue
                    tasks[(name, src, dst, method)] = pool.submit(render, dst, words(r["values"]),
                                                                  "%s_%s_%s_%s" % (name, src, dst, method))
        renders = {k: f.result() for k, f in tasks.items()}
    for name, _, _, _ in mats:
        for src, dst in PAIRS:
            renders.setdefault((name, src, dst, "fit-ior"), renders[(name, src, dst, "fit")])
    print("evaluation-translations: %d renders under each map, %.0f s" % (len(tasks), time.time() - t0),
          file=sys.stderr)

    def ssim(a, b, key):
        out = json.loads(run([bin_, "ssim", a, b, "--mask", mask, "--exposure", "%.9g" % exposure[key], "--json"]))
        return out["object_ssim"], out["object_relative_rmse"]

    rows = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=2) as pool:
        for name, origin, ss, op in mats:
            for src, dst in PAIRS:
                row = {"material": name, "from": src, "to": dst}
                source = renders[(name, src, "source")]
                for method in METHODS:
                    r = results[(name, src, dst, method)]
                    row[method] = {"values": r["values"], "fit_scene_ssim": r["ssim"],
                                   "relative_rmse": r["relative_rmse"], "outcome": r.get("outcome", "")}
                    for key, _ in MAPS:
                        row[method][key] = pool.submit(ssim, source[key][0],
                                                       renders[(name, src, dst, method)][key][0], key)
                rows.append(row)
        for row in rows:
            for method in METHODS:
                for key, _ in MAPS:
                    row[method][key], row[method][key + "_rmse"] = row[method][key].result()
    seconds = time.time() - t0
    cpu = os.times().children_user + os.times().children_system
    with open(os.path.join(work, "results.json"), "w") as f:
        json.dump({"exposure": exposure, "rows": rows, "seconds": seconds, "cpu_seconds": cpu}, f, indent=1)

    # Montages: per pair, one row per material: source | graph | fit under studio, then the same under tabac.
    pictures = os.path.join(root, "docs", "evaluation-translations")
    os.makedirs(pictures, exist_ok=True)
    for src, dst in PAIRS:
        cells = []
        text = "--text:x=%d:y=%d:size=12:color=1,1,1:font=DejaVuSans"
        for row, (name, _, _, _) in enumerate(mats):
            for key, _ in MAPS:
                for column, kind in enumerate(("source", "materialx", "fit")):
                    stem = (name, src, "source") if kind == "source" else (name, src, dst, kind)
                    cells.append(renders[stem][key][1])
                    if kind == "source":
                        cells += [text % (3, 13), name]
                    if row == 0:
                        label = {"source": "source", "materialx": "graph", "fit": "fit"}[kind]
                        cells += [text % (3, CELL - 4), "%s: %s" % (key, label)]
        out = os.path.join(pictures, "%s-to-%s.png" % (src, dst))
        run(["oiiotool"] + cells + ["--mosaic:pad=2", "6x%d" % len(mats), "-d", "uint8", "-o", out])

    write_doc(root, build, mats, rows, exposure, seconds, cpu, only)
    print("evaluation-translations: %d materials x %d pairs in %.0f s" % (len(mats), len(PAIRS), seconds))


def rgb(m):
    """Object RMSE of linear RGB relative to the source's mean radiance on the object, mean over both maps."""
    return sum(m[key + "_rmse"] for key, _ in MAPS) / len(MAPS)


def write_doc(root, build, mats, rows, exposure, seconds, cpu, only):
    lines = []
    date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    lines.append("Made by `make evaluation-translations` (`scripts/evaluate-translations.sh %s%s`) on %s in %.0f s "
                 "wall, %.0f s of CPU time in the commands it ran (a shared 2-core machine); exposures: %s." % (
                     build, " " + " ".join(sorted(only)) if only else "", date, seconds, cpu,
                     ", ".join("%s %.4g" % (k, v) for k, v in exposure.items())))
    lines.append("")
    lines.append("Object SSIM against the source's render (1 = identical), per map: the MaterialX graph, the fit "
                 "(`matremap remap` as a user runs it: the target's default holds and ties, the IOR tied to the "
                 "source's), and the fit with the IOR held at 1.5 instead (`fit 1.5`: `--hold ior=1.5`, "
                 "`--hold specular_ior=1.5`; the default before the IOR tie; `=` where the source's IOR is 1.5 and "
                 "this is the fit). `RGB error`: the object's RMSE of linear RGB relative to the "
                 "source's mean radiance there (`object_relative_rmse` of `matremap ssim --mask`), mean over both "
                 "maps: SSIM is computed on luma and does not see a change of hue. `fit scene` is the SSIM the command itself prints "
                 "(whole 64² frame, point light); the fit's outcome last.")
    for src, dst in PAIRS:
        lines.append("")
        lines.append("### %s → %s" % (src, dst))
        lines.append("")
        lines.append("| material | graph studio | graph tabac | fit studio | fit tabac | fit 1.5 studio | "
                     "fit 1.5 tabac | RGB error graph / fit / fit 1.5 | graph fit scene | fit fit scene | fit outcome |")
        lines.append("|---|---|---|---|---|---|---|---|---|---|---|")
        sel = [r for r in rows if r["from"] == src and r["to"] == dst]
        for r in sel:
            g, f, fi = r["materialx"], r["fit"], r["fit-ior"]
            same = fi is f or fi["values"] == f["values"]

            def cell(a, b):
                return ("**%.4f**" % a) if a > b + 5e-5 else "%.4f" % a
            lines.append("| %s | %s | %s | %s | %s | %s | %s | %.3f / %.3f / %s | %.4f | %.4f | %s |" % (
                r["material"], cell(g["studio"], f["studio"]), cell(g["tabac"], f["tabac"]),
                cell(f["studio"], g["studio"]), cell(f["tabac"], g["tabac"]),
                "=" if same else "%.4f" % fi["studio"], "=" if same else "%.4f" % fi["tabac"],
                rgb(g), rgb(f), "=" if same else "%.3f" % rgb(fi), g["fit_scene_ssim"], f["fit_scene_ssim"],
                f["outcome"] + ("" if same else " (1.5: %s)" % fi["outcome"])))
        n = len(sel)

        def mean(method, key):
            return sum(r[method][key] for r in sel) / n
        lines.append("| **mean** | %.4f | %.4f | %.4f | %.4f | %.4f | %.4f | %.3f / %.3f / %.3f | %.4f | %.4f | |" % (
            mean("materialx", "studio"), mean("materialx", "tabac"), mean("fit", "studio"), mean("fit", "tabac"),
            mean("fit-ior", "studio"), mean("fit-ior", "tabac"),
            sum(rgb(r["materialx"]) for r in sel) / n, sum(rgb(r["fit"]) for r in sel) / n,
            sum(rgb(r["fit-ior"]) for r in sel) / n,
            mean("materialx", "fit_scene_ssim"), mean("fit", "fit_scene_ssim")))
        wins = sum(1 for r in sel for k, _ in MAPS if r["fit"][k] > r["materialx"][k] + 5e-5)
        losses = sum(1 for r in sel for k, _ in MAPS if r["materialx"][k] > r["fit"][k] + 5e-5)
        lines.append("")
        lines.append("Fit better in %d of %d material × map cells, graph better in %d (bold: the better by more "
                     "than 5e-5). Pictures: [%s-to-%s.png](evaluation-translations/%s-to-%s.png)." % (
                         wins, 2 * n, losses, src, dst, src, dst))
    lines.append("")
    lines.append("### The materials")
    lines.append("")
    lines.append("| material | from | standard-surface | openpbr |")
    lines.append("|---|---|---|---|")
    for name, origin, ss, op in mats:
        lines.append("| %s | %s | `%s` | `%s` |" % (name, origin, ss, op))
    lines.append("")
    lines.append("Translated and fitted values of every row: `%s/evaluation-translations/results.json`." % build)
    path = os.path.join(root, "docs", "evaluation-translations.md")
    begin, end = "<!-- BEGIN evaluation-translations -->", "<!-- END evaluation-translations -->"
    text = open(path).read() if os.path.exists(path) else "%s\n%s\n" % (begin, end)
    a, b = text.index(begin) + len(begin), text.index(end)
    text = text[:a] + "\n" + "\n".join(lines) + "\n" + text[b:]
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)


if __name__ == "__main__":
    main()
