"""The bookkeeping of scripts/evaluate-clients.sh (make evaluation-clients; docs/evaluation-clients.md): which
documents and materials, the three.js job file, matremap's renders of the same materials, the object metrics, the
pictures and the Markdown table.

    evaluate_clients.py prepare WORK ASSETS MATREMAP DOC_WRITE   (the documents, WORK/cases.json)
    evaluate_clients.py jobs WORK HDRI_DIR CHROMIUM  (WORK/client-jobs.json)
    evaluate_clients.py matremap WORK HDRI_DIR MATREMAP   (matremap's renders, after three.js: its map scales)
    evaluate_clients.py metrics WORK OBJECT_METRICS  (JSON lines on stdout)
    evaluate_clients.py pictures WORK OUT_DIR
    evaluate_clients.py table WORK DATE VERSION THREE_S TOTAL_S

A case is one material of one document: (material, document kind, the document's file, the material's name in it),
rendered by three.js (client_render.mjs) and by `matremap render MODEL name=value ...` with the values the document
holds (read back from it: what the client reads is what matremap renders), or, for the textured asset, by
`matremap render ASSET.gltf` (the export's source, its maps being carried exactly into the documents).
Standard library only.
"""
import json
import math
import os
import re
import subprocess
import sys
import textwrap
import xml.etree.ElementTree as ET

ENVS = {"studio": "studio_small_03_1k.hdr", "tabac": "tabac_plant_vogl.hdr"}
ENV_MEAN = 0.5
FOV = 35.0
# three.js reads direction d of an equirectangular map at u = atan2(d.z, d.x) / 2pi + 0.5 (u = 0.5 at +x);
# matremap puts u = 0.5 at -z (docs/rendering.md): a quarter turn about +y (scene.environmentRotation.y).
ENV_ROTATION = math.pi / 2
ENV_SAMPLES, REFLECTION_SAMPLES = 1024, 32
# The textured asset's view: the direction from its centre to the camera (matremap render --camera-direction).
ASSET_DIRECTION = (0.5, 0.3, 1.0)

KINDS = {  # document kind: label, the surface node, the matremap model
    "gltf-source": ("three.js GLTFLoader, the source", "glTF (export's input)", "gltf"),
    "openpbr": (".mtlx open_pbr_surface", "open_pbr_surface", "openpbr"),
    "standard-surface": (".mtlx standard_surface", "standard_surface", "standard-surface"),
    "gltf": (".mtlx gltf_pbr", "gltf_pbr", "gltf"),
    "usd-preview": (".usda UsdPreviewSurface", "UsdPreviewSurface", "usd-preview"),
}
SHORT = {"gltf-source": "GLTFLoader", "openpbr": "open_pbr", "standard-surface": "std_surface", "gltf": "gltf_pbr",
         "usd-preview": "USD"}
MTLX_NODE_MODEL = {"open_pbr_surface": "openpbr", "standard_surface": "standard-surface", "gltf_pbr": "gltf"}


def snake(name):
    return re.sub(r"(?<=[a-z])([A-Z])", r"_\1", name).lower()


def mtlx_values(path, material):
    """The constant inputs of the surface node of `material` in a .mtlx document, as matremap parameters."""
    root = ET.parse(path).getroot()
    mat = next(m for m in root.findall("surfacematerial") if m.get("name") == material)
    shader = mat.find("input[@name='surfaceshader']").get("nodename")
    node = next(n for n in root if n.get("name") == shader)
    values = {}
    for i in node.findall("input"):
        if i.get("value") is not None:
            values[snake(i.get("name"))] = i.get("value").replace(" ", "")
    return MTLX_NODE_MODEL[node.tag], values


def usda_values(path, material):
    """The constant inputs of /Materials/<material>/Surface in a .usda layer, as matremap parameters."""
    text = open(path).read()
    start = text.index('def Material "%s"' % material)
    block = text[start:text.index('token outputs:surface\n', start)]
    values = {}
    for name, value in re.findall(r"^\s*(?:color3f|float|int) inputs:(\w+) = ([^\n]+)$", block, re.M):
        values[snake(name)] = value.strip("()").replace(" ", "")
    return "usd-preview", values


def cases_path(work):
    return os.path.join(work, "cases.json")


def render_path(work, who, case, env):
    return os.path.join(work, "renders", who, "%s_%s.exr" % (case["keys"][who], env))


