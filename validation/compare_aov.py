#!/usr/bin/env python3
"""Do radia's AOVs equal Mitsuba 3's `aov` integrator's? Renders each scene wrapped
in an aov integrator (every AOV type both support) in radia and in Mitsuba, K
passes each with distinct seeds (independent sampler, box filter), and tests every
channel of every pixel.

  validation/.venv/bin/python validation/compare_aov.py [SCENE...] [--quick]

The test. An AOV pixel is the mean, over the pixel's samples, of a function of the
sample's position in the pixel (depth, normal, uv, albedo, id of the surface seen
there). Inside a surface that function is smooth, at a silhouette or a texture
edge it jumps; either way a pass's pixel value is a Monte Carlo estimate of the
same pixel integral in both renderers, with a variance the K passes measure. So
each pixel channel gets Welch's t-test of the two pass means, at a family-wise
level alpha (Sidak over all pixel channels). Where the function is constant over
the pixel (a flat wall's normal, a constant albedo, a shape id) both variances
are 0 and the test degenerates; there the two values must agree to float
rounding, so a difference up to eps = 1e-4 * (1 + |value|) passes: two ray
tracers' hit points and interpolated attributes differ by a few ulps, far below
that, while any semantic difference (a flipped normal, another id, a missing
texture) is orders of magnitude above it. Unlike radiance, no block sums are
needed: AOV samples are not heavy-tailed, and edge pixels are what must be right.

Mitsuba's scene is loaded with optimize=False: its default loader merges meshes
that share a BSDF into one shape, which renumbers shape_index and prim_index;
radia, like Mitsuba without that optimisation, numbers shapes in the order the
scene declares them (1-based, 0 where nothing was hit) and triangles within each.

radia renders through its Python package (validation/setup builds it): the aov scene is
loaded once and each pass is one radia.render into numpy, whose layers equal the CLI's EXR
channels bit for bit (tests/test_radia_package_aov.py).

Exit status 0 when every channel of every scene passes, 1 when one fails, 2 when
a render cannot be made (or the radia package is missing or stale).
"""
import argparse
import os
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from radiaval.common import (REPO_ROOT, ValidationError, log, mitsuba,  # noqa: E402
                             mitsuba_scene_xml, radia_package, rel_to_repo, set_mitsuba_threads)
from radiaval.stats import sidak_alpha, t_critical  # noqa: E402

AOVS = ("dd.y:depth,pos:position,uv:uv,gn:geo_normal,nn:sh_normal,alb:albedo,"
        "dpdu:dp_du,si:shape_index,pi:prim_index")
SCENES = [os.path.join(REPO_ROOT, "scenes", s) for s in ("cornell-box.xml", "textured.xml")]
QUICK = dict(res=32, spp=16, passes=8)
FULL = dict(res=64, spp=64, passes=16)
EPS = 1e-4


def aov_scene(scene_path, res, spp, out_dir):
    """The scene with its integrator nested in an aov integrator (as the layer
    `image`), film and sampler overridden, file names made absolute."""
    root = ET.fromstring(mitsuba_scene_xml(scene_path, res, spp, "independent", "box"))
    base = os.path.dirname(os.path.abspath(scene_path))
    for e in root.iter("string"):
        if e.get("name") == "filename" and not os.path.isabs(e.get("value")):
            e.set("value", os.path.join(base, e.get("value")))
    inner = root.find("integrator")
    aov = ET.Element("integrator", type="aov")
    ET.SubElement(aov, "string", name="aovs", value=AOVS)
    if inner is not None:
        idx = list(root).index(inner)
        root.remove(inner)
        inner.set("name", "image")
        aov.append(inner)
    else:
        idx = len([c for c in root if c.tag == "default"])
        ET.SubElement(aov, "integrator", type="path", name="image")
    root.insert(idx, aov)
    path = os.path.join(out_dir, os.path.basename(scene_path))
    ET.ElementTree(root).write(path)
    return path


def layers(bitmap):
    """{channel name: (H, W) float64} of a Mitsuba Bitmap, without the root RGB."""
    out = {}
    for name, b in bitmap.split():
        if name == "<root>":
            continue
        a = np.array(b, dtype=np.float64)
        if a.ndim == 2:
            a = a[..., None]
        suffixes = [f.name.split(".")[-1] for f in b.struct_()]
        for c, s in enumerate(suffixes):
            out[f"{name}.{s}"] = a[..., c]
    return out


def render_mitsuba(mi, path, passes):
    scene = mi.load_file(path, optimize=False)
    out = []
    for seed in range(passes):
        mi.render(scene, seed=seed)
        out.append(layers(scene.sensors()[0].film().bitmap()))
    return out


