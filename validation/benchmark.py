#!/usr/bin/env python3
"""Run time against error: radia and Mitsuba 3 at a ladder of spp, same thread
count, relMSE against a high-spp Mitsuba reference.

  validation/.venv/bin/python validation/benchmark.py SCENE... [--res 256] [--threads 2]
        [--max-spp 1024] [--variants llvm_ad_rgb,scalar_rgb] [--ref-spp 4096]

Writes validation/out/benchmark/: benchmark.csv (one row per renderer and spp),
NAME.png (log-log relMSE against time, both renderers on one chart per scene),
benchmark.md (per scene: time to reach relMSE 1e-2 and 1e-3 and the ratios
radia/Mitsuba) and benchmark.html (the table and the plots).

relMSE = mean((x - ref)^2 / (ref^2 + 0.01)) over pixels and channels. The
reference's own noise adds to it; its estimate mean(var_ref / (ref^2 + 0.01))
is subtracted ("corrected" relMSE, used for the times to a target).

Timings (wall clock, time.perf_counter):
  radia    render  = the render time radia prints (no loading, no EXR write)
           total   = the whole process: start, scene load and BVH build, render, EXR write
  Mitsuba  load    = mi.load_file(...)
           render  = warm mi.render + transfer to numpy (JIT variants: a second render
                     of the same spp, kernels already compiled); scalar: the only render
           cold    = first mi.render after loading at that spp (JIT: tracing, compiling
                     or loading the kernel from Dr.Jit's cache)
           total   = load + cold render (the Python interpreter and `import mitsuba`
                     are not included; they are printed once as import_s)
"""
import argparse
import csv
import math
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np  # noqa: E402

from radiaval import stats  # noqa: E402
from radiaval.common import (DEFAULT_RADIA, OUT_DIR, REFERENCE_DIR, RadiaRenderer,  # noqa: E402
                             ValidationError, log, mitsuba, rel_to_repo, set_mitsuba_threads)
from radiaval.references import load_reference, make_reference  # noqa: E402

TARGETS = (1e-2, 1e-3)
MAX_LANES = 1 << 24   # JIT variants: at most this many samples per mi.render call


