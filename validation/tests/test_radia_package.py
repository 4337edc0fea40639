"""Tests of the radia Python package (crates/python, built into validation/.venv by
validation/setup): the same image as the CLI bit for bit, an exact split and merge, merges
refused for mismatched parts (Python and `radia merge`), errors with file and line, Ctrl-C,
the GIL released while rendering.

Run:  validation/.venv/bin/python -m unittest -v tests.test_radia_package   (from validation/)
"""
import os
import pickle
import signal
import subprocess
import threading
import time
import unittest
import warnings

import numpy as np

from .helpers import NODEFAULTS, SIMPLE, VALIDATION, tmpdir
from radiaval.common import DEFAULT_RADIA, read_exr

try:
    import radia
except ImportError as e:  # a failure, not a skip: validation/setup installs it
    raise ImportError(f"the radia package is not installed in this venv ({e}); "
                      "run validation/setup") from e

CORNELL = os.path.join(os.path.dirname(VALIDATION), "scenes", "cornell-box.xml")
F32_EPS = float(np.finfo(np.float32).eps)


def cli(*args, check=True):
    r = subprocess.run([DEFAULT_RADIA, *map(str, args)], capture_output=True, text=True)
    if check and r.returncode != 0:
        raise AssertionError(f"radia {' '.join(map(str, args))} failed:\n{r.stderr}")
    return r


def bits(a):
    return np.ascontiguousarray(a, dtype=np.float32).view(np.uint32)


def rounding_bound(spp, filter_radius=0.5):
    """How far apart two float32 sums of the same non-negative terms in another grouping can
    be, relative (Higham §4.2: (n - 1)·u·Σ|x| each), in numerator and weight, n the number of
    (sample, pixel) contributions to a pixel; see tests/tests/split_merge.rs."""
    n = spp * (2 * np.ceil(filter_radius) + 1) ** 2
    return 2 * (2 * (n - 1) * F32_EPS / 2) + F32_EPS


class LoadTest(unittest.TestCase):
    def test_scene_object_counts(self):
        s = radia.load_file(SIMPLE, res=24, spp=8)
        self.assertEqual(s.resolution, (24, 24))
        self.assertEqual((s.width, s.height, s.spp), (24, 24, 8))
        self.assertEqual(s.emitters, 1)
        self.assertEqual(s.shapes, 2)
        self.assertEqual(s.sampler, "independent")
        self.assertEqual(len(s.fingerprint), 16)
        self.assertIn("24x24", repr(s))
        # Defines change the content, hence the fingerprint; the same defines do not.
        self.assertNotEqual(s.fingerprint, radia.load_file(SIMPLE, res=25).fingerprint)
        self.assertEqual(s.fingerprint, radia.load_file(SIMPLE, res="24", spp=8).fingerprint)

    def test_load_error_carries_file_line_and_message(self):
        d = tmpdir(self)
        bad = os.path.join(d, "bad.xml")
        with open(bad, "w") as f:
            f.write('<scene version="3.0.0">\n  <shape type="sphere">\n'
                    '    <float name="radius" value="abc"/>\n  </shape>\n</scene>\n')
        with self.assertRaises(radia.LoadError) as cm:
            radia.load_file(bad)
        e = cm.exception
        self.assertEqual(os.path.abspath(e.file), os.path.abspath(bad))
        self.assertEqual(e.line, 3)
        self.assertIn("abc", e.message)
        self.assertIn(f"{e.file}:3", str(e))
        with self.assertRaises(radia.LoadError) as cm:
            radia.load_file(os.path.join(d, "missing.xml"))
        self.assertTrue(cm.exception.file.endswith("missing.xml"))


