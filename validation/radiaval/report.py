"""report.html: per scene, the images side by side, false-colour maps of the
relative difference and of the t statistics, the t histogram and the verdict."""
import datetime
import html
import math
import os

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.colors import Normalize  # noqa: E402
import numpy as np  # noqa: E402

from . import stats  # noqa: E402
from .common import mitsuba_version, rel_to_repo  # noqa: E402

plt.rcParams.update({"font.size": 10, "axes.titlesize": 10, "figure.dpi": 100})


def luminance(img):
    return 0.2126 * img[..., 0] + 0.7152 * img[..., 1] + 0.0722 * img[..., 2]


def exposure_for(ref):
    p = float(np.percentile(luminance(ref), 99))
    if p <= 0:
        return 1.0
    return 1.0 if 0.3 <= p <= 1.5 else 1.0 / p


def to_srgb(img, exposure=1.0):
    x = np.clip(np.nan_to_num(np.asarray(img, np.float64) * exposure, nan=0.0, posinf=1.0), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def _axis_off(ax):
    ax.set_xticks([])
    ax.set_yticks([])


def images_png(r, path):
    A = r["_arrays"]
    ref = A["ref_mean"]
    exp = exposure_for(ref)
    panels = [(A["cand_mean"], f"{r['candidate_label']}\nmean of {r['passes']} passes x {r['spp']} spp"),
              (ref, f"Mitsuba reference ({r['reference']['variant']})\n{r['reference']['total_spp']} spp")]
    if A.get("mts_mean") is not None:
        panels.append((A["mts_mean"], f"Mitsuba {r['parity_variant']}\nsame spp: {r['passes']} x {r['spp']}"))
    panels.append((A["cand_pass0"], f"{r['candidate_label']}\none pass, {r['spp']} spp"))
    n = len(panels)
    fig, axes = plt.subplots(1, n, figsize=(3.3 * n, 3.9), constrained_layout=True)
    for ax, (img, title) in zip(axes, panels):
        ax.imshow(to_srgb(img, exp), interpolation="nearest")
        ax.set_title(title)
        _axis_off(ax)
    fig.supxlabel(f"linear RGB x {exp:.3g}, clipped to [0, 1], sRGB; "
             f"{r['res']}x{r['res']} px shown with nearest-neighbour upscaling",
             fontsize=8, color="#444")
    fig.savefig(path, bbox_inches="tight", pad_inches=0.12)
    plt.close(fig)


def _signed_max_channel(t):
    idx = np.abs(t).argmax(axis=-1)
    return np.take_along_axis(t, idx[..., None], axis=-1)[..., 0]


def maps_png(r, path):
    A = r["_arrays"]
    test = A["test"]
    cand, ref = A["cand_mean"], A["ref_mean"]
    c_l, r_l = cand.mean(axis=-1), ref.mean(axis=-1)
    eps = 1e-3 * max(float(r_l.mean()), 1e-6)
    rel = (c_l - r_l) / np.maximum(np.abs(r_l), eps)
    b = 4 if min(cand.shape[:2]) >= 8 else 1
    cb = stats.block_sum(cand, b).mean(axis=-1)
    rb = stats.block_sum(ref, b).mean(axis=-1)
    relb = (cb - rb) / np.maximum(np.abs(rb), eps * b * b)
    lv1, lvb = test.level(1), test.level(b)
    t1, tb = _signed_max_channel(lv1.t), _signed_max_channel(lvb.t)
    tc = stats.t_critical(test.alpha_test, float(np.median(lv1.nu)))

    def _lim(x):
        x = np.abs(x[np.isfinite(x)])
        return min(max(float(np.percentile(x, 95)) if x.size else 0.0, 0.02), 1.0)
    lim_rel, lim_relb = _lim(rel), _lim(relb)
    lim_t = max(tc, 3.0)
    fig, axes = plt.subplots(1, 4, figsize=(16, 4.3), constrained_layout=True)
    specs = [
        (axes[0], 100 * rel, 100 * lim_rel, "relative difference per pixel",
         "(candidate − reference) / reference  [%]", None),
        (axes[1], 100 * relb, 100 * lim_relb, f"relative difference per {b}x{b} block",
         "(candidate − reference) / reference  [%]", None),
        (axes[2], t1, lim_t, "Welch t per pixel (max-|t| channel)",
         "t statistic  [standard errors]", lv1.rejected.any(axis=-1)),
        (axes[3], tb, lim_t, f"Welch t per {b}x{b} block",
         "t statistic  [standard errors]", lvb.rejected.any(axis=-1)),
    ]
    for ax, img, lim, title, clabel, rej in specs:
        im = ax.imshow(img, cmap="coolwarm", norm=Normalize(-lim, lim), interpolation="nearest")
        cbar = fig.colorbar(im, ax=ax, shrink=0.85)
        cbar.set_label(clabel)
        if rej is not None:
            ys, xs = np.nonzero(rej)
            if len(xs):
                ax.scatter(xs, ys, marker="s", s=max(4, 1600 / max(img.shape) ** 1.0),
                           facecolors="none", edgecolors="black", linewidths=1.0,
                           label=f"rejected ({len(xs)})")
                ax.legend(loc="lower right", fontsize=8, framealpha=0.8)
            title += f"\nsaturates at |t| = {lim:.2f} (Šidák critical)"
        else:
            title += f"\nsaturates at ±{lim:.3g}%"
        ax.set_title(title)
        _axis_off(ax)
    fig.savefig(path, bbox_inches="tight", pad_inches=0.12)
    plt.close(fig)


def hist_png(r, path):
    test = r["_arrays"]["test"]
    lv1 = test.level(1)
    t = lv1.t.ravel()
    nu = float(np.median(lv1.nu))
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.6), constrained_layout=True)
    ax = axes[0]
    lim = max(6.0, min(float(np.abs(t).max()) * 1.05, 60.0))
    bins = np.linspace(-lim, lim, 121)
    ax.hist(np.clip(t, -lim, lim), bins=bins, density=True, color="#4477aa", alpha=0.75,
            label=f"pixel-level t ({t.size} tests)"
            + (f"; |t| > {lim:.0f} piled at the edges" if np.abs(t).max() > lim else ""))
    xs = np.linspace(-lim, lim, 600)
    lg = (math.lgamma((nu + 1) / 2) - math.lgamma(nu / 2) - 0.5 * math.log(nu * math.pi))
    ax.plot(xs, np.exp(lg - (nu + 1) / 2 * np.log1p(xs * xs / nu)), "k-", lw=1.2,
            label=f"Student t, {nu:.0f} dof (expected under H0)")
    tc = stats.t_critical(test.alpha_test, nu)
    for s in (-tc, tc):
        ax.axvline(s, color="red", ls="--", lw=1)
    ax.set_yscale("log")
    ax.set_ylim(1e-6, 1.0)
    ax.set_xlabel("t statistic (candidate − reference) / standard error  [dimensionless]")
    ax.set_ylabel("probability density  [1 / unit of t]")
    ax.set_title("pixel-level t statistics; red: Sidak critical values ±%.2f" % tc)
    ax.legend(fontsize=8, loc="upper right")
    # per-level bar chart
    ax = axes[1]
    names = [l.name() for l in test.levels]
    frac = [100.0 * l.n_rejected / l.n_tests for l in test.levels]
    allowed = [100.0 * l.allowed / l.n_tests for l in test.levels]
    xs = np.arange(len(names))
    cols = ["#2a9d4b" if l.passed else "#d1352b" for l in test.levels]
    ax.bar(xs, frac, color=cols, width=0.6, label="rejected tests")
    ax.plot(xs, allowed, "k_", markersize=30, mew=2, label="allowed")
    ax.set_xticks(xs, [f"{n}\n({l.n_tests} tests)" for n, l in zip(names, test.levels)])
    ax.set_xlabel("test level (block size)")
    ax.set_ylabel("rejected tests  [% of the level's tests]")
    ax.set_title("rejections per level (green: level passes)")
    top = max(max(frac), max(allowed), 0.5)
    ax.set_ylim(0, top * 1.25)
    ax.legend(fontsize=8)
    fig.savefig(path, bbox_inches="tight", pad_inches=0.12)
    plt.close(fig)


