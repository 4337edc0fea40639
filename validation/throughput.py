#!/usr/bin/env python3
"""Samples per second of radia and Mitsuba 3 on the same scenes, in one run: issue #9's
throughput table (how many camera samples each renderer draws per second, render time
only, whatever their noise; efficiency is benchmark.py's business).

  validation/.venv/bin/python validation/throughput.py [SCENE...] [--res 512] [--spp 64]
        [--threads 2] [--repeats 3] [--samplers independent,sobol]
        [--radia-alt NAME=PATH ...] [--out validation/out/throughput]

SCENE defaults to every scenes/*.xml. Each scene renders at --res x --res, --spp samples per
pixel, box filter, --threads threads in both renderers:
  radia    the release binary (--radia, and each --radia-alt, e.g. an older build), once per
           sampler of --samplers; its own "render" time (load and EXR write excluded);
  Mitsuba  llvm_ad_rgb (--variant), the independent sampler (Mitsuba's samplers differ
           little in cost), the scene loaded once and rendered --repeats + 1 times: the first
           render compiles (or loads from Dr.Jit's cache) the kernel and is not counted.
Each figure is the median over --repeats renders; ratios are radia / Mitsuba.

Writes throughput.md and throughput.csv in --out.
"""
import argparse
import csv
import os
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np  # noqa: E402

from radiaval.common import (DEFAULT_RADIA, OUT_DIR, check_radia, list_scenes,  # noqa: E402
                             load_mitsuba_scene, log, mitsuba, parse_radia_output,
                             rel_to_repo, set_mitsuba_threads)


def radia_msamples(binary, scene, res, spp, threads, sampler, repeats):
    """Median M samples/s of `repeats` renders, as the binary reports them."""
    figures = []
    with tempfile.TemporaryDirectory(prefix="radia-tp-") as tmp:
        out = os.path.join(tmp, "out.exr")
        for seed in range(repeats):
            cmd = [binary, "render", scene, "-o", out, "--spp", str(spp), "--seed", str(seed),
                   "--resolution", f"{res}x{res}", "--threads", str(threads),
                   "--rfilter", "box", "--sampler", sampler]
            proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                  text=True)
            if proc.returncode != 0:
                log(f"  {os.path.basename(binary)} cannot render {scene}: "
                    f"{proc.stdout.strip().splitlines()[-1:]}")
                return None
            info = parse_radia_output(proc.stdout)
            figures.append(info["width"] * info["height"] * info["spp"] / info["render_s"] / 1e6)
    return statistics.median(figures)


def mitsuba_msamples(mi, scene_path, res, spp, repeats):
    import drjit as dr
    scene = load_mitsuba_scene(mi, scene_path, res=res, spp=spp, sampler="independent",
                               rfilter="box")
    spp = int(scene.sensors()[0].sampler().sample_count())
    figures = []
    for seed in range(repeats + 1):
        t0 = time.perf_counter()
        img = mi.render(scene, seed=seed)
        np.array(img, dtype=np.float32, copy=True)
        dr.sync_thread()
        if seed > 0:
            figures.append(res * res * spp / (time.perf_counter() - t0) / 1e6)
    return statistics.median(figures)


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="*")
    ap.add_argument("--res", type=int, default=512)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--samplers", default="independent,sobol")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--radia", default=DEFAULT_RADIA)
    ap.add_argument("--radia-alt", action="append", default=[], metavar="NAME=PATH")
    ap.add_argument("--out", default=os.path.join(OUT_DIR, "throughput"))
    args = ap.parse_args()

    binaries = [("radia", check_radia(args.radia))]
    for alt in args.radia_alt:
        name, _, path = alt.partition("=")
        binaries.append((name, check_radia(path)))
    samplers = args.samplers.split(",")
    scenes = args.scenes or list_scenes()
    mi = mitsuba(args.variant)
    set_mitsuba_threads(args.threads)

    rows = []
    for scene in scenes:
        name = os.path.splitext(os.path.basename(scene))[0]
        row = {"scene": name,
               "mitsuba": mitsuba_msamples(mi, scene, args.res, args.spp, args.repeats)}
        for bname, binary in binaries:
            for s in samplers:
                row[f"{bname} {s}"] = radia_msamples(binary, scene, args.res, args.spp,
                                                     args.threads, s, args.repeats)
        log(f"{name}: " + ", ".join(f"{k} {v:.2f}" for k, v in row.items()
                                    if isinstance(v, float)))
        rows.append(row)

    os.makedirs(args.out, exist_ok=True)
    cols = [f"{b} {s}" for b, _ in binaries for s in samplers]
    with open(os.path.join(args.out, "throughput.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["scene", "mitsuba"] + cols)
        w.writeheader()
        w.writerows(rows)

    def fmt(v):
        return "-" if v is None else f"{v:.2f}"

    lines = [f"M samples/s at {args.res}x{args.res}, {args.spp} spp, {args.threads} threads, "
             f"median of {args.repeats} (Mitsuba: {args.variant}, independent, warm kernel). "
             f"Ratio: radia's {cols[0].split(' ', 1)[1]} / Mitsuba.", "",
             "| scene | Mitsuba | " + " | ".join(cols) + " | ratio |",
             "|---" * (len(cols) + 3) + "|"]
    ratios = []
    for r in rows:
        ratio = r[cols[0]] / r["mitsuba"] if r[cols[0]] else None
        if ratio:
            ratios.append(ratio)
        lines.append(f"| {r['scene']} | {fmt(r['mitsuba'])} | "
                     + " | ".join(fmt(r[c]) for c in cols) + f" | {fmt(ratio)} |")
    if ratios:
        lines += ["", f"Median ratio {statistics.median(ratios):.2f} over {len(ratios)} scenes."]
    text = "\n".join(lines) + "\n"
    with open(os.path.join(args.out, "throughput.md"), "w") as f:
        f.write(text)
    print(text)
    log(f"wrote {rel_to_repo(os.path.join(args.out, 'throughput.md'))}")


if __name__ == "__main__":
    main()
