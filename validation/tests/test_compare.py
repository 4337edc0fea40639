"""Tests of the validation instrument itself: the statistics, the verdict's
teeth (a 2% bias and a slightly wrong albedo must fail, independent Mitsuba
renders must pass), stale-reference detection and the command line."""
import json
import math
import os
import shutil
import stat
import subprocess
import sys

import numpy as np
import pytest

from conftest import RES, SIMPLE, VALIDATION
from radiaval import stats
from radiaval.common import DEFAULT_RADIA, ValidationError, scene_files
from radiaval.core import run_scene
from radiaval.references import load_reference, make_reference

PY = sys.executable
COMPARE = os.path.join(VALIDATION, "compare.py")
SPP, PASSES = 16, 32


# ---------------------------------------------------------------- statistics

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


def test_t_distribution_matches_closed_form():
    for nu in (1, 2, 3, 4, 7, 15, 31, 64):
        for t in (0.0, 0.3, 1.0, 2.0, 4.0, 8.0):
            want = _t_sf2_integer(t, nu)
            got = float(stats.t_two_sided_p(t, nu))
            assert got == pytest.approx(want, rel=1e-9, abs=1e-14), (nu, t)
    # large dof -> normal
    assert float(stats.t_two_sided_p(1.959963985, 1e9)) == pytest.approx(0.05, rel=1e-6)
    assert float(stats.t_two_sided_p(1.959963985, math.inf)) == pytest.approx(0.05, rel=1e-8)


def test_sidak():
    a = stats.sidak_alpha(0.01, 1000)
    assert 1 - (1 - a) ** 1000 == pytest.approx(0.01, rel=1e-9)
    assert stats.t_critical(0.05, math.inf) == pytest.approx(1.959964, rel=1e-5)


def test_null_hypothesis_false_alarm_rate_synthetic():
    """Gaussian synthetic passes from the same mean: the test passes nearly
    always (family-wise alpha = 1%), and a 2% bias fails always."""
    rng = np.random.default_rng(1)
    truth = rng.uniform(0.1, 1.0, size=(32, 32, 3))
    sigma = 0.2 * truth
    fails, fails_biased = 0, 0
    for trial in range(20):
        ref_passes = truth + sigma / np.sqrt(64) * rng.standard_normal((32,) + truth.shape)
        rm, rv, rk = stats.pass_moments(ref_passes)
        cand = truth + sigma * rng.standard_normal((32,) + truth.shape)
        fails += not stats.compare_to_reference(cand, rm, rv, rk).passed
        fails_biased += not stats.compare_to_reference(cand * 1.02, rm, rv, rk).passed
    assert fails == 0
    assert fails_biased == 20


# ---------------------------------------------------------------- teeth

def _run(ref_dir, tmp_path, **kw):
    kw.setdefault("parity", False)
    return run_scene(SIMPLE, RES, SPP, PASSES, candidate="mitsuba", ref_dir=ref_dir,
                     out_dir=str(tmp_path), **kw)


def test_two_independent_mitsuba_renders_pass(ref_dir, tmp_path):
    r = _run(ref_dir, tmp_path, parity=True)
    assert r["passed"], r["levels"]
    assert abs(r["parity"]["mean_ratio_vs_mitsuba"] - 1) < 0.01
    assert r["parity"]["relmse_ratio"] < 1.1


def test_two_percent_bias_fails(ref_dir, tmp_path):
    r = _run(ref_dir, tmp_path, bias=1.02)
    assert not r["passed"]
    image = [l for l in r["levels"] if l["level"] == "image"][0]
    assert image["rejected"] == 3          # the whole-image mean of each channel


def test_two_percent_low_bias_fails(ref_dir, tmp_path):
    assert not _run(ref_dir, tmp_path, bias=0.98)["passed"]


def test_slightly_wrong_albedo_fails(ref_dir, tmp_path):
    """The sphere's albedo 2% too high: the image mean moves by only ~0.2%."""
    text = open(SIMPLE).read()
    assert "0.7, 0.4, 0.2" in text
    wrong = tmp_path / "simple_wrong_albedo.xml"
    wrong.write_text(text.replace("0.7, 0.4, 0.2", "0.714, 0.408, 0.204"))
    r = _run(ref_dir, tmp_path, candidate_scene=str(wrong))
    assert not r["passed"]
    assert abs(r["parity"]["mean_ratio_vs_reference"] - 1) < 0.01   # a loose threshold would miss it


# ---------------------------------------------------------------- references