class RenderTest(unittest.TestCase):
    def test_render_equals_the_cli_bit_for_bit(self):
        d = tmpdir(self)
        # A box filter with the independent sampler, and a Gaussian filter with the stratified
        # sampler (nodefaults.xml); a scene with an area light and meshes.
        for path, defines, spp, seed in [(SIMPLE, {"res": 24}, 32, 5),
                                         (NODEFAULTS, {}, 16, 0),
                                         (CORNELL, {"res": 20}, 16, 3)]:
            with self.subTest(scene=os.path.basename(path)):
                out = os.path.join(d, "cli.exr")
                args = [a for k, v in defines.items() for a in ("-D", f"{k}={v}")]
                cli("render", path, *args, "--spp", spp, "--seed", seed, "-q", "-o", out)
                scene = radia.load_file(path, **defines)
                img = radia.render(scene, spp=spp, seed=seed, threads=2)
                self.assertEqual(img.dtype, np.float32)
                self.assertEqual(img.shape, (scene.height, scene.width, 3))
                self.assertTrue(img.flags["C_CONTIGUOUS"])
                ref = read_exr(out)
                self.assertGreater(float(ref.mean()), 0.01)
                np.testing.assert_array_equal(bits(img), bits(ref))

    def test_threads_do_not_change_the_image(self):
        scene = radia.load_file(SIMPLE, res=40)
        a = radia.render(scene, spp=8, seed=1, threads=1)
        b = radia.render(scene, spp=8, seed=1)
        np.testing.assert_array_equal(bits(a), bits(b))
        self.assertFalse(np.array_equal(a, radia.render(scene, spp=8, seed=2)))

    def test_write_image_round_trips(self):
        d = tmpdir(self)
        img = radia.render(radia.load_file(SIMPLE, res=16), spp=4)
        radia.write_image(img, os.path.join(d, "a.exr"))
        np.testing.assert_array_equal(bits(read_exr(os.path.join(d, "a.exr"))), bits(img))
        radia.write_image(img.astype(np.float64), os.path.join(d, "b.png"))
        self.assertGreater(os.path.getsize(os.path.join(d, "b.png")), 0)
        with self.assertRaises(ValueError):
            radia.write_image(np.zeros((4, 4, 2), np.float32), os.path.join(d, "c.exr"))

    def test_gil_is_released_while_rendering(self):
        scene = radia.load_file(SIMPLE, res=64)
        # A render long enough to tell on any machine: spp from a timed short one (a fixed
        # 256 spp took 0.195 s on a quiet machine, too short for the check below).
        t0 = time.perf_counter()
        radia.render(scene, spp=16)
        spp = int(min(1 << 16, max(256, 16 * 0.6 / max(time.perf_counter() - t0, 1e-4))))
        ticks = [0]
        stop = threading.Event()

        def count():
            while not stop.is_set():
                ticks[0] += 1
                time.sleep(0.001)
        t = threading.Thread(target=count)
        t.start()
        t0 = time.perf_counter()
        radia.render(scene, spp=spp)
        secs = time.perf_counter() - t0
        stop.set()
        t.join()
        # Held GIL: the counter would not move. Released: ~1 tick per ms (sleep granularity).
        self.assertGreater(secs, 0.2, "render too short to tell")
        self.assertGreater(ticks[0], 0.2 * secs * 1000, f"{ticks[0]} ticks in {secs:.2f} s")

    def test_ctrl_c_interrupts_the_render(self):
        scene = radia.load_file(SIMPLE, res=128)
        # Python's own SIGINT handler, as in a terminal: a process started in the background
        # by a non-interactive shell (`cmd &`) inherits SIGINT ignored, and Python keeps it so.
        previous = signal.signal(signal.SIGINT, signal.default_int_handler)
        timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
        t0 = time.perf_counter()
        timer.start()
        try:
            with self.assertRaises(KeyboardInterrupt):
                radia.render(scene, spp=1 << 16)  # minutes if not interrupted
        finally:
            timer.cancel()
            signal.signal(signal.SIGINT, previous)
        self.assertLess(time.perf_counter() - t0, 5.0)