# The uniform materials, as glTF factors (base colour, metallic, roughness): `matremap export` converts them into
# each document (a remap in the fit scene to openpbr, standard-surface and usd-preview; a copy to gltf_pbr).
UNIFORM = [
    ("Gold", [1.0, 0.77, 0.34], 1.0, 0.3),
    ("GlossyAluminium", [0.91, 0.92, 0.92], 1.0, 0.15),
    ("RoughCopper", [0.95, 0.64, 0.54], 1.0, 0.6),
    ("RedPlastic", [0.6, 0.05, 0.04], 0.0, 0.5),
    ("GlossyBlue", [0.05, 0.2, 0.7], 0.0, 0.15),
    ("RoughWhite", [0.8, 0.8, 0.8], 0.0, 0.9),
]
# Materials glTF's model cannot hold (a coat, a metal's edge tint, a rough diffuse): written by the library's own
# writer (BUILD/tools/doc_write), every parameter a constant as export writes them. Per material, per model.
EXTRA = [
    ("CoatedRed", [
        ("openpbr", "base_color=0.6,0.05,0.04 specular_roughness=0.5 coat_weight=1 coat_color=0.9,0.75,0.45 "
                    "coat_roughness=0.05"),
        ("standard-surface", "base_color=0.6,0.05,0.04 specular_roughness=0.5 coat=1 coat_color=0.9,0.75,0.45 "
                             "coat_roughness=0.05"),
        ("usd-preview", "diffuse_color=0.6,0.05,0.04 roughness=0.5 clearcoat=1 clearcoat_roughness=0.05"),
    ]),
    ("CoatedGold", [
        ("openpbr", "base_color=1,0.77,0.34 base_metalness=1 specular_roughness=0.4 coat_weight=1 "
                    "coat_roughness=0.02"),
        ("standard-surface", "base_color=1,0.77,0.34 metalness=1 specular_roughness=0.4 coat=1 coat_roughness=0.02"),
    ]),
    ("EdgeTintedCopper", [
        ("openpbr", "base_color=0.95,0.64,0.54 base_metalness=1 specular_color=0.6,0.75,1 specular_roughness=0.25"),
        ("standard-surface", "base_color=0.95,0.64,0.54 metalness=1 specular_color=0.6,0.75,1 "
                             "specular_roughness=0.25"),
    ]),
    ("RoughDiffuse", [
        ("openpbr", "base_color=0.8,0.8,0.8 base_diffuse_roughness=1 specular_roughness=0.6"),
        ("standard-surface", "base_color=0.8,0.8,0.8 diffuse_roughness=1 specular_roughness=0.6"),
    ]),
]
# The textured asset: exported to every document kind whose texture route exists (export refuses the others).
TEXTURED = ("WaterBottle", "metalrough/WaterBottle/glTF/WaterBottle.gltf")
EXT = {"openpbr": "mtlx", "standard-surface": "mtlx", "gltf": "mtlx", "usd-preview": "usda"}


# Checks of the explanations (docs/evaluation-clients.md): the approximation that three.js makes, applied on one side,
# should take the residual away. ("matremap", values): matremap renders the document's material with these values
# changed, three.js's render is the document's; ("three", input): three.js opens a copy of the document without
# that input, matremap's render is the document's.
EXPLAIN = {
    ("RoughDiffuse", "openpbr"): ("matremap", {"base_diffuse_roughness": "0"}, "matremap: base_diffuse_roughness 0"),
    ("RoughDiffuse", "standard-surface"): ("matremap", {"diffuse_roughness": "0"}, "matremap: diffuse_roughness 0"),
    ("EdgeTintedCopper", "openpbr"): ("matremap", {"specular_color": "1,1,1"}, "matremap: specular_color 1"),
    ("EdgeTintedCopper", "standard-surface"): ("matremap", {"specular_color": "1,1,1"},
                                               "matremap: specular_color 1"),
    ("CoatedRed", "openpbr"): ("matremap", {"coat_color": "1,1,1", "coat_darkening": "0"},
                               "matremap: coat_color 1, coat_darkening 0"),
    ("CoatedRed", "standard-surface"): ("matremap", {"coat_color": "1,1,1", "base_color": "0.54,0.0375,0.018"},
                                        "matremap: coat_color on base_color"),
}


