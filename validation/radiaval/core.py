"""One scene's comparison: candidate passes against a cached reference, plus
the parity figures of issue #2 against Mitsuba at the same spp."""
import json
import os
import time

import numpy as np

from . import stats
from .common import (OUT_DIR, MitsubaRenderer, log, make_radia_renderer, rel_to_repo,
                     write_exr)
from .references import load_reference

PARITY_MEAN_TOL = 0.01      # image mean within 1%
PARITY_RELMSE_RATIO = 1.1   # relMSE(radia) <= 1.1 x relMSE(Mitsuba) at the same spp


def scene_name(scene_path):
    return os.path.splitext(os.path.basename(scene_path))[0]


def parity_figures(cand, mts, ref_mean):
    """cand, mts: (K, H, W, 3) passes at the same spp; ref_mean: high-spp reference."""
    c_mean = float(cand.mean())
    m_mean = float(mts.mean()) if mts is not None else None
    r_mean = float(ref_mean.mean())
    rel_c = float(np.mean([stats.rel_mse(x, ref_mean) for x in cand]))
    out = dict(image_mean_candidate=c_mean, image_mean_reference=r_mean,
               mean_ratio_vs_reference=c_mean / r_mean if r_mean else float("nan"),
               relmse_candidate=rel_c)
    if mts is not None:
        rel_m = float(np.mean([stats.rel_mse(x, ref_mean) for x in mts]))
        out.update(image_mean_mitsuba=m_mean,
                   mean_ratio_vs_mitsuba=c_mean / m_mean if m_mean else float("nan"),
                   relmse_mitsuba=rel_m,
                   relmse_ratio=rel_c / rel_m if rel_m else float("nan"))
        out["mean_ok"] = abs(out["mean_ratio_vs_mitsuba"] - 1.0) <= PARITY_MEAN_TOL
        out["relmse_ok"] = out["relmse_ratio"] <= PARITY_RELMSE_RATIO
    return out


def run_scene(scene_path, res, spp, passes, candidate="radia", radia=None,
              threads=2, bias=1.0, parity=True, parity_variant="scalar_rgb",
              ref_dir=None, out_dir=OUT_DIR, alpha=0.01, tolerance=0.0025,
              candidate_scene=None, cand_label=None, candidate_defines=(),
              candidate_sampler=None):
    """Compare one scene; returns a dict (also written to out_dir/NAME/result.json).

    candidate: "radia" (the Python package, or the binary at the path radia names) or
    "mitsuba" (independent Mitsuba passes: the self-check that must pass). bias multiplies the candidate's images (to show
    the test fails). candidate_scene renders the candidate from another XML
    (e.g. with a slightly wrong albedo) against the reference of scene_path.
    candidate_sampler names the candidate's sampler (None: the scene's own).
    Every render uses a box filter at res x res, whatever the scene says: the
    reference's (independent sampler, box filter: independent pixels).
    """
    name = scene_name(scene_path)
    t_start = time.perf_counter()
    kw = {} if ref_dir is None else {"ref_dir": ref_dir}
    ref = load_reference(scene_path, res, **kw)
    cscene = candidate_scene or scene_path
    label = cand_label or ("radia" if candidate == "radia" else "Mitsuba (independent passes)")
    if bias != 1.0:
        label += f" x {bias:g}"
    if candidate_defines:
        label += " with " + " ".join(candidate_defines)
    if candidate_scene:
        label += f" rendering {os.path.basename(candidate_scene)}"
    if candidate_sampler:
        label += f", {candidate_sampler} sampler"

    def prog(what):
        def f(i, n):
            if i == n:
                log(f"  {what}: {n} passes x {spp} spp done")
        return f

    t0 = time.perf_counter()
    info = {}
    if candidate == "radia":
        r = make_radia_renderer(cscene, res, spp, binary=radia, threads=threads, bias=bias,
                                extra_defines=candidate_defines, sampler=candidate_sampler)
        cand = r.passes(passes, seed0=0, progress=prog("radia"))
        info = dict(invalid_samples=r.invalid,
                    candidate_spp_rendered=r.infos[-1].get("spp") if r.infos else None,
                    candidate_sampler=(r.infos[-1].get("sampler") if r.infos else None)
                    or candidate_sampler,
                    radia_render_s=sum(i.get("render_s", 0.0) for i in r.infos),
                    radia_load_s=sum(i.get("load_s", 0.0) for i in r.infos),
                    radia_wall_s=sum(i["wall_s"] for i in r.infos),
                    radia_mrays_s=[i.get("mrays_s") for i in r.infos][-1],
                    radia_last_output=r.infos[-1]["output"].strip().splitlines()[-1:]
                    if r.infos else [])
    elif candidate == "mitsuba":
        r = MitsubaRenderer(cscene, res, spp, variant=parity_variant, threads=threads,
                            defines=candidate_defines, sampler=candidate_sampler)
        info = dict(candidate_spp_rendered=r.spp, candidate_sampler=candidate_sampler
                    or "scene's own")
        # Seeds far from the reference's (REF_SEED_BASE + k) and from the parity
        # passes (0..K-1): independent of both.
        cand = r.passes(passes, seed0=2000, progress=prog("Mitsuba candidate"))
        if bias != 1.0:
            cand = cand * np.float32(bias)
    else:
        raise ValueError(candidate)
    cand_time = time.perf_counter() - t0

    mts = None
    mts_time = 0.0
    if parity:
        t0 = time.perf_counter()
        m = MitsubaRenderer(scene_path, res, spp, variant=parity_variant, threads=threads)
        mts = m.passes(passes, seed0=0, progress=prog(f"Mitsuba {parity_variant}"))
        mts_time = time.perf_counter() - t0

    nonfinite = int((~np.isfinite(cand)).sum())
    if nonfinite:
        info["nonfinite_values"] = nonfinite
    res_test = stats.compare_to_reference(cand, ref.mean, ref.var, ref.passes,
                                          alpha=alpha, tolerance=tolerance)
    par = parity_figures(cand, mts, ref.mean)
    cand_mean = cand.mean(axis=0)
    cand_var = cand.var(axis=0, ddof=1) / cand.shape[0]

    sdir = os.path.join(out_dir, name)
    os.makedirs(sdir, exist_ok=True)
    write_exr(os.path.join(sdir, "candidate_mean.exr"), cand_mean)
    write_exr(os.path.join(sdir, "reference_mean.exr"), ref.mean)

    result = dict(
        scene=rel_to_repo(scene_path), name=name, candidate=candidate, candidate_label=label,
        candidate_scene=rel_to_repo(cscene), bias=bias, res=res, spp=spp, passes=passes,
        threads=threads, passed=res_test.passed, alpha=alpha,
        alpha_per_test=res_test.alpha_test, tolerance=tolerance, n_tests=res_test.n_tests,
        levels=res_test.summary_rows(),
        reference=dict(total_spp=ref.total_spp, passes=ref.passes, variant=ref.entry["variant"],
                       mitsuba_version=ref.entry["mitsuba_version"], hash=ref.entry["hash"],
                       render_time_s=ref.entry.get("render_time_s")),
        parity=par, parity_variant=parity_variant if parity else None,
        candidate_time_s=cand_time, mitsuba_time_s=mts_time,
        total_time_s=time.perf_counter() - t_start, **info)
    with open(os.path.join(sdir, "result.json"), "w") as f:
        json.dump(result, f, indent=2)
    # arrays for the report
    result["_arrays"] = dict(cand_mean=cand_mean, cand_var=cand_var, ref_mean=ref.mean,
                             ref_var=ref.var, mts_mean=None if mts is None else mts.mean(axis=0),
                             cand_pass0=cand[0], test=res_test)
    return result


