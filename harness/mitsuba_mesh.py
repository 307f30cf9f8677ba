#!/usr/bin/env python3
"""Render a ptui scene of quads, spheres and meshes with Mitsuba 3: references for
tests/integration/reference_mesh.rs (`torus-knot`, `spot`) and the equal-time runs of
harness/equal_time.sh.

The scene is read from the ptui scene file itself. Meshes come from ptui: `cargo xtask
export-meshes` writes each `[[mesh]]` as ptui places it (triangles, winding and shading normals),
so Mitsuba sees the same triangles and interpolates the same per-corner normals. What is matched,
and checked on the loaded Mitsuba scene before rendering (see docs/REFERENCES.md):

- quads: two triangles with ptui's vertex order, face normal edge1 x edge2 (an emissive quad's
  one-sided `area` emitter shines that way; its BSDF is black, as ptui's emitters do not reflect);
- diffuse: ptui's diffuse reflects on both faces, so Mitsuba's one-sided `diffuse` is wrapped in
  `twosided`; mirror: `conductor` with material "none" (reflectance 1) times the colour; glass:
  `dielectric` with ptui's ior inside and exactly 1.0 outside (Mitsuba's default outside is air,
  1.000277), both lobes times the colour, radiance scaled by 1/eta^2 on refraction as in ptui;
- `background`: a `constant` emitter (ptui's constant sky: seen by camera rays and lighting the
  scene; ptui finds it by BSDF sampling only, Mitsuba also by emitter sampling: same expectation);
- camera: `perspective`, fov_axis "y" with ptui's vertical fov, row 0 = top, world forward x up
  to the image's right; box pixel filter; `path` with max_depth -1, emitters visible.

Without --passes the script writes a reference: the mean of independent passes and its noise
estimate (`.txt` beside the EXR, `noise_rmse = ...`). With --time-spp it instead renders once at
that spp and prints the render's wall time and, with --reference, its RMSE (equal-time runs).
"""

import argparse
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
from mitsuba_cornell_mesh import (
    SceneFileError,
    base_scene,
    fail,
    load_toml,
    quad_vertices,
    read_camera,
    rgb,
    vec3,
    write_ply,
)
from mitsuba_passes import Passes

ROUGH_KEYS = {"alpha", "alpha_u", "alpha_v", "distribution", "eta", "k", "metal", "specular"}
MATERIAL_KEYS = {"color", "emission", "material", "ior", "name"} | ROUGH_KEYS
QUAD_KEYS = MATERIAL_KEYS | {"corner", "edge1", "edge2"}
SPHERE_KEYS = MATERIAL_KEYS | {"center", "radius"}
MESH_KEYS = MATERIAL_KEYS | {"path", "torus_knot", "smooth", "scale", "rotate", "translate"}
TOP_KEYS = {
    "camera", "render", "quad", "sphere", "mesh", "background", "environment", "accel", "check"
}
# ptui's defaults (src/scene/materials.rs): DEFAULT_COLOR, DEFAULT_IOR, DEFAULT_PLASTIC_IOR,
# and SPECULAR_ALPHA (src/material/mod.rs), below which a rough material is built smooth.
DEFAULT_COLOR = 0.75
DEFAULT_IOR = 1.5
DEFAULT_PLASTIC_IOR = 1.49
SPECULAR_ALPHA = 1e-4


