#!/usr/bin/env python3
"""Writes coarse-sphere.obj: a unit UV sphere of 12 segments x 6 rings with
per-vertex normals (the exact sphere normals), for the classic integrator's
flat / Gouraud / Phong comparison (scenes/integrators/classic-shading.xml).
Coarse on purpose: the facets, the Mach bands of Gouraud shading and the
highlights it loses between vertices must show."""
import math
import os

SEGMENTS, RINGS = 12, 6


def main():
    verts, faces = [], []
    for j in range(RINGS + 1):
        theta = math.pi * j / RINGS
        for i in range(SEGMENTS + 1):
            phi = 2 * math.pi * i / SEGMENTS
            verts.append((math.sin(theta) * math.cos(phi), math.cos(theta),
                          math.sin(theta) * math.sin(phi)))
    row = SEGMENTS + 1
    for j in range(RINGS):
        for i in range(SEGMENTS):
            a, b = j * row + i, j * row + i + 1
            c, d = a + row, b + row
            if j > 0:
                faces.append((a, b, c))   # counter-clockwise seen from outside
            if j < RINGS - 1:
                faces.append((b, d, c))
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "coarse-sphere.obj")
    with open(path, "w") as f:
        f.write("# written by make_coarse_sphere.py\n")
        for v in verts:
            f.write("v %.6f %.6f %.6f\n" % v)
        for v in verts:
            f.write("vn %.6f %.6f %.6f\n" % v)
        for a, b, c in faces:
            f.write("f %d//%d %d//%d %d//%d\n" % (a + 1, a + 1, b + 1, b + 1, c + 1, c + 1))


if __name__ == "__main__":
    main()
