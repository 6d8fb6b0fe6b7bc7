#!/usr/bin/env python3
"""standard_surface_reference.py -- an independent evaluation of the `standard-surface` model (Autodesk Standard
Surface 1.0.1, src/brdf/standard_surface.c) from the specification's formulas, compared with the library.

Written apart from the C code and in other algebra where there is a choice: the dielectric Fresnel in the
Cook-Torrance g-form, the conductor Fresnel with complex arithmetic (cos_t = sqrt(1 - sin^2/(n + ik)^2)), Smith's
height-correlated G2 from the Lambdas, GGX D in its (alpha^2 - 1) cos^2 + 1 form, Oren-Nayar from the angles.
Shared by definition: Gulbrandsen's (r, g) -> (n, k) map (one formula) and the directional albedo table of all
layered models, src/brdf/ggx_albedo_tables.h (mr_ggx_alb_dielectric), with the interpolation the model file and
brdf_internal.h document (linear in sqrt(mu), sqrt((r - 0.01)/0.99), sqrt((eta - 1)/2), in double: until issue 31
the model stored the (r, eta) blend as float curves, and this script rounded it likewise).

Usage: standard_surface_reference.py ROOT DRIVER   (DRIVER: tests/lib/brdf_eval.c built against the library)
Prints ok/FAIL lines and "N passed, N failed"; exit status 1 on any failure. Tolerance: 1e-6 relative.
"""
import cmath
import math
import re
import subprocess
import sys

import numpy as np

TOL = 1e-6

DEFAULTS = {
    "base": 1.0, "base_color": (0.8, 0.8, 0.8), "diffuse_roughness": 0.0, "metalness": 0.0, "specular": 1.0,
    "specular_color": (1.0, 1.0, 1.0), "specular_roughness": 0.2, "specular_ior": 1.5, "coat": 0.0,
    "coat_color": (1.0, 1.0, 1.0), "coat_roughness": 0.1, "coat_ior": 1.5, "coat_affect_color": 0.0,
    "coat_affect_roughness": 0.0,
}

CASES = [
    "",
    "base_color=0.9,0.5,0.2 metalness=1 specular_color=0.9,0.8,0.3 specular_roughness=0.35",
    "metalness=0.4 base_color=0.3,0.6,0.8 diffuse_roughness=0.7 specular_ior=1.8 specular_roughness=0.5 coat=0.7 "
    "coat_color=0.9,0.7,0.5 coat_roughness=0.15 coat_ior=1.45",
    "coat=1 coat_affect_color=0.6 coat_affect_roughness=0.8 coat_roughness=0.4 base_color=0.2,0.4,0.6 specular=0.6 "
    "specular_color=1,0.8,0.6",
    "specular_ior=1.05 specular_roughness=0.03 base=0.7 diffuse_roughness=1 metalness=0.2",
    "base_color=1 specular_ior=2.6 specular_roughness=0.9 coat=0.3 coat_ior=2.2 coat_roughness=0.8",
]


def unit(theta, phi):
    return (math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta))


PAIRS = [
    (unit(0.0, 0.0), unit(0.0, 0.0)),
    (unit(0.5, 0.0), unit(0.5, math.pi)),
    (unit(1.2, 0.3), unit(0.4, 2.0)),
    (unit(1.4, 0.0), unit(1.39, 3.1)),
    (unit(0.2, 1.0), unit(1.0, 1.5)),
    (unit(0.9, 0.0), unit(0.7, 0.2)),
]


def load_table(root):
    text = open(root + "/src/brdf/ggx_albedo_tables.h").read()
    dims = [int(re.search(r"#define MR_GGX_ALB_N_%s (\d+)" % k, text).group(1)) for k in ("ETA", "R", "MU")]
    body = text[text.index("static const float mr_ggx_alb_dielectric["):]
    body = body[body.index("=") + 1:body.index("};")]
    body = re.sub(r"/\*.*?\*/", "", body, flags=re.S)
    values = [float(x) for x in re.findall(r"[-+]?[0-9.]+(?:[eE][-+]?[0-9]+)?", body)]
    return np.array(values, dtype=np.float32).astype(np.float64).reshape(dims)


def cell(x, n):
    t = min(max(x, 0.0), 1.0) * (n - 1)
    i = min(int(t), n - 2)
    return i, t - i


def albedo(table, mu, r, eta):
    n_eta, n_r, n_mu = table.shape
    jr, fr = cell(math.sqrt(max(r - 0.01, 0.0) / 0.99), n_r)
    je, fe = cell(math.sqrt(max(eta - 1.0, 0.0) / 2.0), n_eta)
    curve = ((1 - fe) * ((1 - fr) * table[je, jr] + fr * table[je, jr + 1]) +
             fe * ((1 - fr) * table[je + 1, jr] + fr * table[je + 1, jr + 1]))
    i, u = cell(math.sqrt(min(mu, 1.0)), n_mu)
    return (1 - u) * curve[i] + u * curve[i + 1]


def fresnel_dielectric(c, eta):  # Cook-Torrance form
    g = math.sqrt(eta * eta - 1.0 + c * c)
    a = (g - c) / (g + c)
    b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0)
    return 0.5 * a * a * (1.0 + b * b)


def fresnel_conductor(c, n, k):  # complex index, s and p amplitudes
    eta = complex(n, k)
    s2 = 1.0 - c * c
    ct = cmath.sqrt(1.0 - s2 / (eta * eta))
    rs = (c - eta * ct) / (c + eta * ct)
    rp = (eta * c - ct) / (eta * c + ct)
    return 0.5 * (abs(rs) ** 2 + abs(rp) ** 2)


