#!/usr/bin/env python3
"""Efficiency of every sampler of both renderers: radia and Mitsuba 3 at the same
spp, resolution and thread count, relMSE against a high-spp Mitsuba reference.

  validation/.venv/bin/python validation/benchmark.py [SCENE...] [--res 128] [--spp 256]
        [--repeats 3] [--threads 2] [--variants llvm_ad_rgb] [--radia-alt NAME=PATH ...]
  validation/.venv/bin/python validation/benchmark.py --ladder SCENE... [--min-spp 1 --max-spp 1024]

SCENE defaults to every scenes/*.xml, written as users write them (no $res/$spp
needed): film size, sampler and spp are overridden for both renderers (Mitsuba: by
editing the loaded XML; radia: --resolution, --sampler, --spp), and the filter is
a box for every render, the reference's, so that relMSE measures noise, not blur.

For each scene, every Mitsuba sampler (independent, stratified, multijitter,
orthogonal, ldsampler) of each --variants and every radia sampler (the same and
sobol) renders --spp samples per pixel, rounded as each sampler rounds them (the
spp actually rendered is reported and used). efficiency = 1 / (relMSE x seconds),
relMSE corrected for the reference's noise. Each measurement is repeated
(--repeats): median times; relMSE is the mean over --seeds renders of distinct
seeds (default twice --repeats; the renders beyond the timed ones are not timed),
the same count for both renderers.

Timings (wall clock, time.perf_counter):
  radia    render  = the render time radia prints (no loading, no EXR write)
           total   = the whole process: start, scene load and BVH build, render, EXR write
  Mitsuba  load    = mi.load_string(...) of the edited scene
           render  = warm mi.render + transfer to numpy (JIT variants: a second render
                     of the same spp on the loaded scene, kernels compiled); scalar: the only render
           cold    = first mi.render after loading (JIT: tracing, compiling or loading
                     the kernel from Dr.Jit's cache; after the first repeat, Dr.Jit's
                     in-process cache); the median over repeats, as the ladder had it.
                     CSV render_first_s: the first repeat's alone
           total   = load + cold render (the Python interpreter and `import mitsuba`
                     are not included; they are printed once as import_s)
efficiency (the headline) uses total; efficiency_render uses render.

Writes validation/out/benchmark/: benchmark.csv (one row per renderer, sampler),
benchmark.md (per scene the table of all samplers; then "best vs best" and "same
estimator" per scene), NAME.png (efficiency per sampler, log scale), ratios.png
(the two ratios per scene) and benchmark.html.

--ladder keeps the older measurement: relMSE against time over an spp ladder,
time to reach relMSE 1e-2 and 1e-3 (bench_lights.py uses its functions).
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
from radiaval.common import (DEFAULT_RADIA, MITSUBA_SAMPLERS, OUT_DIR, RADIA_SAMPLERS,  # noqa: E402
                             REFERENCE_DIR, RadiaRenderer, ValidationError, check_radia,
                             list_scenes, load_mitsuba_scene, log, mitsuba, mitsuba_scene_spp,
                             mitsuba_scene_xml, rel_to_repo, set_mitsuba_threads)
from radiaval.references import load_reference, make_reference  # noqa: E402

TARGETS = (1e-2, 1e-3)
MAX_LANES = 1 << 24   # JIT variants: at most this many samples per mi.render call


def get_reference(scene, res, ref_spp, ref_passes, refcache, threads, defines=()):
    """The committed reference if it exists at this resolution (and no -D is
    given), else one made (once, then cached by scene hash) in
    validation/out/benchmark/refcache: Mitsuba llvm_ad_rgb, independent sampler,
    box filter, at least ref_spp in ref_passes passes."""
    if not defines:
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
    make_reference(scene, res, spp=max(1, -(-ref_spp // ref_passes)), passes=ref_passes,
                   variant="llvm_ad_rgb", ref_dir=refcache, threads=threads, defines=defines)
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


def bench_radia(scene, res, ladder, threads, binary, ref, repeats=0, defines=()):
    """--ladder: radia with the scene's own sampler and a box filter."""
    rows = []
    r = RadiaRenderer(scene, res, ladder[0], binary=binary, threads=threads,
                      extra_defines=defines)
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


