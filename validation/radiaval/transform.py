"""A Mitsuba XML scene moved as a whole: every shape and the camera scaled about the origin,
then translated, so that a renderer that is right at every scale and position renders the
same image (issue #11: the Cornell box scaled by 1e-4 and 1e5, and translated by 1e5).

Shapes get `<scale>` and `<translate>` appended to their `to_world` (Mitsuba composes a
transform's children left to right, each applied after the ones before it,
`src/core/xml.cpp`), or a new `to_world` holding just those. The camera's `lookat` origin
and target are moved directly (Mitsuba's perspective camera refuses scale in its
`to_world`), and its near and far clip planes are scaled with the scene. Area emitters keep
their radiance: radiance does not change with scale. Scenes with point, spot or other
positioned emitters are refused (their intensity or position would need the same care).
"""
import math
import os
import re
import xml.etree.ElementTree as ET

import numpy as np

from .common import derive_scene

# Mitsuba's perspective defaults (src/sensors/perspective.cpp).
NEAR_CLIP, FAR_CLIP = 1e-2, 1e4


def _vec(text):
    return [float(x) for x in re.split(r"[,\s]+", text.strip()) if x]


def _fmt(v):
    return ", ".join(repr(float(x)) for x in v)


def transform_scene(src, dst_dir, scale=1.0, translate=(0.0, 0.0, 0.0), near_clip=None):
    """Write `src` moved by x -> scale * x + translate into dst_dir; returns the new path.
    near_clip (before scaling) replaces the sensor's."""
    path = derive_scene(src, dst_dir, [])
    tree = ET.parse(path)
    root = tree.getroot()
    tx, ty, tz = translate
    for e in root.iter("emitter"):
        if e.get("type") not in ("area", "constant", "envmap", "directional"):
            raise ValueError(f"{src}: a {e.get('type')} emitter would need moving too")
    for shape in root.findall("shape"):
        tr = next((t for t in shape.findall("transform") if t.get("name") == "to_world"), None)
        if tr is None:
            tr = ET.SubElement(shape, "transform", name="to_world")
        ET.SubElement(tr, "scale", value=repr(float(scale)))
        ET.SubElement(tr, "translate", x=repr(tx), y=repr(ty), z=repr(tz))
    for sensor in root.iter("sensor"):
        tr = next((t for t in sensor.findall("transform") if t.get("name") == "to_world"), None)
        looks = [] if tr is None else list(tr)
        if len(looks) != 1 or looks[0].tag != "lookat":
            raise ValueError(f"{src}: the sensor's to_world must be a single <lookat>")
        la = looks[0]
        for key in ("origin", "target"):
            x, y, z = _vec(la.get(key))
            la.set(key, _fmt((x * scale + tx, y * scale + ty, z * scale + tz)))
        for name, default in (("near_clip", NEAR_CLIP), ("far_clip", FAR_CLIP)):
            el = next((f for f in sensor.findall("float") if f.get("name") == name), None)
            if el is None:
                el = ET.SubElement(sensor, "float", name=name, value=repr(default))
            if name == "near_clip" and near_clip is not None:
                el.set("value", repr(near_clip))
            el.set("value", repr(float(el.get("value")) * scale))
    tree.write(path)
    return path


# ---------------------------------------------------------------------------
# Snapping: a scene whose every coordinate is a multiple of a power of two, so that
# translating it by a multiple of that power (1e5 by 2^-7, say) is exact in float32. The
# translated render then differs from the original only by the renderer's own rounding,
# not by the quantization of its input to the coarser floats far from the origin.
# ---------------------------------------------------------------------------

def _snap(x, grid):
    return np.round(np.asarray(x, np.float64) / grid) * grid


def _snap_obj(src, dst, grid):
    out = []
    for line in open(src):
        if line.startswith("v "):
            v = _snap([float(t) for t in line.split()[1:4]], grid)
            line = "v " + " ".join(repr(float(x)) for x in v) + "\n"
        out.append(line)
    with open(dst, "w") as f:
        f.writelines(out)