class OverrideTest(unittest.TestCase):
    """load_file(resolution=, rfilter=) and render(sampler=) as the CLI's --resolution,
    --rfilter and --sampler; render(stats=True) with the CLI's figures."""

    def test_overrides_equal_the_cli_bit_for_bit(self):
        d = tmpdir(self)
        out = os.path.join(d, "cli.exr")
        # nodefaults.xml: a literal 48x36 film, a gaussian filter, a stratified sampler.
        for resolution, size, rfilter, sampler in [((20, 14), "20x14", "box", "independent"),
                                                    (18, "18", "gaussian", "sobol"),
                                                    (16, "16", "box", None)]:
            with self.subTest(resolution=resolution, rfilter=rfilter, sampler=sampler):
                args = ["--sampler", sampler] if sampler else []
                cli("render", NODEFAULTS, "--resolution", size, "--rfilter", rfilter, *args,
                    "--spp", 16, "--seed", 2, "-q", "-o", out)
                scene = radia.load_file(NODEFAULTS, resolution=resolution, rfilter=rfilter)
                w, h = (resolution, resolution) if isinstance(resolution, int) else resolution
                self.assertEqual(scene.resolution, (w, h))
                img = radia.render(scene, spp=16, seed=2, sampler=sampler)
                np.testing.assert_array_equal(bits(img), bits(read_exr(out)))
        # The override is part of the scene's content: parts of other sizes are told apart.
        self.assertNotEqual(radia.load_file(NODEFAULTS, resolution=16).fingerprint,
                            radia.load_file(NODEFAULTS).fingerprint)
        self.assertNotEqual(radia.load_file(NODEFAULTS, rfilter="box").fingerprint,
                            radia.load_file(NODEFAULTS).fingerprint)

    def test_stats(self):
        scene = radia.load_file(SIMPLE, res=16)
        img, st = radia.render(scene, spp=9, seed=1, stats=True)
        np.testing.assert_array_equal(bits(img), bits(radia.render(scene, spp=9, seed=1)))
        self.assertEqual((st.spp, st.samples, st.invalid_samples), (9, 16 * 16 * 9, 0))
        self.assertGreaterEqual(st.rays, st.samples)   # a camera ray per sample, and more
        self.assertGreater(st.seconds, 0.0)
        self.assertIn("invalid samples", repr(st))
        # With samples= the result is the Part, the stats of its range.
        part, st = radia.render(scene, spp=32, seed=1, samples=(16, 32), stats=True)
        self.assertEqual((part.samples, st.spp, st.samples), ([(16, 32)], 16, 16 * 16 * 16))
        # The stratified sampler rounds 8 to 9, and says so.
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always")
            _, st = radia.render(scene, spp=8, sampler="stratified", stats=True)
        self.assertEqual(st.spp, 9)
        self.assertTrue(any("renders 9 spp" in str(x.message) for x in w))

    def test_bad_overrides_are_value_errors(self):
        for kwargs, what in [({"resolution": 0}, "at least 1"),
                             ({"resolution": (4, 0)}, "at least 1"),
                             ({"resolution": "abc"}, r"int or a \(width, height\)"),
                             ({"resolution": (1, 2, 3)}, r"int or a \(width, height\)"),
                             ({"rfilter": "tent"}, "box or gaussian")]:
            with self.subTest(**kwargs):
                with self.assertRaisesRegex(ValueError, what):
                    radia.load_file(SIMPLE, **kwargs)
        with self.assertRaisesRegex(ValueError, "unknown sampler.*independent"):
            radia.render(radia.load_file(SIMPLE, res=4), spp=1, sampler="halton")


