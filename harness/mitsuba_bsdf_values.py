#!/usr/bin/env python3
"""Mitsuba 3's values of ptui's microfacet materials, direction by direction: the fixture
tests/refs/bsdf-values.tsv that tests/integration/bsdf_mitsuba.rs holds ptui's `Material::eval`
to (f cos and pdf), with no Monte Carlo noise in between.

Each case is a ptui material (its scene keys, as a scene file writes them), translated to
Mitsuba by the same `bsdf()` the reference harnesses use, and evaluated by Mitsuba's
`scalar_rgb` variant in the local frame (normal +z) at fixed direction pairs: random ones,
grazing ones, and ones near the specular reflection and refraction, where the lobes are.
Directions are rounded to float32 before both renderers see them, so both evaluate the same pair.

    target/mitsuba-venv/bin/python harness/mitsuba_bsdf_values.py   # writes the fixture
"""

import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mitsuba_mesh import material  # noqa: E402
from mitsuba_mesh import bsdf as mitsuba_bsdf  # noqa: E402
from mitsuba_passes import atomic_write_text  # noqa: E402

# (ptui's keys, pairs from below the surface too)
CASES = [
    ('material = "conductor", alpha = 0.05', False),
    ('material = "conductor", alpha = 0.3', False),
    ('material = "conductor", metal = "Au", alpha = 0.1', True),
    ('material = "conductor", metal = "Cu", alpha = 0.2, distribution = "beckmann"', False),
    ('material = "conductor", eta = [0.2, 0.9, 1.1], k = [3.9, 2.4, 2.1], alpha = 0.5, color = [0.9, 0.8, 0.7]', False),
    ('material = "conductor", metal = "Al", alpha_u = 0.05, alpha_v = 0.3', False),
    ('material = "conductor", alpha_u = 0.4, alpha_v = 0.1, distribution = "beckmann"', False),
    ('material = "glass", alpha = 0.1', True),
    ('material = "glass", alpha = 0.4, ior = 1.33, distribution = "beckmann", color = [0.9, 0.95, 1.0]', True),
    ('material = "glass", alpha_u = 0.05, alpha_v = 0.2, ior = 1.7', True),
    ('material = "plastic", color = [0.6, 0.2, 0.1]', True),
    ('material = "plastic", color = [0.1, 0.3, 0.5], ior = 1.7, specular = 0.5', False),
    ('material = "plastic", alpha = 0.1, color = [0.6, 0.06, 0.05]', True),
    ('material = "plastic", alpha = 0.3, ior = 1.33, color = 0.8, distribution = "beckmann"', False),
]
PAIRS = 48


def parse_keys(keys):
    """The case's keys as the dict a TOML table would give."""
    import tomllib

    return tomllib.loads("x = {" + keys + "}")["x"]


def f32(v):
    return np.array(v, dtype=np.float32).astype(np.float64)


def unit(v):
    return f32(v / np.linalg.norm(v))


def pairs(rng, glass, below):
    """Direction pairs (wo towards the viewer, wi the other), float32-exact and unit."""
    out = []
    for i in range(PAIRS):
        cos_o = rng.uniform(0.02, 1.0) if i % 6 else rng.uniform(1e-3, 0.05)
        phi = rng.uniform(0, 2 * math.pi)
        s = math.sqrt(1 - cos_o * cos_o)
        wo = np.array([s * math.cos(phi), s * math.sin(phi), cos_o])
        if below and i % 2:
            wo[2] = -wo[2]
        kind = i % 3
        if kind == 0:
            wi = rng.normal(size=3)
        elif kind == 1:
            # Near the mirror direction.
            wi = np.array([-wo[0], -wo[1], wo[2]]) + rng.normal(scale=0.08, size=3)
        else:
            if glass:
                # Near the refracted direction (ior about 1.5), on the other side.
                wi = np.array([-wo[0] / 1.5, -wo[1] / 1.5, 0.0])
                wi[2] = -math.copysign(math.sqrt(max(0.0, 1 - wi[0] ** 2 - wi[1] ** 2)), wo[2])
                wi = wi + rng.normal(scale=0.08, size=3)
            else:
                wi = rng.normal(size=3)
                wi[2] = abs(wi[2]) * math.copysign(1, wo[2])
        if not glass:
            wi[2] = abs(wi[2]) * math.copysign(1, wo[2])
        out.append((unit(wo), unit(wi)))
    return out


def main():
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    here = os.path.dirname(os.path.abspath(__file__))
    out_path = os.path.join(os.path.dirname(here), "tests", "refs", "bsdf-values.tsv")
    rng = np.random.default_rng(20261206)
    lines = [
        "# Mitsuba 3's f cos and pdf of ptui materials, local frame (normal +z); written by",
        f"# harness/mitsuba_bsdf_values.py with Mitsuba {mi.__version__} scalar_rgb; do not edit.",
        "# keys\two_x\two_y\two_z\twi_x\twi_y\twi_z\tf_r\tf_g\tf_b\tpdf",
    ]
    ctx = mi.BSDFContext()
    for keys, below in CASES:
        d = parse_keys(keys)
        m = material("case", keys, d, emissive_allowed=False)
        b = mi.load_dict(mitsuba_bsdf(m))
        for wo, wi in pairs(rng, m["kind"] == "glass", below):
            si = mi.SurfaceInteraction3f()
            si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
            si.wi = mi.Vector3f(*wo)
            f = np.array(b.eval(ctx, si, mi.Vector3f(*wi)), dtype=np.float64).ravel()
            pdf = float(np.array(b.pdf(ctx, si, mi.Vector3f(*wi))).ravel()[0])
            row = [keys] + [repr(float(x)) for x in list(wo) + list(wi) + list(f)] + [repr(pdf)]
            lines.append("\t".join(row))
    atomic_write_text(out_path, "\n".join(lines) + "\n")
    print(f"wrote {out_path}: {len(lines) - 3} values of {len(CASES)} materials")


if __name__ == "__main__":
    main()