def material(path, where, d, emissive_allowed):
    """ptui's material fields of one object, with ptui's defaults (src/scene/materials.rs; ptui
    itself rejects keys given to a material they do not apply to)."""
    emission = rgb(path, f"{where}.emission", d.get("emission", 0))
    if emission.max() > 0 and not emissive_allowed:
        fail(path, f"{where}.emission", "only quads and spheres may emit in this harness")
    kind = d.get("material", "diffuse")
    if kind not in ("diffuse", "mirror", "glass", "conductor", "plastic"):
        fail(path, f"{where}.material", f"{kind!r} is not a ptui material")
    if emission.max() > 0 and kind != "diffuse":
        fail(path, f"{where}.material", "an emitter must be diffuse")
    # ptui: emitters do not reflect unless given a colour; a conductor's colour is a factor on
    # its reflectance (default 1); others default to grey 0.75.
    default_color = 0.0 if emission.max() > 0 else 1.0 if kind == "conductor" else DEFAULT_COLOR
    color = rgb(path, f"{where}.color", d.get("color", default_color))
    if (color > 1).any():
        fail(path, f"{where}.color", "reflectance above 1")
    alpha_u = float(d.get("alpha_u", d.get("alpha", 0.0)))
    alpha_v = float(d.get("alpha_v", d.get("alpha", 0.0)))
    rough = max(alpha_u, alpha_v) >= SPECULAR_ALPHA
    return {
        "kind": kind,
        "color": color,
        "emission": emission,
        "ior": float(d.get("ior", DEFAULT_PLASTIC_IOR if kind == "plastic" else DEFAULT_IOR)),
        # Mitsuba clamps alpha to 1e-4 as ptui does above SPECULAR_ALPHA.
        "alpha_u": max(alpha_u, SPECULAR_ALPHA) if rough else 0.0,
        "alpha_v": max(alpha_v, SPECULAR_ALPHA) if rough else 0.0,
        "distribution": d.get("distribution", "ggx"),
        "metal": d.get("metal"),
        "eta": rgb(path, f"{where}.eta", d["eta"]) if "eta" in d else None,
        "k": rgb(path, f"{where}.k", d["k"]) if "k" in d else None,
        "specular": rgb(path, f"{where}.specular", d.get("specular", 1.0)),
    }


def read_scene(path):
    """The camera, background, quads, spheres and meshes of a ptui scene file, checked for what
    this harness supports."""
    desc = load_toml(path)
    unsupported = set(desc) - TOP_KEYS
    if unsupported:
        fail(path, ", ".join(sorted(unsupported)), "not supported by this harness")
    camera = read_camera(path, desc)
    background = rgb(path, "background", desc.get("background", 0))

    def entries(key, keys):
        for i, d in enumerate(desc.get(key, [])):
            where = f"{key}[{i}] ({d.get('name', 'unnamed')})"
            extra = set(d) - keys
            if extra:
                fail(path, where, f"unknown keys {sorted(extra)}")
            yield i, where, d

    quads = []
    for i, where, q in entries("quad", QUAD_KEYS):
        for key in ("corner", "edge1", "edge2"):
            if key not in q:
                fail(path, f"{where}.{key}", "missing")
        quads.append(
            {
                "name": q.get("name", f"quad {i}"),
                "corner": vec3(path, f"{where}.corner", q["corner"]),
                "edge1": vec3(path, f"{where}.edge1", q["edge1"]),
                "edge2": vec3(path, f"{where}.edge2", q["edge2"]),
                **material(path, where, q, emissive_allowed=True),
            }
        )
    spheres = []
    for i, where, s in entries("sphere", SPHERE_KEYS):
        radius = s.get("radius")
        if not isinstance(radius, (int, float)) or radius <= 0:
            fail(path, f"{where}.radius", f"expected a positive number, got {radius!r}")
        spheres.append(
            {
                "name": s.get("name", f"sphere {i}"),
                "center": vec3(path, f"{where}.center", s.get("center")),
                "radius": float(radius),
                **material(path, where, s, emissive_allowed=True),
            }
        )
    meshes = []
    for i, where, m in entries("mesh", MESH_KEYS):
        meshes.append(
            {
                "name": m.get("name", f"mesh {i}"),
                "index": i,
                **material(path, where, m, emissive_allowed=False),
            }
        )
    env = desc.get("environment")
    if env is not None and (env.get("map") != "builtin:sky" or set(env) - {"map", "intensity"}):
        fail(path, "environment", 'only map = "builtin:sky" with an intensity is supported')
    sky = None if env is None else float(env.get("intensity", 1.0))
    if sky is not None and background.max() > 0:
        fail(path, "background", "both a background and an environment")
    if not any(o["emission"].max() > 0 for o in quads + spheres) and sky is None:
        fail(path, "quad", "no emitter and no environment")
    return camera, (background, sky), quads, spheres, meshes


def read_ply_normals(path):
    """The vertex normals of a PLY written by `cargo xtask export-meshes` (None if flat)."""
    with open(path, "rb") as f:
        header = b""
        while not header.endswith(b"end_header\n"):
            line = f.readline()
            if not line:
                raise SystemExit(f"{path}: no end_header")
            header += line
        text = header.decode()
        n = int(text.split("element vertex ")[1].split()[0])
        if "property float nx" not in text:
            return None
        data = np.frombuffer(f.read(n * 24), dtype="<f4").reshape(n, 6)
    return data[:, 3:].astype(np.float64)