CSS = """
body { font-family: -apple-system, 'DejaVu Sans', Arial, sans-serif; margin: 24px; color: #222; max-width: 1650px; }
h1 { font-size: 22px; } h2 { font-size: 18px; margin-top: 36px; border-bottom: 1px solid #ccc; }
table { border-collapse: collapse; margin: 8px 0; font-size: 13px; }
td, th { border: 1px solid #ccc; padding: 3px 8px; text-align: right; }
th { background: #f0f0f0; } td.l, th.l { text-align: left; }
.pass { background: #2a9d4b; color: white; font-weight: bold; padding: 2px 8px; border-radius: 3px; }
.fail { background: #d1352b; color: white; font-weight: bold; padding: 2px 8px; border-radius: 3px; }
.err { background: #8a5a00; color: white; font-weight: bold; padding: 2px 8px; border-radius: 3px; }
img { max-width: 100%; display: block; margin: 6px 0; }
.note { color: #555; font-size: 13px; max-width: 1100px; }
code { background: #f4f4f4; padding: 0 3px; }
"""


def _v(ok):
    return '<span class="pass">PASS</span>' if ok else '<span class="fail">FAIL</span>'


def _fmt(x, f="{:.4g}"):
    return "–" if x is None else f.format(x)


def write_report(results, errors, out_dir, mode="full", total_time=None):
    os.makedirs(out_dir, exist_ok=True)
    for r in results:
        sdir = os.path.join(out_dir, r["name"])
        os.makedirs(sdir, exist_ok=True)
        images_png(r, os.path.join(sdir, "images.png"))
        maps_png(r, os.path.join(sdir, "maps.png"))
        hist_png(r, os.path.join(sdir, "tstats.png"))

    h = []
    h.append(f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>radia validation</title>"
             f"<style>{CSS}</style></head><body>")
    n_fail = sum(not r["passed"] for r in results)
    h.append(f"<h1>radia vs Mitsuba {html.escape(mitsuba_version())}: "
             f"{len(results) - n_fail} passed, {n_fail} failed"
             + (f", {len(errors)} errors" if errors else "") + "</h1>")
    h.append(f"<p class='note'>Generated {datetime.datetime.now().isoformat(timespec='seconds')}, "
             f"mode <b>{mode}</b>" + (f", {total_time:.1f} s" if total_time else "") +
             ". H0: the candidate's expected image equals Mitsuba's. Each candidate pass is an "
             "independent render (own seed); per pixel, per block and for the whole image, per "
             "channel, Welch's t-test of the candidate's mean against the cached high-spp Mitsuba "
             "reference, with variances estimated from the passes. Family-wise level α over all "
             "tests, Šidák-corrected per test; a level passes if at most ⌊0.25% of its tests⌋ "
             "reject. See <code>validation/README.md</code>.</p>")
    h.append("<table><tr><th class='l'>scene</th><th class='l'>candidate</th><th>verdict</th>"
             "<th>res</th><th>passes × spp</th><th>ref spp</th>"
             "<th>rejected (pixel / 4x4 / 16x16 / image)</th><th>max |t| image</th>"
             "<th>mean ratio cand/ref</th><th>relMSE cand</th><th>relMSE Mitsuba</th>"
             "<th>relMSE ratio</th><th>time [s]</th></tr>")
    for r in results:
        p = r["parity"]
        rej = " / ".join(f"{l['rejected']}" for l in r["levels"])
        img_t = [l for l in r["levels"] if l["level"] == "image"][0]["max_abs_t"]
        h.append(f"<tr><td class='l'><a href='#{r['name']}'>{html.escape(r['scene'])}</a></td>"
                 f"<td class='l'>{html.escape(r['candidate_label'])}</td><td>{_v(r['passed'])}</td>"
                 f"<td>{r['res']}</td><td>{r['passes']} × {r['spp']}</td>"
                 f"<td>{r['reference']['total_spp']}</td><td>{rej}</td><td>{img_t:.2f}</td>"
                 f"<td>{p['mean_ratio_vs_reference']:.4f}</td><td>{p['relmse_candidate']:.3e}</td>"
                 f"<td>{_fmt(p.get('relmse_mitsuba'), '{:.3e}')}</td>"
                 f"<td>{_fmt(p.get('relmse_ratio'), '{:.3f}')}</td>"
                 f"<td>{r['total_time_s']:.1f}</td></tr>")
    for s, e in errors:
        h.append(f"<tr><td class='l'>{html.escape(rel_to_repo(s))}</td><td></td>"
                 f"<td><span class='err'>ERROR</span></td><td class='l' colspan='10'>{html.escape(e)}</td></tr>")
    h.append("</table>")

    for r in results:
        n = r["name"]
        p = r["parity"]
        h.append(f"<h2 id='{n}'>{html.escape(r['scene'])} {_v(r['passed'])}</h2>")
        h.append(f"<p class='note'>Candidate: <b>{html.escape(r['candidate_label'])}</b>, "
                 f"{r['passes']} passes × {r['spp']} spp at {r['res']}×{r['res']}, {r['threads']} threads. "
                 f"Reference: Mitsuba {r['reference']['mitsuba_version']} {r['reference']['variant']}, "
                 f"{r['reference']['passes']} passes, {r['reference']['total_spp']} spp. "
                 f"α = {r['alpha']}, per-test α (Šidák over {r['n_tests']} tests) = {r['alpha_per_test']:.3g}.</p>")
        h.append(f"<img src='{n}/images.png' alt='images'>")
        h.append("<table><tr><th class='l'>level</th><th>tests</th><th>rejected</th><th>allowed</th>"
                 "<th>max |t|</th><th>min p</th><th>verdict</th></tr>")
        for l in r["levels"]:
            h.append(f"<tr><td class='l'>{l['level']}</td><td>{l['tests']}</td><td>{l['rejected']}</td>"
                     f"<td>{l['allowed']}</td><td>{l['max_abs_t']:.2f}</td><td>{l['min_p']:.2e}</td>"
                     f"<td>{_v(l['passed'])}</td></tr>")
        h.append("</table>")
        par = (f"Parity at {r['spp']} spp (issue #2): image mean candidate / reference = "
               f"{p['mean_ratio_vs_reference']:.4f}")
        if "relmse_mitsuba" in p:
            par += (f"; candidate / Mitsuba {r['parity_variant']} = {p['mean_ratio_vs_mitsuba']:.4f} "
                    f"({'within' if p['mean_ok'] else '<b>not</b> within'} 1%); relMSE against the "
                    f"reference, mean over passes: candidate {p['relmse_candidate']:.4e}, Mitsuba "
                    f"{p['relmse_mitsuba']:.4e}, ratio {p['relmse_ratio']:.3f} "
                    f"({'≤' if p['relmse_ok'] else '<b>&gt;</b>'} 1.1).")
        if r.get("invalid_samples"):
            par += f" <b>radia reported {r['invalid_samples']} invalid samples.</b>"
        h.append(f"<p class='note'>{par}</p>")
        h.append(f"<img src='{n}/maps.png' alt='difference maps'>")
        h.append(f"<img src='{n}/tstats.png' alt='t statistics'>")
    h.append("</body></html>")
    path = os.path.join(out_dir, "report.html")
    with open(path, "w") as f:
        f.write("\n".join(h))
    return path