def variants(cases, docs):
    """The explanation checks (EXPLAIN) and, for the textured asset's MaterialX documents, the render on the
    asset's own glTF texture coordinates (what three.js's MaterialXLoader samples: v = 0 at the image's top)."""
    out = []
    for case in cases:
        how = EXPLAIN.get((case["material"], case["kind"]))
        if how is not None:
            v = json.loads(json.dumps(case))
            v["variant"] = how[2]
            if how[0] == "matremap":
                v["values"].update(how[1])
                v["keys"]["matremap"] += "_explained"
            else:
                copy = os.path.join(docs, "%s_%s_without_%s.%s" % (case["material"], case["kind"], how[1],
                                                                   EXT[case["kind"]]))
                with open(case["doc"]) as f, open(copy, "w") as g:
                    g.writelines(line for line in f if "inputs:%s " % how[1] not in line)
                v["doc"] = copy
                v["keys"]["three"] += "_explained"
            out.append(v)
        if case["mesh"] and case["format"] == "mtlx":
            v = json.loads(json.dumps(case))
            v["variant"] = "three.js: mesh with glTF's texture coordinates"
            v["gltf_uv"] = True
            v["keys"]["three"] += "_gltfuv"
            out.append(v)
    return out


def run(cmd, **kw):
    print("  " + " ".join(cmd), file=sys.stderr)
    return subprocess.run(cmd, **kw)


def cmd_prepare(work, assets, matremap, doc_write):
    """The documents (WORK/docs) and WORK/cases.json: one case per material and document."""
    docs = os.path.join(work, "docs")
    os.makedirs(docs, exist_ok=True)
    cases = []
    source = os.path.join(docs, "uniform.gltf")
    json.dump({"asset": {"version": "2.0", "generator": "make evaluation-clients"}, "materials": [
        {"name": n, "pbrMetallicRoughness": {"baseColorFactor": c + [1.0], "metallicFactor": m, "roughnessFactor": r}}
        for n, c, m, r in UNIFORM]}, open(source, "w"), indent=1)
    names = [n for n, _, _, _ in UNIFORM]
    exports = {}
    for model in ("openpbr", "standard-surface", "gltf", "usd-preview"):
        out = os.path.join(docs, "uniform_%s.%s" % (model, EXT[model]))
        res = run([matremap, "export", source, "-o", out, "--to", model, "--json"], check=True,
                  capture_output=True, text=True)
        exports["uniform " + model] = json.loads(res.stdout)
    for n in names:
        cases.append({"material": n, "name": n, "kind": "gltf-source", "format": "gltf", "doc": source,
                      "model": "gltf", "values": None})
        for model in ("openpbr", "standard-surface", "gltf", "usd-preview"):
            cases.append({"material": n, "name": n, "kind": model, "format": EXT[model],
                          "doc": os.path.join(docs, "uniform_%s.%s" % (model, EXT[model]))})
    for n, per_model in EXTRA:
        for model, values in per_model:
            out = os.path.join(docs, "%s_%s.%s" % (n, model, EXT[model]))
            run([doc_write, out, model, n] + values.split(), check=True)
            cases.append({"material": n, "name": n, "kind": model, "format": EXT[model], "doc": out})
    # The textured asset, stripped of what the documents do not carry (normal, occlusion and emissive maps), its
    # buffers and images linked beside it: matremap renders it, three.js takes its meshes (and, as the source,
    # its materials).
    name, rel = TEXTURED
    src = os.path.join(assets, rel)
    folder = os.path.join(docs, name)
    os.makedirs(folder, exist_ok=True)
    gltf = json.load(open(src))
    for f in [b["uri"] for b in gltf.get("buffers", [])] + [i["uri"] for i in gltf.get("images", [])]:
        link = os.path.join(folder, f)
        if not os.path.exists(link):
            os.symlink(os.path.join(os.path.dirname(src), f), link)
    for m in gltf["materials"]:
        for k in ("normalTexture", "occlusionTexture", "emissiveTexture", "emissiveFactor"):
            m.pop(k, None)
    stripped = os.path.join(folder, name + ".gltf")
    json.dump(gltf, open(stripped, "w"), indent=1)
    cases.append({"material": name, "name": None, "kind": "gltf-source", "format": "gltf", "doc": stripped,
                  "mesh": stripped, "reference": stripped})
    for model in ("gltf", "usd-preview", "openpbr", "standard-surface"):
        out = os.path.join(docs, "%s_%s.%s" % (name, model, EXT[model]))
        res = run([matremap, "export", src, "-o", out, "--to", model, "--json"], capture_output=True, text=True)
        if res.returncode != 0:
            exports["%s %s" % (name, model)] = {"refused": res.stderr.strip().splitlines()[-1]}
            continue
        exports["%s %s" % (name, model)] = json.loads(res.stdout)
        for m in json.loads(res.stdout)["materials"]:
            cases.append({"material": name, "name": re.sub(r"\W", "_", m["name"]), "kind": model,
                          "format": EXT[model], "doc": out, "mesh": stripped, "reference": stripped})
    for case in cases:
        key = "%s_%s" % (case["material"], case["kind"])
        case["keys"] = {"matremap": key, "three": key}
        case.setdefault("mesh", None)
        case.setdefault("reference", None)
        if case["format"] == "mtlx":
            case["model"], case["values"] = mtlx_values(case["doc"], case["name"])
        elif case["format"] == "usda":
            case["model"], case["values"] = usda_values(case["doc"], case["name"])
        elif case.get("values") is None and case["reference"] is None:  # a uniform source material: its factors
            n, c, m, r = next(u for u in UNIFORM if u[0] == case["name"])
            case["values"] = {"base_color": ",".join("%g" % x for x in c), "metallic": "%g" % m,
                              "roughness": "%g" % r}
        if case["reference"] is not None:  # the asset: matremap renders the asset, not name=value
            case["model"] = None
    cases += variants(cases, docs)
    json.dump(cases, open(cases_path(work), "w"), indent=1)
    json.dump(exports, open(os.path.join(work, "exports.json"), "w"), indent=1)


