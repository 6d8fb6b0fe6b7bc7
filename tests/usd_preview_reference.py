#!/usr/bin/env python3
"""usd_preview_reference.py -- UsdPreviewSurface 2.5 written out again, independently of src/brdf/usd_preview.c.

The formulas come from OpenUSD's docs/spec_usdpreviewsurface.rst (inputs diffuseColor, useSpecularWorkflow,
specularColor, metallic, roughness, clearcoat, clearcoatRoughness, ior) with the lobe structure of Pixar's Storm
shader (previewSurface.glslfx) and the height-correlated Smith G2 of MaterialX, as src/brdf/usd_preview.c
documents. This script uses a different route through them on purpose: the half vector is normalised explicitly,
GGX D is written with n.h (not tan(theta_h)), G2 is the Smith height-correlated masking-shadowing function
1/(1 + Lambda(wi) + Lambda(wo)) divided by 4 n.l n.v, and the Fresnel mix is numpy's interpolation.

Prints one line per case: 12 parameter values in the model's packed order (diffuse_color RGB,
use_specular_workflow, specular_color RGB, metallic, roughness, clearcoat, clearcoat_roughness, ior), wi (3), wo (3),
then f_r's diffuse RGB and specular RGB, every number with 17 significant digits. tests/test_brdf.c
(known_usd_preview_matches_python) reads them and compares them with the model at 1e-6 relative.
Needs Debian's python3-numpy.
"""
import numpy as np


def ggx_d(alpha, n_dot_h):
    a2 = alpha * alpha
    t = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0
    return a2 / (np.pi * t * t)


def smith_lambda(alpha, cos_t):
    tan2 = (1.0 - cos_t * cos_t) / (cos_t * cos_t)
    return 0.5 * (np.sqrt(1.0 + alpha * alpha * tan2) - 1.0)


def microfacet(alpha, wi, wo):
    """D G2 / (4 n.l n.v) for GGX with height-correlated Smith G2."""
    h = (wi + wo) / np.linalg.norm(wi + wo)
    g2 = 1.0 / (1.0 + smith_lambda(alpha, wi[2]) + smith_lambda(alpha, wo[2]))
    return ggx_d(alpha, h[2]) * g2 / (4.0 * wi[2] * wo[2])


def usd_preview(p, wi, wo):
    diffuse_color = np.array(p[0:3])
    specular_workflow = p[3] >= 0.5
    specular_color = np.array(p[4:7])
    metallic, roughness, clearcoat, clearcoat_roughness, ior = p[7:12]
    h = (wi + wo) / np.linalg.norm(wi + wo)
    fresnel = (1.0 - np.dot(wi, h)) ** 5  # Schlick's weight
    r2 = ((1.0 - ior) / (1.0 + ior)) ** 2
    if specular_workflow:
        f0, f90, weight = specular_color, np.ones(3), 1.0
    else:
        spec_color = (1.0 - metallic) * np.ones(3) + metallic * diffuse_color  # mix(1, albedo, metallic)
        f0 = (1.0 - metallic) * (r2 * spec_color) + metallic * spec_color  # mix(R^2 specColor, specColor, m)
        f90 = spec_color
        weight = 1.0 - metallic  # pure metals have no diffuse
    F = f0 * (1.0 - fresnel) + f90 * fresnel
    diffuse = weight * (1.0 - F) * diffuse_color / np.pi
    coat_f = r2 * (1.0 - fresnel) + fresnel
    specular = F * microfacet(roughness ** 2, wi, wo) + clearcoat * coat_f * microfacet(clearcoat_roughness ** 2,
                                                                                        wi, wo)
    return diffuse, specular


def direction(theta_deg, phi_deg):
    t, f = np.radians(theta_deg), np.radians(phi_deg)
    return np.array([np.sin(t) * np.cos(f), np.sin(t) * np.sin(f), np.cos(t)])


PARAMS = [
    # diffuse RGB,       spec wf, specular RGB,      metallic, rough, coat, coat rough, ior
    [0.18, 0.18, 0.18, 0, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.01, 1.5],  # the specification's fallbacks
    [0.9, 0.5, 0.1, 0, 0.0, 0.0, 0.0, 0.35, 0.4, 0.0, 0.2, 1.5],
    [0.8, 0.6, 0.3, 0, 0.0, 0.0, 0.0, 1.0, 0.25, 0.0, 0.2, 1.5],
    [0.2, 0.7, 0.4, 0, 0.0, 0.0, 0.0, 0.6, 0.7, 0.8, 0.15, 2.2],
    [0.6, 0.3, 0.9, 1, 0.04, 0.5, 0.9, 0.7, 0.3, 0.0, 0.1, 1.5],
    [0.5, 0.5, 0.2, 1, 0.9, 0.2, 0.05, 0.0, 0.8, 0.5, 0.3, 1.3],
    [0.3, 0.3, 0.3, 0, 0.0, 0.0, 0.0, 0.0, 0.05, 1.0, 0.6, 1.0],
]
PAIRS = [((0, 0), (0, 0)), ((30, 0), (30, 180)), ((60, 10), (20, 200)), ((75, 0), (75, 180)),
         ((45, 90), (80, 300)), ((10, 0), (70, 40)), ((85, 0), (40, 180))]

for p in PARAMS:
    for (ti, fi), (to, fo) in PAIRS:
        wi, wo = direction(ti, fi), direction(to, fo)
        d, s = usd_preview(p, wi, wo)
        numbers = list(p) + list(wi) + list(wo) + list(d) + list(s)
        print(" ".join("%.17g" % x for x in numbers))
