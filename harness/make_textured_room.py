#!/usr/bin/env python3
"""Write scenes/examples/textured/: one small textured scene as OBJ + MTL + PNG textures and the
same scene as a binary glTF (room.glb), for the texture reference against Mitsuba 3
(harness/mitsuba_textured.py) and the glTF-against-OBJ equivalence test
(tests/integration/models.rs). Standard library only; the output is the same bytes every run.

  python3 harness/make_textured_room.py

The scene: a floor (6 x 6, its checker texture tiled 3 times), a wall (2 x 2) whose picture has
red, green, blue and white quadrants (red at the top left, so an image the wrong way round
shows), and a box (a cube of side 0.6) with the checker on its faces. In the glTF the wall and
the box are placed by node transforms (translation, rotation, scale), in the OBJ their vertices
are written where those transforms put them. The glTF materials are metallic 0 with
KHR_materials_specular factor 0: exactly the Lambertian base, like the OBJ's `Kd` + `map_Kd`.
"""
import json
import math
import os
import struct
import zlib

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
OUT = os.path.join(ROOT, "scenes", "examples", "textured")


def png(width, height, pixel):
    """An 8-bit RGB PNG; pixel(x, y) gives (r, g, b) with y = 0 the top row."""
    raw = b"".join(
        b"\x00" + b"".join(bytes(pixel(x, y)) for x in range(width)) for y in range(height)
    )

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")


def wall_pixel(x, y):
    top, left = y < 32, x < 32
    colour = {(True, True): (220, 40, 30), (True, False): (40, 200, 60),
              (False, True): (30, 60, 220), (False, False): (235, 235, 235)}[(top, left)]
    # A dark cross through the middle, so filtering at the edges is seen too.
    if abs(x - 31.5) < 2 or abs(y - 31.5) < 2:
        return (20, 20, 20)
    return colour


