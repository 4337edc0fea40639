"""A stand-in for the radia binary, for testing compare.py end to end without
it: renders with Mitsuba (scalar_rgb) and speaks radia's command line

    fake_radia.py render SCENE -o OUT.exr [--spp N] [--seed S] [--threads N] [-D k=v ...]

FAKE_RADIA_BIAS=F in the environment multiplies the image by F.
"""
import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from radiaval.common import mitsuba, write_exr, set_mitsuba_threads  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("cmd", choices=["render"])
    ap.add_argument("scene")
    ap.add_argument("-o", "--output", required=True)
    ap.add_argument("--spp", type=int)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", type=int)
    ap.add_argument("-D", action="append", default=[])
    a = ap.parse_args()
    mi = mitsuba("scalar_rgb")
    set_mitsuba_threads(a.threads)
    defs = dict(d.split("=", 1) for d in a.D)
    if a.spp:
        defs["spp"] = str(a.spp)
    t0 = time.perf_counter()
    scene = mi.load_file(a.scene, **defs)
    t1 = time.perf_counter()
    print(f"radia: loaded {a.scene} in {t1 - t0:.3f} s: fake", file=sys.stderr)
    # Seeds offset so that the fake's passes are independent of the references'.
    import numpy as np
    img = np.array(mi.render(scene, seed=a.seed + 7000), dtype=np.float32)[..., :3]
    img *= np.float32(float(os.environ.get("FAKE_RADIA_BIAS", "1")))
    t2 = time.perf_counter()
    write_exr(a.output, img)
    h, w = img.shape[:2]
    spp = int(defs.get("spp", 0))
    print(f"radia: {w}x{h}, {spp} spp, {t2 - t1:.3f} s render, "
          f"{w * h * spp / (t2 - t1) / 1e6:.2f} Msamples/s, 0.00 Mrays/s, 0 invalid samples dropped -> {a.output}")


if __name__ == "__main__":
    main()