def test_reference_manifest(ref_dir):
    man = json.load(open(os.path.join(ref_dir, "manifest.json")))
    (key, e), = man["references"].items()
    assert key.endswith("simple.xml@32")
    for field in ("hash", "spp_per_pass", "passes", "total_spp", "mitsuba_version",
                  "variant", "render_time_s", "files"):
        assert field in e
    assert e["total_spp"] == e["passes"] * e["spp_per_pass"]
    ref = load_reference(SIMPLE, RES, ref_dir=ref_dir)
    assert ref.mean.shape == (RES, RES, 3) and (ref.var >= 0).all()


def test_stale_reference_is_an_error(tmp_path):
    scene = tmp_path / "scene.xml"
    shutil.copy(SIMPLE, scene)
    d = str(tmp_path / "refs")
    make_reference(str(scene), 16, spp=4, passes=2, variant="scalar_rgb", ref_dir=d)
    load_reference(str(scene), 16, ref_dir=d)          # fresh: fine
    scene.write_text(scene.read_text().replace('value="0.5, 0.5, 0.5"', 'value="0.5, 0.5, 0.6"'))
    with pytest.raises(ValidationError, match="STALE"):
        load_reference(str(scene), 16, ref_dir=d)
    # and from the command line: exit status 2
    p = subprocess.run([PY, COMPARE, str(scene), "--res", "16", "--ref-dir", d, "--candidate",
                        "mitsuba", "--out", str(tmp_path / "out"), "--no-report"],
                       capture_output=True, text=True)
    assert p.returncode == 2, p.stdout + p.stderr
    assert "STALE" in p.stdout


def test_stale_when_a_referenced_file_changes(tmp_path):
    mesh = tmp_path / "tri.obj"
    mesh.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    text = open(SIMPLE).read().replace(
        "</scene>", '<shape type="obj"><string name="filename" value="tri.obj"/></shape>\n</scene>')
    scene = tmp_path / "scene.xml"
    scene.write_text(text)
    assert str(mesh) in scene_files(str(scene))
    d = str(tmp_path / "refs")
    make_reference(str(scene), 8, spp=2, passes=2, variant="scalar_rgb", ref_dir=d)
    load_reference(str(scene), 8, ref_dir=d)
    mesh.write_text("v 0 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(ValidationError, match="STALE.*tri.obj"):
        load_reference(str(scene), 8, ref_dir=d)


def test_missing_reference_is_an_error(tmp_path):
    with pytest.raises(ValidationError, match="no reference"):
        load_reference(SIMPLE, 17, ref_dir=str(tmp_path))


# ---------------------------------------------------------------- command line

def _fake_radia(tmp_path):
    exe = tmp_path / "radia"
    exe.write_text(f"#!/bin/sh\nexec {PY} {os.path.join(VALIDATION, 'tests', 'fake_radia.py')} \"$@\"\n")
    exe.chmod(exe.stat().st_mode | stat.S_IXUSR)
    return str(exe)


@pytest.mark.parametrize("bias,code", [("1", 0), ("1.5", 1)])
def test_cli_with_a_radia_binary(ref_dir, tmp_path, bias, code):
    """compare.py drives a binary with radia's command line (here a Mitsuba
    stand-in), reads its EXRs, writes the report and sets the exit status."""
    env = dict(os.environ, FAKE_RADIA_BIAS=bias)
    out = tmp_path / "out"
    p = subprocess.run([PY, COMPARE, SIMPLE, "--res", str(RES), "--spp", "8", "--passes", "6",
                        "--ref-dir", ref_dir, "--radia", _fake_radia(tmp_path), "--out", str(out)],
                       capture_output=True, text=True, env=env)
    assert p.returncode == code, p.stdout + p.stderr
    assert (out / "report.html").exists()
    for f in ("images.png", "maps.png", "tstats.png", "result.json"):
        assert (out / "simple" / f).exists()
    assert "relMSE vs reference" in p.stdout


def test_missing_binary_is_an_error(ref_dir, tmp_path):
    p = subprocess.run([PY, COMPARE, SIMPLE, "--res", str(RES), "--ref-dir", ref_dir,
                        "--radia", str(tmp_path / "nope"), "--out", str(tmp_path)],
                       capture_output=True, text=True)
    assert p.returncode == 2 and "radia binary not found" in p.stdout


@pytest.mark.skipif(not os.path.exists(DEFAULT_RADIA), reason="target/release/radia not built")
def test_real_radia_on_fixture(ref_dir, tmp_path):
    r = run_scene(SIMPLE, RES, SPP, PASSES, candidate="radia", ref_dir=ref_dir,
                  out_dir=str(tmp_path), parity=False)
    assert r["passed"], r["levels"]