def cmd_jobs(work, hdri, chromium):
    size = int(os.environ.get("CLIENTS_SIZE", "256"))
    jobs = []
    os.makedirs(os.path.join(work, "renders", "three"), exist_ok=True)
    seen = set()
    for case in json.load(open(cases_path(work))):
        if case["keys"]["three"] in seen:
            continue
        seen.add(case["keys"]["three"])
        for env, hdr in ENVS.items():
            jobs.append({"noUvFlip": bool(case.get("gltf_uv")), "format": case["format"], "doc": case["doc"],
                         "material": case["name"],
                         "mesh": case["mesh"], "cameraDirection": ASSET_DIRECTION, "fov": FOV,
                         "env": os.path.join(hdri, hdr), "envMean": ENV_MEAN, "envRotation": ENV_ROTATION,
                         "flipRows": True, "out": render_path(work, "three", case, env), "size": size,
                         "supersample": 2})
    json.dump({"chromium": chromium, "jobs": jobs}, open(os.path.join(work, "client-jobs.json"), "w"), indent=1)


def env_scales(work):
    """The map scales three.js used (mean luminance ENV_MEAN), by map file: matremap renders with the same."""
    scales = {}
    with open(os.path.join(work, "three-done.jsonl")) as f:
        for line in f:
            d = json.loads(line)
            env = next(e for e in ENVS if d["out"].endswith("_%s.exr" % e))
            scales[env] = d["env_scale"]
    return scales


def cmd_matremap(work, hdri, matremap):
    """matremap's render of every case (the same material: the document's values, or the asset) under both maps,
    RGB plus coverage joined into one RGBA EXR as three.js writes it. Cases with the same model and values share
    a render (the gltf_pbr document holds the source's own values)."""
    size = int(os.environ.get("CLIENTS_SIZE", "256"))
    scales = env_scales(work)
    os.makedirs(os.path.join(work, "renders", "matremap"), exist_ok=True)
    done = {}
    for case in json.load(open(cases_path(work))):
        for env, hdr in ENVS.items():
            out = render_path(work, "matremap", case, env)
            if case.get("model"):
                what = [case["model"]] + ["%s=%s" % kv for kv in sorted(case["values"].items())]
            else:
                what = [case["reference"], "--camera-direction", ",".join("%g" % x for x in ASSET_DIRECTION)]
            key = (tuple(what), env)
            if os.path.exists(out):
                continue
            if key in done:
                os.link(done[key], out)
                continue
            rgb, mask = out.replace(".exr", "_rgb.exr"), out.replace(".exr", "_mask.exr")
            cmd = [matremap, "render"] + what + [
                "--env", os.path.join(hdri, hdr), "--env-scale", "%.9g" % scales[env], "--env-samples",
                str(ENV_SAMPLES), "--env-reflection-samples", str(REFLECTION_SAMPLES), "--size", str(size),
                "--mask", mask, "-o", rgb]
            subprocess.run(cmd, check=True, stderr=subprocess.DEVNULL)
            subprocess.run(["oiiotool", rgb, mask, "--chappend", "--chnames", "R,G,B,A", "-o", out], check=True)
            os.remove(rgb)
            os.remove(mask)
            done[key] = out
            print(" ".join(cmd[:2] + [os.path.basename(out)]), file=sys.stderr)


