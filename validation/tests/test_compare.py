"""Tests of the validation instrument itself: the statistics, the verdict's
teeth (a 2% bias and a slightly wrong albedo must fail, independent Mitsuba
renders must pass), stale-reference detection and the command line.

Run:  validation/.venv/bin/python -m pytest -q validation/tests
  or  validation/.venv/bin/python -m unittest discover -s validation/tests -t validation
"""
import json
import math
import os
import shutil
import stat
import subprocess
import sys
import unittest

import numpy as np

from .helpers import NODEFAULTS, RES, SENSOR_ONLY, SIMPLE, VALIDATION, shared_ref_dir, tmpdir
from radiaval import stats
from radiaval.common import (ValidationError, derive_scene, load_mitsuba_scene,
                             mitsuba, mitsuba_scene_spp, parse_radia_output, scene_files)
from radiaval.core import run_scene
from radiaval.references import load_reference, make_reference

PY = sys.executable
COMPARE = os.path.join(VALIDATION, "compare.py")
BENCHMARK = os.path.join(VALIDATION, "benchmark.py")
SPP, PASSES = 16, 32


def _t_sf2_integer(t, nu):
    """Two-sided tail of Student's t for integer dof (Abramowitz & Stegun 26.7.3-4)."""
    th = math.atan(t / math.sqrt(nu))
    s, c = math.sin(th), math.cos(th)
    if nu % 2:
        if nu == 1:
            return 1 - 2 * th / math.pi
        term = acc = c
        for j in range(1, (nu - 3) // 2 + 1):
            term *= c * c * (2 * j) / (2 * j + 1)
            acc += term
        return 1 - 2 / math.pi * (th + s * acc)
    term = acc = 1.0
    for j in range(1, (nu - 2) // 2 + 1):
        term *= c * c * (2 * j - 1) / (2 * j)
        acc += term
    return 1 - s * acc


class Statistics(unittest.TestCase):
    def test_t_distribution_matches_closed_form(self):
        for nu in (1, 2, 3, 4, 7, 15, 31, 64):
            for t in (0.0, 0.3, 1.0, 2.0, 4.0, 8.0):
                want = _t_sf2_integer(t, nu)
                got = float(stats.t_two_sided_p(t, nu))
                self.assertAlmostEqual(got, want, delta=1e-9 * want + 1e-14, msg=(nu, t))
        self.assertAlmostEqual(float(stats.t_two_sided_p(1.959963985, 1e9)), 0.05, delta=1e-7)
        self.assertAlmostEqual(float(stats.t_two_sided_p(1.959963985, math.inf)), 0.05, delta=1e-9)

    def test_sidak(self):
        a = stats.sidak_alpha(0.01, 1000)
        self.assertAlmostEqual(1 - (1 - a) ** 1000, 0.01, delta=1e-12)
        self.assertAlmostEqual(stats.t_critical(0.05, math.inf), 1.959964, delta=1e-5)

    def test_synthetic_null_and_bias(self):
        """Gaussian passes with the same mean pass (family-wise alpha 1%); a 2%
        bias fails every time."""
        rng = np.random.default_rng(1)
        truth = rng.uniform(0.1, 1.0, size=(32, 32, 3))
        sigma = 0.2 * truth
        fails = fails_biased = 0
        for _ in range(20):
            ref_passes = truth + sigma / 8 * rng.standard_normal((32,) + truth.shape)
            rm, rv, rk = stats.pass_moments(ref_passes)
            cand = truth + sigma * rng.standard_normal((32,) + truth.shape)
            fails += not stats.compare_to_reference(cand, rm, rv, rk).passed
            fails_biased += not stats.compare_to_reference(cand * 1.02, rm, rv, rk).passed
        self.assertEqual(fails, 0)
        self.assertEqual(fails_biased, 20)


    def test_nan_pixels_fail(self):
        rng = np.random.default_rng(2)
        truth = rng.uniform(0.1, 1.0, size=(32, 32, 3))
        rm, rv, rk = stats.pass_moments(truth + 0.01 * rng.standard_normal((32,) + truth.shape))
        cand = truth + 0.05 * rng.standard_normal((32,) + truth.shape)
        self.assertTrue(stats.compare_to_reference(cand, rm, rv, rk).passed)
        cand[3, :, :5, :] = np.nan        # one pass, 5 columns of NaN
        res = stats.compare_to_reference(cand, rm, rv, rk)
        self.assertFalse(res.passed)
        self.assertEqual(res.level(0).n_rejected, 3)


class Teeth(unittest.TestCase):
    """Mitsuba against a Mitsuba reference of the fixture scene."""

    def run_mitsuba(self, **kw):
        kw.setdefault("parity", False)
        return run_scene(SIMPLE, RES, SPP, PASSES, candidate="mitsuba", ref_dir=shared_ref_dir(),
                         out_dir=tmpdir(self), **kw)

    def test_two_independent_mitsuba_renders_pass(self):
        r = self.run_mitsuba(parity=True)
        self.assertTrue(r["passed"], r["levels"])
        self.assertLess(abs(r["parity"]["mean_ratio_vs_mitsuba"] - 1), 0.01)
        self.assertLess(r["parity"]["relmse_ratio"], 1.1)

    def test_two_percent_bias_fails(self):
        r = self.run_mitsuba(bias=1.02)
        self.assertFalse(r["passed"])
        image = [l for l in r["levels"] if l["level"] == "image"][0]
        self.assertEqual(image["rejected"], 3)   # the whole-image mean, every channel

    def test_two_percent_low_bias_fails(self):
        self.assertFalse(self.run_mitsuba(bias=0.98)["passed"])

    def test_slightly_wrong_albedo_fails(self):
        """The sphere's albedo 2% too high moves the image mean by only ~0.2%."""
        text = open(SIMPLE).read()
        self.assertIn("0.7, 0.4, 0.2", text)
        wrong = os.path.join(tmpdir(self), "simple_wrong_albedo.xml")
        with open(wrong, "w") as f:
            f.write(text.replace("0.7, 0.4, 0.2", "0.714, 0.408, 0.204"))
        r = self.run_mitsuba(candidate_scene=wrong)
        self.assertFalse(r["passed"])
        # a loose 1% threshold on the image mean would have missed it
        self.assertLess(abs(r["parity"]["mean_ratio_vs_reference"] - 1), 0.01)


class References(unittest.TestCase):
    def test_manifest(self):
        d = shared_ref_dir()
        man = json.load(open(os.path.join(d, "manifest.json")))
        (key, e), = man["references"].items()
        self.assertTrue(key.endswith("simple.xml@32"))
        for field in ("hash", "spp_per_pass", "passes", "total_spp", "mitsuba_version",
                      "variant", "render_time_s", "files"):
            self.assertIn(field, e)
        self.assertEqual(e["total_spp"], e["passes"] * e["spp_per_pass"])
        ref = load_reference(SIMPLE, RES, ref_dir=d)
        self.assertEqual(ref.mean.shape, (RES, RES, 3))
        self.assertTrue((ref.var >= 0).all())

    def test_stale_reference_is_an_error(self):
        tmp = tmpdir(self)
        scene = os.path.join(tmp, "scene.xml")
        shutil.copy(SIMPLE, scene)
        d = os.path.join(tmp, "refs")
        make_reference(scene, 16, spp=4, passes=2, variant="scalar_rgb", ref_dir=d)
        load_reference(scene, 16, ref_dir=d)          # fresh: fine
        text = open(scene).read()
        with open(scene, "w") as f:
            f.write(text.replace('value="0.5, 0.5, 0.5"', 'value="0.5, 0.5, 0.6"'))
        with self.assertRaisesRegex(ValidationError, "STALE"):
            load_reference(scene, 16, ref_dir=d)
        p = subprocess.run([PY, COMPARE, scene, "--res", "16", "--ref-dir", d, "--candidate",
                            "mitsuba", "--out", os.path.join(tmp, "out"), "--no-report"],
                           capture_output=True, text=True)
        self.assertEqual(p.returncode, 2, p.stdout + p.stderr)
        self.assertIn("STALE", p.stdout)

    def test_stale_when_a_referenced_file_changes(self):
        tmp = tmpdir(self)
        mesh = os.path.join(tmp, "tri.obj")
        with open(mesh, "w") as f:
            f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
        scene = os.path.join(tmp, "scene.xml")
        with open(scene, "w") as f:
            f.write(open(SIMPLE).read().replace(
                "</scene>", '<shape type="obj"><string name="filename" value="tri.obj"/></shape>\n</scene>'))
        self.assertIn(mesh, scene_files(scene))
        d = os.path.join(tmp, "refs")
        make_reference(scene, 8, spp=2, passes=2, variant="scalar_rgb", ref_dir=d)
        load_reference(scene, 8, ref_dir=d)
        with open(mesh, "w") as f:
            f.write("v 0 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\n")
        with self.assertRaisesRegex(ValidationError, "STALE.*tri.obj"):
            load_reference(scene, 8, ref_dir=d)

    def test_missing_reference_is_an_error(self):
        with self.assertRaisesRegex(ValidationError, "no reference"):
            load_reference(SIMPLE, 17, ref_dir=tmpdir(self))


def fake_radia(tmp):
    exe = os.path.join(tmp, "radia")
    with open(exe, "w") as f:
        f.write(f"#!/bin/sh\nexec {PY} {os.path.join(VALIDATION, 'tests', 'fake_radia.py')} \"$@\"\n")
    os.chmod(exe, os.stat(exe).st_mode | stat.S_IXUSR)
    return exe


class SceneOverrides(unittest.TestCase):
    """Scenes as users write them: film size, sampler and filter are overridden by
    editing the loaded description, not through $res/$spp defaults."""

    def sensor(self, path, **kw):
        mi = mitsuba("scalar_rgb")
        sc = load_mitsuba_scene(mi, path, **kw)
        s = sc.sensors()[0]
        return (tuple(s.film().size()), mitsuba_scene_spp(sc), str(s.film().rfilter()),
                str(s.sampler()))

    def test_no_defaults_scene(self):
        size, spp, rf, _ = self.sensor(NODEFAULTS)
        self.assertEqual((size, spp), ((48, 36), 9))
        self.assertIn("Gaussian", rf)
        size, spp, rf, smp = self.sensor(NODEFAULTS, res=16, spp=8, sampler="independent",
                                         rfilter="box")   # relative floor.obj resolves
        self.assertEqual((size, spp), ((16, 16), 8))
        self.assertIn("Box", rf)
        self.assertIn("Independent", smp)
        self.assertEqual(self.sensor(NODEFAULTS, res=(20, 10), spp=20, sampler="ldsampler")[:2],
                         ((20, 10), 64))   # Mitsuba rounds: a power-of-two square

    def test_sensor_without_film_or_sampler(self):
        self.assertEqual(self.sensor(SENSOR_ONLY)[:2], ((768, 576), 4))
        size, spp, rf, _ = self.sensor(SENSOR_ONLY, res=8, spp=3, rfilter="box")
        self.assertEqual((size, spp), ((8, 8), 3))
        self.assertIn("Box", rf)

    def test_defines_still_work_and_unused_ones_are_dropped(self):
        mi = mitsuba("scalar_rgb")
        furnace = os.path.join(os.path.dirname(VALIDATION), "scenes", "furnace.xml")
        if not os.path.exists(furnace):
            self.skipTest("no scenes/furnace.xml")
        # spp is no longer referenced once sample_count is overridden: dropped, not an error
        sc = load_mitsuba_scene(mi, furnace, res=8, spp=4, defines=["albedo=0.5", "spp=99"])
        self.assertEqual(mitsuba_scene_spp(sc), 4)
        self.assertLess(float(np.array(mi.render(sc)).mean()), 0.99)

    def test_parse_radia_output(self):
        info = parse_radia_output(
            "radia: loaded s.xml in 0.010 s: 2 primitives, 1 emitters, 32x32 at 25 spp "
            "(orthogonal sampler)\nradia: 32x32, 25 spp, 0.5 s render, 1.00 Msamples/s, "
            "2.00 Mrays/s, 0 invalid samples dropped -> o.exr")
        self.assertEqual((info["spp"], info["sampler"], info["load_s"]), (25, "orthogonal", 0.01))

    def test_reference_and_compare_without_defaults(self):
        """--make-references and the test itself on a scene with no $res/$spp,
        a gaussian filter and a stratified sampler; the candidate with the
        scene's own sampler and with --sampler sobol."""
        tmp = tmpdir(self)
        d = os.path.join(tmp, "refs")
        p = subprocess.run([PY, COMPARE, "--make-references", NODEFAULTS, "--res", "16",
                            "--ref-spp", "64", "--ref-passes", "16", "--ref-dir", d],
                           capture_output=True, text=True)
        self.assertEqual(p.returncode, 0, p.stdout + p.stderr)
        exe = fake_radia(tmp)
        for extra in ([], ["--sampler", "sobol"]):
            p = subprocess.run([PY, COMPARE, NODEFAULTS, "--res", "16", "--spp", "4",
                                "--passes", "8", "--ref-dir", d, "--radia", exe, "--no-report",
                                "--out", os.path.join(tmp, "out")] + extra,
                               capture_output=True, text=True)
            self.assertEqual(p.returncode, 0, p.stdout + p.stderr)
            self.assertIn("PASS", p.stdout)
        p = subprocess.run([PY, COMPARE, NODEFAULTS, "--res", "16", "--ref-dir", d, "--radia", exe,
                            "--sampler", "nope", "--no-report"], capture_output=True, text=True)
        self.assertEqual(p.returncode, 2, p.stdout + p.stderr)

    def test_benchmark_smoke(self):
        """benchmark.py end to end with the fake radia, on the no-defaults scene."""
        tmp = tmpdir(self)
        out = os.path.join(tmp, "bench")
        p = subprocess.run([PY, BENCHMARK, NODEFAULTS, "--res", "8", "--spp", "5", "--repeats", "1",
                            "--ref-spp", "64", "--variants", "scalar_rgb", "--radia", fake_radia(tmp),
                            "--radia-samplers", "independent,orthogonal", "--mitsuba-samplers",
                            "independent,ldsampler", "--radia-alt", f"before={fake_radia(tmp)}",
                            "--out", out], capture_output=True, text=True)
        self.assertEqual(p.returncode, 0, p.stdout + p.stderr)
        for f in ("benchmark.md", "benchmark.csv", "benchmark.html", "nodefaults.png"):
            self.assertTrue(os.path.exists(os.path.join(out, f)), f)
        with open(os.path.join(out, "benchmark.md")) as f:
            md = f.read()
        self.assertIn("Best vs best", md)
        self.assertIn("Same estimator", md)
        self.assertIn("radia[before]", md)
        with open(os.path.join(out, "benchmark.csv")) as f:
            rows = f.read()
        self.assertIn(",orthogonal,", rows)
        self.assertIn(",orthogonal,2,8,5,9,", rows)   # orthogonal renders 9 spp when asked for 5
        self.assertIn(",ldsampler,2,8,5,16,", rows)   # ldsampler 16


class CommandLine(unittest.TestCase):
    def fake_radia(self, tmp):
        return fake_radia(tmp)

    def run_cli(self, bias, code, invalid="0", extra=()):
        """compare.py drives a binary with radia's command line (a Mitsuba
        stand-in), reads its EXRs, writes the report and sets the exit status."""
        tmp = tmpdir(self)
        out = os.path.join(tmp, "out")
        env = dict(os.environ, FAKE_RADIA_BIAS=bias, FAKE_RADIA_INVALID=invalid)
        p = subprocess.run([PY, COMPARE, SIMPLE, "--res", str(RES), "--spp", "8", "--passes", "6",
                            "--ref-dir", shared_ref_dir(), "--radia", self.fake_radia(tmp),
                            "--out", out, *extra], capture_output=True, text=True, env=env)
        self.assertEqual(p.returncode, code, p.stdout + p.stderr)
        self.assertTrue(os.path.exists(os.path.join(out, "report.html")))
        for f in ("images.png", "maps.png", "tstats.png", "result.json"):
            self.assertTrue(os.path.exists(os.path.join(out, "simple", f)), f)
        self.assertIn("relMSE vs reference", p.stdout)

    def test_cli_pass(self):
        self.run_cli("1", 0)

    def test_cli_fail(self):
        self.run_cli("1.5", 1)

    def test_dropped_samples_fail_with_fail_on_invalid(self):
        self.run_cli("1", 0, invalid="3")
        self.run_cli("1", 1, invalid="3", extra=["--fail-on-invalid"])

    def test_missing_binary_is_an_error(self):
        tmp = tmpdir(self)
        p = subprocess.run([PY, COMPARE, SIMPLE, "--res", str(RES), "--ref-dir", shared_ref_dir(),
                            "--radia", os.path.join(tmp, "nope"), "--out", tmp],
                           capture_output=True, text=True)
        self.assertEqual(p.returncode, 2)
        self.assertIn("radia binary not found", p.stdout)


REPO = os.path.dirname(VALIDATION)
CORNELL = os.path.join(REPO, "scenes", "cornell-box.xml")
FURNACE = os.path.join(REPO, "scenes", "furnace.xml")


def _have_reference(scene):
    from radiaval.references import load_manifest, entry_key
    return os.path.exists(scene) and entry_key(scene, 64) in load_manifest()["references"]


class RealRadia(unittest.TestCase):
    """The teeth with the real renderer (the radia Python package, as compare.py renders by
    default) on the real scenes (committed references), at compare.py --quick settings."""

    def test_radia_on_fixture(self):
        r = run_scene(SIMPLE, RES, SPP, PASSES, candidate="radia", ref_dir=shared_ref_dir(),
                      out_dir=tmpdir(self), parity=False)
        self.assertTrue(r["passed"], r["levels"])

    @unittest.skipUnless(_have_reference(CORNELL), "no scenes/cornell-box.xml reference")
    def test_cornell_two_percent_bias_fails(self):
        r = run_scene(CORNELL, 64, 16, 32, bias=1.02, out_dir=tmpdir(self), parity=False)
        self.assertFalse(r["passed"])

    @unittest.skipUnless(_have_reference(CORNELL), "no scenes/cornell-box.xml reference")
    def test_cornell_wrong_white_albedo_fails(self):
        wrong = derive_scene(CORNELL, tmpdir(self), [("0.725, 0.71, 0.68", "0.7395, 0.7242, 0.6936")])
        r = run_scene(CORNELL, 64, 16, 32, candidate_scene=wrong, out_dir=tmpdir(self), parity=False)
        self.assertFalse(r["passed"])

    @unittest.skipUnless(_have_reference(FURNACE), "no scenes/furnace.xml reference")
    def test_furnace_albedo_098_fails(self):
        r = run_scene(FURNACE, 64, 16, 32, candidate_defines=["albedo=0.98"],
                      out_dir=tmpdir(self), parity=False)
        self.assertFalse(r["passed"])