def bench_mitsuba(scene, res, ladder, threads, variant, ref, repeats=0, defines=()):
    """--ladder: Mitsuba with the scene's own sampler and a box filter."""
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
            sc = load_mitsuba_scene(mi, scene, res=res, spp=spp, rfilter="box", defines=defines)
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


# ---------------------------------------------------------------------------
# Efficiency of every sampler (the default mode)
# ---------------------------------------------------------------------------

def efficiency(relmse, seconds):
    """1 / (relMSE x seconds); None when the corrected relMSE is not positive
    (the reference's noise swamps the render's: make a better reference)."""
    if relmse is None or seconds is None or not relmse > 0 or not seconds > 0:
        return None
    return 1.0 / (relmse * seconds)


def _finish_row(row, rels):
    row["relmse"], row["relmse_corrected"], row["ref_noise"] = (
        float(np.mean([x[i] for x in rels])) for i in range(3))
    row["efficiency"] = efficiency(row["relmse_corrected"], row["total_s"])
    row["efficiency_render"] = efficiency(row["relmse_corrected"], row["render_s"])
    return row


def measure_radia(scene, res, spp, sampler, binary, label, threads, ref, repeats, seeds,
                  defines=()):
    """One radia binary and sampler: `seeds` processes with distinct seeds, the first
    `repeats` of them timed."""
    r = RadiaRenderer(scene, res, spp, binary=binary, threads=threads, sampler=sampler,
                      rfilter="box", extra_defines=defines)
    # One untimed render first: the first process after Mitsuba's renders ran up to a third
    # slower (page cache, CPU frequency), which the median of three did not always hide.
    r.render(seed=0, spp=min(spp, 16))
    r.infos.clear()
    rels = []
    for k in range(max(repeats, seeds)):
        img = r.render(seed=1 + k, spp=spp)
        rels.append(relmse_pair(img, ref))
    infos = r.infos[:repeats]
    spps = sorted({i.get("spp") for i in infos})
    render = _median([i.get("render_s") for i in infos])
    row = dict(renderer=label, binary=binary, sampler=sampler, spp_requested=spp,
               spp=spps[-1] if len(spps) == 1 else ",".join(map(str, spps)), repeats=len(infos),
               load_s=_median([i.get("load_s") for i in infos]), render_s=render,
               render_cold_s=render, total_s=_median([i["wall_s"] for i in infos]),
               mrays_s=_median([i.get("mrays_s") for i in infos]))
    row["msamples_s"] = res * res * row["spp"] / render / 1e6 if render and isinstance(row["spp"], int) else None
    return _finish_row(row, rels)


def measure_mitsuba(scene, res, spp, sampler, variant, threads, ref, repeats, seeds,
                    defines=()):
    """One Mitsuba variant and sampler: `repeats` times load + cold render (+ a
    warm render for JIT variants) of the scene edited to res, box filter,
    sampler and spp; then untimed renders of further seeds until `seeds` renders.
    relMSE is the mean over every render."""
    import drjit as dr
    t0 = time.perf_counter()
    mi = mitsuba(variant)
    import_s = time.perf_counter() - t0
    set_mitsuba_threads(threads)
    jit = "llvm" in variant or "cuda" in variant
    xml = mitsuba_scene_xml(scene, res, spp, sampler, "box")   # not timed: the file as written

    def render(sc, seed):
        img = np.array(mi.render(sc, seed=seed), dtype=np.float64)[..., :3]
        dr.sync_thread()
        return img

    loads, colds, warms, rels, spps = [], [], [], [], set()
    for k in range(repeats):
        t0 = time.perf_counter()
        sc = load_mitsuba_scene(mi, scene, xml_text=xml, defines=defines)
        t1 = time.perf_counter()
        img = render(sc, seed=1 + 2 * k)
        t2 = time.perf_counter()
        loads.append(t1 - t0)
        colds.append(t2 - t1)
        rels.append(relmse_pair(img, ref))
        n = mitsuba_scene_spp(sc)
        spps.add(n)
        if jit:
            t3 = time.perf_counter()
            img = render(sc, seed=2 + 2 * k)
            warms.append(time.perf_counter() - t3)
            rels.append(relmse_pair(img, ref))
        else:
            warms.append(t2 - t1)
        if res * res * n > MAX_LANES and jit:
            log(f"  note: {res}x{res} x {n} spp = {res * res * n} lanes in one mi.render")
        if k + 1 == repeats:
            # The relMSE of the further seeds (not timed), on the last scene loaded.
            seed = 2 * repeats + 1
            while len(rels) < seeds:
                rels.append(relmse_pair(render(sc, seed=seed), ref))
                seed += 1
        del sc
    spps = sorted(spps)
    load, cold, warm = _median(loads), _median(colds), _median(warms)
    row = dict(renderer=f"mitsuba-{variant}", binary=variant, sampler=sampler, spp_requested=spp,
               spp=spps[-1] if len(spps) == 1 else ",".join(map(str, spps)), repeats=len(loads),
               load_s=load, render_s=warm, render_cold_s=cold, total_s=load + cold,
               render_first_s=colds[0], mrays_s=None, import_s=import_s)
    row["msamples_s"] = res * res * spps[-1] / warm / 1e6
    return _finish_row(row, rels)


