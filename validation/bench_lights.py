#!/usr/bin/env python3
"""Light selection: run time against error for radia's three ways of choosing the light
that next-event estimation samples (--light-sampler uniform, power, bvh) and for Mitsuba 3
(which chooses uniformly), on benchmark.py's spp ladder and with its measurements.

  validation/.venv/bin/python validation/bench_lights.py [SCENE...] [--res 128]
        [--max-spp 2048] [--samplers uniform,power,bvh] [--variants llvm_ad_rgb]

SCENE defaults to scenes/many-lights.xml. Writes validation/out/bench_lights/:
bench_lights.csv (one row per renderer and spp) and bench_lights.md (per scene: the time to
reach relMSE 1e-2 and 1e-3, render only and including the scene load, relMSE at 64 spp and
samples per second at the top of the ladder).

Everything is benchmark.py's: the reference (the committed one if it exists at --res, else
16 x 256 spp of Mitsuba llvm_ad_rgb cached by hash), relMSE corrected for the reference's
noise, times interpolated log-log between ladder points, the same thread count for both
renderers. radia runs through a one-line wrapper that appends --light-sampler to its
command line.
"""
import argparse
import csv
import os
import stat
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from benchmark import (TARGETS, bench_mitsuba, bench_radia, fmt_t,  # noqa: E402
                       get_reference, time_to)
from radiaval.common import DEFAULT_RADIA, OUT_DIR, REPO_ROOT, check_radia, log  # noqa: E402


def wrapper(binary, sampler, directory):
    """An executable that runs `binary` with --light-sampler `sampler` appended."""
    path = os.path.join(directory, f"radia-{sampler}")
    with open(path, "w") as f:
        f.write(f'#!/bin/sh\nexec "{os.path.abspath(binary)}" "$@" --light-sampler {sampler}\n')
    os.chmod(path, os.stat(path).st_mode | stat.S_IXUSR)
    return path


def at_spp(rows, spp, key):
    for r in rows:
        if r["spp"] == spp:
            return r[key]
    return None


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="*",
                    default=[os.path.join(REPO_ROOT, "scenes", "many-lights.xml")])
    ap.add_argument("--res", type=int, default=128, help="width = height (default 128)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--min-spp", type=int, default=1)
    ap.add_argument("--max-spp", type=int, default=2048)
    ap.add_argument("--samplers", default="uniform,power,bvh",
                    help="radia light samplers, comma-separated (default uniform,power,bvh)")
    ap.add_argument("--variants", default="llvm_ad_rgb",
                    help="Mitsuba variants, comma-separated (default llvm_ad_rgb; '' for none)")
    ap.add_argument("--ref-spp", type=int, default=4096)
    ap.add_argument("--ref-passes", type=int, default=16)
    ap.add_argument("--repeats", type=int, default=0)
    ap.add_argument("--radia", default=DEFAULT_RADIA)
    ap.add_argument("--out", default=os.path.join(OUT_DIR, "bench_lights"))
    a = ap.parse_args(argv)

    ladder = []
    s = a.min_spp
    while s <= a.max_spp:
        ladder.append(s)
        s *= 2
    samplers = [x for x in a.samplers.split(",") if x]
    variants = [x for x in a.variants.split(",") if x]
    check_radia(a.radia)
    os.makedirs(a.out, exist_ok=True)
    wrappers = tempfile.mkdtemp(prefix="radia-lights-")
    all_rows = []
    md = ["# Light selection: time to reach a relMSE\n",
          f"{a.res}x{a.res} px, {a.threads} threads for every renderer, spp ladder "
          f"{ladder[0]}..{ladder[-1]}; seconds, wall clock; relMSE corrected for the "
          f"reference's noise (validation/benchmark.py's method). radia: "
          f"`--light-sampler uniform|power|bvh` (bvh is the default); Mitsuba chooses "
          f"emitters uniformly.\n"]
    for scene in a.scenes:
        name = os.path.splitext(os.path.basename(scene))[0]
        log(f"== {name}")
        ref = get_reference(scene, a.res, a.ref_spp, a.ref_passes,
                            os.path.join(a.out, "refcache"), a.threads)
        rows_by = {}
        for sampler in samplers:
            log(f"radia --light-sampler {sampler}")
            rows = bench_radia(scene, a.res, ladder, a.threads,
                               wrapper(a.radia, sampler, wrappers), ref, a.repeats)
            for r in rows:
                r["renderer"] = f"radia-{sampler}"
            rows_by[f"radia-{sampler}"] = rows
        for v in variants:
            log(f"Mitsuba {v}")
            rows_by[f"mitsuba-{v}"] = bench_mitsuba(scene, a.res, ladder, a.threads, v, ref,
                                                    a.repeats)
        md.append(f"\n## {name}\n")
        md.append("| renderer | to 1e-2, render | to 1e-2, incl. load | to 1e-3, render "
                  "| relMSE @ 64 spp | Msamples/s @ top |")
        md.append("| --- | ---: | ---: | ---: | ---: | ---: |")
        for rend, rows in rows_by.items():
            top = max(rows, key=lambda r: r["spp"])
            rel64 = at_spp(rows, 64, "relmse_corrected")
            md.append(f"| {rend} | {fmt_t(time_to(rows, TARGETS[0], 'render_s'))} "
                      f"| {fmt_t(time_to(rows, TARGETS[0], 'total_s'))} "
                      f"| {fmt_t(time_to(rows, TARGETS[1], 'render_s'))} "
                      f"| {'–' if rel64 is None else f'{rel64:.3e}'} "
                      f"| {top['msamples_s']:.3g} |")
            for r in rows:
                all_rows.append(dict(scene=name, res=a.res, threads=a.threads, **r))
        log("\n".join(md[-len(rows_by) - 3:]))
    keys = sorted({k for r in all_rows for k in r})
    with open(os.path.join(a.out, "bench_lights.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(all_rows)
    with open(os.path.join(a.out, "bench_lights.md"), "w") as f:
        f.write("\n".join(md) + "\n")
    log(f"wrote {os.path.join(a.out, 'bench_lights.md')}")


if __name__ == "__main__":
    sys.exit(main())
