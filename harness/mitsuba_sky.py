#!/usr/bin/env python3
"""Render ptui's `sky` scene with Mitsuba 3: an independent reference for its environment light.

The scene is read from the TOML file ptui embeds (scenes/sky.toml): spheres (diffuse, mirror,
glass) lit only by the built-in sky map, which `cargo xtask sky-map` writes texel for texel.

The map's conventions are Mitsuba's `envmap` (ptui took them from it: u = atan2(d.x, -d.z) / 2pi,
v = acos(d.y) / pi, row 0 at the top). The one difference is the lookup. ptui holds each texel
constant over its cell: column floor(u W), row floor(v H). Mitsuba interpolates bilinearly between
samples placed at u = (x + 1/2) / W and v = y / (H - 1). So Mitsuba is not given the map itself
but the map resampled at its own sample positions, UPSAMPLE times finer (ptui's texel at each
position): between two samples it blends only across ptui's cell edges, over 1/UPSAMPLE of a
cell, and the blend is symmetric about the edge up to half a fine cell (0.04 degrees here).

Conventions matched to ptui (docs/REFERENCES.md): pinhole camera with the vertical field of view
(`fov_axis = "y"`), box pixel filter, unbounded depth with Russian roulette, the sky visible to
the camera, glass as `dielectric` between ptui's ior and vacuum (`ext_ior = 1`, not Mitsuba's
default air), mirror as a perfect `conductor` scaled by its colour, `scalar_rgb` (linear rgb).

Run through harness/mitsuba_sky.sh, which makes a virtual environment with Mitsuba.
"""

import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np
from mitsuba_cornell_mesh import (
    SceneFileError,
    base_scene,
    fail,
    load_toml,
    read_camera,
    rgb,
    vec3,
)
from mitsuba_mesh import DEFAULT_IOR, bsdf, xtask
from mitsuba_passes import Passes

UPSAMPLE = 8
SPHERE_KEYS = {"name", "center", "radius", "color", "material", "ior"}



def read_scene(path):
    """The environment, camera and spheres of a ptui scene file, checked for what this harness
    supports."""
    desc = load_toml(path)
    unsupported = set(desc) - {"environment", "camera", "render", "sphere"}
    if unsupported:
        fail(path, ", ".join(sorted(unsupported)), "not supported by this harness")
    env = desc.get("environment", {})
    if env.get("map") != "builtin:sky" or set(env) - {"map", "intensity"}:
        fail(path, "environment", 'only map = "builtin:sky" with an intensity is supported')
    intensity = float(env.get("intensity", 1.0))
    camera = read_camera(path, desc)
    spheres = []
    for i, s in enumerate(desc.get("sphere", [])):
        where = f"sphere[{i}] ({s.get('name', 'unnamed')})"
        extra = set(s) - SPHERE_KEYS
        if extra:
            fail(path, where, f"unknown keys {sorted(extra)}")
        material = s.get("material", "diffuse")
        if material not in ("diffuse", "mirror", "glass"):
            fail(path, f"{where}.material", f"{material!r} is not supported")
        color = rgb(path, f"{where}.color", s.get("color", 0.75))
        if material == "glass" and not np.allclose(color, 1):
            fail(path, f"{where}.color", "only clear glass (color = 1) is supported")
        spheres.append(
            {
                "name": s.get("name", f"sphere {i}"),
                "center": vec3(path, f"{where}.center", s["center"]),
                "radius": float(s["radius"]),
                "kind": material,
                "color": color,
                "ior": float(s.get("ior", DEFAULT_IOR)),
            }
        )
    return intensity, camera, spheres


