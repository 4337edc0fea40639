"""A stand-in for the radia binary, for testing compare.py and benchmark.py end
to end without it: renders with Mitsuba (scalar_rgb) and speaks radia's command line

    fake_radia.py render SCENE -o OUT.exr [--spp N] [--seed S] [--threads N]
        [--sampler NAME] [--resolution WxH] [--rfilter box|gaussian] [-D k=v ...]

Overrides are applied as radia applies them (film size, filter, sampler type and
spp on top of the scene's own); --sampler sobol renders with Mitsuba's
independent sampler. Prints radia's "loaded" and final lines, with the spp the
sampler actually rendered. FAKE_RADIA_INVALID=N makes it report N dropped samples; FAKE_RADIA_BIAS=F in the environment multiplies the
image by F.
"""
import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from radiaval.common import (RADIA_SAMPLERS, load_mitsuba_scene, mitsuba,  # noqa: E402
                             mitsuba_scene_spp, set_mitsuba_threads, write_exr)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("cmd", choices=["render"])
    ap.add_argument("scene")
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("--spp", type=int)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", type=int)
    ap.add_argument("--sampler", choices=RADIA_SAMPLERS)
    ap.add_argument("--resolution")
    ap.add_argument("--rfilter", choices=["box", "gaussian"])
    ap.add_argument("--light-sampler")
    ap.add_argument("-q", "--quiet", action="store_true")
    ap.add_argument("-D", action="append", default=[])
    a = ap.parse_args()
    mi = mitsuba("scalar_rgb")
    set_mitsuba_threads(a.threads)
    res = None
    if a.resolution:
        w, _, h = a.resolution.lower().partition("x")
        res = (int(w), int(h or w))
    sampler = {"sobol": "independent"}.get(a.sampler, a.sampler)
    t0 = time.perf_counter()
    scene = load_mitsuba_scene(mi, a.scene, res=res, spp=a.spp, sampler=sampler,
                               rfilter=a.rfilter, defines=a.D)
    t1 = time.perf_counter()
    spp = mitsuba_scene_spp(scene)
    name = a.sampler or type(scene.sensors()[0].sampler()).__name__
    print(f"radia: loaded {a.scene} in {t1 - t0:.3f} s: fake, at {spp} spp ({name} sampler)",
          file=sys.stderr)
    # Seeds offset so that the fake's passes are independent of the references'.
    import numpy as np
    img = np.array(mi.render(scene, seed=a.seed + 7000), dtype=np.float32)[..., :3]
    img *= np.float32(float(os.environ.get("FAKE_RADIA_BIAS", "1")))
    t2 = time.perf_counter()
    write_exr(a.output, img)
    h, w = img.shape[:2]
    print(f"radia: {w}x{h}, {spp} spp, {t2 - t1:.3f} s render, "
          f"{w * h * spp / (t2 - t1) / 1e6:.2f} Msamples/s, 0.00 Mrays/s, {os.environ.get('FAKE_RADIA_INVALID', '0')} invalid samples dropped -> {a.output}")


if __name__ == "__main__":
    main()