def floor_pixel(x, y):
    return (200, 170, 120) if ((x // 8) + (y // 8)) % 2 == 0 else (60, 70, 90)


def quad(p0, p1, p2, p3, uv_up):
    """Two triangles (p0 p1 p2, p0 p2 p3) with OBJ-style texture coordinates (v up)."""
    return [(p0, p1, p2), (p0, p2, p3)], [(uv_up[0], uv_up[1], uv_up[2]), (uv_up[0], uv_up[2], uv_up[3])]


def cube(size):
    """A cube centred at the origin: 12 triangles facing out, each face's texture whole."""
    h = size / 2
    faces = []
    for axis in range(3):
        for sign in (1, -1):
            n = [0, 0, 0]
            n[axis] = sign
            u = [0, 0, 0]
            u[(axis + 1) % 3] = 1
            v = [0, 0, 0]
            v[(axis + 2) % 3] = 1
            if sign < 0:
                u = [-c for c in u]
            c = [n[i] * h for i in range(3)]
            corner = lambda a, b: tuple(c[i] + (a * u[i] + b * v[i]) * h for i in range(3))
            faces.append(quad(corner(-1, -1), corner(1, -1), corner(1, 1), corner(-1, 1),
                              [(0, 0), (1, 0), (1, 1), (0, 1)]))
    tris, uvs = [], []
    for t, w in faces:
        tris += t
        uvs += w
    return tris, uvs


def rotate_y(p, degrees):
    a = math.radians(degrees)
    x, y, z = p
    return (math.cos(a) * x + math.sin(a) * z, y, -math.sin(a) * x + math.cos(a) * z)


# Objects in their own space, with the node transform the glTF gives them.
FLOOR = quad((-3, 0, 3), (3, 0, 3), (3, 0, -3), (-3, 0, -3), [(0, 0), (3, 0), (3, 3), (0, 3)])
WALL = quad((-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0), [(0, 0), (1, 0), (1, 1), (0, 1)])
WALL_NODE = {"translation": [0.0, 1.0, -1.0]}
BOX = cube(1.0)
BOX_NODE = {"translation": [1.3, 0.3, 0.4], "scale": [0.6, 0.6, 0.6],
            "rotation": [0.0, math.sin(math.radians(15)), 0.0, math.cos(math.radians(15))]}


def place(p, node):
    s = node.get("scale", [1, 1, 1])
    p = (p[0] * s[0], p[1] * s[1], p[2] * s[2])
    if "rotation" in node:
        p = rotate_y(p, 30)  # the quaternion above: 30 degrees about y
    t = node.get("translation", [0, 0, 0])
    return (p[0] + t[0], p[1] + t[1], p[2] + t[2])


def fmt(x):
    return f"{x:.9g}"


def write_obj():
    lines = ["# harness/make_textured_room.py", "mtllib room.mtl"]
    vt_lines, f_lines = [], []
    v_count = 0
    for name, (tris, uvs), node, mat in (("floor", FLOOR, {}, "floor"), ("wall", WALL, WALL_NODE, "wall"),
                                         ("box", BOX, BOX_NODE, "floor")):
        f_lines.append(f"o {name}")
        f_lines.append(f"usemtl {mat}")
        for t, w in zip(tris, uvs):
            idx = []
            for p, uv in zip(t, w):
                q = place(p, node)
                lines.append("v " + " ".join(fmt(c) for c in q))
                vt_lines.append(f"vt {fmt(uv[0])} {fmt(uv[1])}")
                v_count += 1
                idx.append(v_count)
            f_lines.append("f " + " ".join(f"{i}/{i}" for i in idx))
    text = "\n".join(lines + vt_lines + f_lines) + "\n"
    open(os.path.join(OUT, "room.obj"), "w").write(text)
    open(os.path.join(OUT, "room.mtl"), "w").write(
        "# harness/make_textured_room.py\n"
        "newmtl floor\nKd 1 1 1\nKs 0 0 0\nmap_Kd floor.png\n\n"
        "newmtl wall\nKd 1 1 1\nKs 0 0 0\nmap_Kd wall.png\n"
    )


def write_glb(floor_png, wall_png):
    bin_data = bytearray()
    views, accessors = [], []

    def add_view(data, target=None):
        while len(bin_data) % 4:
            bin_data.append(0)
        view = {"buffer": 0, "byteOffset": len(bin_data), "byteLength": len(data)}
        if target:
            view["target"] = target
        bin_data.extend(data)
        views.append(view)
        return len(views) - 1

    def add_accessor(values, kind, comp=5126):
        flat = [c for v in values for c in (v if isinstance(v, tuple) else (v,))]
        fmt_char = {5126: "f", 5125: "I"}[comp]
        view = add_view(struct.pack("<%d%s" % (len(flat), fmt_char), *flat),
                        34963 if comp == 5125 else 34962)
        acc = {"bufferView": view, "componentType": comp, "count": len(values), "type": kind}
        if kind == "VEC3":
            acc["min"] = [min(v[i] for v in values) for i in range(3)]
            acc["max"] = [max(v[i] for v in values) for i in range(3)]
        accessors.append(acc)
        return len(accessors) - 1

    meshes = []
    for (tris, uvs), material in ((FLOOR, 0), (WALL, 1), (BOX, 0)):
        pos, tex = [], []
        for t, w in zip(tris, uvs):
            for p, uv in zip(t, w):
                pos.append(tuple(float(c) for c in p))
                tex.append((float(uv[0]), 1.0 - float(uv[1])))  # glTF's v runs down
        indices = list(range(len(pos)))
        meshes.append({"primitives": [{
            "attributes": {"POSITION": add_accessor(pos, "VEC3"), "TEXCOORD_0": add_accessor(tex, "VEC2")},
            "indices": add_accessor(indices, "SCALAR", 5125), "material": material}]})
    images = [{"bufferView": add_view(floor_png), "mimeType": "image/png"},
              {"bufferView": add_view(wall_png), "mimeType": "image/png"}]
    plain = {"KHR_materials_specular": {"specularFactor": 0.0}}
    doc = {
        "asset": {"version": "2.0", "generator": "harness/make_textured_room.py"},
        "extensionsUsed": ["KHR_materials_specular"],
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [{"mesh": 0, "name": "floor"}, dict(mesh=1, name="wall", **WALL_NODE),
                  dict(mesh=2, name="box", **BOX_NODE)],
        "meshes": meshes,
        "materials": [
            {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0,
                                      "roughnessFactor": 1.0}, "extensions": plain},
            {"pbrMetallicRoughness": {"baseColorTexture": {"index": 1}, "metallicFactor": 0.0,
                                      "roughnessFactor": 1.0}, "extensions": plain},
        ],
        "textures": [{"source": 0, "sampler": 0}, {"source": 1, "sampler": 0}],
        "samplers": [{"wrapS": 10497, "wrapT": 10497}],
        "images": images,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(bin_data)}],
    }
    js = json.dumps(doc, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    while len(bin_data) % 4:
        bin_data.append(0)
    body = struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(bin_data), 0x004E4942) + bytes(bin_data)
    glb = struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body
    open(os.path.join(OUT, "room.glb"), "wb").write(glb)


def main():
    os.makedirs(OUT, exist_ok=True)
    floor_png = png(32, 32, floor_pixel)
    wall_png = png(64, 64, wall_pixel)
    open(os.path.join(OUT, "floor.png"), "wb").write(floor_png)
    open(os.path.join(OUT, "wall.png"), "wb").write(wall_png)
    write_obj()
    write_glb(floor_png, wall_png)
    print("wrote", OUT)


if __name__ == "__main__":
    main()