def mitsuba_map(ptui_map):
    """ptui's piecewise-constant map sampled where Mitsuba's bilinear lookup puts its samples,
    UPSAMPLE times finer: column x at u = (x + 1/2) / W', row y at v = y / (H' - 1). Columns
    fall inside ptui's cells, so each blend is centred on a cell edge. Every UPSAMPLE-th row
    falls on an edge: it takes the mean of the two cells it parts, which centres those blends too
    (a row given either cell alone would shift the edge by half a fine row, and bias a gradient by
    1/(4 UPSAMPLE) of its step per cell: 0.3% of the sky's red, seen before this)."""
    h, w, _ = ptui_map.shape
    wf, hf = w * UPSAMPLE, h * UPSAMPLE + 1
    cols = ((np.arange(wf) + 0.5) / wf * w).astype(int)
    fine = ptui_map[:, cols]
    rows = np.minimum(np.arange(hf) // UPSAMPLE, h - 1)
    out = fine[rows]
    edges = np.arange(1, h) * UPSAMPLE
    out[edges] = 0.5 * (fine[np.arange(h - 1)] + fine[np.arange(1, h)])
    return np.ascontiguousarray(out)


def build_scene(mi, intensity, camera, spheres, sky, width, height):
    scene = base_scene(mi, camera, width, height)
    scene["sky"] = {
        "type": "envmap",
        "bitmap": mi.Bitmap(sky.astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB),
        "scale": intensity,
    }
    for i, s in enumerate(spheres):
        scene[f"sphere{i}"] = {
            "type": "sphere",
            "center": s["center"].tolist(),
            "radius": s["radius"],
            "bsdf": bsdf(s),
        }
    return scene


def check_conventions(mi, scene, ptui_map, intensity):
    """Fail loudly if Mitsuba would not see the sky ptui does: in directions well inside ptui's
    cells (away from the blends at their edges), Mitsuba's radiance must be ptui's texel times
    the intensity, and the sun must stand where ptui's map has it."""
    sky = next(e for e in scene.emitters() if "Environment" in str(e))
    h, w, _ = ptui_map.shape
    rng = np.random.default_rng(1)
    for _ in range(2000):
        x, y = rng.integers(w), rng.integers(h)
        # A point in the cell's middle half: at least a quarter cell from every edge.
        u = (x + rng.uniform(0.25, 0.75)) / w
        v = (y + rng.uniform(0.25, 0.75)) / h
        theta, phi = np.pi * v, 2 * np.pi * u
        d = [np.sin(phi) * np.sin(theta), np.cos(theta), -np.cos(phi) * np.sin(theta)]
        si = mi.SurfaceInteraction3f()
        si.wi = mi.ScalarVector3f(-np.array(d))
        got = np.array(sky.eval(si), dtype=np.float64).ravel()
        want = ptui_map[y, x] * intensity
        if not np.allclose(got, want, rtol=1e-4, atol=1e-6):
            raise SystemExit(f"sky at texel ({x}, {y}): Mitsuba {got}, ptui {want}")
    print("sky: Mitsuba's envmap reads ptui's texels inside their cells (2000 directions)")


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.dirname(here)
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default=os.path.join(root, "scenes", "sky.toml"))
    ap.add_argument("--out", default=os.path.join(root, "tests", "refs", "sky.exr"))
    ap.add_argument("--width", type=int, default=160)
    ap.add_argument("--height", type=int, default=120)
    ap.add_argument("--spp", type=int, default=1024, help="samples per pixel of each pass")
    ap.add_argument("--passes", type=int, default=32, help="independent passes (seeds)")
    ap.add_argument("--seed", type=int, default=0, help="seed of the first pass")
    ap.add_argument("--variant", default="scalar_rgb", choices=["scalar_rgb", "llvm_ad_rgb"])
    args = ap.parse_args()
    if args.passes < 2 or args.spp < 1 or args.width < 1 or args.height < 1:
        ap.error("need --passes >= 2 and positive --spp, --width, --height")

    import mitsuba as mi

    mi.set_variant(args.variant)
    try:
        intensity, camera, spheres = read_scene(args.scene)
    except SceneFileError as e:
        sys.exit(str(e))

    with tempfile.TemporaryDirectory() as workdir:
        exr = os.path.join(workdir, "sky.exr")
        subprocess.run(xtask() + ["sky-map", exr], check=True, cwd=root)
        ptui_map = np.array(mi.Bitmap(exr), dtype=np.float64)[:, :, :3]
    print(f"ptui's sky: {ptui_map.shape[1]}x{ptui_map.shape[0]}, given to Mitsuba "
          f"{UPSAMPLE}x finer")
    scene = mi.load_dict(
        build_scene(
            mi, intensity, camera, spheres, mitsuba_map(ptui_map), args.width, args.height
        )
    )
    check_conventions(mi, scene, ptui_map, intensity)
    passes = Passes(mi, scene, args.spp, args.passes, args.seed)
    passes.write(
        mi,
        args.out,
        root,
        __file__,
        [
            f"scene = {os.path.relpath(args.scene, root)}",
            f"sky = ptui's builtin:sky ({ptui_map.shape[1]}x{ptui_map.shape[0]}), "
            f"resampled {UPSAMPLE}x finer for Mitsuba's bilinear lookup",
            f"renderer = Mitsuba {mi.__version__}, {args.variant}, path, max_depth -1, box filter",
        ],
    )


if __name__ == "__main__":
    main()