def get_reference(scene, res, ref_spp, ref_passes, refcache, threads):
    """The committed reference if it exists at this resolution, else one made
    (once, then cached by scene hash) in validation/out/benchmark/refcache."""
    try:
        ref = load_reference(scene, res, REFERENCE_DIR)
        if ref.total_spp >= ref_spp:
            return ref
    except ValidationError:
        pass
    try:
        ref = load_reference(scene, res, refcache)
        if ref.total_spp >= ref_spp:
            return ref
    except ValidationError:
        pass
    make_reference(scene, res, spp=max(1, ref_spp // ref_passes), passes=ref_passes,
                   variant="llvm_ad_rgb", ref_dir=refcache, threads=threads)
    return load_reference(scene, res, refcache)


def relmse_pair(img, ref):
    r = stats.rel_mse(img, ref.mean)
    floor = float(np.mean(ref.var / (ref.mean ** 2 + 0.01)))
    return r, r - floor, floor


def repeats_for(spp, repeats):
    """Low-spp points are cheap and their relMSE noisy: repeat them (median
    time, mean relMSE) unless --repeats is given."""
    if repeats:
        return repeats
    return max(1, min(8, 16 // spp))


def _median(xs):
    xs = [x for x in xs if x is not None]
    return float(np.median(xs)) if xs else None


def bench_radia(scene, res, ladder, threads, binary, ref, repeats=0):
    rows = []
    r = RadiaRenderer(scene, res, ladder[0], binary=binary, threads=threads)
    for spp in ladder:
        rels, infos = [], []
        for k in range(repeats_for(spp, repeats)):
            img = r.render(seed=spp * 100 + k, spp=spp)
            infos.append(r.infos[-1])
            rels.append(relmse_pair(img, ref))
        rel, relc, floor = (float(np.mean([x[i] for x in rels])) for i in range(3))
        render = _median([i.get("render_s") for i in infos]) or float("nan")
        wall = _median([i["wall_s"] for i in infos])
        rows.append(dict(renderer="radia", spp=spp, repeats=len(infos),
                         load_s=_median([i.get("load_s") for i in infos]), render_s=render,
                         render_cold_s=render, total_s=wall, relmse=rel,
                         relmse_corrected=relc, ref_noise=floor,
                         msamples_s=res * res * spp / render / 1e6 if render else None,
                         mrays_s=_median([i.get("mrays_s") for i in infos])))
        log(f"  radia {spp:5d} spp x{len(infos)}: render {render:8.3f} s, total {wall:8.3f} s, "
            f"relMSE {rel:.3e}")
    return rows


def bench_mitsuba(scene, res, ladder, threads, variant, ref, repeats=0):
    import drjit as dr
    t0 = time.perf_counter()
    mi = mitsuba(variant)
    import_s = time.perf_counter() - t0
    set_mitsuba_threads(threads)
    jit = "llvm" in variant or "cuda" in variant
    rows = []

    def render(sc, spp, seed):
        """mi.render in chunks of at most MAX_LANES samples (JIT variants)."""
        chunk = max(1, MAX_LANES // (res * res)) if jit else spp
        acc, done, k = None, 0, 0
        while done < spp:
            n = min(chunk, spp - done)
            img = np.array(mi.render(sc, seed=seed * 1000 + k, spp=n), dtype=np.float64)[..., :3]
            dr.sync_thread()
            acc = img * n if acc is None else acc + img * n
            done += n
            k += 1
        return acc / spp

    for spp in ladder:
        loads, colds, warms, rels = [], [], [], []
        for k in range(repeats_for(spp, repeats)):
            t0 = time.perf_counter()
            sc = mi.load_file(scene, res=res, spp=spp)
            t1 = time.perf_counter()
            img = render(sc, spp, seed=spp * 100 + k)
            t2 = time.perf_counter()
            loads.append(t1 - t0)
            colds.append(t2 - t1)
            rels.append(relmse_pair(img, ref))
            if jit:
                t3 = time.perf_counter()
                img = render(sc, spp, seed=spp * 100 + k + 50)
                warms.append(time.perf_counter() - t3)
                rels.append(relmse_pair(img, ref))
            else:
                warms.append(t2 - t1)
            del sc
        rel, relc, floor = (float(np.mean([x[i] for x in rels])) for i in range(3))
        load, cold, warm = _median(loads), _median(colds), _median(warms)
        rows.append(dict(renderer=f"mitsuba-{variant}", spp=spp, repeats=len(loads), load_s=load,
                         render_s=warm, render_cold_s=cold, total_s=load + cold, relmse=rel,
                         relmse_corrected=relc, ref_noise=floor,
                         msamples_s=res * res * spp / warm / 1e6, mrays_s=None,
                         import_s=import_s))
        log(f"  mitsuba {variant} {spp:5d} spp x{len(loads)}: load {load:6.3f} s, render {warm:8.3f} s "
            f"(cold {cold:8.3f} s), relMSE {rel:.3e}")
    return rows


def time_to(rows, target, key):
    """Time at which relMSE (corrected) first reaches target, interpolated
    log-log between ladder points. Returns (seconds, flag): flag '' exact,
    '<=' reached at the first point already, '>' not reached (last time)."""
    pts = sorted((r["spp"], r[key], r["relmse_corrected"]) for r in rows)
    prev = None
    for spp, t, e in pts:
        if e <= target:
            if prev is None:
                return t, "<="
            t0, e0 = prev
            if e0 <= 0 or e <= 0 or t0 <= 0 or t <= 0 or e0 == e:
                return t, ""
            f = (math.log(target) - math.log(e0)) / (math.log(e) - math.log(e0))
            return math.exp(math.log(t0) + f * (math.log(t) - math.log(t0))), ""
        prev = (t, e)
    return (pts[-1][1] if pts else float("nan")), ">"


def fmt_t(tf):
    t, flag = tf
    if t is None or (isinstance(t, float) and math.isnan(t)):
        return "–"
    s = f"{t:.3g}"
    return {"": s, "<=": f"≤ {s}", ">": f"> {s} (not reached)"}[flag]


def plot_scene(name, rows_by, res, threads, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(8.5, 6), constrained_layout=True)
    colors = {"radia": "#d1352b", "mitsuba-llvm_ad_rgb": "#2c6fbb", "mitsuba-scalar_rgb": "#2a9d4b"}
    floor = None
    for rend, rows in rows_by.items():
        rows = sorted(rows, key=lambda r: r["spp"])
        c = colors.get(rend, None)
        tr = [r["render_s"] for r in rows]
        tt = [r["total_s"] for r in rows]
        e = [max(r["relmse_corrected"], 1e-9) for r in rows]
        label = rend.replace("mitsuba-", "Mitsuba ")
        ax.loglog(tr, e, "o-", color=c, label=f"{label}: render only")
        ax.loglog(tt, e, "s--", color=c, mfc="none", alpha=0.8, label=f"{label}: incl. scene load")
        if rend == "radia":
            for r, t, ee in zip(rows, tr, e):
                ax.annotate(f"{r['spp']}", (t, ee), textcoords="offset points", xytext=(4, 4),
                            fontsize=7, color=c)
        floor = rows[0]["ref_noise"]
    for tg in TARGETS:
        ax.axhline(tg, color="gray", ls=":", lw=1)
        ax.annotate(f"relMSE {tg:g}", (ax.get_xlim()[0], tg), textcoords="offset points",
                    xytext=(3, 3), fontsize=8, color="gray")
    if floor:
        ax.axhline(floor, color="black", ls="-.", lw=0.8, label=f"reference noise (subtracted): {floor:.1e}")
    ax.set_xlabel("wall-clock time [s]")
    ax.set_ylabel("relMSE = mean((x − ref)² / (ref² + 0.01))  [dimensionless]")
    ax.set_title(f"{name}: {res}x{res}, {threads} threads (labels: radia spp)")
    ax.grid(True, which="both", alpha=0.25)
    ax.legend(fontsize=8)
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="+")
    ap.add_argument("--res", type=int, default=256, help="width = height (default 256)")
    ap.add_argument("--threads", type=int, default=2, help="threads for both renderers (default 2)")
    ap.add_argument("--min-spp", type=int, default=1)
    ap.add_argument("--max-spp", type=int, default=1024, help="ladder: powers of 2 from --min-spp (default 1..1024)")
    ap.add_argument("--variants", default="llvm_ad_rgb,scalar_rgb",
                    help="Mitsuba variants, comma-separated (default llvm_ad_rgb,scalar_rgb)")
    ap.add_argument("--ref-spp", type=int, default=4096, help="reference spp if one must be made (default 4096)")
    ap.add_argument("--ref-passes", type=int, default=16)
    ap.add_argument("--repeats", type=int, default=0,
                    help="renders per ladder point (median time, mean relMSE); default: "
                         "max(1, min(8, 16 // spp))")
    ap.add_argument("--radia", default=DEFAULT_RADIA)
    ap.add_argument("--no-radia", action="store_true", help="Mitsuba only (to try the tool without radia)")
    ap.add_argument("--out", default=os.path.join(OUT_DIR, "benchmark"))
    a = ap.parse_args(argv)

    ladder = []
    s = a.min_spp
    while s <= a.max_spp:
        ladder.append(s)
        s *= 2
    variants = [v for v in a.variants.split(",") if v]
    os.makedirs(a.out, exist_ok=True)
    refcache = os.path.join(a.out, "refcache")
    all_rows, md, html_parts = [], [], []
    md.append(f"# radia vs Mitsuba: time to reach a relMSE\n")
    md.append(f"{a.res}x{a.res} px, {a.threads} threads for both, spp ladder {ladder[0]}..{ladder[-1]}; "
              f"times in seconds, wall clock. relMSE corrected for the reference's noise. "
              f"'render only': radia's printed render time, Mitsuba's warm mi.render; 'incl. load': "
              f"radia's whole process (load, BVH, render, EXR write), Mitsuba load_file + first "
              f"render (JIT: includes kernel compilation or cache load; Python start-up and "
              f"`import mitsuba` excluded). Ratio < 1: radia is faster.\n")
    try:
        for scene in a.scenes:
            name = os.path.splitext(os.path.basename(scene))[0]
            log(f"== {rel_to_repo(scene)} at {a.res}x{a.res}, {a.threads} threads")
            ref = get_reference(scene, a.res, a.ref_spp, a.ref_passes, refcache, a.threads)
            log(f"  reference: {ref.total_spp} spp ({ref.entry['variant']})")
            rows_by = {}
            if not a.no_radia:
                rows_by["radia"] = bench_radia(scene, a.res, ladder, a.threads, a.radia, ref, a.repeats)
            for v in variants:
                rows_by[f"mitsuba-{v}"] = bench_mitsuba(scene, a.res, ladder, a.threads, v, ref, a.repeats)
            for rend, rows in rows_by.items():
                for r in rows:
                    r.update(scene=rel_to_repo(scene), threads=a.threads, res=a.res,
                             ref_spp=ref.total_spp)
                    all_rows.append(r)
            plot_scene(name, rows_by, a.res, a.threads, os.path.join(a.out, f"{name}.png"))

            rends = list(rows_by)
            md.append(f"\n## {rel_to_repo(scene)}\n")
            md.append(f"Reference: Mitsuba {ref.entry['variant']}, {ref.total_spp} spp. Plot: `{name}.png`.\n")
            head = "| | " + " | ".join(r.replace("mitsuba-", "Mitsuba ") for r in rends)
            ratios = [r for r in rends if r != "radia"] if "radia" in rows_by else []
            head += "".join(f" | radia / {r.replace('mitsuba-', '')}" for r in ratios) + " |"
            md.append(head)
            md.append("|---" * (1 + len(rends) + len(ratios)) + "|")
            for tg in TARGETS:
                for key, what in (("render_s", "render only"), ("total_s", "incl. load")):
                    vals = {r: time_to(rows_by[r], tg, key) for r in rends}
                    line = f"| time to relMSE {tg:g}, {what} [s] | " + " | ".join(fmt_t(vals[r]) for r in rends)
                    for m in ratios:
                        (tr, fr), (tm, fm) = vals["radia"], vals[m]
                        ok = fr == "" and fm == "" and tm > 0
                        line += f" | {tr / tm:.2f}" if ok else " | –"
                    md.append(line + " |")
            top = {r: max(rows_by[r], key=lambda x: x["spp"]) for r in rends}
            line = f"| at {ladder[-1]} spp: render [s] | " + " | ".join(f"{top[r]['render_s']:.3g}" for r in rends)
            line += "".join(f" | {top['radia']['render_s'] / top[m]['render_s']:.2f}" for m in ratios)
            md.append(line + " |")
            line = f"| at {ladder[-1]} spp: total [s] | " + " | ".join(f"{top[r]['total_s']:.3g}" for r in rends)
            line += "".join(f" | {top['radia']['total_s'] / top[m]['total_s']:.2f}" for m in ratios)
            md.append(line + " |")
            md.append(f"| at {ladder[-1]} spp: Msamples/s | " + " | ".join(f"{top[r]['msamples_s']:.3g}" for r in rends)
                      + "".join(" | " for _ in ratios) + " |")
            md.append(f"| at {ladder[-1]} spp: relMSE | " + " | ".join(f"{top[r]['relmse_corrected']:.3g}" for r in rends)
                      + "".join(" | " for _ in ratios) + " |")
            if "radia" in rows_by and top["radia"].get("mrays_s"):
                md.append(f"\nradia at {ladder[-1]} spp: {top['radia']['mrays_s']:.3g} Mrays/s "
                          f"({a.threads} threads).\n")
            html_parts.append((name, rel_to_repo(scene)))
    except ValidationError as e:
        log(f"ERROR: {e}")
        return 2

    fields = ["scene", "renderer", "threads", "res", "spp", "repeats", "load_s", "render_s", "render_cold_s",
              "total_s", "relmse", "relmse_corrected", "ref_noise", "ref_spp", "msamples_s",
              "mrays_s", "import_s"]
    with open(os.path.join(a.out, "benchmark.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields, extrasaction="ignore")
        w.writeheader()
        for r in all_rows:
            w.writerow(r)
    text = "\n".join(md) + "\n"
    with open(os.path.join(a.out, "benchmark.md"), "w") as f:
        f.write(text)
    _write_html(a.out, text, html_parts)
    print(text)
    log(f"wrote {rel_to_repo(os.path.join(a.out, 'benchmark.csv'))}, benchmark.md, benchmark.html and plots")
    return 0


def _write_html(out, md_text, parts):
    import html
    body = []
    table = []

    def flush():
        if table:
            rows = [l.strip().strip("|").split("|") for l in table if not set(l) <= set("|-")]
            h = "<table>" + "".join(
                "<tr>" + "".join((f"<th>{html.escape(c.strip())}</th>" if i == 0 else
                                  f"<td>{html.escape(c.strip())}</td>") for c in row) + "</tr>"
                for i, row in enumerate(rows)) + "</table>"
            body.append(h)
            table.clear()
    for line in md_text.splitlines():
        if line.startswith("|"):
            table.append(line)
            continue
        flush()
        if line.startswith("## "):
            scene = line[3:].strip()
            body.append(f"<h2>{html.escape(scene)}</h2>")
            name = os.path.splitext(os.path.basename(scene))[0]
            body.append(f"<img src='{name}.png' alt='relMSE against time'>")
        elif line.startswith("# "):
            body.append(f"<h1>{html.escape(line[2:])}</h1>")
        elif line.strip():
            body.append(f"<p>{html.escape(line)}</p>")
    flush()
    css = ("body{font-family:'DejaVu Sans',Arial,sans-serif;margin:24px;max-width:1200px}"
           "table{border-collapse:collapse;font-size:13px}td,th{border:1px solid #ccc;padding:3px 8px;"
           "text-align:right}th{background:#f0f0f0}tr td:first-child{text-align:left;font-weight:bold}"
           "p{font-size:13px;color:#444}img{max-width:100%}")
    with open(os.path.join(out, "benchmark.html"), "w") as f:
        f.write(f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>radia benchmark</title>"
                f"<style>{css}</style></head><body>" + "\n".join(body) + "</body></html>")


if __name__ == "__main__":
    sys.exit(main())
