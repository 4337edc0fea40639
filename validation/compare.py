#!/usr/bin/env python3
"""Does radia converge to the same image as Mitsuba 3? A statistical test per
scene against cached high-spp Mitsuba references. See validation/README.md.

  validation/.venv/bin/python validation/compare.py [SCENE...] [--quick] [--spp N]
  validation/.venv/bin/python validation/compare.py --make-references [SCENE...]

SCENE defaults to every scenes/*.xml. Exit status: 0 all scenes pass, 1 a scene
fails the test, 2 the run could not be made (missing or stale reference,
radia package missing or stale, missing radia binary, render error). radia renders
through its Python package (validation/setup builds it), or with --radia PATH the binary.
"""
import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from radiaval import references  # noqa: E402
from radiaval.common import (OUT_DIR, REFERENCE_DIR, ValidationError, list_scenes,  # noqa: E402
                             log, rel_to_repo)

QUICK = dict(res=64, spp=16, passes=32)
FULL = dict(res=64, spp=64, passes=32)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="*", help="Mitsuba XML scenes (default: scenes/*.xml)")
    ap.add_argument("--quick", action="store_true",
                    help=f"CI mode: {QUICK['res']}x{QUICK['res']}, {QUICK['passes']} passes x {QUICK['spp']} spp")
    ap.add_argument("--spp", type=int, help="spp of each candidate pass (quick %d, default %d)" % (QUICK["spp"], FULL["spp"]))
    ap.add_argument("--passes", type=int, help="independent candidate passes (default %d)" % FULL["passes"])
    ap.add_argument("--res", type=int, help="resolution (width = height); a reference at it must exist (default %d)" % FULL["res"])
    ap.add_argument("--threads", type=int, default=2, help="threads for radia and Mitsuba (default 2)")
    ap.add_argument("--radia", metavar="PATH",
                    help="render radia's passes with this binary (e.g. target/release/radia), one "
                         "process per pass (default: the radia Python package that "
                         "validation/setup builds, the scene loaded once; the same images)")
    ap.add_argument("--candidate", choices=("radia", "mitsuba"), default="radia",
                    help="what to test against the reference: radia, or independent Mitsuba "
                         "passes (a self-check of the instrument; must pass)")
    ap.add_argument("--inject-bias", type=float, default=1.0, metavar="F",
                    help="multiply the candidate's images by F (e.g. 1.02) to show the test fails")
    ap.add_argument("--candidate-define", action="append", default=[], metavar="NAME=VALUE",
                    help="-D for the candidate's renders only (e.g. albedo=0.98 on the furnace: must fail)")
    ap.add_argument("--sampler", metavar="NAME",
                    help="the candidate's sampler: radia's independent, stratified, multijitter, "
                         "orthogonal, ldsampler, sobol or sobol+adaptive (--adaptive; default: the scene's own; the reference "
                         "is always Mitsuba's independent sampler with a box filter)")
    ap.add_argument("--candidate-scene", metavar="XML",
                    help="render the candidate from this XML instead (one SCENE only): must fail "
                         "if it differs, e.g. a slightly wrong albedo")
    ap.add_argument("--no-parity", action="store_true",
                    help="skip the Mitsuba renders at the candidate's spp (issue #2 parity figures)")
    ap.add_argument("--parity-variant", default="scalar_rgb",
                    help="Mitsuba variant for the same-spp renders (default scalar_rgb)")
    ap.add_argument("--alpha", type=float, default=0.01, help="family-wise significance level (default 0.01)")
    ap.add_argument("--tolerance", type=float, default=0.0025,
                    help="fraction of a level's tests allowed to reject (default 0.0025)")
    ap.add_argument("--ref-dir", default=REFERENCE_DIR, help="reference cache (default validation/references)")
    ap.add_argument("--out", default=OUT_DIR, help="output directory for the report (default validation/out)")
    ap.add_argument("--no-report", action="store_true", help="do not write report.html")
    ap.add_argument("--fail-on-invalid", action="store_true",
                    help="fail if radia drops any NaN/Inf sample on any scene (its 'invalid samples "
                         "dropped' count), even where the statistics pass (tests/run-all uses it)")
    g = ap.add_argument_group("references")
    g.add_argument("--make-references", action="store_true",
                   help="(re)render the references of the given scenes (default: all of scenes/) and exit")
    g.add_argument("--ref-spp", type=int, default=references.DEFAULT_REF_SPP, help="spp per reference pass (default %(default)s)")
    g.add_argument("--ref-passes", type=int, default=references.DEFAULT_REF_PASSES, help="reference passes (default %(default)s)")
    g.add_argument("--ref-variant", default=references.DEFAULT_REF_VARIANT, help="Mitsuba variant (default %(default)s)")
    g.add_argument("--check-references", action="store_true",
                   help="only check that every scene has a current (non-stale) reference")
    a = ap.parse_args(argv)

    mode = QUICK if a.quick else FULL
    res = a.res or mode["res"]
    spp = a.spp or mode["spp"]
    passes = a.passes or mode["passes"]
    scenes = a.scenes or list_scenes()
    if not scenes:
        log("compare.py: no scenes given and none in scenes/")
        return 2
    for s in scenes:
        if not os.path.isfile(s):
            log(f"compare.py: no such scene: {s}")
            return 2

    from radiaval.common import MITSUBA_SAMPLERS, RADIA_SAMPLERS
    allowed = RADIA_SAMPLERS if a.candidate == "radia" else MITSUBA_SAMPLERS
    if a.sampler and a.sampler not in allowed:
        log(f"compare.py: --sampler {a.sampler}: the {a.candidate} candidate's samplers are "
            + ", ".join(allowed))
        return 2

    if a.make_references:
        for s in scenes:
            references.make_reference(s, res, spp=a.ref_spp, passes=a.ref_passes,
                                      variant=a.ref_variant, ref_dir=a.ref_dir, threads=a.threads)
        return 0

    if a.check_references:
        bad = 0
        for s in scenes:
            try:
                references.load_reference(s, res, ref_dir=a.ref_dir)
                log(f"ok     {rel_to_repo(s)} @ {res}")
            except ValidationError as e:
                log(f"ERROR  {e}")
                bad += 1
        return 2 if bad else 0

    from radiaval.core import format_result, run_scene
    if a.candidate_scene and len(scenes) != 1:
        log("compare.py: --candidate-scene needs exactly one SCENE")
        return 2

    t0 = time.perf_counter()
    results, errors = [], []
    for s in scenes:
        log(f"== {rel_to_repo(s)}")
        try:
            r = run_scene(s, res, spp, passes, candidate=a.candidate, radia=a.radia,
                          threads=a.threads, bias=a.inject_bias, parity=not a.no_parity,
                          parity_variant=a.parity_variant, ref_dir=a.ref_dir, out_dir=a.out,
                          alpha=a.alpha, tolerance=a.tolerance, candidate_scene=a.candidate_scene,
                          candidate_defines=a.candidate_define, candidate_sampler=a.sampler)
        except ValidationError as e:
            log(f"ERROR  {rel_to_repo(s)}: {e}")
            errors.append((s, str(e)))
            continue
        except Exception as e:  # e.g. Mitsuba cannot load the scene
            log(f"ERROR  {rel_to_repo(s)}: {type(e).__name__}: {e}")
            errors.append((s, f"{type(e).__name__}: {e}"))
            continue
        log(format_result(r))
        results.append(r)
    total = time.perf_counter() - t0

    if (results or errors) and not a.no_report:
        from radiaval.report import write_report
        path = write_report(results, errors, a.out, mode="quick" if a.quick else "full",
                            total_time=total)
        log(f"report: {rel_to_repo(path)}")

    n_fail = sum(not r["passed"] for r in results)
    n_pass = len(results) - n_fail
    log(f"compare: {n_pass} passed, {n_fail} failed, {len(errors)} errors in {total:.1f} s")
    invalid = [(r["scene"], r["invalid_samples"]) for r in results if r.get("invalid_samples")]
    for scene, n in invalid:
        log(f"INVALID {scene}: radia dropped {n} NaN/Inf samples")
    if errors:
        return 2
    if a.fail_on_invalid and invalid:
        return 1
    return 1 if n_fail else 0


if __name__ == "__main__":
    sys.exit(main())