def roughness(m):
    """Mitsuba's roughness keys for a rough material: the distribution said outright (Mitsuba's
    default is Beckmann, ptui's GGX) and alpha or alpha_u/alpha_v."""
    out = {"distribution": m["distribution"]}
    if m["alpha_u"] == m["alpha_v"]:
        out["alpha"] = m["alpha_u"]
    else:
        out["alpha_u"], out["alpha_v"] = m["alpha_u"], m["alpha_v"]
    return out


def bsdf(m):
    """The Mitsuba BSDF of a ptui material. ptui's opaque materials scatter on both faces, so
    Mitsuba's one-sided ones are wrapped in `twosided`; every interface is against exactly 1.0
    outside (Mitsuba's default is air, 1.000277)."""
    rgbv = lambda v: {"type": "rgb", "value": [float(x) for x in v]}
    c = rgbv(m["color"])
    kind = m["kind"]
    rough = m.get("alpha_u", 0.0) > 0
    if kind == "diffuse":
        return {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": c}}
    if kind == "mirror":
        return {"type": "conductor", "material": "none", "specular_reflectance": c}
    if kind == "glass":
        out = {
            "type": "roughdielectric" if rough else "dielectric",
            "int_ior": m["ior"],
            "ext_ior": 1.0,
            "specular_reflectance": c,
            "specular_transmittance": c,
        }
        return {**out, **roughness(m)} if rough else out
    if kind == "conductor":
        out = {"type": "roughconductor" if rough else "conductor", "specular_reflectance": c}
        if m["metal"]:
            # Mitsuba's own spectral data for the metal, integrated to RGB by Mitsuba.
            out["material"] = m["metal"]
        elif m["eta"] is not None:
            out["eta"], out["k"] = rgbv(m["eta"]), rgbv(m["k"])
        else:
            out["material"] = "none"
        return {"type": "twosided", "bsdf": {**out, **roughness(m)} if rough else out}
    if kind == "plastic":
        out = {
            "type": "roughplastic" if rough else "plastic",
            "diffuse_reflectance": c,
            "specular_reflectance": rgbv(m["specular"]),
            "int_ior": m["ior"],
            "ext_ior": 1.0,
            "nonlinear": False,
        }
        return {"type": "twosided", "bsdf": {**out, **roughness(m)} if rough else out}
    raise SystemExit(f"no Mitsuba translation for material {kind!r}")


def xtask():
    """How to run ptui's xtask: $PTUI_XTASK (set by harness/mitsuba_env.sh), else cargo."""
    if os.environ.get("PTUI_XTASK"):
        return [os.environ["PTUI_XTASK"]]
    return ["cargo", "xtask"]


def export_meshes(scene_path, workdir, root):
    """Each [[mesh]] as ptui places it, by ptui's own code (cargo xtask export-meshes)."""
    subprocess.run(xtask() + ["export-meshes", scene_path, workdir], check=True, cwd=root)


def build_scene(mi, camera, background, quads, spheres, meshes, width, height, workdir, sky_map=None):
    """`background` is (constant colour, builtin:sky intensity or None); `sky_map` ptui's sky,
    as `cargo xtask sky-map` writes it, when the scene has one."""
    scene = base_scene(mi, camera, width, height)
    background, intensity = background
    if background.max() > 0:
        scene["sky"] = {"type": "constant", "radiance": {"type": "rgb", "value": background.tolist()}}
    if intensity is not None:
        from mitsuba_sky import mitsuba_map

        scene["sky"] = {
            "type": "envmap",
            "bitmap": mi.Bitmap(
                mitsuba_map(sky_map).astype(np.float32), pixel_format=mi.Bitmap.PixelFormat.RGB
            ),
            "scale": intensity,
        }
    for i, q in enumerate(quads):
        ply = os.path.join(workdir, f"quad{i}.ply")
        write_ply(ply, quad_vertices(q))
        shape = {"type": "ply", "filename": ply, "face_normals": True, "bsdf": bsdf(q)}
        if q["emission"].max() > 0:
            shape["emitter"] = {
                "type": "area",
                "radiance": {"type": "rgb", "value": q["emission"].tolist()},
            }
        scene[f"quad{i}"] = shape
    for i, s in enumerate(spheres):
        scene[f"sphere{i}"] = {
            "type": "sphere",
            "center": s["center"].tolist(),
            "radius": s["radius"],
            "bsdf": bsdf(s),
        }
        if s["emission"].max() > 0:
            # ptui's sphere lights are seen from outside here; Mitsuba's emit outwards.
            scene[f"sphere{i}"]["emitter"] = {
                "type": "area",
                "radiance": {"type": "rgb", "value": s["emission"].tolist()},
            }
    for m in meshes:
        ply = os.path.join(workdir, f"mesh{m['index']}.ply")
        normals = read_ply_normals(ply)
        m["ply_normals"] = normals
        scene[f"mesh{m['index']}"] = {
            "type": "ply",
            "filename": ply,
            # Smooth: interpolate the exported per-corner normals, as ptui does.
            "face_normals": normals is None,
            "bsdf": bsdf(m),
        }
    return scene


def check_conventions(mi, scene, camera, background, quads, spheres, meshes, sky_map=None):
    """Fail loudly if Mitsuba would not render what ptui does."""
    shapes = {s.id(): s for s in scene.shapes()}
    background, intensity = background
    if intensity is not None:
        from mitsuba_sky import check_conventions as check_sky

        check_sky(mi, scene, sky_map, intensity)
    # Lights: face normal edge1 x edge2, radiance the scene's along it.
    for i, q in enumerate(quads):
        if q["emission"].max() <= 0:
            continue
        shape = shapes[f"quad{i}"]
        params = mi.traverse(shape)
        pos = np.array(params["vertex_positions"], dtype=np.float64).reshape(-1, 3)
        faces = np.array(params["faces"]).reshape(-1, 3)
        want = np.cross(q["edge1"], q["edge2"])
        want /= np.linalg.norm(want)
        for f in faces:
            n = np.cross(pos[f[1]] - pos[f[0]], pos[f[2]] - pos[f[0]])
            n /= np.linalg.norm(n)
            if n.dot(want) < 1 - 1e-6:
                raise SystemExit(f"light {q['name']}: Mitsuba face normal {n} is not {want}")
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(0, 0, 1)
        got = np.array(shape.emitter().eval(si), dtype=np.float64).ravel()
        if not np.allclose(got, q["emission"], rtol=1e-6):
            raise SystemExit(f"light {q['name']}: Mitsuba emits {got}, not {q['emission']}")
        print(f"light {q['name']}: one-sided, normal {want}, radiance {got}")
    # The constant sky: the same radiance from every direction.
    emitters = [e for e in scene.emitters() if e.is_environment()]
    if background.max() > 0:
        if len(emitters) != 1:
            raise SystemExit(f"expected one constant emitter, found {len(emitters)}")
        si = mi.SurfaceInteraction3f()
        for d in ([0, 0, 1], [0, -1, 0], [0.6, 0.8, 0]):
            si.wi = mi.Vector3f(*d)
            got = np.array(emitters[0].eval(si), dtype=np.float64).ravel()
            if not np.allclose(got, background, rtol=1e-6):
                raise SystemExit(f"constant sky gives {got}, not {background}")
        print(f"background: constant {background}")
    elif emitters and intensity is None:
        raise SystemExit("an environment emitter in a scene without background")
    # Materials, each checked at normal incidence from the outside (local +z).
    ctx = mi.BSDFContext()
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    # Mitsuba merges meshes that have equal BSDFs (the merged shape has no id), so each
    # translation is checked on a BSDF loaded from the same description as the scene's.
    for obj in quads + spheres + meshes:
        kind = obj["kind"]
        b = mi.load_dict(bsdf(obj))
        c = obj["color"]
        if kind == "diffuse":
            # Both faces reflect: wi and wo below the surface as well as above.
            for z in (1, -1):
                si.wi = mi.Vector3f(0, 0, z)
                got = np.array(b.eval(ctx, si, mi.Vector3f(0, 0, z)), dtype=np.float64).ravel()
                if not np.allclose(got, c / math.pi, rtol=1e-5, atol=1e-7):
                    raise SystemExit(f"{obj['name']}: diffuse f cos {got} on side {z}, not {c / math.pi}")
            si.wi = mi.Vector3f(0, 0, 1)
        elif kind == "mirror":
            bs, w = b.sample(ctx, si, 0.5, mi.Point2f(0.5, 0.5))
            w = np.array(w, dtype=np.float64).ravel()
            if not np.allclose(w, c, rtol=1e-5):
                raise SystemExit(f"{obj['name']}: mirror weight {w}, not {c}")
        elif kind != "glass" or obj["alpha_u"] > 0:
            # The microfacet materials are compared with ptui value for value by
            # tests/integration/bsdf_mitsuba.rs (harness/mitsuba_bsdf_values.py); here: opaque
            # ones reflect alike on both faces, as ptui's do.
            if kind != "glass":
                wi = mi.Vector3f(0.3, 0.2, 0.932738)
                wo = mi.Vector3f(-0.4, 0.1, 0.911043)
                si.wi = wi
                up = np.array(b.eval(ctx, si, wo), dtype=np.float64).ravel()
                si.wi = mi.Vector3f(wi.x, wi.y, -wi.z)
                down = np.array(b.eval(ctx, si, mi.Vector3f(wo.x, wo.y, -wo.z)), dtype=np.float64).ravel()
                si.wi = mi.Vector3f(0, 0, 1)
                if not (up.max() > 0 and np.allclose(up, down, rtol=1e-5)):
                    raise SystemExit(f"{obj['name']}: {kind} not two-sided: {up} above, {down} below")
        else:
            ior = obj["ior"]
            r = ((ior - 1) / (ior + 1)) ** 2
            bs, w = b.sample(ctx, si, 0.5 * r, mi.Point2f(0.5, 0.5))
            w = np.array(w, dtype=np.float64).ravel()
            pdf = float(np.array(bs.pdf).ravel()[0])
            if not (np.allclose(w, c, rtol=1e-5) and abs(pdf - r) < 1e-5):
                raise SystemExit(f"{obj['name']}: glass reflection weight {w}, pdf {bs.pdf}; wanted {c}, {r}")
            bs, w = b.sample(ctx, si, 0.5 + 0.5 * r, mi.Point2f(0.5, 0.5))
            w = np.array(w, dtype=np.float64).ravel()
            eta = float(np.array(bs.eta).ravel()[0])
            if abs(eta - ior) > 1e-6 or not np.allclose(w, c / ior**2, rtol=1e-5):
                raise SystemExit(f"{obj['name']}: glass refraction eta {eta}, weight {w}; wanted {ior}, {c / ior**2}")
        rough = f", alpha {obj['alpha_u']}x{obj['alpha_v']} {obj['distribution']}" if obj["alpha_u"] > 0 else ""
        print(f"{obj['name']}: {kind} {c}" + (f", ior {obj['ior']} in 1.0" if kind in ("glass", "plastic") else "") + rough)
    # Meshes: Mitsuba holds the exported normals (smooth) or none (flat).
    for m in meshes:
        sid = f"mesh{m['index']}"
        if sid not in shapes:
            raise SystemExit(f"{m['name']}: merged with another shape by Mitsuba, cannot check")
        params = mi.traverse(shapes[sid])
        has = "vertex_normals" in params.keys() and len(np.array(params["vertex_normals"])) > 0
        want = m["ply_normals"]
        if (want is not None) != has:
            raise SystemExit(f"{m['name']}: Mitsuba vertex normals {has}, ptui's {want is not None}")
        if want is not None:
            got = np.array(params["vertex_normals"], dtype=np.float64).reshape(-1, 3)
            dev = np.abs(got - want).max()
            if dev > 1e-5:
                raise SystemExit(f"{m['name']}: Mitsuba's vertex normals differ from ptui's by {dev}")
        n = len(np.array(params["faces"])) // 3
        print(f"{m['name']}: {n} triangles, {'ptui normals interpolated' if has else 'face normals'}")
    # rgb values come back as they are (linear, not upsampled or converted).
    for value in ([0.8, 0.45, 0.2], [0.05, 0.06, 0.08]):
        tex = mi.load_dict({"type": "rgb", "value": value})
        got = np.array(tex.eval(mi.SurfaceInteraction3f()), dtype=np.float64).ravel()
        if not np.allclose(got, value, rtol=1e-6):
            raise SystemExit(f"Mitsuba's rgb texture turns {value} into {got}")
    # Camera: the film's top row looks above the view axis, its right column to forward x up.
    sensor = scene.sensors()[0]
    fwd = camera["look_at"] - camera["position"]
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, camera["up"])
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    for pos, axis, what in (((0.5, 0.05), up, "top"), ((0.95, 0.5), right, "right")):
        ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f(*pos), mi.Point2f(0.5, 0.5))
        d = np.array(ray.d, dtype=np.float64).ravel()
        if d.dot(axis) <= 0:
            raise SystemExit(f"camera: the film's {what} looks along {d}, not towards {axis}")
    # Vertical fov: the top edge's ray makes vfov/2 with the view axis.
    ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f(0.5, 0.0), mi.Point2f(0.5, 0.5))
    d = np.array(ray.d, dtype=np.float64).ravel()
    half = math.degrees(math.acos(min(1.0, d.dot(fwd) / np.linalg.norm(d))))
    if abs(2 * half - camera["vfov"]) > 1e-3:
        raise SystemExit(f"camera: vertical fov {2 * half}, not {camera['vfov']}")
    print(f"camera: row 0 on top, forward x up to the right, vertical fov {2 * half:.4f}")