def _fmt(x, f=".3g"):
    return "–" if x is None else format(x, f)


def _best(rows, key):
    ok = [r for r in rows if r.get(key) is not None]
    return max(ok, key=lambda r: r[key]) if ok else None


def _ratio(a, b):
    return a / b if a is not None and b else None


def plot_efficiency(name, rows, res, threads, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    samplers = [s for s in RADIA_SAMPLERS if any(r["sampler"] == s for r in rows)]
    rends = list(dict.fromkeys(r["renderer"] for r in rows))
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.8), constrained_layout=True, sharey=True)
    width = 0.8 / max(1, len(rends))
    palette = ["#d1352b", "#f08a24", "#8e44ad", "#2c6fbb", "#2a9d4b", "#7f7f7f"]
    for ax, key, what in ((axes[0], "efficiency", "incl. load"),
                          (axes[1], "efficiency_render", "render only")):
        for j, rend in enumerate(rends):
            xs, ys, labels = [], [], []
            for i, s in enumerate(samplers):
                for r in rows:
                    if r["renderer"] == rend and r["sampler"] == s and r.get(key):
                        xs.append(i + (j - (len(rends) - 1) / 2) * width)
                        ys.append(r[key])
                        labels.append(str(r["spp"]))
            bars = ax.bar(xs, ys, width, label=rend.replace("mitsuba-", "Mitsuba "),
                          color=palette[j % len(palette)])
            for b, l in zip(bars, labels):
                ax.annotate(l, (b.get_x() + b.get_width() / 2, b.get_height()),
                            textcoords="offset points", xytext=(0, 2), ha="center", fontsize=6)
        ax.set_yscale("log")
        ax.set_xticks(range(len(samplers)))
        ax.set_xticklabels(samplers)
        ax.set_title(f"{name}, {what}")
        ax.grid(True, axis="y", which="both", alpha=0.25)
    axes[0].set_ylabel("efficiency = 1 / (relMSE × s)  [1/s]")
    axes[0].legend(fontsize=8)
    fig.suptitle(f"{res}x{res}, {threads} threads (labels: spp rendered)", fontsize=9)
    fig.savefig(path, dpi=100)
    plt.close(fig)


