#!/usr/bin/python3
"""Independent reference values of the `blender-principled` model (src/brdf/blender_principled.c), written from the
Cycles sources of Blender 4.2 (kernel/svm/closure.h, the CLOSURE_BSDF_PRINCIPLED_ID case; closure/bsdf_microfacet.h
microfacet_fresnel, microfacet_ggx_preserve_energy, bsdf_microfacet_estimate_albedo and the setup_fresnel_*
functions; closure/bsdf_util.h closure_layering_weight, the F82-tint curve) and the model's doc block, without
reading blender_principled.c's arithmetic. Other routes to the same quantities: the dielectric Fresnel in its
textbook form (the s- and p-polarised amplitudes averaged), GGX D and Smith's Lambda written out, Cycles' layering
followed closure by closure (each closure's weight, its darkening from microfacet_ggx_preserve_energy, its albedo
estimate, closure_layering_weight as weight * (1 - max_c(albedo_c/weight_c))).

Where the model deviates from Cycles on purpose, this follows the model's documented choice:
  - Cycles' lookup tables (ggx_E, ggx_Eavg, ggx_gen_schlick_ior_s) -> the library's GGX albedo table
    (src/brdf/ggx_albedo_tables.h), parsed here and interpolated by this file's own code (linear in the square-root
    node coordinates); s = (E_F - F0 E)/((1 - F0) E) from it.
  - Cycles' fitted fresnel_dielectric_Fss -> the average 2 int F mu dmu; E_avg = 2 int E mu dmu. Both taken with the
    65-node Simpson rule the library uses for these averages (layering.c, brdf_internal.h; so that quadrature
    error does not enter the comparison); the integrands are this file's.
  - float -> double; CLOSURE_WEIGHT_CUTOFF not applied.
Cycles' own F82 average fresnel_f82_Fss, mix(F0, 1, 1/21) - b/126, is already the exact average: no substitution.
One point follows Cycles where the model first did not: bsdf_microfacet_setup_fresnel_dielectric (the coat) takes no
multiscatter flag and always calls microfacet_ggx_preserve_energy, so the coat keeps its energy compensation and
darkening with multiscatter = 0 (blender_principled.c was changed to match; the last parameter set checks it).

    tests/blender_principled_reference.py > tests/blender_principled_reference.txt

Each output line: the 17 packed values, wi (3, the view direction, Cycles' sd->wi), wo (3), then the expected
diffuse (3) and specular (3) parts. test_brdf's known_blender_principled_reference compares the model with them
(1e-6 relative); tests/blender_principled_reference.sh checks that this script still writes the committed file.
"""
import math
import os
import re
import sys

import numpy as np

ROOT = os.environ.get("MR_ROOT", os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))


