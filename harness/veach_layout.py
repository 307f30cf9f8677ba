#!/usr/bin/env python3
"""Lays out the plates of scenes/veach.toml: each plate's normal halves the angle between the
camera and the middle of the light row at the plate's centre (so the camera sees the lights'
reflections near its middle), and the script checks that no plate stands between another
plate and a light or the camera. Prints the plates as [[quad]] tables:

    target/mitsuba-venv/bin/python harness/veach_layout.py
"""
import numpy as np

CAMERA = np.array([0.0, 2.0, 15.0])
LIGHT_Y, LIGHT_Z = 1.0, 0.0
LIGHTS = [np.array([x, LIGHT_Y, LIGHT_Z]) for x in (-3.75, -1.25, 1.25, 3.75)]
AIM = np.array([0.0, LIGHT_Y, LIGHT_Z])
# Plate centres (front to back), depths and roughness; every plate spans x in [-4, 4].
CENTRES = [(-2.7, 4.6), (-2.05, 3.25), (-1.45, 2.05), (-0.95, 0.95)]
DEPTHS = [0.7, 0.6, 0.5, 0.45]
ALPHAS = [0.1, 0.05, 0.02, 0.005]
X = np.array([1.0, 0.0, 0.0])


def plates():
    out = []
    for (y, z), d in zip(CENTRES, DEPTHS):
        p = np.array([0.0, y, z])
        n = (CAMERA - p) / np.linalg.norm(CAMERA - p) + (AIM - p) / np.linalg.norm(AIM - p)
        n /= np.linalg.norm(n)
        t = np.cross(n, X)
        t /= np.linalg.norm(t)
        # edge1 x edge2 = X x (d t) = d n: the front face looks up at the camera and lights.
        out.append((p - 4 * X - 0.5 * d * t, 8 * X, d * t, n))
    return out


def hit(o, d, quad):
    c, e1, e2, n = quad
    den = d.dot(n)
    if abs(den) < 1e-12:
        return None
    t = (c - o).dot(n) / den
    if t <= 1e-6:
        return None
    q = o + d * t - c
    a, b = q.dot(e1) / e1.dot(e1), q.dot(e2) / e2.dot(e2)
    return t if 0 <= a <= 1 and 0 <= b <= 1 else None


def blocked(quads):
    count = 0
    for i, (c, e1, e2, _) in enumerate(quads):
        for a in np.linspace(0.02, 0.98, 25):
            for b in np.linspace(0.02, 0.98, 7):
                p = c + a * e1 + b * e2
                for target in LIGHTS + [CAMERA]:
                    d = target - p
                    dist = np.linalg.norm(d)
                    for j, other in enumerate(quads):
                        t = hit(p, d / dist, other) if j != i else None
                        count += t is not None and t < dist
    return count


def main():
    quads = plates()
    n = blocked(quads)
    if n:
        raise SystemExit(f"{n} segments from plates to lights or the camera are blocked")
    fmt = lambda v: "[" + ", ".join(f"{x:.5f}".rstrip("0").rstrip(".") if x else "0" for x in v) + "]"
    for (c, e1, e2, _), alpha in zip(quads, ALPHAS):
        print(f'[[quad]]\nname = "plate, alpha {alpha}"\ncorner = {fmt(c)}\nedge1 = {fmt(e1)}')
        print(f'edge2 = {fmt(e2)}\nmaterial = "conductor"\nalpha = {alpha}\ncolor = 0.35\n')


if __name__ == "__main__":
    main()