def _snap_ply(src, dst, grid):
    data = open(src, "rb").read()
    end = data.index(b"end_header") + len(b"end_header")
    end = data.index(b"\n", end) + 1
    header = data[:end].decode("ascii").splitlines()
    fmt = next(l.split()[1] for l in header if l.startswith("format"))
    props, n_vertex, in_vertex = [], 0, False
    for l in header:
        w = l.split()
        if w[:1] == ["element"]:
            in_vertex = w[1] == "vertex"
            n_vertex = int(w[2]) if in_vertex else n_vertex
        elif w[:1] == ["property"] and in_vertex:
            if w[1] != "float":
                raise ValueError(f"{src}: vertex property {w[-1]} is not a float")
            props.append(w[-1])
    xyz = [props.index(c) for c in "xyz"]
    body = data[end:]
    if fmt == "binary_little_endian":
        n = len(props) * n_vertex
        verts = np.frombuffer(body[:4 * n], "<f4").reshape(n_vertex, len(props)).copy()
        verts[:, xyz] = _snap(verts[:, xyz], grid)
        body = verts.astype("<f4").tobytes() + body[4 * n:]
    elif fmt == "ascii":
        lines = body.decode("ascii").splitlines(keepends=True)
        for i in range(n_vertex):
            v = [float(t) for t in lines[i].split()]
            for k in xyz:
                v[k] = float(_snap(v[k], grid))
            lines[i] = " ".join(repr(x) for x in v) + "\n"
        body = "".join(lines).encode("ascii")
    else:
        raise ValueError(f"{src}: PLY format {fmt} not handled")
    with open(dst, "wb") as f:
        f.write(data[:end] + body)


def _to_world_matrix(tr):
    """Mitsuba's composition of scale / rotate / translate children (src/core/xml.cpp)."""
    m = np.eye(4)
    for op in tr:
        if op.tag == "scale":
            v = op.get("value")
            s = [float(v)] * 3 if v is not None else [float(op.get(k, 1)) for k in "xyz"]
            step = np.diag(s + [1.0])
        elif op.tag == "translate":
            step = np.eye(4)
            step[:3, 3] = [float(op.get(k, 0)) for k in "xyz"]
        elif op.tag == "rotate":
            axis = np.array([float(op.get(k, 0)) for k in "xyz"])
            axis /= np.linalg.norm(axis)
            a = math.radians(float(op.get("angle")))
            x, y, z = axis
            c, s_ = math.cos(a), math.sin(a)
            step = np.eye(4)
            step[:3, :3] = [[c + x * x * (1 - c), x * y * (1 - c) - z * s_, x * z * (1 - c) + y * s_],
                            [y * x * (1 - c) + z * s_, c + y * y * (1 - c), y * z * (1 - c) - x * s_],
                            [z * x * (1 - c) - y * s_, z * y * (1 - c) + x * s_, c + z * z * (1 - c)]]
        elif op.tag == "matrix":
            step = np.array(_vec(op.get("value"))).reshape(4, 4)
        else:
            raise ValueError(f"cannot snap a <{op.tag}> transform")
        m = step @ m
    return m


def snap_scene(src, dst_dir, grid=2.0 ** -7):
    """Write `src` with every mesh vertex, transform entry and camera point rounded to a
    multiple of `grid` into dst_dir (meshes copied there); returns the new scene's path."""
    path = derive_scene(src, dst_dir, [])
    tree = ET.parse(path)
    root = tree.getroot()
    for shape in root.findall("shape"):
        kind = shape.get("type")
        if kind in ("obj", "ply"):
            fn = next(e for e in shape.findall("string") if e.get("name") == "filename")
            dst = os.path.join(dst_dir, os.path.basename(fn.get("value")))
            (_snap_obj if kind == "obj" else _snap_ply)(fn.get("value"), dst, grid)
            fn.set("value", dst)
        for tr in [t for t in shape.findall("transform") if t.get("name") == "to_world"]:
            m = _snap(_to_world_matrix(tr), grid)
            for child in list(tr):
                tr.remove(child)
            ET.SubElement(tr, "matrix", value=" ".join(repr(float(x)) for x in m.ravel()))
    for la in root.iter("lookat"):
        for key in ("origin", "target"):
            la.set(key, _fmt(_snap(_vec(la.get(key)), grid)))
    tree.write(path)
    return path


def moved_name(scale, translate):
    return f"scale{scale:g}-translate{'_'.join(f'{t:g}' for t in translate)}"


__all__ = ["transform_scene", "snap_scene", "moved_name"]
