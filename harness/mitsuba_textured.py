#!/usr/bin/env python3
"""Mitsuba 3 reference of scenes/examples/textured/room.toml, the textured OBJ with its .mtl:
tests/refs/textured-room.exr (and .txt), for tests/integration/models.rs.

Mitsuba reads the OBJ's vertices and `vt` itself (its OBJ loader turns v to run downwards, as
ptui does) but not the .mtl: the OBJ is split by `usemtl` into one file per material, and each
material is the `diffuse` BSDF of a `bitmap` texture of the `map_Kd` file (bilinear, repeat,
sRGB-decoded: Mitsuba's defaults, what ptui's textures do), in `twosided` as ptui's diffuse
reflects on both faces. The camera, the constant environment and the film follow
harness/mitsuba_cornell_mesh.py's `base_scene`.

  harness/mitsuba_env.sh; "$venv/bin/python" harness/mitsuba_textured.py --spp 256 --passes 16
"""

import argparse
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mitsuba_cornell_mesh import base_scene, load_toml, read_camera  # noqa: E402
from mitsuba_passes import Passes  # noqa: E402

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
SCENE = os.path.join(ROOT, "scenes", "examples", "textured", "room.toml")


def split_obj(obj_path, out_dir):
    """One OBJ per `usemtl` name (all the file's v and vt kept, faces of that material)."""
    head, faces, current = [], {}, None
    for line in open(obj_path):
        word = line.split(maxsplit=1)[0] if line.strip() else ""
        if word in ("v", "vt", "vn"):
            head.append(line)
        elif word == "usemtl":
            current = line.split(maxsplit=1)[1].strip()
        elif word == "f":
            faces.setdefault(current, []).append(line)
    paths = {}
    for name, fs in faces.items():
        p = os.path.join(out_dir, f"{name}.obj")
        open(p, "w").write("".join(head + fs))
        paths[name] = p
    return paths


def map_kd(mtl_path):
    """Each material's `map_Kd` file, relative to the .mtl."""
    out, current = {}, None
    for line in open(mtl_path):
        words = line.split()
        if words[:1] == ["newmtl"]:
            current = words[1]
        elif words[:1] == ["map_Kd"]:
            out[current] = os.path.join(os.path.dirname(mtl_path), words[-1])
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--passes", type=int, default=16)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--variant", default="scalar_rgb")
    ap.add_argument("--out", default=os.path.join(ROOT, "tests", "refs", "textured-room.exr"))
    args = ap.parse_args()
    import mitsuba as mi

    mi.set_variant(args.variant)
    desc = load_toml(SCENE)
    camera = read_camera(SCENE, desc)
    width, height = desc["render"]["width"], desc["render"]["height"]
    scene = base_scene(mi, camera, width, height)
    scene["environment"] = {"type": "constant", "radiance": {"type": "rgb", "value": [1.0, 1.0, 1.0]}}
    folder = os.path.dirname(SCENE)
    textures = map_kd(os.path.join(folder, "room.mtl"))
    with tempfile.TemporaryDirectory() as tmp:
        for name, path in split_obj(os.path.join(folder, "room.obj"), tmp).items():
            scene[f"shape_{name}"] = {
                "type": "obj",
                "filename": path,
                "face_normals": True,
                "bsdf": {
                    "type": "twosided",
                    "bsdf": {
                        "type": "diffuse",
                        "reflectance": {
                            "type": "bitmap",
                            "filename": textures[name],
                            "filter_type": "bilinear",
                            "wrap_mode": "repeat",
                        },
                    },
                },
            }
        loaded = mi.load_dict(scene)
        passes = Passes(mi, loaded, args.spp, args.passes, args.seed)
    passes.write(
        mi,
        args.out,
        ROOT,
        __file__,
        [
            f"scene = {os.path.relpath(SCENE, ROOT)}",
            f"renderer = Mitsuba {mi.__version__}, {args.variant}, path, max_depth -1, box filter, "
            "bitmap textures (bilinear, repeat, sRGB)",
        ],
    )


if __name__ == "__main__":
    main()
