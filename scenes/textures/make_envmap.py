#!/usr/bin/env python3
"""Writes sky-sun.exr: a 128 x 64 latitude-longitude environment map (Mitsuba's `envmap`
layout: row 0 is the zenith, the last row the nadir, column u = 0 looks along -z) with a blue
sky, a brighter horizon, a dim brown ground and a small sun: a disc of about 4 degrees radius
at 36 degrees elevation, some 1000 times brighter than the sky, carrying most of the light.

Plain Python (no numpy), uncompressed float32 OpenEXR, so the file is reproducible byte for
byte:  python3 scenes/textures/make_envmap.py
"""
import math
import os
import struct

W, H = 128, 64
SUN_U, SUN_V = 0.30, 0.30           # texture coordinates of the sun's centre
SUN_RADIUS = math.radians(4.0)
SUN_RADIANCE = (900.0, 820.0, 700.0)


def direction(u, v):
    """Mitsuba's envmap uv_to_direction (src/emitters/envmap.cpp)."""
    theta, phi = v * math.pi, u * 2 * math.pi
    return (math.sin(phi) * math.sin(theta), math.cos(theta), -math.cos(phi) * math.sin(theta))


def radiance(i, j):
    # Texel centres: columns at (i + 1/2) / W, rows corner-aligned at j / (H - 1).
    u, v = (i + 0.5) / W, j / (H - 1)
    d = direction(u, v)
    elevation = math.asin(max(-1.0, min(1.0, d[1])))
    if elevation >= 0:
        t = elevation / (math.pi / 2)
        sky = (0.9 - 0.6 * t, 1.0 - 0.45 * t, 1.15 - 0.25 * t)
    else:
        sky = (0.12, 0.09, 0.06)
    s = direction(SUN_U, SUN_V)
    angle = math.acos(max(-1.0, min(1.0, sum(a * b for a, b in zip(d, s)))))
    # A disc with a soft rim one texel wide.
    w = max(0.0, min(1.0, (SUN_RADIUS - angle) / math.radians(2.8) + 0.5))
    return tuple(c + w * l for c, l in zip(sky, SUN_RADIANCE))


def attribute(name, kind, data):
    return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(data)) + data


def write_exr(path, width, height, pixel):
    channels = b"".join(c.encode() + b"\0" + struct.pack("<iB3xii", 2, 0, 1, 1) for c in "BGR") + b"\0"
    box = struct.pack("<iiii", 0, 0, width - 1, height - 1)
    header = (b"\x76\x2f\x31\x01" + struct.pack("<i", 2)
              + attribute("channels", "chlist", channels)
              + attribute("compression", "compression", b"\0")
              + attribute("dataWindow", "box2i", box)
              + attribute("displayWindow", "box2i", box)
              + attribute("lineOrder", "lineOrder", b"\0")
              + attribute("pixelAspectRatio", "float", struct.pack("<f", 1.0))
              + attribute("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0))
              + attribute("screenWindowWidth", "float", struct.pack("<f", 1.0))
              + b"\0")
    line_size = 3 * 4 * width
    first = len(header) + 8 * height
    offsets = b"".join(struct.pack("<Q", first + y * (8 + line_size)) for y in range(height))
    lines = []
    for y in range(height):
        row = [pixel(x, y) for x in range(width)]
        data = b"".join(struct.pack("<%df" % width, *[p[c] for p in row]) for c in (2, 1, 0))
        lines.append(struct.pack("<ii", y, len(data)) + data)
    with open(path, "wb") as f:
        f.write(header + offsets + b"".join(lines))


if __name__ == "__main__":
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "sky-sun.exr")
    write_exr(out, W, H, radiance)
    print("wrote", out)