def cmd_metrics(work, tool):
    for case in json.load(open(cases_path(work))):
        for env in ENVS:
            ref, test = render_path(work, "matremap", case, env), render_path(work, "three", case, env)
            row = {"material": case["material"], "kind": case["kind"], "variant": case.get("variant"),
                   "env": env}
            if not (os.path.exists(ref) and os.path.exists(test)):
                row["missing"] = True
            else:
                out = subprocess.run([tool, ref, test], check=True, capture_output=True, text=True)
                row.update(json.loads(out.stdout))
            print(json.dumps(row), flush=True)


def load_rows(work):
    rows = {}
    with open(os.path.join(work, "metrics.jsonl")) as f:
        for line in f:
            r = json.loads(line)
            rows[(r["material"], r["kind"], r.get("variant"), r["env"])] = r
    return rows


def materials_in_order(cases):
    seen = []
    for c in cases:
        if c["material"] not in seen:
            seen.append(c["material"])
    return seen


def cmd_pictures(work, out_dir):
    """One picture per material under the studio map: per document a pair, matremap | three.js, each at the
    exposure that puts matremap's object at mid-grey (so brightness differences show), sRGB, clamped."""
    rows = load_rows(work)
    cases = json.load(open(cases_path(work)))
    cell = int(os.environ.get("CLIENTS_CELL", "128"))
    os.makedirs(out_dir, exist_ok=True)
    for material in materials_in_order(cases):
        mine = [c for c in cases if c["material"] == material and (not c.get("variant") or c.get("gltf_uv"))]
        args = ["oiiotool"]
        for case in mine:
            exposure = rows.get((material, case["kind"], case.get("variant"), "studio"), {}).get("exposure", 1.0)
            for who in ("matremap", "three"):
                path = render_path(work, who, case, "studio")
                label = ("matremap %s" % (case.get("model") or "(asset)") if who == "matremap"
                         else "three %s%s" % (SHORT[case["kind"]], " glTF UV" if case.get("gltf_uv") else ""))
                if os.path.exists(path):
                    args += [path, "--ch", "R,G,B", "--mulc", "%.6g" % exposure, "--clamp:min=0:max=1",
                             "--resize", "%dx%d" % (cell, cell), "--colorconvert", "linear", "sRGB"]
                else:
                    args += ["--create", "%dx%d" % (cell, cell), "3"]
                    label += " (n/a)"
                args += ["--text:x=3:y=11:size=9:color=1,1,1:font=DejaVuSans", label]
        args += ["--mosaic:pad=2", "%dx1" % (2 * len(mine)), "-o", os.path.join(out_dir, "%s.png" % material)]
        subprocess.run(args, check=True)


def fmt(row, key, digits=4):
    if row is None or row.get("missing") or key not in row:
        return "-"
    return "%.*f" % (digits, row[key])


METALS = ("Gold", "GlossyAluminium", "RoughCopper")