def read_tables():
    src = open(os.path.join(ROOT, "src", "brdf", "ggx_albedo_tables.h")).read()
    sizes = dict((k, int(v)) for k, v in re.findall(r"#define MR_GGX_ALB_(\w+) (\d+)\b", src))

    def floats(name):
        start = src.index("static const float " + name + "[")
        body = src[src.index("{", src.index("=", start)):src.index("};", start)]
        body = re.sub(r"/\*.*?\*/", "", body, flags=re.S)
        nums = re.findall(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?f?", body)
        return np.array([np.float32(x.rstrip("f")) for x in nums], dtype=np.float64)

    d = floats("mr_ggx_alb_dielectric").reshape(sizes["N_ETA"], sizes["N_R"], sizes["N_MU"])
    o = floats("mr_ggx_alb_one").reshape(sizes["ONE_N_R"], sizes["N_MU"])
    return d, o


TAB_D, TAB_1 = read_tables()


def node(t, n):
    """Index and weight of a coordinate t in [0, 1] on n equally spaced nodes."""
    t = 0.0 if not t > 0.0 else min(t, 1.0)
    x = t * (n - 1)
    i = min(int(x), n - 2)
    return i, x - i


def coords_mu_r(mu, r, n_r):
    return node(math.sqrt(min(max(mu, 0.0), 1.0)), TAB_D.shape[2]), node(math.sqrt(max(r - 0.01, 0.0) / 0.99), n_r)


def bilinear(grid, mu, r):
    (i, a), (j, b) = coords_mu_r(mu, r, grid.shape[0])
    row0 = grid[j, i] * (1 - a) + grid[j, i + 1] * a
    row1 = grid[j + 1, i] * (1 - a) + grid[j + 1, i + 1] * a
    return row0 * (1 - b) + row1 * b


def E_one(mu, r):
    return bilinear(TAB_1, mu, r)


def E_diel(mu, r, eta):
    k, c = node(math.sqrt((eta - 1.0) / 2.0), TAB_D.shape[0])
    return bilinear(TAB_D[k], mu, r) * (1 - c) + bilinear(TAB_D[k + 1], mu, r) * c


def simpson_avg(fn):
    """2 int_0^1 fn(mu) mu dmu by the library's 65-node Simpson rule."""
    x = np.linspace(0.0, 1.0, 65)
    w = np.array([1.0 if i in (0, 64) else (4.0 if i % 2 else 2.0) for i in range(65)])
    return float(np.sum(w * 2.0 * x * np.array([fn(t) for t in x]))) / (3.0 * 64.0)


def fresnel(cos_i, eta):
    """Unpolarised dielectric Fresnel from the s and p amplitudes (Snell's law for cos_t)."""
    sin_t2 = (1.0 - cos_i * cos_i) / (eta * eta)
    if sin_t2 >= 1.0:
        return 1.0
    cos_t = math.sqrt(1.0 - sin_t2)
    rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return 0.5 * (rs * rs + rp * rp)


def ggx(alpha, wi, wo):
    """D G2 / (4 cos_i cos_o) written out, and cos(wi, h)."""
    h = (wi + wo) / np.linalg.norm(wi + wo)
    a2 = alpha * alpha
    ch = h[2]
    D = a2 / (math.pi * (ch * ch * (a2 - 1.0) + 1.0) ** 2)

    def Lam(w):
        tan2 = (1.0 - w[2] ** 2) / w[2] ** 2
        return (-1.0 + math.sqrt(1.0 + a2 * tan2)) / 2.0

    return D / (1.0 + Lam(wi) + Lam(wo)) / (4.0 * wi[2] * wo[2]), float(h @ wi)


def schlick(mu, f0):
    return f0 + (1.0 - f0) * (1.0 - mu) ** 5


def f82_b(f0, tint):
    mb = 1.0 / 7.0
    return schlick(mb, f0) * (1.0 - tint) / (mb * (1.0 - mb) ** 6)


class Closure:
    """One Cycles microfacet closure: weight (RGB, darkening included), fresnel(cos_h) (RGB), energy scale."""

    def __init__(self, weight, alpha, fresnel_fn, scale):
        self.weight, self.alpha, self.fresnel_fn, self.scale = np.array(weight), alpha, fresnel_fn, scale

    def eval(self, wi, wo):
        dv, ch = ggx(self.alpha, wi, wo)
        return self.weight * self.fresnel_fn(ch) * dv * self.scale


def preserve_energy(mu, r, fss):
    """microfacet_ggx_preserve_energy: energy_scale 1/E, weight *= (1 + F_ms (1 - E)/E)/(1/E)."""
    E = max(E_one(mu, r), 1e-6)
    E_avg = simpson_avg(lambda t: E_one(t, r))
    fss = np.array(fss, dtype=float)
    f_ms = fss * E_avg / (1.0 - fss * (1.0 - E_avg))
    energy_scale = 1.0 / E
    return (1.0 + f_ms * (1.0 - E) / E) / energy_scale, energy_scale


def gen_schlick_s(mu, r, eta, f0):
    """ggx_gen_schlick_ior_s's quantity from the library table: the lobe's mean of (F - F0)/(1 - F0)."""
    E = max(E_one(mu, r), 1e-6)
    return min(max((E_diel(mu, r, eta) - f0 * E) / ((1.0 - f0) * E), 0.0), 1.0)


def layer(weight, albedo):
    """closure_layering_weight: weight * saturate(1 - max_c(albedo_c / weight_c))."""
    ratio = [a / w if w != 0.0 else 0.0 for a, w in zip(albedo, weight)]
    return weight * min(max(1.0 - max(ratio), 0.0), 1.0)


def principled(p, wi, wo):
    mu = wi[2]
    base = np.array(p["base_color"])
    metallic, ms = p["metallic"], p["multiscatter"] >= 0.5
    r = max(p["roughness"], 0.01)
    alpha = r * r
    tint = np.array(p["specular_tint"])
    weight = np.ones(3)
    closures = []
    # Coat: GGX with dielectric Fresnel (bsdf_microfacet_setup_fresnel_dielectric)
    C = p["coat_weight"]
    if C > 0.0:
        rc, nc = max(p["coat_roughness"], 0.01), p["coat_ior"]
        # setup_fresnel_dielectric takes no multiscatter flag: the coat's energy is preserved in either mode
        dark, scale = preserve_energy(mu, rc, simpson_avg(lambda t: fresnel(max(t, 1e-9), nc)))
        w = C * weight * dark
        f0c = ((nc - 1.0) / (nc + 1.0)) ** 2
        est = f0c + (1.0 - f0c) * gen_schlick_s(mu, rc, nc, f0c) if nc > 1.0 else 0.0
        closures.append(Closure(w, rc * rc, lambda ch, nc=nc: fresnel(ch, nc) if nc > 1.0 else 0.0, scale))
        weight = layer(weight, w * est)
        cos_t = math.sqrt(1.0 - (1.0 - mu * mu) / (nc * nc))
        weight = weight * (1.0 + (np.array(p["coat_tint"]) ** (1.0 / cos_t) - 1.0) * C)
    # Metal: F82-tint (bsdf_microfacet_setup_fresnel_f82_tint)
    if metallic > 0.0:
        b = np.array([f82_b(f, t) for f, t in zip(base, np.minimum(tint, 1.0))])
        w, scale = metallic * weight, 1.0
        if ms:
            fss = base + (1.0 - base) / 21.0 - b / 126.0
            dark, scale = preserve_energy(mu, r, fss)
            w = w * dark
        closures.append(Closure(w, alpha, lambda ch, b=b: np.clip(
            np.array([schlick(ch, f) for f in base]) - b * ch * (1.0 - ch) ** 6, 0.0, 1.0), scale))
        weight = weight * (1.0 - metallic)
    # Dielectric specular: generalized Schlick with a negative exponent (the real Fresnel curve remapped)
    f0 = ((p["ior"] - 1.0) / (p["ior"] + 1.0)) ** 2
    if p["specular_ior_level"] != 0.5:
        f0 = min(f0 * 2.0 * p["specular_ior_level"], 0.99)
    eta = (1.0 + math.sqrt(f0)) / (1.0 - math.sqrt(f0))
    if eta != 1.0:
        F0 = f0 * tint

        def remap(x):
            return min(max((x - f0) / (1.0 - f0), 0.0), 1.0)

        w, scale = weight.copy(), 1.0
        if ms:
            fss = F0 + (1.0 - F0) * remap(simpson_avg(lambda t: fresnel(max(t, 1e-9), eta)))
            dark, scale = preserve_energy(mu, r, fss)
            w = w * dark
        closures.append(Closure(w, alpha, lambda ch: F0 + (1.0 - F0) * remap(fresnel(ch, eta)), scale))
        est = F0 + (1.0 - F0) * gen_schlick_s(mu, r, eta, f0)
        weight = layer(weight, w * est)
    diffuse = weight * base / math.pi
    specular = sum((c.eval(wi, wo) for c in closures), np.zeros(3))
    return diffuse, specular


ORDER = [("base_color", 3), ("metallic", 1), ("roughness", 1), ("ior", 1), ("specular_ior_level", 1),
         ("specular_tint", 3), ("coat_weight", 1), ("coat_roughness", 1), ("coat_ior", 1), ("coat_tint", 3),
         ("multiscatter", 1)]
DEFAULTS = {"base_color": [0.8] * 3, "metallic": 0.0, "roughness": 0.5, "ior": 1.5, "specular_ior_level": 0.5,
            "specular_tint": [1.0] * 3, "coat_weight": 0.0, "coat_roughness": 0.03, "coat_ior": 1.5,
            "coat_tint": [1.0] * 3, "multiscatter": 1.0}
SETS = [
    {},
    {"multiscatter": 0.0},
    {"base_color": [0.6, 0.3, 0.1], "specular_tint": [1.0, 0.7, 0.4], "specular_ior_level": 0.7, "ior": 1.6,
     "roughness": 0.35},
    {"base_color": [0.2, 0.5, 0.7], "specular_tint": [0.5, 0.9, 1.0], "specular_ior_level": 0.3, "ior": 1.4,
     "roughness": 0.6, "multiscatter": 0.0},
    {"metallic": 1.0, "base_color": [0.95, 0.64, 0.54], "specular_tint": [0.9, 0.6, 0.8], "roughness": 0.3},
    {"metallic": 1.0, "base_color": [0.9, 0.85, 0.3], "specular_tint": [0.4, 0.8, 1.0], "roughness": 0.45,
     "multiscatter": 0.0},
    {"metallic": 0.4, "base_color": [0.3, 0.6, 0.9], "specular_tint": [0.8, 0.8, 0.5], "roughness": 0.25,
     "specular_ior_level": 0.65},
    {"coat_weight": 1.0, "coat_tint": [0.9, 0.7, 0.5], "coat_roughness": 0.2, "base_color": [0.5, 0.2, 0.1],
     "roughness": 0.5},
    {"coat_weight": 0.6, "coat_tint": [0.6, 0.8, 1.0], "coat_roughness": 0.35, "coat_ior": 1.8, "metallic": 1.0,
     "base_color": [0.9, 0.9, 0.9], "specular_tint": [1.0, 0.8, 0.6], "roughness": 0.4},
    {"coat_weight": 0.8, "coat_tint": [0.7, 0.9, 0.6], "coat_roughness": 0.1, "coat_ior": 1.4, "ior": 1.45,
     "specular_ior_level": 0.4, "specular_tint": [0.9, 1.0, 0.8], "base_color": [0.2, 0.8, 0.4],
     "roughness": 0.7, "multiscatter": 0.0},
]


def direction(theta_deg, phi_deg):
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])


PAIRS = [((0, 0), (0, 0)), ((30, 0), (30, 180)), ((50, 20), (35, 230)), ((70, 0), (20, 60)), ((15, 90), (75, 100)),
         ((80, 0), (80, 180)), ((85, 40), (60, 200))]


def main():
    for s in SETS:
        p = dict(DEFAULTS)
        p.update(s)
        packed = []
        for name, ch in ORDER:
            packed += list(p[name]) if ch == 3 else [p[name]]
        for a, b in PAIRS:
            wi, wo = direction(*a), direction(*b)
            d, sp = principled(p, wi, wo)
            row = packed + list(wi) + list(wo) + list(d) + list(sp)
            sys.stdout.write(" ".join("%.17g" % float(x) for x in row) + "\n")


if __name__ == "__main__":
    main()
