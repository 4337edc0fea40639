#!/usr/bin/env python3
"""Measure the test's false-alarm rate and power on a scene: N trials of
independent Mitsuba candidate passes (llvm_ad_rgb, fresh seeds each trial)
against the cached reference, unbiased and scaled by a few factors.

  validation/.venv/bin/python validation/calibrate.py scenes/cornell-box.xml [--trials 100]

Under H0 the fraction of failed trials should be at most alpha (0.01); every
biased trial should fail.
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np  # noqa: E402

from radiaval import stats  # noqa: E402
from radiaval.common import REFERENCE_DIR, MitsubaRenderer, log, rel_to_repo  # noqa: E402
from radiaval.references import load_reference  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="+")
    ap.add_argument("--trials", type=int, default=100)
    ap.add_argument("--res", type=int, default=64)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--passes", type=int, default=32)
    ap.add_argument("--biases", default="1.01,1.005,0.995,0.99")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--ref-dir", default=REFERENCE_DIR)
    a = ap.parse_args(argv)
    biases = [float(b) for b in a.biases.split(",") if b]
    for scene in a.scenes:
        ref = load_reference(scene, a.res, a.ref_dir)
        r = MitsubaRenderer(scene, a.res, a.spp, variant=a.variant)
        fails, fails_b, rej = 0, {b: 0 for b in biases}, []
        for t in range(a.trials):
            cand = r.passes(a.passes, seed0=10000 + a.passes * t)
            res = stats.compare_to_reference(cand, ref.mean, ref.var, ref.passes)
            fails += not res.passed
            rej.append([l.n_rejected for l in res.levels])
            for b in biases:
                fails_b[b] += not stats.compare_to_reference(cand * b, ref.mean, ref.var,
                                                             ref.passes).passed
        rej = np.array(rej)
        names = [l.name() for l in res.levels]
        log(f"{rel_to_repo(scene)}: {a.trials} trials of {a.passes} x {a.spp} spp at {a.res}x{a.res}")
        log(f"  H0 (unbiased): {fails} failed ({100.0 * fails / a.trials:.1f}%)")
        for b in biases:
            log(f"  x {b:g}: {fails_b[b]} failed ({100.0 * fails_b[b] / a.trials:.1f}%)")
        log("  H0 rejections per level, max / mean: " + ", ".join(
            f"{n} {rej[:, i].max()} / {rej[:, i].mean():.2f}" for i, n in enumerate(names)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
