#!/usr/bin/env python3
"""Writes the meshes of scenes/cornell-box.xml into this directory.

A 2 m Cornell box: x in [-1, 1] (red wall at x = -1, green at x = +1), floor y = 0,
ceiling y = 2, back wall z = -1, open towards +z where the camera is. Every face is
counter-clockwise seen from the side its normal points to (Mitsuba's front face).

  cbox_white.obj   floor, ceiling, back wall  (f v/vt/vn)
  cbox_red.obj     left wall                  (f v//vn)
  cbox_green.obj   right wall                 (f v, normals recomputed by the loader)
  cbox_short.ply   short box, binary little endian, x y z only (normals recomputed)
  cbox_tall.ply    tall box, ASCII, x y z nx ny nz u v

Run: python3 scenes/meshes/make_cornell.py
"""

import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def check_quad(q, n):
    """The quad's winding must agree with its intended outward normal n."""
    g = cross(sub(q[1], q[0]), sub(q[2], q[0]))
    assert dot(g, n) > 0, (q, n)


def fmt(x):
    s = f"{x:.6f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


# Walls: (corners counter-clockwise seen from inside the box, inward normal).
FLOOR = ([(-1, 0, 1), (1, 0, 1), (1, 0, -1), (-1, 0, -1)], (0, 1, 0))
CEILING = ([(-1, 2, 1), (-1, 2, -1), (1, 2, -1), (1, 2, 1)], (0, -1, 0))
BACK = ([(-1, 0, -1), (1, 0, -1), (1, 2, -1), (-1, 2, -1)], (0, 0, 1))
LEFT = ([(-1, 0, 1), (-1, 0, -1), (-1, 2, -1), (-1, 2, 1)], (1, 0, 0))
RIGHT = ([(1, 0, -1), (1, 0, 1), (1, 2, 1), (1, 2, -1)], (-1, 0, 0))

for quad, n in (FLOOR, CEILING, BACK, LEFT, RIGHT):
    check_quad(quad, n)


def write_white(path):
    lines = ["# Cornell box: floor, ceiling, back wall (white). Written by make_cornell.py"]
    faces = []
    for w, (quad, n) in enumerate((FLOOR, CEILING, BACK)):
        for p in quad:
            lines.append("v " + " ".join(fmt(c) for c in p))
        lines.append("vn " + " ".join(fmt(c) for c in n))
        base = 4 * w
        faces.append(
            "f " + " ".join(f"{base + k + 1}/{k + 1}/{w + 1}" for k in range(4))
        )
    for uv in ((0, 0), (1, 0), (1, 1), (0, 1)):
        lines.append("vt " + " ".join(fmt(c) for c in uv))
    lines += faces
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def write_red(path):
    quad, n = LEFT
    lines = ["# Cornell box: left wall (red). Written by make_cornell.py"]
    lines += ["v " + " ".join(fmt(c) for c in p) for p in quad]
    lines.append("vn " + " ".join(fmt(c) for c in n))
    lines.append("f 1//1 2//1 3//1")
    lines.append("f 1//1 3//1 4//1")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def write_green(path):
    quad, _ = RIGHT
    lines = ["# Cornell box: right wall (green). No normals. Written by make_cornell.py", "o right_wall"]
    lines += ["v " + " ".join(fmt(c) for c in p) for p in quad]
    lines.append("f 1 2 3 4")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def box(center, size, angle_deg):
    """Five faces (no bottom) of a box standing on the floor, rotated about +y.
    Returns a list of (4 corners, outward normal, 4 uvs)."""
    cx, cy, cz = center
    hx, hy, hz = (s / 2 for s in size)
    a = math.radians(angle_deg)
    ca, sa = math.cos(a), math.sin(a)

    def rot(v):  # rotation about +y (right-handed)
        return (ca * v[0] + sa * v[2], v[1], -sa * v[0] + ca * v[2])

    def world(p):
        q = rot(p)
        return (q[0] + cx, q[1] + cy, q[2] + cz)

    local_faces = [
        ([(-hx, hy, hz), (hx, hy, hz), (hx, hy, -hz), (-hx, hy, -hz)], (0, 1, 0)),  # top
        ([(-hx, -hy, hz), (hx, -hy, hz), (hx, hy, hz), (-hx, hy, hz)], (0, 0, 1)),  # front
        ([(hx, -hy, -hz), (-hx, -hy, -hz), (-hx, hy, -hz), (hx, hy, -hz)], (0, 0, -1)),  # back
        ([(hx, -hy, hz), (hx, -hy, -hz), (hx, hy, -hz), (hx, hy, hz)], (1, 0, 0)),  # right
        ([(-hx, -hy, -hz), (-hx, -hy, hz), (-hx, hy, hz), (-hx, hy, -hz)], (-1, 0, 0)),  # left
    ]
    uvs = [(0, 0), (1, 0), (1, 1), (0, 1)]
    faces = []
    for quad, n in local_faces:
        wq = [world(p) for p in quad]
        wn = rot(n)
        check_quad(wq, wn)
        faces.append((wq, wn, uvs))
    return faces


def write_short_box(path):
    faces = box((0.45, 0.3, 0.4), (0.6, 0.6, 0.6), -18.0)
    verts = [p for quad, _, _ in faces for p in quad]
    header = (
        "ply\n"
        "format binary_little_endian 1.0\n"
        "comment Cornell box: short box. Written by make_cornell.py\n"
        f"element vertex {len(verts)}\n"
        "property float x\nproperty float y\nproperty float z\n"
        f"element face {2 * len(faces)}\n"
        "property list uchar int vertex_indices\n"
        "end_header\n"
    )
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        for p in verts:
            f.write(struct.pack("<3f", *p))
        # Mitsuba's ply plugin accepts triangles only: two per quad.
        for i in range(len(faces)):
            b = 4 * i
            f.write(struct.pack("<B3i", 3, b, b + 1, b + 2))
            f.write(struct.pack("<B3i", 3, b, b + 2, b + 3))


def write_tall_box(path):
    faces = box((-0.4, 0.6, -0.4), (0.6, 1.2, 0.6), 17.0)
    lines = [
        "ply",
        "format ascii 1.0",
        "comment Cornell box: tall box. Written by make_cornell.py",
        f"element vertex {4 * len(faces)}",
        "property float x",
        "property float y",
        "property float z",
        "property float nx",
        "property float ny",
        "property float nz",
        "property float u",
        "property float v",
        f"element face {2 * len(faces)}",
        "property list uchar uint vertex_indices",
        "end_header",
    ]
    for quad, n, uvs in faces:
        for p, uv in zip(quad, uvs):
            lines.append(" ".join(fmt(c) for c in (*p, *n, *uv)))
    for i in range(len(faces)):
        b = 4 * i
        lines.append(f"3 {b} {b + 1} {b + 2}")
        lines.append(f"3 {b} {b + 2} {b + 3}")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    write_white(os.path.join(HERE, "cbox_white.obj"))
    write_red(os.path.join(HERE, "cbox_red.obj"))
    write_green(os.path.join(HERE, "cbox_green.obj"))
    write_short_box(os.path.join(HERE, "cbox_short.ply"))
    write_tall_box(os.path.join(HERE, "cbox_tall.ply"))