def format_result(r):
    lines = []
    v = "PASS" if r["passed"] else "FAIL"
    lines.append(f"{v}  {r['scene']}  [{r['candidate_label']}]  {r['res']}x{r['res']}, "
                 f"{r['passes']} passes x {r['spp']} spp vs reference {r['reference']['total_spp']} spp "
                 f"({r['reference']['variant']})")
    lines.append(f"  Welch t-test, alpha {r['alpha']} family-wise, Sidak per-test "
                 f"{r['alpha_per_test']:.3g} over {r['n_tests']} tests:")
    for l in r["levels"]:
        lines.append(f"    {l['level']:>6}: {l['rejected']:5d}/{l['tests']:<6d} rejected "
                     f"(allowed {l['allowed']}), max|t| {l['max_abs_t']:.2f}, min p {l['min_p']:.2e}"
                     f"  {'ok' if l['passed'] else 'FAIL'}")
    p = r["parity"]
    s = (f"  parity @ {r['spp']} spp: image mean {r['candidate']}/reference "
         f"{p['mean_ratio_vs_reference']:.4f}")
    if "relmse_mitsuba" in p:
        s += (f", {r['candidate']}/Mitsuba {r['parity_variant']} {p['mean_ratio_vs_mitsuba']:.4f} "
              f"({'within' if p['mean_ok'] else 'NOT within'} 1%)")
        lines.append(s)
        lines.append(f"    relMSE vs reference: {r['candidate']} {p['relmse_candidate']:.4e}, "
                     f"Mitsuba {p['relmse_mitsuba']:.4e}, ratio {p['relmse_ratio']:.3f} "
                     f"({'<=' if p['relmse_ok'] else '>'} 1.1)")
    else:
        lines.append(s + f", relMSE vs reference {p['relmse_candidate']:.4e}")
    if r.get("candidate_spp_rendered") and r["candidate_spp_rendered"] != r["spp"]:
        lines.append(f"  NOTE: the candidate's {r.get('candidate_sampler')} sampler rendered "
                     f"{r['candidate_spp_rendered']} spp per pass, not {r['spp']}")
    if r.get("invalid_samples"):
        lines.append(f"  WARNING: radia reported {r['invalid_samples']} invalid samples")
    if r.get("nonfinite_values"):
        lines.append(f"  WARNING: {r['nonfinite_values']} NaN or infinite values in the candidate's passes")
    lines.append(f"  time: candidate {r['candidate_time_s']:.1f} s, Mitsuba {r['mitsuba_time_s']:.1f} s, "
                 f"total {r['total_time_s']:.1f} s")
    return "\n".join(lines)