def render(mi, scene, seed, spp):
    img = np.array(mi.render(scene, seed=seed, spp=spp), dtype=np.float64)[:, :, :3]
    if not np.isfinite(img).all():
        sys.exit(f"seed {seed}: non-finite pixels")
    return img


def read_exr(mi, path):
    return np.array(mi.Bitmap(path), dtype=np.float64)[:, :, :3]


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.dirname(here)
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", help="ptui scene file (e.g. scenes/torus-knot.toml)")
    ap.add_argument("--out", help="reference EXR (default tests/refs/<scene stem>.exr)")
    ap.add_argument("--width", type=int, default=160)
    ap.add_argument("--height", type=int, default=120)
    ap.add_argument("--spp", type=int, default=256, help="samples per pixel of each pass")
    ap.add_argument("--passes", type=int, default=16, help="independent passes (seeds)")
    ap.add_argument("--seed", type=int, default=0, help="seed of the first pass")
    ap.add_argument("--variant", default="llvm_ad_rgb", choices=["scalar_rgb", "llvm_ad_rgb"])
    ap.add_argument("--threads", type=int, default=0, help="render threads (0: all cores)")
    ap.add_argument(
        "--time-spp",
        type=int,
        help="equal-time mode: render once at this spp (after a warm-up render that compiles "
        "the kernels) and print its seconds and, with --reference, its RMSE",
    )
    ap.add_argument("--reference", help="reference EXR for --time-spp")
    ap.add_argument("--runs", type=int, default=1, help="--time-spp renders, distinct seeds")
    args = ap.parse_args()
    if args.passes < 2 or args.spp < 1 or args.width < 1 or args.height < 1:
        ap.error("need --passes >= 2 and positive --spp, --width, --height")
    scene_path = os.path.abspath(args.scene)
    out = args.out or os.path.join(
        root, "tests", "refs", os.path.splitext(os.path.basename(scene_path))[0] + ".exr"
    )

    import drjit as dr
    import mitsuba as mi

    mi.set_variant(args.variant)
    if args.threads:
        dr.set_thread_count(args.threads)
    try:
        camera, background, quads, spheres, meshes = read_scene(scene_path)
    except SceneFileError as e:
        sys.exit(str(e))

    with tempfile.TemporaryDirectory() as workdir:
        if meshes:
            export_meshes(scene_path, workdir, root)
        sky_map = None
        if background[1] is not None:
            exr = os.path.join(workdir, "sky.exr")
            subprocess.run(xtask() + ["sky-map", exr], check=True, cwd=root)
            sky_map = read_exr(mi, exr)
        t_load = time.time()
        desc = build_scene(
            mi, camera, background, quads, spheres, meshes, args.width, args.height, workdir, sky_map
        )
        scene = mi.load_dict(desc)
        load_seconds = time.time() - t_load
        check_conventions(mi, scene, camera, background, quads, spheres, meshes, sky_map)

        if args.time_spp:
            # The first render of a scene compiles its kernels (LLVM); time the later ones,
            # as a user rendering for a while would see.
            t0 = time.time()
            render(mi, scene, 10_000, 1)
            print(f"scene load {load_seconds:.2f} s, warm-up (kernel compile) {time.time() - t0:.2f} s")
            ref = read_exr(mi, args.reference) if args.reference else None
            for k in range(args.runs):
                t0 = time.time()
                img = render(mi, scene, args.seed + k, args.time_spp)
                seconds = time.time() - t0
                line = f"mitsuba {args.variant} spp {args.time_spp} seconds {seconds:.3f}"
                if ref is not None:
                    line += f" rmse {math.sqrt(((img - ref) ** 2).mean()):.6f}"
                print(line, flush=True)
            return

        passes = Passes(mi, scene, args.spp, args.passes, args.seed)
    passes.write(
        mi,
        out,
        root,
        __file__,
        [
            f"scene = {os.path.relpath(scene_path, root)}",
            f"renderer = Mitsuba {mi.__version__}, {args.variant}, path, max_depth -1, box filter",
        ],
    )

if __name__ == "__main__":
    main()
