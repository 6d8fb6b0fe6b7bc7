#!/usr/bin/python3
"""Independent reference values of the `openpbr` model (src/brdf/openpbr.c), written from the OpenPBR Surface
1.1.1 specification's equations and the choices openpbr.c's doc block states, without reading that code's
arithmetic: other formulas for the same quantities where there are several (Walter's form of the dielectric
Fresnel, Smith's Lambda for the height-correlated G2, the Oren-Nayar albedo's <E> integrated numerically here
instead of the closed form). Only the albedo tables are shared: they are data (src/brdf/ggx_albedo_tables.h),
parsed here and interpolated by this file's own code.

    tests/openpbr_reference.py > tests/openpbr_reference.txt

Each output line: the 19 packed values, wi (3), wo (3), then the expected diffuse (3) and specular (3) parts.
test_brdf's known_openpbr_reference compares the model with them (1e-6 relative); tests/openpbr_reference.sh
checks that this script still writes the committed file.
"""
import math
import os
import re
import sys

import numpy as np

ROOT = os.environ.get("MR_ROOT", os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))


def load_tables():
    text = open(os.path.join(ROOT, "src", "brdf", "ggx_albedo_tables.h")).read()
    dims = {k: int(v) for k, v in re.findall(r"#define MR_GGX_ALB_(N_MU|N_R|N_ETA|ONE_N_R) (\d+)", text)}

    def array(name):
        body = text.split("static const float " + name + "[", 1)[1].split("= {", 1)[1].split("};", 1)[0]
        body = re.sub(r"/\*.*?\*/", "", body, flags=re.S)
        values = [float(x) for x in re.findall(r"[-+]?[0-9.]+(?:[eE][-+]?[0-9]+)?", body)]
        return np.array(values, dtype=np.float32).astype(np.float64)  # the C table is float

    diel = array("mr_ggx_alb_dielectric").reshape(dims["N_ETA"], dims["N_R"], dims["N_MU"])
    one = array("mr_ggx_alb_one").reshape(dims["ONE_N_R"], dims["N_MU"])
    return diel, one


DIEL, ONE = load_tables()
NE, NR, NT = DIEL.shape


def cell(x, n):
    """Node and fraction of the table coordinate x in [0, 1] (clamped) on n nodes."""
    x = min(max(x, 0.0), 1.0) * (n - 1)
    i = min(int(math.floor(x)), n - 2)
    return i, x - i


# Every axis of the tables is quadratic in its node index: mu = t^2, r = 0.01 + 0.99 t^2, eta = 1 + 2 t^2 (the
# white table ONE has more r nodes than the dielectric one).
def table_dielectric(mu, r, eps):
    it, a = cell(math.sqrt(min(max(mu, 0.0), 1.0)), NT)
    ir, b = cell(math.sqrt(max(r - 0.01, 0.0) / 0.99), NR)
    e = min(max(eps, 0.0), 0.5)
    ie, c = cell(math.sqrt(((1 + e) / (1 - e) - 1.0) / 2.0), NE)
    cube = DIEL[ie:ie + 2, ir:ir + 2, it:it + 2]
    w_t = np.array([1 - a, a])
    w_r = np.array([1 - b, b])
    w_e = np.array([1 - c, c])
    return float(np.einsum("erk,e,r,k->", cube, w_e, w_r, w_t))


def table_one(mu, r):
    it, a = cell(math.sqrt(min(max(mu, 0.0), 1.0)), NT)
    ir, b = cell(math.sqrt(max(r - 0.01, 0.0) / 0.99), ONE.shape[0])
    sq = ONE[ir:ir + 2, it:it + 2]
    return float(np.array([1 - b, b]) @ sq @ np.array([1 - a, a]))


def fresnel(c, eta):
    """Exact unpolarised dielectric Fresnel, Walter et al. 2007 eq. 22 form."""
    if eta == 1.0:
        return 0.0
    g2 = eta * eta - 1.0 + c * c
    g = math.sqrt(g2)
    a = (g - c) / (g + c)
    b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0)
    return min(max(0.5 * a * a * (1.0 + b * b), 0.0), 1.0)