def plot_ratios(summary, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    labels = [f"{s['name']}\n{s['radia']}" if s["radia"] != "radia" else s["name"] for s in summary]
    fig, ax = plt.subplots(figsize=(max(6, 0.9 * len(summary) + 2), 4.5), constrained_layout=True)
    x = np.arange(len(summary))
    for off, key, lab, c in ((-0.2, "best_ratio", "best vs best", "#d1352b"),
                             (0.2, "indep_ratio", "same estimator (independent)", "#2c6fbb")):
        ys = [s.get(key) or np.nan for s in summary]
        ax.bar(x + off, ys, 0.4, label=lab, color=c)
    ax.axhline(1, color="black", lw=0.8)
    ax.set_yscale("log")
    ax.set_xticks(x)
    ax.set_xticklabels(labels, fontsize=8, rotation=30, ha="right")
    ax.set_ylabel("efficiency radia / Mitsuba")
    ax.set_title("efficiency ratio incl. load (> 1: radia more efficient)", fontsize=10)
    ax.grid(True, axis="y", which="both", alpha=0.25)
    ax.legend(fontsize=8)
    fig.savefig(path, dpi=100)
    plt.close(fig)


def efficiency_main(a):
    variants = [v for v in a.variants.split(",") if v]
    m_samplers = [s for s in a.mitsuba_samplers.split(",") if s]
    r_samplers = [s for s in a.radia_samplers.split(",") if s]
    alt_samplers = [s for s in a.alt_samplers.split(",") if s]
    for s in m_samplers:
        if s not in MITSUBA_SAMPLERS:
            log(f"benchmark.py: unknown Mitsuba sampler {s} (one of {', '.join(MITSUBA_SAMPLERS)})")
            return 2
    for s in r_samplers + alt_samplers:
        if s not in RADIA_SAMPLERS:
            log(f"benchmark.py: unknown radia sampler {s} (one of {', '.join(RADIA_SAMPLERS)})")
            return 2
    binaries = [] if a.no_radia else [("radia", a.radia)]
    for alt in a.radia_alt:
        if "=" not in alt:
            log(f"benchmark.py: --radia-alt wants NAME=PATH, got {alt}")
            return 2
        n, p = alt.split("=", 1)
        binaries.append((f"radia[{n}]", p))
    try:
        for _, p in binaries:
            check_radia(p)
    except ValidationError as e:
        log(f"ERROR: {e}")
        return 2
    os.makedirs(a.out, exist_ok=True)
    refcache = os.path.join(a.out, "refcache")
    all_rows, summary, images = [], [], {}
    md = ["# radia vs Mitsuba: efficiency of every sampler\n",
          f"{a.res}x{a.res} px, {a.spp} spp asked (each sampler rounds it; the spp column is what "
          f"it rendered), box filter, {a.threads} threads for both, median of {a.repeats} "
          f"repeats (relMSE: mean over {a.seeds} seeds). efficiency = 1 / (relMSE × seconds), "
          f"relMSE corrected for "
          f"the reference's noise; 'incl. load' (the headline): radia's whole process (load, "
          f"BVH, render, EXR write), Mitsuba load + first render (JIT: kernel compilation or "
          f"cache load; Python start-up and `import mitsuba` excluded); 'render only': radia's "
          f"printed render time, Mitsuba's warm mi.render. Binaries: "
          + ", ".join(f"{n} = `{rel_to_repo(p)}`" for n, p in binaries) + ".\n"]
    try:
        for scene in a.scenes:
            name = os.path.splitext(os.path.basename(scene))[0]
            log(f"== {rel_to_repo(scene)} at {a.res}x{a.res}, {a.spp} spp, {a.threads} threads")
            ref = get_reference(scene, a.res, a.ref_spp, a.ref_passes, refcache, a.threads,
                                a.define)
            log(f"  reference: {ref.total_spp} spp ({ref.entry['variant']})")
            rows = []
            for label, binary in binaries:
                for s in (r_samplers if label == "radia" else alt_samplers):
                    try:
                        r = measure_radia(scene, a.res, a.spp, s, binary, label, a.threads,
                                          ref, a.repeats, a.seeds, a.define)
                    except ValidationError as e:
                        if label == "radia":
                            raise
                        # An older binary may not read a newer scene: no row for it here.
                        log(f"  {label:14s} skipped: it cannot render this scene ({str(e).splitlines()[0]})")
                        break
                    rows.append(r)
                    log(f"  {label:14s} {s:12s} {r['spp']:>5} spp: total {r['total_s']:7.3f} s, "
                        f"render {r['render_s']:7.3f} s, relMSE {r['relmse_corrected']:.3e}, "
                        f"efficiency {_fmt(r['efficiency'])}")
            for v in variants:
                for s in m_samplers:
                    r = measure_mitsuba(scene, a.res, a.spp, s, v, a.threads, ref, a.repeats,
                                        a.seeds, a.define)
                    rows.append(r)
                    log(f"  {'mitsuba ' + v:14s} {s:12s} {r['spp']:>5} spp: total {r['total_s']:7.3f} s "
                        f"(load {r['load_s']:.3f}), render {r['render_s']:7.3f} s, relMSE "
                        f"{r['relmse_corrected']:.3e}, efficiency {_fmt(r['efficiency'])}")
            for r in rows:
                r.update(scene=rel_to_repo(scene), threads=a.threads, res=a.res,
                         ref_spp=ref.total_spp)
            all_rows += rows
            plot_efficiency(name, rows, a.res, a.threads, os.path.join(a.out, f"{name}.png"))
            images[name] = [f"{name}.png"]

            md.append(f"\n## {rel_to_repo(scene)}\n")
            md.append(f"Reference: Mitsuba {ref.entry['variant']}, {ref.total_spp} spp "
                      f"(noise subtracted: {rows[0]['ref_noise']:.2e}). Plot: `{name}.png`.\n")
            md.append("| renderer | sampler | spp | time incl. load [s] | render only [s] | load [s] "
                      "| relMSE | efficiency incl. load [1/s] | efficiency render only [1/s] |")
            md.append("|---|---|---|---|---|---|---|---|---|")
            for r in rows:
                md.append(f"| {r['renderer'].replace('mitsuba-', 'Mitsuba ')} | {r['sampler']} "
                          f"| {r['spp']} | {_fmt(r['total_s'])} | {_fmt(r['render_s'])} "
                          f"| {_fmt(r['load_s'])} | {_fmt(r['relmse_corrected'])} "
                          f"| {_fmt(r['efficiency'])} | {_fmt(r['efficiency_render'])} |")
            mts = [r for r in rows if r["renderer"].startswith("mitsuba-")]
            m_best, m_best_r = _best(mts, "efficiency"), _best(mts, "efficiency_render")
            m_ind = [r for r in mts if r["sampler"] == "independent"]
            m_ind = m_ind[0] if m_ind else None     # the first variant's
            for label, _ in binaries:
                rr = [r for r in rows if r["renderer"] == label]
                r_best, r_best_r = _best(rr, "efficiency"), _best(rr, "efficiency_render")
                r_ind = [r for r in rr if r["sampler"] == "independent"]
                r_ind = r_ind[0] if r_ind else None
                summary.append(dict(
                    scene=rel_to_repo(scene), name=name, radia=label,
                    radia_best=r_best, mitsuba_best=m_best,
                    best_ratio=_ratio(r_best and r_best["efficiency"], m_best and m_best["efficiency"]),
                    radia_best_render=r_best_r, mitsuba_best_render=m_best_r,
                    best_ratio_render=_ratio(r_best_r and r_best_r["efficiency_render"],
                                             m_best_r and m_best_r["efficiency_render"]),
                    radia_indep=r_ind, mitsuba_indep=m_ind,
                    indep_ratio=_ratio(r_ind and r_ind["efficiency"], m_ind and m_ind["efficiency"]),
                    indep_ratio_render=_ratio(r_ind and r_ind["efficiency_render"],
                                              m_ind and m_ind["efficiency_render"])))
    except ValidationError as e:
        log(f"ERROR: {e}")
        return 2

    def who(r, key):
        if r is None:
            return "–"
        rend = r["renderer"].replace("mitsuba-", "Mitsuba ")
        return f"{rend} {r['sampler']} ({r['spp']} spp): {_fmt(r[key])}"

    md.append("\n## Best vs best\n")
    md.append("Each renderer's most efficient sampler (incl. load; render only picks its own best). "
              "Ratio radia / Mitsuba > 1: radia is more efficient.\n")
    md.append("| scene | radia best [1/s] | Mitsuba best [1/s] | ratio incl. load | radia best, render only "
              "| Mitsuba best, render only | ratio render only |")
    md.append("|---|---|---|---|---|---|---|")
    for s in summary:
        md.append(f"| {s['name']} | {who(s['radia_best'], 'efficiency')} "
                  f"| {who(s['mitsuba_best'], 'efficiency')} | {_fmt(s['best_ratio'])} "
                  f"| {who(s['radia_best_render'], 'efficiency_render')} "
                  f"| {who(s['mitsuba_best_render'], 'efficiency_render')} "
                  f"| {_fmt(s['best_ratio_render'])} |")
    md.append("\n## Same estimator\n")
    md.append("Independent sampler on both sides (Mitsuba: the first of --variants"
              + (f", {variants[0]}" if variants else "") + "): the same estimator, so the ratio "
              "is speed alone if the relMSEs agree.\n")
    md.append("| scene | radia independent [1/s] | Mitsuba independent [1/s] | relMSE radia / Mitsuba "
              "| ratio incl. load | ratio render only |")
    md.append("|---|---|---|---|---|---|")
    for s in summary:
        ri, mi_ = s["radia_indep"], s["mitsuba_indep"]
        rel = _ratio(ri and ri["relmse_corrected"], mi_ and mi_["relmse_corrected"])
        md.append(f"| {s['name']} | {who(ri, 'efficiency')} | {who(mi_, 'efficiency')} "
                  f"| {_fmt(rel)} | {_fmt(s['indep_ratio'])} | {_fmt(s['indep_ratio_render'])} |")
    if summary:
        plot_ratios(summary, os.path.join(a.out, "ratios.png"))
        images["Best vs best"] = ["ratios.png"]

    fields = ["scene", "renderer", "binary", "sampler", "threads", "res", "spp_requested", "spp",
              "repeats", "load_s", "render_s", "render_cold_s", "render_first_s", "total_s", "relmse",
              "relmse_corrected", "ref_noise", "ref_spp", "efficiency", "efficiency_render",
              "msamples_s", "mrays_s", "import_s"]
    with open(os.path.join(a.out, "benchmark.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields, extrasaction="ignore")
        w.writeheader()
        for r in all_rows:
            w.writerow(r)
    text = "\n".join(md) + "\n"
    with open(os.path.join(a.out, "benchmark.md"), "w") as f:
        f.write(text)
    _write_html(a.out, text, images)
    print(text)
    log(f"wrote {rel_to_repo(os.path.join(a.out, 'benchmark.csv'))}, benchmark.md, benchmark.html and plots")
    return 0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="*", help="Mitsuba XML scenes (default: scenes/*.xml)")
    ap.add_argument("--res", type=int, default=128, help="width = height (default 128)")
    ap.add_argument("--spp", type=int, default=256,
                    help="spp asked of every sampler; each rounds it as it must (default 256)")
    ap.add_argument("--threads", type=int, default=2, help="threads for both renderers (default 2)")
    ap.add_argument("--repeats", type=int, default=None,
                    help="measurements per sampler, median time, mean relMSE (default 3; "
                         "--ladder: max(1, min(8, 16 // spp)))")
    ap.add_argument("--seeds", type=int, default=None,
                    help="renders per sampler whose relMSE is averaged, the first --repeats of "
                         "them timed (default 2 x --repeats: what a JIT variant's cold and warm "
                         "renders give; caustics' relMSE is heavy-tailed, three seeds measure it "
                         "to about +-20%%)")
    ap.add_argument("--variants", default=None,
                    help="Mitsuba variants, comma-separated (default llvm_ad_rgb; --ladder: "
                         "llvm_ad_rgb,scalar_rgb)")
    ap.add_argument("--mitsuba-samplers", default=",".join(MITSUBA_SAMPLERS),
                    help="default: all of " + ",".join(MITSUBA_SAMPLERS))
    ap.add_argument("--radia-samplers", default=",".join(RADIA_SAMPLERS),
                    help="default: all of " + ",".join(RADIA_SAMPLERS))
    ap.add_argument("--radia", default=DEFAULT_RADIA, help="radia binary (default target/release/radia)")
    ap.add_argument("--alt-samplers", default="independent,sobol",
                    help="radia samplers measured with each --radia-alt binary (default independent,sobol)")
    ap.add_argument("--radia-alt", action="append", default=[], metavar="NAME=PATH",
                    help="another radia binary, reported as extra rows radia[NAME] (repeatable), "
                         "e.g. the build before a change")
    ap.add_argument("--no-radia", action="store_true", help="Mitsuba only (to try the tool without radia)")
    ap.add_argument("-D", "--define", action="append", default=[], metavar="NAME=VALUE",
                    help="scene parameter, for both renderers and the reference (repeatable)")
    ap.add_argument("--ref-spp", type=int, default=8192,
                    help="reference spp if one must be made (default 8192; the committed "
                         "reference is used if it exists at --res and has at least this many)")
    ap.add_argument("--ref-passes", type=int, default=32)
    ap.add_argument("--out", default=os.path.join(OUT_DIR, "benchmark"))
    g = ap.add_argument_group("--ladder: relMSE against time over an spp ladder (the older benchmark)")
    g.add_argument("--ladder", action="store_true")
    g.add_argument("--min-spp", type=int, default=1)
    g.add_argument("--max-spp", type=int, default=1024, help="powers of 2 from --min-spp (default 1..1024)")
    a = ap.parse_args(argv)
    a.scenes = a.scenes or list_scenes()
    if not a.scenes:
        log("benchmark.py: no scenes given and none in scenes/")
        return 2
    for s in a.scenes:
        if not os.path.isfile(s):
            log(f"benchmark.py: no such scene: {s}")
            return 2
    if a.ladder:
        if a.variants is None:
            a.variants = "llvm_ad_rgb,scalar_rgb"
        a.repeats = a.repeats or 0
        return ladder_main(a)
    if a.variants is None:
        a.variants = "llvm_ad_rgb"
    a.repeats = a.repeats or 3
    a.seeds = a.seeds or 2 * a.repeats
    return efficiency_main(a)


def ladder_main(a):
    """The --ladder mode: relMSE against time over an spp ladder."""
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
            ref = get_reference(scene, a.res, a.ref_spp, a.ref_passes, refcache, a.threads,
                                a.define)
            log(f"  reference: {ref.total_spp} spp ({ref.entry['variant']})")
            rows_by = {}
            if not a.no_radia:
                rows_by["radia"] = bench_radia(scene, a.res, ladder, a.threads, a.radia, ref,
                                               a.repeats, a.define)
            for v in variants:
                rows_by[f"mitsuba-{v}"] = bench_mitsuba(scene, a.res, ladder, a.threads, v, ref,
                                                        a.repeats, a.define)
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
    _write_html(a.out, text, {n: [f"{n}.png"] for n, _ in html_parts})
    print(text)
    log(f"wrote {rel_to_repo(os.path.join(a.out, 'benchmark.csv'))}, benchmark.md, benchmark.html and plots")
    return 0


def _write_html(out, md_text, images):
    """md_text as HTML; images: {heading key: [png, ...]} shown under "## heading"
    (key: the heading's file stem, e.g. cornell-box for "## scenes/cornell-box.xml")."""
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
            heading = line[3:].strip()
            body.append(f"<h2>{html.escape(heading)}</h2>")
            key = os.path.splitext(os.path.basename(heading))[0]
            for png in images.get(key, images.get(heading, [])):
                body.append(f"<img src='{html.escape(png)}' alt='{html.escape(heading)}'>")
        elif line.startswith("# "):
            body.append(f"<h1>{html.escape(line[2:])}</h1>")
        elif line.strip():
            body.append(f"<p>{html.escape(line)}</p>")
    flush()
    css = ("body{font-family:'DejaVu Sans',Arial,sans-serif;margin:24px;max-width:1400px}"
           "table{border-collapse:collapse;font-size:13px}td,th{border:1px solid #ccc;padding:3px 8px;"
           "text-align:right}th{background:#f0f0f0}tr td:first-child{text-align:left;font-weight:bold}"
           "p{font-size:13px;color:#444}img{max-width:100%}")
    with open(os.path.join(out, "benchmark.html"), "w") as f:
        f.write(f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>radia benchmark</title>"
                f"<style>{css}</style></head><body>" + "\n".join(body) + "</body></html>")


if __name__ == "__main__":
    sys.exit(main())
