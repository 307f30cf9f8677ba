#!/usr/bin/env python3
"""Render ptui's `cornell-mesh` scene with Mitsuba 3: an independent reference for tests/reference.rs.

The scene is read from the same TOML file ptui embeds (scenes/cornell-mesh.toml) and built quad by
quad with the same vertex order, so each face's normal is ptui's front normal (edge1 x edge2).
Mitsuba's `area` emitter is one-sided (it emits along the shape's normal), as ptui's emissive
quads are; `--two-sided` adds a flipped copy of each light just behind it, to match a renderer
whose emitters shine from both faces (a harness validation, not a reference).

Conventions matched to ptui (see docs/REFERENCES.md): pinhole camera from the scene's position,
look_at and up with the *vertical* field of view (`fov_axis = "y"`; Mitsuba's default is `x`),
box pixel filter, unbounded path depth with Russian roulette, emitters visible to the camera, no
environment, RGB variant with linear `rgb` reflectances, row 0 = top of the image.

The image is the mean of `--passes` independent passes (distinct seeds) of `--spp` samples each;
the spread of the passes gives each pixel's standard error, summarised as the RMSE of the
reference against the truth, written next to the EXR (same stem, `.txt`).

Run through harness/mitsuba_cornell_mesh.sh, which makes a virtual environment with Mitsuba.
"""

import argparse
import os
import sys
import tempfile
import tomllib

import numpy as np
from mitsuba_passes import Passes

VFOV_KEYS = {"position", "look_at", "up", "vfov", "near", "direction"}
QUAD_KEYS = {"name", "corner", "edge1", "edge2", "color", "emission", "material"}


class SceneFileError(Exception):
    pass


def fail(path, field, problem):
    raise SceneFileError(f"{path}: {field}: {problem}")


def vec3(path, field, value):
    if (
        not isinstance(value, list)
        or len(value) != 3
        or not all(isinstance(v, (int, float)) for v in value)
    ):
        fail(path, field, f"expected three numbers, got {value!r}")
    return np.array(value, dtype=np.float64)


def rgb(path, field, value):
    if isinstance(value, (int, float)):
        value = [value] * 3
    v = vec3(path, field, value)
    if (v < 0).any():
        fail(path, field, f"negative value {value!r}")
    return v


def load_toml(path):
    """A scene file's TOML, or a SceneFileError naming the file."""
    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
    except (OSError, tomllib.TOMLDecodeError) as e:
        raise SceneFileError(f"{path}: {e}") from e


def read_camera(path, desc):
    """The [camera] of a scene file's TOML `desc`, checked for what the harnesses support: a
    pinhole from position, look_at and up with a vertical field of view."""
    cam = desc.get("camera")
    if not isinstance(cam, dict):
        fail(path, "camera", "missing [camera] table")
    extra = set(cam) - VFOV_KEYS
    if extra:
        fail(path, "camera", f"unknown keys {sorted(extra)}")
    if "direction" in cam or cam.get("near", 0) != 0:
        fail(path, "camera", "only position/look_at/up/vfov with near = 0 are supported")
    for key in ("position", "look_at", "vfov"):
        if key not in cam:
            fail(path, f"camera.{key}", "missing")
    camera = {
        "position": vec3(path, "camera.position", cam["position"]),
        "look_at": vec3(path, "camera.look_at", cam["look_at"]),
        "up": vec3(path, "camera.up", cam.get("up", [0, 1, 0])),
        "vfov": float(cam["vfov"]),
    }
    if not 0 < camera["vfov"] < 180:
        fail(path, "camera.vfov", f"{camera['vfov']} is not in (0, 180) degrees")
    return camera


def base_scene(mi, camera, width, height):
    """A Mitsuba scene of ptui's conventions, without shapes or emitters: the `path` integrator,
    unbounded, emitters visible; a perspective sensor from `camera` with its vertical field of
    view (Mitsuba's default axis is x), independent samples, a box filter, linear float RGB."""
    T = mi.ScalarTransform4f
    return {
        "type": "scene",
        "integrator": {
            "type": "path",
            "max_depth": -1,  # unbounded; Russian roulette from depth 5 (Mitsuba's default)
            "hide_emitters": False,
        },
        "sensor": {
            "type": "perspective",
            "id": "camera",
            "fov": camera["vfov"],
            "fov_axis": "y",
            "near_clip": 1e-3,
            "far_clip": 1e6,
            "to_world": T().look_at(
                origin=camera["position"].tolist(),
                target=camera["look_at"].tolist(),
                up=camera["up"].tolist(),
            ),
            "sampler": {"type": "independent"},
            "film": {
                "type": "hdrfilm",
                "width": width,
                "height": height,
                "pixel_format": "rgb",
                "component_format": "float32",
                "rfilter": {"type": "box"},
            },
        },
    }


