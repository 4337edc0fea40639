#!/usr/bin/env python3
"""Writes the small PNG textures of scenes/textured.xml (plain Python, no numpy; the files are
reproducible byte for byte):  python3 scenes/textures/make_textures.py

  tiles.png      32 x 32 RGB, sRGB-encoded: 4 x 4 coloured tiles with a diagonal gradient in
                 each, so nearest and bilinear lookups, wraps and uv transforms all show.
  roughness.png  32 x 32 grey, linear (load it raw): vertical bands of GGX alpha 0.04 .. 0.6.
  normals.png    64 x 64 RGB, linear (raw): a 4 x 4 grid of round bumps as tangent-space
                 normals n = 2 rgb - 1 (z up).
  height.png     64 x 64 grey, linear (raw): the same bumps as heights in [0, 1].
  ../meshes/uv-panel.obj  a bulged 2 x 2 panel, z = 0.2 (1 - (x^2 + y^2) / 2), with smooth
                 normals and a rotated, stretched uv layout (u along -y, v along x).
"""
import math
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))


def write_png(name, width, height, channels, rows):
    """rows: height lists of width * channels ints in [0, 255]; row 0 is the top."""
    color_type = {1: 0, 3: 2}[channels]
    raw = b"".join(b"\x00" + bytes(r) for r in rows)

    def chunk(tag, data):
        body = tag + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)

    png = (b"\x89PNG\r\n\x1a\n"
           + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, color_type, 0, 0, 0))
           + chunk(b"IDAT", zlib.compress(raw, 9))
           + chunk(b"IEND", b""))
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(png)


def byte(x):
    return max(0, min(255, int(round(x * 255))))


def tiles():
    palette = [(0.9, 0.2, 0.1), (0.1, 0.6, 0.2), (0.15, 0.3, 0.9), (0.95, 0.8, 0.1),
               (0.6, 0.1, 0.7), (0.1, 0.8, 0.8), (0.9, 0.5, 0.6), (0.3, 0.3, 0.3)]
    rows = []
    for y in range(32):
        row = []
        for x in range(32):
            c = palette[((x // 8) + 3 * (y // 8)) % len(palette)]
            g = 0.45 + 0.55 * ((x % 8) + (y % 8)) / 14.0
            row += [byte(v * g) for v in c]
        rows.append(row)
    write_png("tiles.png", 32, 32, 3, rows)


def roughness():
    rows = []
    for y in range(32):
        rows.append([byte(0.04 + 0.56 * (x // 4) / 7.0) for x in range(32)])
    write_png("roughness.png", 32, 32, 1, rows)


def bump(x, y):
    """Height in [0, 1] and its gradient, per texel, of a 4 x 4 grid of round bumps."""
    cell = 16
    cx, cy = (x % cell) + 0.5 - cell / 2, (y % cell) + 0.5 - cell / 2
    r = math.hypot(cx, cy) / (cell * 0.42)
    if r >= 1:
        return 0.0, 0.0, 0.0
    h = math.cos(r * math.pi / 2) ** 2
    # d/dr cos^2(r pi/2) = -pi/2 sin(r pi)
    dh_dr = -math.pi / 2 * math.sin(r * math.pi) / (cell * 0.42)
    rr = max(math.hypot(cx, cy), 1e-6)
    return h, dh_dr * cx / rr, dh_dr * cy / rr


def normals_and_height():
    nrows, hrows = [], []
    strength = 6.0  # height units per texel of slope for the normal map
    for y in range(64):
        nrow, hrow = [], []
        for x in range(64):
            h, gx, gy = bump(x, y)
            # Image y runs down while v runs down too: the tangent frame is (u, v, n).
            n = (-strength * gx, -strength * gy, 1.0)
            length = math.sqrt(sum(c * c for c in n))
            nrow += [byte(0.5 * (c / length) + 0.5) for c in n]
            hrow.append(byte(h))
        nrows.append(nrow)
        hrows.append(hrow)
    write_png("normals.png", 64, 64, 3, nrows)
    write_png("height.png", 64, 64, 1, hrows)


def uv_panel():
    lines = ["# A bulged 2 x 2 panel with smooth normals and a rotated, stretched uv layout (u along -y,",
             "# v along x) for scenes/textured.xml: mesh uv, dp/du, dp/dv and shading normals that",
             "# differ from the face normals. Written by scenes/textures/make_textures.py."]
    vs, vts, vns = [], [], []
    for j in range(3):
        for i in range(3):
            x, y = i - 1, j - 1
            vs.append((x, y, 0.2 * (1 - (x * x + y * y) / 2)))
            vts.append(((1 - y) / 2, (x + 1) / 2 * 1.5))
            n = (0.2 * x, 0.2 * y, 1.0)
            length = math.sqrt(sum(c * c for c in n))
            vns.append(tuple(c / length for c in n))
    lines += ["v %g %g %g" % v for v in vs]
    lines += ["vt %g %g" % t for t in vts]
    lines += ["vn %.6f %.6f %.6f" % n for n in vns]
    for j in range(2):
        for i in range(2):
            a = j * 3 + i + 1
            for tri in ((a, a + 1, a + 4), (a, a + 4, a + 3)):
                lines.append("f " + " ".join("%d/%d/%d" % (k, k, k) for k in tri))
    with open(os.path.join(HERE, "..", "meshes", "uv-panel.obj"), "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    uv_panel()
    tiles()
    roughness()
    normals_and_height()