def explanation(case):
    """The approximation that explains a row's residual (docs/evaluation-clients.md says why, with the numbers)."""
    m, kind = case["material"], case["kind"]
    if case.get("variant"):
        return "check"
    if kind == "gltf-source":
        return "floor: PMREM, multiple scattering on rough metals"
    if m == "WaterBottle":
        return "floor" if kind == "usd-preview" else "images read with v = 0 at the top"
    if kind == "gltf":
        return "floor (the same BRDF)"
    if kind == "usd-preview":
        return "floor (USD metal drawn as glTF's)" if m in METALS else "floor (no specularColor written)"
    by = {
        ("RoughCopper", "openpbr"): "remap's lower base colour in three.js's metal",
        ("CoatedRed", "openpbr"): "coat_color unused, no darkening, coat F0 0.04",
        ("CoatedRed", "standard-surface"): "coat tint on the base colour; near floor",
        ("CoatedGold", "openpbr"): "coat F0 0.04; floor",
        ("EdgeTintedCopper", "openpbr"): "no F82 tint",
        ("EdgeTintedCopper", "standard-surface"): "no edge tint; Gulbrandsen's curve vs Schlick",
        ("RoughDiffuse", "openpbr"): "base_diffuse_roughness ignored (Lambert)",
        ("RoughDiffuse", "standard-surface"): "diffuse_roughness ignored (Lambert)",
    }
    if (m, kind) in by:
        return by[(m, kind)]
    if kind == "standard-surface" and m in METALS + ("CoatedGold",):
        return "Gulbrandsen's metal Fresnel vs Schlick"
    return "floor"


def cmd_table(work, date, version, three_s, total_s):
    rows = load_rows(work)
    cases = json.load(open(cases_path(work)))
    done = {}
    with open(os.path.join(work, "three-done.jsonl")) as f:
        for line in f:
            d = json.loads(line)
            done[d["out"]] = d
    any_done = next(iter(done.values()))
    size = json.load(open(os.path.join(work, "client-jobs.json")))["jobs"][0]["size"]
    p = print
    wall, cpu = (float(x) for x in three_s.split())
    header = (
        "Measured by `make evaluation-clients` on %s: matremap %s; three.js r%s (%s backend of WebGPURenderer) in "
        "headless Chromium, %d², 2×2 supersampled, 4× MSAA each, %d renders in %.0f s wall-clock (%.0f s CPU of "
        "node); the whole run %s s. Each material of each document is opened by three.js's own loader and "
        "rendered on a unit sphere (the textured asset: on its meshes) under the HDR map, scaled to a mean "
        "luminance of %.1f, beside `matremap render` of the same material (the values the document holds; the "
        "asset itself for the textured one) with the same camera, map orientation and scale, %d environment "
        "samples and %d reflection samples. SSIM = matremap's SSIM over the object (object_metrics: the SSIM map "
        "within 5 pixels of a covered pixel, at the exposure that puts matremap's object at mid-grey); lum. = "
        "three.js's mean object luminance over matremap's. Warnings: what the loader reported for the document "
        "(MaterialXLoader's log; USDLoader's console)."
        % (date, version, any_done["revision"], any_done["backend"], size, len(done), wall, cpu, total_s,
           ENV_MEAN, ENV_SAMPLES, REFLECTION_SAMPLES))
    p(textwrap.fill(header, 115, break_on_hyphens=False))
    p()
    p("| material | document | SSIM studio | lum. studio | SSIM tabac | lum. tabac | residual | loader warnings |")
    p("|---|---|---:|---:|---:|---:|---|---|")
    for material in materials_in_order(cases):
        for case in [c for c in cases if c["material"] == material]:
            st, tb = (rows.get((material, case["kind"], case.get("variant"), env)) for env in ENVS)
            d = done.get(render_path(work, "three", case, "studio"), {})
            report = d.get("report", {})
            warns = sorted(set(report.get("warnings", []) + report.get("errors", []) +
                               [c for c in report.get("console", []) if "404" not in c]))
            ignored = [re.search(r'input "(\w+)" is currently ignored', w) for w in warns]
            short = ["ignored: " + ", ".join("`%s`" % g.group(1) for g in ignored if g)] if any(ignored) else []
            short += [w.replace("|", "/")[:80] for w, g in zip(warns, ignored) if not g]
            p("| %s | %s | %s | %s | %s | %s | %s | %s |" % (
                material, KINDS[case["kind"]][0] + (" — check: %s" % case["variant"] if case.get("variant") else ""),
                fmt(st, "ssim_object"), fmt(st, "luminance_ratio"),
                fmt(tb, "ssim_object"), fmt(tb, "luminance_ratio"), explanation(case),
                ", ".join(short) if short else "none"))


def main():
    cmd, args = sys.argv[1], sys.argv[2:]
    {"prepare": cmd_prepare, "jobs": cmd_jobs, "matremap": cmd_matremap, "metrics": cmd_metrics,
     "pictures": cmd_pictures, "table": cmd_table}[cmd](*args)


main()
