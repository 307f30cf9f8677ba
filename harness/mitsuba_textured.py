#!/usr/bin/env python3
"""Mitsuba 3 references of scenes whose one `[[mesh]]` is an OBJ with its .mtl and textures,
under a constant sky: tests/refs/textured-room.exr (scenes/examples/textured/room.toml) and
tests/refs/pyglet-box.exr (scenes/pyglet-box.toml, pyglet's example cube from PyPI), each with
its .txt, for tests/integration/models.rs.

Mitsuba reads the OBJ's vertices and `vt` itself (its OBJ loader turns v to run downwards, as
ptui does) but not the .mtl: the OBJ is split by `usemtl` into one file per material, and each
material is mapped as ptui's MTL table maps it (docs/MODELS.md), for the two kinds these scenes
use, refusing any other:

- `Kd` / `map_Kd` alone: `diffuse`, of a `bitmap` texture of the `map_Kd` file (bilinear, repeat,
  sRGB-decoded: Mitsuba's defaults, what ptui's textures do) or of the `Kd` colour;
- `Ks` > 0 with a non-black `Kd` and `illum` not 0 or 1: `roughplastic` with that diffuse
  reflectance, `specular_reflectance` Ks, `int_ior` Ni (1.49 when absent or at most 1) against
  exactly 1.0 outside, GGX of alpha (1 - sqrt(Ns) / 30)^2, `nonlinear` false, as ptui's plastic.

Both wrapped in `twosided`, as ptui's opaque materials reflect on both faces. The camera and the
film follow harness/mitsuba_cornell_mesh.py's `base_scene`; the sky is a `constant` emitter of
the scene's `[environment] color`.

  harness/mitsuba_env.sh
  "$venv/bin/python" harness/mitsuba_textured.py --spp 256 --passes 32
  harness/get_pyglet_box.sh
  "$venv/bin/python" harness/mitsuba_textured.py --scene scenes/pyglet-box.toml \\
      --out tests/refs/pyglet-box.exr --spp 256 --passes 32
"""

import argparse
import math
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mitsuba_cornell_mesh import base_scene, fail, load_toml, read_camera  # noqa: E402
from mitsuba_passes import Passes  # noqa: E402

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
SCENE = os.path.join(ROOT, "scenes", "examples", "textured", "room.toml")
# ptui's DEFAULT_PLASTIC_IOR (src/scene/materials.rs).
DEFAULT_PLASTIC_IOR = 1.49


def split_obj(obj_path, out_dir):
    """One OBJ per `usemtl` name (all the file's v, vt and vn kept, faces of that material), and
    the file's `mtllib` names."""
    head, faces, libs, current = [], {}, [], None
    for line in open(obj_path):
        words = line.split(maxsplit=1)
        word = words[0] if words else ""
        if word in ("v", "vt", "vn"):
            head.append(line)
        elif word == "mtllib":
            libs.append(words[1].strip())
        elif word == "usemtl":
            current = words[1].strip()
        elif word == "f":
            faces.setdefault(current, []).append(line)
    paths = {}
    for i, (name, fs) in enumerate(faces.items()):
        p = os.path.join(out_dir, f"part{i}.obj")
        open(p, "w").write("".join(head + fs))
        paths[name] = p
    return paths, libs


def read_mtl(mtl_path):
    """Each material's statements: numbers as floats (colours as lists), `map_Kd` as the file
    relative to the .mtl (options other than none refused)."""
    out, current = {}, None
    for n, line in enumerate(open(mtl_path), 1):
        words = line.split()
        if not words or words[0].startswith("#"):
            continue
        key, rest = words[0], words[1:]
        if key == "newmtl":
            current = out.setdefault(" ".join(rest), {})
        elif current is None:
            continue
        elif key == "map_Kd":
            if rest[0].startswith("-"):
                fail(mtl_path, f"line {n}", "map_Kd options are not supported by this harness")
            current[key] = os.path.join(os.path.dirname(mtl_path), " ".join(rest))
        elif key in ("Kd", "Ks", "Ke", "Tf"):
            current[key] = [float(x) for x in rest[:3]] * (3 if len(rest) == 1 else 1)
        elif key in ("Ns", "Ni", "d"):
            current[key] = float(rest[0])
        elif key == "illum":
            current[key] = int(rest[0])
    return out