def read_scene(path):
    """The camera and quads of a ptui scene file, checked for what this harness supports."""
    desc = load_toml(path)
    unsupported = set(desc) - {"camera", "render", "quad"}
    if unsupported:
        fail(path, ", ".join(sorted(unsupported)), "not supported by this harness (quads only)")
    camera = read_camera(path, desc)
    quads = []
    for i, q in enumerate(desc.get("quad", [])):
        where = f"quad[{i}] ({q.get('name', 'unnamed')})"
        extra = set(q) - QUAD_KEYS
        if extra:
            fail(path, where, f"unknown keys {sorted(extra)}")
        if q.get("material", "diffuse") != "diffuse":
            fail(path, f"{where}.material", "only diffuse quads are supported")
        for key in ("corner", "edge1", "edge2"):
            if key not in q:
                fail(path, f"{where}.{key}", "missing")
        emission = rgb(path, f"{where}.emission", q.get("emission", 0))
        # ptui: emitters do not reflect unless given a colour; others default to grey 0.75.
        default_color = 0.0 if emission.max() > 0 else 0.75
        color = rgb(path, f"{where}.color", q.get("color", default_color))
        if (color > 1).any():
            fail(path, f"{where}.color", "reflectance above 1")
        quads.append(
            {
                "name": q.get("name", f"quad {i}"),
                "corner": vec3(path, f"{where}.corner", q["corner"]),
                "edge1": vec3(path, f"{where}.edge1", q["edge1"]),
                "edge2": vec3(path, f"{where}.edge2", q["edge2"]),
                "color": color,
                "emission": emission,
            }
        )
    if not any(q["emission"].max() > 0 for q in quads):
        fail(path, "quad", "no emissive quad")
    return camera, quads


def quad_vertices(q, flip=False, offset=None):
    """ptui's parallelogram: corner, corner + edge1, corner + edge1 + edge2, corner + edge2, so the
    triangles (0, 1, 2), (0, 2, 3) face along edge1 x edge2. `flip` reverses the winding."""
    c, e1, e2 = q["corner"], q["edge1"], q["edge2"]
    v = np.array([c, c + e1, c + e1 + e2, c + e2])
    if flip:
        v = v[[0, 3, 2, 1]]
    if offset is not None:
        v = v + offset
    return v


def write_ply(path, vertices):
    """An ASCII PLY of one quad as two triangles, no normals (Mitsuba then uses face normals)."""
    with open(path, "w") as f:
        f.write("ply\nformat ascii 1.0\n")
        f.write(f"element vertex {len(vertices)}\n")
        f.write("property float x\nproperty float y\nproperty float z\n")
        f.write("element face 2\nproperty list uchar int vertex_indices\nend_header\n")
        for p in vertices:
            f.write(" ".join(repr(float(x)) for x in p) + "\n")
        f.write("3 0 1 2\n3 0 2 3\n")


def build_scene(mi, camera, quads, width, height, workdir, two_sided):
    scene = base_scene(mi, camera, width, height)
    lights = []
    for i, q in enumerate(quads):
        copies = [(False, None)]
        if two_sided and q["emission"].max() > 0:
            # Mitsuba's emitters are one-sided: a second copy facing the other way, a hair
            # behind the first (same plane would make the two fight for every hit), emits to the
            # back. 0.002 mm is ~30 float32 ulps at 550 mm and 2% of this light's gap.
            n = np.cross(q["edge1"], q["edge2"])
            copies.append((True, -2e-3 * n / np.linalg.norm(n)))
        for k, (flip, offset) in enumerate(copies):
            ply = os.path.join(workdir, f"quad{i}_{k}.ply")
            write_ply(ply, quad_vertices(q, flip, offset))
            shape = {
                "type": "ply",
                "filename": ply,
                "face_normals": True,
                "bsdf": {
                    "type": "diffuse",
                    "reflectance": {"type": "rgb", "value": q["color"].tolist()},
                },
            }
            if q["emission"].max() > 0:
                shape["emitter"] = {
                    "type": "area",
                    "radiance": {"type": "rgb", "value": q["emission"].tolist()},
                }
                lights.append((f"q{i}_{k}", q, flip))
            scene[f"q{i}_{k}"] = shape
    return scene, lights


