#!/usr/bin/env python3
"""Writes big_mesh.ply next to this script: a load-time benchmark mesh (issue #8).

A displaced grid (a height field of a few sine waves over [-1, 1]^2, y up) tessellated into
N x N quads, two triangles each: 2 (N - 1)^2 triangles, 4,004,450 for the default N = 1416.
Binary little endian, the layout most exporters write (and the PLY loader's fast path):

    element vertex: float x y z nx ny nz u v   (analytic unit normals)
    element face:   list uchar int vertex_indices

The file (about 121 MB) is not committed; big-mesh.xml renders it. Pure Python, ~10 s.

Run: python3 validation/loadtime/make_big_mesh.py [--positions-only] [N [OUT.ply]]

--positions-only writes x y z alone (flat shading, no uvs): 12 bytes a vertex instead of 32.

N = 2238 gives the 10,008,338-triangle scale test of issue #11 (about 190 MB): write it outside
the repository, copy big-mesh.xml next to it as the scene, and see validation/README.md.
"""

import math
import os
import struct
import sys
from array import array

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    args = sys.argv[1:]
    positions_only = "--positions-only" in args
    args = [a for a in args if a != "--positions-only"]
    n = int(args[0]) if args else 1416
    amp = 0.05
    verts = array("f")
    for j in range(n):
        z = -1.0 + 2.0 * j / (n - 1)
        for i in range(n):
            x = -1.0 + 2.0 * i / (n - 1)
            # y = amp * sin(6x) * cos(5z) + amp/2 * sin(17x + 11z)
            y = amp * math.sin(6 * x) * math.cos(5 * z) + 0.5 * amp * math.sin(17 * x + 11 * z)
            dx = amp * 6 * math.cos(6 * x) * math.cos(5 * z) + 0.5 * amp * 17 * math.cos(17 * x + 11 * z)
            dz = -amp * 5 * math.sin(6 * x) * math.sin(5 * z) + 0.5 * amp * 11 * math.cos(17 * x + 11 * z)
            inv = 1.0 / math.sqrt(dx * dx + 1.0 + dz * dz)
            if positions_only:
                verts.extend((x, y, z))
            else:
                verts.extend((x, y, z, -dx * inv, inv, -dz * inv, i / (n - 1), j / (n - 1)))
    if sys.byteorder != "little":
        verts.byteswap()

    nf = 2 * (n - 1) * (n - 1)
    face = struct.Struct("<B3i")
    faces = bytearray(face.size * nf)
    off = 0
    for j in range(n - 1):
        row = j * n
        for i in range(n - 1):
            a = row + i
            b, c, d = a + 1, a + n, a + n + 1
            # Counter-clockwise seen from +y.
            face.pack_into(faces, off, 3, a, c, b)
            face.pack_into(faces, off + face.size, 3, b, c, d)
            off += 2 * face.size

    header = (
        "ply\nformat binary_little_endian 1.0\n"
        "comment radia load-time benchmark, validation/loadtime/make_big_mesh.py\n"
        f"element vertex {n * n}\n"
        "property float x\nproperty float y\nproperty float z\n"
        + (
            ""
            if positions_only
            else "property float nx\nproperty float ny\nproperty float nz\n"
            "property float u\nproperty float v\n"
        )
        + f"element face {nf}\n"
        "property list uchar int vertex_indices\nend_header\n"
    )
    path = args[1] if len(args) > 1 else os.path.join(HERE, "big_mesh.ply")
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(verts.tobytes())
        f.write(faces)
    print(f"{path}: {n * n} vertices, {nf} triangles")


if __name__ == "__main__":
    main()