def artistic_ior(r, g):  # Gulbrandsen 2014
    r = min(max(r, 0.0), 1.0 - 1e-9)
    n_min = (1 - r) / (1 + r)
    n_max = (1 + math.sqrt(r)) / (1 - math.sqrt(r))
    n = g * n_min + (1 - g) * n_max
    k2 = ((n + 1) ** 2 * r - (n - 1) ** 2) / (1 - r)
    return n, math.sqrt(max(k2, 0.0))


def ggx_lobe(alpha, wi, wo):  # D G2 / (4 cos_i cos_o), and wi.h
    h = [wi[j] + wo[j] for j in range(3)]
    hl = math.sqrt(sum(x * x for x in h))
    h = [x / hl for x in h]
    a2 = alpha * alpha
    D = a2 / (math.pi * ((a2 - 1.0) * h[2] * h[2] + 1.0) ** 2)

    def lam(z):
        t2 = (1.0 - z * z) / (z * z)
        return 0.5 * (-1.0 + math.sqrt(1.0 + a2 * t2))

    G2 = 1.0 / (1.0 + lam(wi[2]) + lam(wo[2]))
    return D * G2 / (4.0 * wi[2] * wo[2]), sum(wi[j] * h[j] for j in range(3))


def oren_nayar(sigma, wi, wo):
    s2 = sigma * sigma
    A = 1.0 - 0.5 * s2 / (s2 + 0.33)
    B = 0.45 * s2 / (s2 + 0.09)
    ti, to = math.acos(wi[2]), math.acos(wo[2])
    if math.sin(ti) < 1e-12 or math.sin(to) < 1e-12:
        cos_dphi = 0.0
    else:
        cos_dphi = (wi[0] * wo[0] + wi[1] * wo[1]) / (math.sin(ti) * math.sin(to))
    return (A + B * max(0.0, cos_dphi) * math.sin(max(ti, to)) * math.tan(min(ti, to))) / math.pi


def parse(assignments):
    p = dict(DEFAULTS)
    for a in assignments.split():
        name, value = a.split("=")
        vals = tuple(float(x) for x in value.split(","))
        if isinstance(DEFAULTS[name], tuple):
            p[name] = vals * 3 if len(vals) == 1 else vals
        else:
            p[name] = vals[0]
    return p


def evaluate(table, p, wi, wo):
    """The specification's closure tree, transmission/sheen/subsurface/emission 0, opacity 1."""
    coat = p["coat"]
    rough_s = p["specular_roughness"]
    rough_s = rough_s + (1.0 - rough_s) * coat * p["coat_affect_roughness"] * p["coat_roughness"]
    rough_c = p["coat_roughness"]
    mu = wi[2]
    e_s = albedo(table, mu, rough_s, p["specular_ior"])
    e_c = albedo(table, mu, rough_c, p["coat_ior"])
    lobe_s, c_h = ggx_lobe(rough_s ** 2, wi, wo)
    lobe_c, _ = ggx_lobe(rough_c ** 2, wi, wo)
    specular_brdf = fresnel_dielectric(c_h, p["specular_ior"]) * lobe_s
    coat_brdf = fresnel_dielectric(c_h, p["coat_ior"]) * lobe_c
    diffuse_brdf = oren_nayar(p["diffuse_roughness"], wi, wo)
    m = p["metalness"]
    d, s = [], []
    for c in range(3):
        sw = p["specular"] * p["specular_color"][c]
        n, k = artistic_ior(p["base"] * p["base_color"][c], sw)
        metal_brdf = fresnel_conductor(c_h, n, k) * lobe_s
        bc = p["base_color"][c] ** (1.0 + coat * p["coat_affect_color"])
        below = (1.0 - coat) + coat * p["coat_color"][c] * (1.0 - e_c)
        d.append(below * (1.0 - m) * (1.0 - sw * e_s) * p["base"] * bc * diffuse_brdf)
        s.append(coat * coat_brdf + below * (m * metal_brdf + (1.0 - m) * sw * specular_brdf))
    return d + s


def main():
    root, driver = sys.argv[1], sys.argv[2]
    table = load_table(root)
    lines, expect = [], []
    for case in CASES:
        p = parse(case)
        for wi, wo in PAIRS:
            lines.append("standard-surface %s ; %.17g %.17g %.17g ; %.17g %.17g %.17g" % ((case,) + wi + wo))
            expect.append((case, wi, wo, evaluate(table, p, wi, wo)))
    out = subprocess.run([driver], input="\n".join(lines) + "\n", capture_output=True, text=True, check=True)
    got = out.stdout.splitlines()
    passed = failed = 0
    worst = 0.0
    for idx, (case, wi, wo, want) in enumerate(expect):
        values = [float(x) for x in got[idx].split()] if idx < len(got) and not got[idx].startswith("error") else []
        if len(values) != 6:
            print("FAIL  case %d: driver said %r" % (idx, got[idx] if idx < len(got) else None))
            failed += 1
            continue
        rel = max(abs(a - b) / max(abs(b), 1e-300) if b != 0.0 else abs(a) for a, b in zip(values, want))
        worst = max(worst, rel)
        label = "case %2d [%s] wi.z %.3f wo.z %.3f" % (idx, case[:40] or "defaults", wi[2], wo[2])
        if rel <= TOL:
            passed += 1
        else:
            failed += 1
            print("FAIL  %s: relative difference %.3g\n      C      %s\n      python %s" % (label, rel, values, want))
    print("ok    %d evaluations agree with the independent python evaluation (worst relative difference %.2g)"
          % (passed, worst))
    print("%d passed, %d failed" % (passed, failed))
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
