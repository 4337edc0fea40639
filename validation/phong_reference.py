#!/usr/bin/env python3
"""Parity of radia's `phong` and `blinnphong` (radia extensions: Mitsuba 3 has no Phong
model) against Mitsuba 3.9.1 running the same two models written in Python through its
plugin API (`mi.register_bsdf`).

  validation/.venv/bin/python validation/phong_reference.py [--quick] [--res R] ...

Method
  1. The two models are written here a second time, in Dr.Jit, from their definitions
     (crates/bsdf/src/phong.rs, blinn_phong.rs):
       phong:       f = kd/pi + ks (n+2)/(2 pi) max(0, r.wo)^n,  r the mirror of wi
       blinnphong:  f = kd/pi + ks (n+2)(n+4)/(8 pi (n + 2^(-n/2))) (n.h)^n
     and sampled by the cosine only: the reference does not share radia's lobe sampling,
     mixture weights or pdf, so those are tested too.
  2. The Python models are checked first by numerical integration of their lobes: the
     directional albedo at normal incidence must be kd + ks (the normalizations), and at
     most that at other angles.
  3. One scene (four spheres of both models filling the frame, an area light and a uniform
     sky; written to validation/out/phong/phong.xml) is rendered by Mitsuba (llvm_ad_rgb, 64 passes x 256
     spp by default) with the Python plugins and by radia, which loads the same XML
     natively (32 passes).
  4. The verdict is compare.py's statistical test (radiaval.stats.compare_to_reference:
     Welch t-tests per pixel, 4x4 and 16x16 block and image mean, Sidak-corrected).

The scene is not in scenes/ because Mitsuba cannot load it without this script's plugins.
Exit status: 0 pass, 1 fail, 2 the run could not be made.
"""
import argparse
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from radiaval import stats  # noqa: E402
from radiaval.common import (OUT_DIR, REF_SEED_BASE, MitsubaRenderer,  # noqa: E402
                             ValidationError, log, make_radia_renderer, mitsuba)

SCENE = """<?xml version="1.0" encoding="utf-8"?>
<!-- Normalized Phong and Blinn-Phong (radia's phong and blinnphong): four spheres filling
     the frame under an area light and a uniform sky. Mitsuba loads it only with the Python
     plugins of validation/phong_reference.py. -->
<scene version="3.0.0">
    <default name="spp" value="64"/>
    <default name="res" value="64"/>
    <integrator type="path"/>
    <sensor type="perspective">
        <float name="fov" value="36"/>
        <transform name="to_world">
            <lookat origin="0, 0, 6.5" target="0, 0, 0" up="0, 1, 0"/>
        </transform>
        <sampler type="independent">
            <integer name="sample_count" value="$spp"/>
        </sampler>
        <film type="hdrfilm">
            <integer name="width" value="$res"/>
            <integer name="height" value="$res"/>
            <string name="pixel_format" value="rgb"/>
            <string name="component_format" value="float32"/>
            <rfilter type="box"/>
        </film>
    </sensor>
    <emitter type="constant">
        <rgb name="radiance" value="0.3"/>
    </emitter>
    <shape type="rectangle">
        <transform name="to_world">
            <scale value="1.2"/>
            <rotate x="1" angle="60"/>
            <translate x="-1.5" y="3.5" z="3"/>
        </transform>
        <emitter type="area">
            <rgb name="radiance" value="8"/>
        </emitter>
    </shape>
    <shape type="sphere">
        <point name="center" x="-1.0" y="1.0" z="0"/>
        <float name="radius" value="0.95"/>
        <bsdf type="phong">
            <rgb name="diffuse_reflectance" value="0.15, 0.3, 0.6"/>
            <rgb name="specular_reflectance" value="0.35"/>
            <float name="exponent" value="20"/>
        </bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" x="1.0" y="1.0" z="0"/>
        <float name="radius" value="0.95"/>
        <bsdf type="phong">
            <rgb name="diffuse_reflectance" value="0.1"/>
            <rgb name="specular_reflectance" value="0.8, 0.7, 0.5"/>
            <float name="exponent" value="150"/>
        </bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" x="-1.0" y="-1.0" z="0"/>
        <float name="radius" value="0.95"/>
        <bsdf type="blinnphong">
            <rgb name="diffuse_reflectance" value="0.6, 0.2, 0.1"/>
            <rgb name="specular_reflectance" value="0.3"/>
            <float name="exponent" value="60"/>
        </bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" x="1.0" y="-1.0" z="0"/>
        <float name="radius" value="0.95"/>
        <bsdf type="blinnphong">
            <rgb name="diffuse_reflectance" value="0"/>
            <rgb name="specular_reflectance" value="0.9"/>
            <float name="exponent" value="8"/>
        </bsdf>
    </shape>
</scene>
"""