# The channel suffixes of each AOV type, in the order of the EXR's (and Mitsuba's) channels.
SUFFIXES = {"depth": "T", "position": "XYZ", "uv": "UV", "geo_normal": "XYZ",
            "sh_normal": "XYZ", "albedo": "RGB", "dp_du": "XYZ", "dp_dv": "XYZ",
            "shape_index": "I", "prim_index": "I"}


def radia_channels(layers):
    """{channel name: (H, W) float64} of radia.render's layers, named as layers() names
    Mitsuba's: NAME.SUFFIX; the nested integrator's layer (`image`) is R, G, B, A."""
    suffixes = {name: SUFFIXES[kind] for name, kind in (p.split(":") for p in AOVS.split(","))}
    out = {}
    for name, a in layers.items():
        s = suffixes.get(name, "RGBA")
        if a.shape[-1] != len(s):
            raise RuntimeError(f"radia's layer {name} has {a.shape[-1]} channels, expected {s}")
        for c, suffix in enumerate(s):
            out[f"{name}.{suffix}"] = a[..., c].astype(np.float64)
    return out


def render_radia(radia, path, spp, passes, threads):
    """K passes of the aov scene with the radia package: loaded once, (image, layers) a pass."""
    scene = radia.load_file(path)
    return [radia_channels(radia.render(scene, spp=spp, seed=seed, threads=threads)[1])
            for seed in range(passes)]


def compare(radia_passes, mts_passes, alpha):
    """[(channel, failing pixels, pixels, max |t| beyond the floor, max |diff|)]."""
    names = sorted(mts_passes[0])
    missing = [n for n in names if n not in radia_passes[0]]
    if missing:
        raise RuntimeError(f"radia's EXR lacks the channels {missing}")
    k = len(radia_passes)
    n_tests = len(names) * radia_passes[0][names[0]].size
    t_crit = t_critical(sidak_alpha(alpha, n_tests), 2 * k - 2)
    rows = []
    for n in names:
        a = np.stack([p[n] for p in radia_passes])
        b = np.stack([p[n] for p in mts_passes])
        ma, mb = a.mean(0), b.mean(0)
        se = np.sqrt(a.var(0, ddof=1) / k + b.var(0, ddof=1) / k)
        diff = np.abs(ma - mb)
        floor = EPS * (1 + np.maximum(np.abs(ma), np.abs(mb)))
        excess = np.maximum(diff - floor, 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.where(excess > 0, excess / se, 0.0)
        fail = t > t_crit
        rows.append((n, int(fail.sum()), diff.size, float(np.nanmax(t)), float(diff.max())))
    return rows, t_crit


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="*", help="scenes (default: the Cornell box and textured.xml)")
    ap.add_argument("--quick", action="store_true", help="%(res)dx%(res)d, %(passes)d passes of %(spp)d spp" % QUICK)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--alpha", type=float, default=0.01, help="family-wise level (default 0.01)")
    a = ap.parse_args(argv)
    mode = QUICK if a.quick else FULL
    try:
        radia = radia_package(binary_option=False)
    except ValidationError as e:
        log(f"compare_aov: {e}")
        return 2
    mi = mitsuba("scalar_rgb")
    set_mitsuba_threads(a.threads)
    failed = errors = 0
    t0 = time.perf_counter()
    for s in a.scenes or SCENES:
        log(f"== {rel_to_repo(s)} (AOVs)")
        with tempfile.TemporaryDirectory(prefix="radia-aov-") as tmp:
            try:
                path = aov_scene(s, mode["res"], mode["spp"], tmp)
                mts = render_mitsuba(mi, path, mode["passes"])
                rad = render_radia(radia, path, mode["spp"], mode["passes"], a.threads)
                rows, t_crit = compare(rad, mts, a.alpha)
            except Exception as e:
                log(f"ERROR  {rel_to_repo(s)}: {type(e).__name__}: {e}")
                errors += 1
                continue
        bad = [r for r in rows if r[1]]
        for n, nf, npx, tmax, dmax in rows:
            log(f"  {'FAIL' if nf else 'ok  '} {n:10s} {nf:4d}/{npx} pixels fail, max |t| {tmax:.3g} "
                f"(critical {t_crit:.3g}), max |diff| {dmax:.3g}")
        log(f"{'FAIL' if bad else 'PASS'}   {rel_to_repo(s)}: {len(rows)} channels")
        failed += bool(bad)
    log(f"compare_aov: {failed} failed, {errors} errors in {time.perf_counter() - t0:.1f} s")
    return 2 if errors else (1 if failed else 0)


if __name__ == "__main__":
    sys.exit(main())