def ggx_dv(alpha, wi, wo):
    h = wi + wo
    h /= np.linalg.norm(h)
    a2 = alpha * alpha
    c2 = h[2] * h[2]
    D = a2 / (math.pi * ((a2 - 1.0) * c2 + 1.0) ** 2)

    def lam(w):
        t2 = (1.0 - w[2] * w[2]) / (w[2] * w[2])
        return 0.5 * (math.sqrt(1.0 + a2 * t2) - 1.0)

    G2 = 1.0 / (1.0 + lam(wi) + lam(wo))
    return D * G2 / (4.0 * wi[2] * wo[2]), float(np.dot(wi, h))


def eon_G(mu):
    th = math.acos(mu)
    s = math.sin(th)
    return s * (th - s * mu) + (2.0 / 3.0) * math.tan(th) * (1.0 - s ** 3) - (2.0 / 3.0) * s


def eon_avg_G():
    # <E> = A + B/pi * 2 * int_0^1 G(mu) mu d mu, Gauss-Legendre in theta
    x, w = np.polynomial.legendre.leggauss(200)
    th = 0.25 * math.pi * (x + 1.0)
    vals = [eon_G(math.cos(t)) * math.cos(t) * math.sin(t) for t in th]
    return 2.0 * 0.25 * math.pi * float(np.dot(w, vals))


AVG_G = eon_avg_G()


def eon(rho, sigma, wi, wo):
    c1 = 0.5 - 2.0 / (3.0 * math.pi)
    A = 1.0 / (1.0 + c1 * sigma)
    B = sigma * A
    s = float(np.dot(wi, wo)) - wi[2] * wo[2]
    s_over_t = s / max(wi[2], wo[2]) if s > 0 else s
    f_on = rho / math.pi * (A + B * s_over_t)
    if sigma == 0.0:
        return f_on
    E_i = A + B / math.pi * eon_G(wi[2])
    E_o = A + B / math.pi * eon_G(wo[2])
    E_avg = A + B / math.pi * AVG_G
    rho_ms = rho * rho * E_avg / (1.0 - rho * (1.0 - E_avg))
    return f_on + rho_ms / math.pi * (1.0 - E_i) * (1.0 - E_o) / (1.0 - E_avg)


def schlick(mu, f0):
    return f0 + (1.0 - f0) * (1.0 - mu) ** 5


def f82(mu, f0, tint):
    mb = 1.0 / 7.0
    corr = mu * (1.0 - mu) ** 6 / (mb * (1.0 - mb) ** 6) * (schlick(mb, f0) - tint * schlick(mb, f0))
    return min(max(schlick(mu, f0) - corr, 0.0), 1.0)


def openpbr(p, wi, wo):
    w, C, M, sigma, xi = p["base_weight"], p["base_color"], p["base_metalness"], p["base_diffuse_roughness"], \
        p["specular_weight"]
    sc, rs, nb = p["specular_color"], max(p["specular_roughness"], 0.01), p["specular_ior"]
    cw, cc, rc, nc, dk = p["coat_weight"], p["coat_color"], p["coat_roughness"], p["coat_ior"], p["coat_darkening"]
    # Roughening
    rB = (1 - cw) * rs + cw * min(1.0, rs ** 4 + 2 * rc ** 4) ** 0.25
    # Specular IOR with the coat and the TIR fix, modulated by specular_weight
    eta_bc = nc / nb if nc > nb else nb / nc
    eta_s = (1 - cw) * nb + cw * eta_bc
    Fs = ((1 - eta_s) / (1 + eta_s)) ** 2
    xi_s = min(xi, 1 / Fs) if Fs > 0 else xi
    eps = math.copysign(1.0, eta_s - 1.0) * math.sqrt(xi_s * Fs)
    eta_p = (1 + eps) / (1 - eps)
    mu_v = wi[2]
    dv, cos_h = ggx_dv(rB * rB, wi, wo)
    E_spec = table_dielectric(mu_v, rB, eps)
    F_d = fresnel(cos_h, eta_p)
    E1 = max(table_one(mu_v, rB), 1e-6)
    diff = np.zeros(3)
    spec = np.zeros(3)
    for c in range(3):
        f0 = w * C[c]
        metal = xi * f82(cos_h, f0, sc[c]) * dv * (1 + xi * f0 * (1 - E1) / E1)
        diff[c] = (1 - M) * (1 - E_spec) * w * eon(C[c], sigma, wi, wo)
        spec[c] = (1 - M) * sc[c] * F_d * dv + M * metal
    if cw > 0:
        rcf = max(rc, 0.01)
        dvc, _ = ggx_dv(rcf * rcf, wi, wo)
        coat = cw * fresnel(cos_h, nc) * dvc
        E_coat = table_dielectric(mu_v, rcf, (nc - 1) / (nc + 1))
        mti = math.sqrt(1 - (1 - wi[2] ** 2) / nc ** 2)
        mto = math.sqrt(1 - (1 - wo[2] ** 2) / nc ** 2)
        EF = min(max(math.log((10893 * nc - 1438.2) / (-774.4 * nc ** 2 + 10212 * nc + 1)), 0.0), 1.0)
        Kr = 1 - (1 - EF) / nc ** 2
        Ks = fresnel(mu_v, nc)
        rd = (1 - min(max(xi_s * Fs, 0), 1)) * 1.0 + min(max(xi_s * Fs, 0), 1) * rs
        rb = (1 - M) * rd + M * rs
        K = (1 - rb) * Ks + rb * Kr
        E_spec1 = table_dielectric(1.0, rB, eps)
        for c in range(3):
            T = cc[c] ** (0.5 * (1 / mti + 1 / mto))
            Eb = (1 - M) * (E_spec1 + (1 - E_spec1) * w * C[c]) + M * xi * w * C[c]
            delta = (1 - K) / (1 - Eb * K)
            scale = (1 - cw + cw * T * (1 - E_coat)) * (1 - cw * dk + cw * dk * delta)
            diff[c] *= scale
            spec[c] = spec[c] * scale + coat
    return diff, spec