class SplitMergeTest(unittest.TestCase):
    def parts(self, scene, spp, seed, ends):
        return [radia.render(scene, spp=spp, seed=seed, samples=(a, b))
                for a, b in zip(ends[:-1], ends[1:])]

    def test_four_ranges_merged_equal_the_single_render(self):
        for path, defines in [(SIMPLE, {"res": 24}), (NODEFAULTS, {})]:
            with self.subTest(scene=os.path.basename(path)):
                scene = radia.load_file(path, **defines)
                spp = 64
                whole = radia.render(scene, spp=spp, seed=9)
                # Unaligned ranges, given out of order.
                parts = self.parts(scene, spp, 9, [0, 5, 21, 40, 64])[::-1]
                merged = radia.merge(parts)
                self.assertEqual(merged.samples, [(0, spp)])
                self.assertEqual(merged.gaps(), [])
                img = merged.develop()
                radius = 0.5 if path == SIMPLE else 2.0   # box / gaussian(0.5) = 4 sigma
                tol = rounding_bound(spp, radius)
                rel = np.abs(img - whole) / np.maximum(np.maximum(np.abs(img), np.abs(whole)),
                                                       np.finfo(np.float32).tiny)
                self.assertLessEqual(float(rel.max()), tol)
                # The pieces are different images: the merge is not trivially equal.
                self.assertFalse(np.array_equal(parts[0].develop(), whole))

    def test_one_pass_pieces_with_a_box_filter_merge_bit_for_bit(self):
        scene = radia.load_file(SIMPLE, res=24)
        whole = radia.render(scene, spp=64, seed=2)
        merged = radia.merge(self.parts(scene, 64, 2, [0, 16, 32, 48, 64]))
        np.testing.assert_array_equal(bits(merged.develop()), bits(whole))

    def test_cli_pieces_merge_to_the_cli_render_and_to_python_merge(self):
        d = tmpdir(self)
        ends = [0, 16, 32, 48, 64]
        files = []
        for a, b in zip(ends[:-1], ends[1:]):
            f = os.path.join(d, f"part-{a}.exr")
            cli("render", SIMPLE, "-D", "res=24", "--spp", 64, "--seed", 4, "--samples",
                f"{a}..{b}", "-q", "-o", f)
            files.append(f)
        cli("render", SIMPLE, "-D", "res=24", "--spp", 64, "--seed", 4, "-q",
            "-o", os.path.join(d, "whole.exr"))
        cli("merge", *files[::-1], "-o", os.path.join(d, "merged.exr"))
        whole = read_exr(os.path.join(d, "whole.exr"))
        merged = read_exr(os.path.join(d, "merged.exr"))
        np.testing.assert_array_equal(bits(merged), bits(whole))
        # The CLI's parts are the Python ones, header included.
        scene = radia.load_file(SIMPLE, res=24)
        p = radia.read_part(files[1])
        self.assertEqual((p.samples, p.spp, p.seed, p.sampler, p.scene),
                         ([(16, 32)], 64, 4, "independent", scene.fingerprint))
        q = radia.render(scene, spp=64, seed=4, samples=(16, 32))
        np.testing.assert_array_equal(bits(p.sums()), bits(q.sums()))
        # And a Python part written to disk merges with CLI parts.
        q.write(os.path.join(d, "py-16.exr"))
        cli("merge", files[0], os.path.join(d, "py-16.exr"), *files[2:],
            "-o", os.path.join(d, "mixed.exr"))
        np.testing.assert_array_equal(bits(read_exr(os.path.join(d, "mixed.exr"))), bits(whole))

    def test_parts_pickle(self):
        scene = radia.load_file(SIMPLE, res=8)
        p = radia.render(scene, spp=16, seed=1, samples=(4, 12))
        q = pickle.loads(pickle.dumps(p))
        self.assertEqual((q.samples, q.spp, q.seed, q.scene), (p.samples, p.spp, p.seed, p.scene))
        np.testing.assert_array_equal(bits(q.sums()), bits(p.sums()))

    def test_merge_refuses_mismatched_parts(self):
        scene = radia.load_file(SIMPLE, res=16)
        a = radia.render(scene, spp=32, seed=1, samples=(0, 16))
        cases = [
            ("seeds", radia.render(scene, spp=32, seed=2, samples=(16, 32))),
            ("sample counts", radia.render(scene, spp=64, seed=1, samples=(16, 32))),
            ("scenes", radia.render(radia.load_file(SCENE_WITH_OTHER_COLOUR(self), res=16),
                                    spp=32, seed=1, samples=(16, 32))),
            ("both render samples 8..16", radia.render(scene, spp=32, seed=1, samples=(8, 24))),
        ]
        for what, b in cases:
            with self.subTest(what=what):
                with self.assertRaises(radia.MergeError) as cm:
                    radia.merge([a, b])
                self.assertIn(what, str(cm.exception))
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always")
            m = radia.merge([a])
        self.assertEqual(m.gaps(), [(16, 32)])
        self.assertTrue(any("16..32" in str(x.message) for x in w), [str(x.message) for x in w])

    def test_cli_merge_refuses_mismatched_parts_and_warns_on_gaps(self):
        d = tmpdir(self)

        def part(name, *extra, samples="0..16", spp=32):
            f = os.path.join(d, name)
            cli("render", SIMPLE, "-D", "res=16", "--spp", spp, "--samples", samples, "-q",
                "-o", f, *extra)
            return f
        a = part("a.exr", "--seed", 1)
        out = os.path.join(d, "out.exr")
        for what, b in [("seeds differ", part("seed.exr", "--seed", 2, samples="16..32")),
                        ("scenes differ", part("scene.exr", "--seed", 1, "-D", "res=17",
                                               samples="16..32")),
                        ("sample counts", part("spp.exr", "--seed", 1, samples="16..32", spp=64)),
                        ("both render samples 8..16", part("overlap.exr", "--seed", 1,
                                                           samples="8..24"))]:
            with self.subTest(what=what):
                r = cli("merge", a, b, "-o", out, check=False)
                self.assertNotEqual(r.returncode, 0)
                self.assertIn(what, r.stderr)
                self.assertIn("a.exr", r.stderr)
                self.assertIn(os.path.basename(b), r.stderr)
                self.assertFalse(os.path.exists(out))
        r = cli("merge", a, "-o", out)
        self.assertIn("samples 16..32 of 0..32 are in no part", r.stderr)
        r = cli("merge", SIMPLE, "-o", out, check=False)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("simple.xml", r.stderr)


def SCENE_WITH_OTHER_COLOUR(case):
    """simple.xml with the sphere's colour changed: another scene of the same size."""
    with open(SIMPLE) as f:
        xml = f.read().replace("0.7, 0.4, 0.2", "0.7, 0.4, 0.3")
    path = os.path.join(tmpdir(case), "other.xml")
    with open(path, "w") as f:
        f.write(xml)
    return path


if __name__ == "__main__":
    unittest.main()