def check_conventions(mi, scene, lights):
    """Fail loudly if Mitsuba would not render what ptui does: each light's face normal must be
    ptui's front normal (flipped for the two-sided copy), and `rgb` values must come back
    unchanged (linear, not upsampled or converted)."""
    shapes = {s.id(): s for s in scene.shapes()}
    for sid, q, flip in lights:
        params = mi.traverse(shapes[sid])
        pos = np.array(params["vertex_positions"], dtype=np.float64).reshape(-1, 3)
        faces = np.array(params["faces"]).reshape(-1, 3)
        want = np.cross(q["edge1"], q["edge2"])
        want = -want if flip else want
        want /= np.linalg.norm(want)
        for f in faces:
            n = np.cross(pos[f[1]] - pos[f[0]], pos[f[2]] - pos[f[0]])
            n /= np.linalg.norm(n)
            if n.dot(want) < 1 - 1e-6:
                raise SystemExit(f"light {q['name']}: Mitsuba face normal {n} is not {want}")
        print(f"light {q['name']}{' (flipped copy)' if flip else ''}: normal {want}")
        # The radiance leaving the front face, straight along the normal (local +z).
        si = mi.SurfaceInteraction3f()
        si.wi = mi.ScalarVector3f(0, 0, 1)
        got = np.array(shapes[sid].emitter().eval(si), dtype=np.float64).ravel()
        if not np.allclose(got, q["emission"], rtol=1e-6):
            raise SystemExit(f"light {q['name']}: Mitsuba emits {got}, not {q['emission']}")
    for value in ([0.725, 0.71, 0.68], [0.14, 0.45, 0.091], [0.63, 0.065, 0.05]):
        tex = mi.load_dict({"type": "rgb", "value": value})
        got = np.array(tex.eval(mi.SurfaceInteraction3f()), dtype=np.float64).ravel()
        if not np.allclose(got, value, rtol=1e-6):
            raise SystemExit(f"Mitsuba's rgb texture turns {value} into {got}")


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.dirname(here)
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default=os.path.join(root, "scenes", "cornell-mesh.toml"))
    ap.add_argument("--out", default=os.path.join(root, "tests", "refs", "cornell-mesh.exr"))
    ap.add_argument("--width", type=int, default=320)
    ap.add_argument("--height", type=int, default=240)
    ap.add_argument("--spp", type=int, default=512, help="samples per pixel of each pass")
    ap.add_argument("--passes", type=int, default=16, help="independent passes (seeds)")
    ap.add_argument("--seed", type=int, default=0, help="seed of the first pass")
    ap.add_argument("--variant", default="scalar_rgb", choices=["scalar_rgb", "llvm_ad_rgb"])
    ap.add_argument(
        "--two-sided",
        action="store_true",
        help="lights shine from both faces (validation of a two-sided renderer)",
    )
    args = ap.parse_args()
    if args.passes < 2 or args.spp < 1 or args.width < 1 or args.height < 1:
        ap.error("need --passes >= 2 and positive --spp, --width, --height")

    import mitsuba as mi

    mi.set_variant(args.variant)
    try:
        camera, quads = read_scene(args.scene)
    except SceneFileError as e:
        sys.exit(str(e))

    with tempfile.TemporaryDirectory() as workdir:
        desc, lights = build_scene(
            mi, camera, quads, args.width, args.height, workdir, args.two_sided
        )
        scene = mi.load_dict(desc)
        check_conventions(mi, scene, lights)

        passes = Passes(mi, scene, args.spp, args.passes, args.seed)

    mean, w = passes.mean, args.width
    # The red wall (high x) must be on the left and the green one on the right, as ptui draws
    # this scene: redder on the left than on the right.
    left = mean[:, : w // 2].reshape(-1, 3).mean(0)
    right = mean[:, w // 2 :].reshape(-1, 3).mean(0)
    if not left[0] / left[1] > right[0] / right[1]:
        sys.exit(f"red wall not on the left: left half {left}, right half {right}")

    passes.write(
        mi,
        args.out,
        root,
        __file__,
        [
            f"scene = {os.path.relpath(args.scene, root)}",
            f"lights = {'two-sided (validation)' if args.two_sided else 'one-sided'}",
            f"renderer = Mitsuba {mi.__version__}, {args.variant}, path, max_depth -1, box filter",
        ],
    )


if __name__ == "__main__":
    main()