ORDER = [("base_weight", 1), ("base_color", 3), ("base_metalness", 1), ("base_diffuse_roughness", 1),
         ("specular_weight", 1), ("specular_color", 3), ("specular_roughness", 1), ("specular_ior", 1),
         ("coat_weight", 1), ("coat_color", 3), ("coat_roughness", 1), ("coat_ior", 1), ("coat_darkening", 1)]
DEFAULTS = {"base_weight": 1.0, "base_color": [0.8] * 3, "base_metalness": 0.0, "base_diffuse_roughness": 0.0,
            "specular_weight": 1.0, "specular_color": [1.0] * 3, "specular_roughness": 0.3, "specular_ior": 1.5,
            "coat_weight": 0.0, "coat_color": [1.0] * 3, "coat_roughness": 0.0, "coat_ior": 1.6, "coat_darkening": 1.0}
SETS = [
    {},
    {"base_color": [0.7, 0.4, 0.15], "base_diffuse_roughness": 0.8, "specular_roughness": 0.55, "specular_ior": 1.8},
    {"base_metalness": 1.0, "base_color": [0.95, 0.64, 0.54], "specular_color": [0.9, 0.85, 0.8],
     "specular_roughness": 0.35},
    {"base_metalness": 0.4, "base_weight": 0.9, "base_color": [0.3, 0.6, 0.9], "specular_weight": 0.6,
     "specular_roughness": 0.2, "base_diffuse_roughness": 0.3},
    {"coat_weight": 1.0, "coat_color": [0.9, 0.7, 0.5], "coat_roughness": 0.15, "base_color": [0.5, 0.2, 0.1],
     "specular_roughness": 0.5},
    {"coat_weight": 0.6, "coat_ior": 1.4, "coat_darkening": 0.5, "coat_roughness": 0.3, "base_metalness": 1.0,
     "base_color": [0.9, 0.9, 0.9], "specular_ior": 1.3, "specular_roughness": 0.25},
    {"coat_weight": 0.8, "coat_ior": 2.0, "specular_ior": 1.5, "specular_color": [0.6, 0.8, 1.0],
     "specular_roughness": 0.7, "base_diffuse_roughness": 1.0, "base_color": [0.2, 0.8, 0.4]},
]


def direction(theta_deg, phi_deg):
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])


PAIRS = [((0, 0), (0, 0)), ((30, 0), (30, 180)), ((50, 20), (35, 230)), ((70, 0), (20, 60)), ((15, 90), (75, 100)),
         ((60, 10), (60, 170))]


def main():
    out = sys.stdout
    for s in SETS:
        p = dict(DEFAULTS)
        p.update(s)
        packed = []
        for name, ch in ORDER:
            packed += list(p[name]) if ch == 3 else [p[name]]
        for a, b in PAIRS:
            wi, wo = direction(*a), direction(*b)
            d, sp = openpbr(p, wi, wo)
            row = packed + list(wi) + list(wo) + list(d) + list(sp)
            out.write(" ".join("%.17g" % float(x) for x in row) + "\n")


if __name__ == "__main__":
    main()