def bsdf(mtl_path, name, m):
    """The Mitsuba BSDF of MTL material `m` as ptui's table maps it (the kinds named above)."""
    if "map_Kd" in m:
        diffuse = {
            "type": "bitmap",
            "filename": m["map_Kd"],
            "filter_type": "bilinear",
            "wrap_mode": "repeat",
        }
    else:
        diffuse = {"type": "rgb", "value": m.get("Kd", [0.75] * 3)}
    if max(m.get("Ke", [0])) > 0 or "Tf" in m or m.get("d", 1) < 1 or m.get("illum") in (4, 6, 7):
        fail(mtl_path, name, "emission and glass are not supported by this harness")
    ks = [min(max(x, 0.0), 1.0) for x in m.get("Ks", [0, 0, 0])]
    if max(ks) <= 0 or m.get("illum") in (0, 1):
        inner = {"type": "diffuse", "reflectance": diffuse}
    else:
        if "map_Kd" not in m and max(m.get("Kd", [1])) <= 0:
            fail(mtl_path, name, "a black Kd (ptui's conductor) is not supported by this harness")
        ni = m.get("Ni", 0.0)
        roughness = min(max(1.0 - math.sqrt(max(m.get("Ns", 0.0), 0.0)) / 30.0, 0.0), 1.0)
        inner = {
            "type": "roughplastic",
            "distribution": "ggx",
            "alpha": roughness * roughness,
            "int_ior": ni if ni > 1.0 else DEFAULT_PLASTIC_IOR,
            "ext_ior": 1.0,
            "nonlinear": False,
            "diffuse_reflectance": diffuse,
            "specular_reflectance": {"type": "rgb", "value": ks},
        }
    return {"type": "twosided", "bsdf": inner}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", default=SCENE)
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--passes", type=int, default=16)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--variant", default="scalar_rgb")
    ap.add_argument("--out", default=os.path.join(ROOT, "tests", "refs", "textured-room.exr"))
    args = ap.parse_args()
    import mitsuba as mi

    mi.set_variant(args.variant)
    path = args.scene
    desc = load_toml(path)
    extra = set(desc) - {"camera", "render", "environment", "mesh"}
    if extra or len(desc.get("mesh", [])) != 1:
        fail(path, ", ".join(sorted(extra)) or "mesh", "only a camera, one mesh and a sky")
    mesh = desc["mesh"][0]
    if set(mesh) - {"path", "name"}:
        fail(path, "mesh[0]", "only `path` (the .mtl gives the materials)")
    env = desc.get("environment", {})
    if set(env) != {"color"}:
        fail(path, "environment", "only a constant `color`")
    sky = env["color"] if isinstance(env["color"], list) else [float(env["color"])] * 3
    camera = read_camera(path, desc)
    width, height = desc["render"]["width"], desc["render"]["height"]
    scene = base_scene(mi, camera, width, height)
    scene["environment"] = {"type": "constant", "radiance": {"type": "rgb", "value": sky}}
    obj = os.path.join(os.path.dirname(path), mesh["path"])
    with tempfile.TemporaryDirectory() as tmp:
        parts, libs = split_obj(obj, tmp)
        materials = {}
        for lib in libs:
            mtl = os.path.join(os.path.dirname(obj), lib)
            materials.update({k: (mtl, v) for k, v in read_mtl(mtl).items()})
        for i, (name, part) in enumerate(parts.items()):
            if name not in materials:
                fail(obj, f"usemtl {name}", "no library has this material")
            mtl, m = materials[name]
            scene[f"shape_{i}"] = {
                "type": "obj",
                "filename": part,
                "face_normals": True,
                "bsdf": bsdf(mtl, name, m),
            }
        loaded = mi.load_dict(scene)
        passes = Passes(mi, loaded, args.spp, args.passes, args.seed)
    kinds = sorted({scene[k]["bsdf"]["bsdf"]["type"] for k in scene if k.startswith("shape_")})
    passes.write(
        mi,
        args.out,
        ROOT,
        __file__,
        [
            f"scene = {os.path.relpath(path, ROOT)}",
            f"renderer = Mitsuba {mi.__version__}, {args.variant}, path, max_depth -1, box filter, "
            f"{' and '.join(kinds)}, bitmap textures (bilinear, repeat, sRGB)",
        ],
    )


if __name__ == "__main__":
    main()