# ---------------------------------------------------------------------------
# The models as Mitsuba plugins
# ---------------------------------------------------------------------------

def register_plugins(mi):
    """Registers `phong` and `blinnphong` for the current variant."""
    import drjit as dr

    class NormalizedPhongBase(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.kd = props.get_texture("diffuse_reflectance", 0.5)
            self.ks = props.get_texture("specular_reflectance", 0.2)
            self.n = float(props.get("exponent", 30.0))
            flags = (mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.GlossyReflection
                     | mi.BSDFFlags.FrontSide)
            self.m_components = [flags]
            self.m_flags = flags

        def lobe(self, wi, wo):
            raise NotImplementedError

        def eval(self, ctx, si, wo, active=True):
            cos_i = mi.Frame3f.cos_theta(si.wi)
            cos_o = mi.Frame3f.cos_theta(wo)
            f = (self.kd.eval(si, active) * dr.inv_pi
                 + self.ks.eval(si, active) * self.lobe(si.wi, wo))
            return dr.select(active & (cos_i > 0) & (cos_o > 0), f * cos_o, 0.0)

        def pdf(self, ctx, si, wo, active=True):
            cos_i = mi.Frame3f.cos_theta(si.wi)
            p = mi.warp.square_to_cosine_hemisphere_pdf(wo)
            return dr.select(active & (cos_i > 0) & (mi.Frame3f.cos_theta(wo) > 0), p, 0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def sample(self, ctx, si, sample1, sample2, active=True):
            wo = mi.warp.square_to_cosine_hemisphere(sample2)
            pdf = mi.warp.square_to_cosine_hemisphere_pdf(wo)
            bs = dr.zeros(mi.BSDFSample3f)
            bs.wo = wo
            bs.pdf = pdf
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.GlossyReflection)
            bs.sampled_component = mi.UInt32(0)
            ok = active & (mi.Frame3f.cos_theta(si.wi) > 0) & (pdf > 0)
            value = self.eval(ctx, si, wo, ok) / dr.maximum(pdf, 1e-20)
            return bs, dr.select(ok, value, 0.0)

        def to_string(self):
            return f"{type(self).__name__}[n={self.n}]"

    class Phong(NormalizedPhongBase):
        def lobe(self, wi, wo):
            r = mi.Vector3f(-wi.x, -wi.y, wi.z)
            c = dr.dot(r, wo)
            n = self.n
            return dr.select(c > 0, (n + 2) * dr.inv_two_pi * dr.power(dr.maximum(c, 1e-30), n), 0.0)

    class BlinnPhong(NormalizedPhongBase):
        def lobe(self, wi, wo):
            h = dr.normalize(wi + wo)
            n = self.n
            norm = (n + 2) * (n + 4) / (8 * np.pi * (n + 2 ** (-n / 2)))
            return dr.select(h.z > 0, norm * dr.power(dr.maximum(h.z, 1e-30), n), 0.0)

    mi.register_bsdf("phong", lambda props: Phong(props))
    mi.register_bsdf("blinnphong", lambda props: BlinnPhong(props))


def check_normalization(mi):
    """The Python models' directional albedo by quadrature over the hemisphere: kd + ks at
    normal incidence, no more than that elsewhere. Returns a list of failures."""
    import drjit as dr
    failures = []
    cases = [("phong", 0.0, 1.0, n) for n in (0.0, 1.0, 20.0, 150.0)]
    cases += [("blinnphong", 0.0, 1.0, n) for n in (0.0, 1.0, 8.0, 60.0)]
    cases += [("phong", 0.3, 0.7, 5.0), ("blinnphong", 0.4, 0.6, 5.0)]
    # Midpoint rule in (theta, phi) over the upper hemisphere, fine enough for n = 150
    # (lobe width ~0.1 rad, 2000 rows of 0.8 mrad).
    nt, nphi = 2000, 400
    t = (np.arange(nt) + 0.5) * (np.pi / 2 / nt)
    p = (np.arange(nphi) + 0.5) * (2 * np.pi / nphi)
    T, P = np.meshgrid(t, p, indexing="ij")
    def f32(x):
        return mi.Float(np.ravel(x).astype(np.float32))
    wo = mi.Vector3f(f32(np.sin(T) * np.cos(P)), f32(np.sin(T) * np.sin(P)), f32(np.cos(T)))
    dw = np.ravel(np.sin(T)) * (np.pi / 2 / nt) * (2 * np.pi / nphi)
    for name, kd, ks, n in cases:
        bsdf = mi.load_dict({"type": name, "diffuse_reflectance": {"type": "rgb", "value": kd},
                             "specular_reflectance": {"type": "rgb", "value": ks},
                             "exponent": n})
        albedo = []
        for cos_i in (1.0, 0.7, 0.3, 0.05):
            si = dr.zeros(mi.SurfaceInteraction3f, dr.width(wo))
            si.wi = mi.Vector3f(float(np.sqrt(1 - cos_i ** 2)), 0.0, cos_i)
            f = np.array(bsdf.eval(mi.BSDFContext(), si, wo))[0]
            albedo.append(float((f * dw).sum()))
        want = kd + ks
        ok = abs(albedo[0] - want) < 2e-3 and max(albedo) <= want + 2e-3
        log(f"  {'ok  ' if ok else 'FAIL'} {name} kd {kd} ks {ks} n {n:g}: albedo at cos "
            f"1/0.7/0.3/0.05 = {', '.join(f'{a:.4f}' for a in albedo)} (normal incidence: {want})")
        if not ok:
            failures.append(name)
    return failures


# ---------------------------------------------------------------------------
# Main
# ---------------------------------------------------------------------------

def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="CI mode: 16 spp candidate passes, "
                    "32 reference passes of 128 spp")
    ap.add_argument("--res", type=int, default=64)
    ap.add_argument("--spp", type=int, help="spp per radia pass (default 64; quick 16)")
    ap.add_argument("--passes", type=int, default=32, help="radia passes (default 32)")
    ap.add_argument("--ref-spp", type=int, help="spp per Mitsuba pass (default 256; quick 128)")
    ap.add_argument("--ref-passes", type=int, help="Mitsuba passes (default 64; quick 32)")
    ap.add_argument("--ref-variant", default="llvm_ad_rgb")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--radia", metavar="PATH",
                    help="render with this radia binary (default: the radia Python package)")
    ap.add_argument("--alpha", type=float, default=0.01)
    ap.add_argument("--tolerance", type=float, default=0.0025)
    a = ap.parse_args(argv)
    spp = a.spp or (16 if a.quick else 64)
    ref_spp = a.ref_spp or (128 if a.quick else 256)
    ref_passes = a.ref_passes or (32 if a.quick else 64)

    out_dir = os.path.join(OUT_DIR, "phong")
    os.makedirs(out_dir, exist_ok=True)
    scene = os.path.join(out_dir, "phong.xml")
    with open(scene, "w") as f:
        f.write(SCENE)

    t0 = time.perf_counter()
    try:
        mi = mitsuba(a.ref_variant)
        register_plugins(mi)
        log("== the Python reference models, by quadrature of their lobes")
        failures = check_normalization(mi)
        if failures:
            log("phong_reference: the reference models are wrong; no comparison")
            return 2

        log(f"== {scene}: Mitsuba {a.ref_variant} with the Python plugins, "
            f"{ref_passes} passes x {ref_spp} spp")
        m = MitsubaRenderer(scene, a.res, ref_spp, variant=a.ref_variant, threads=a.threads)
        ref = m.passes(ref_passes, seed0=REF_SEED_BASE)
        ref_mean, ref_var, ref_k = stats.pass_moments(ref)

        log(f"== radia: {a.passes} passes x {spp} spp")
        r = make_radia_renderer(scene, a.res, spp, binary=a.radia, threads=a.threads)
        cand = r.passes(a.passes, seed0=0)
    except ValidationError as e:
        log(f"ERROR  {e}")
        return 2

    res = stats.compare_to_reference(cand, ref_mean, ref_var, ref_k,
                                     alpha=a.alpha, tolerance=a.tolerance)
    verdict = "PASS" if res.passed else "FAIL"
    log(f"{verdict}  phong/blinnphong  [radia]  {a.res}x{a.res}, {a.passes} passes x {spp} spp "
        f"vs Mitsuba with Python plugins {ref_k * ref_spp} spp")
    log(f"  Welch t-test, alpha {a.alpha} family-wise, Sidak per-test {res.alpha_test:.3g} "
        f"over {res.n_tests} tests:")
    for row in res.summary_rows():
        log(f"    {row['level']:>6}: {row['rejected']:5d}/{row['tests']:<6d} rejected "
            f"(allowed {row['allowed']}), max|t| {row['max_abs_t']:.2f}, "
            f"min p {row['min_p']:.2e}  {'ok' if row['passed'] else 'FAIL'}")
    ratio = float(cand.mean() / ref_mean.mean())
    log(f"  image mean radia/reference {ratio:.4f}; invalid radia samples: {r.invalid}")
    log(f"  time {time.perf_counter() - t0:.1f} s")
    return 0 if res.passed else 1


if __name__ == "__main__":
    sys.exit(main())
