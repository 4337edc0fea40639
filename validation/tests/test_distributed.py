"""radia.distributed on a local Ray cluster started here (2 CPUs, loopback only): pieces
rendered by Ray actors and merged equal the single render; with a worker's process killed
mid-render, Ray restarts it and re-runs its piece, the log says so, and the image is the same.

Skipped (with the reason) when Ray is not installed; validation/requirements.txt has it.
Run:  validation/.venv/bin/python -m unittest -v tests.test_distributed   (from validation/)
"""
import contextlib
import io
import os
import signal
import sys
import time
import unittest

import numpy as np

from .helpers import SIMPLE, tmpdir

import radia
import radia.distributed as rd   # imports without Ray; its functions need it

try:
    import ray
except ImportError:
    ray = None


def bits(a):
    return np.ascontiguousarray(a, dtype=np.float32).view(np.uint32)


@unittest.skipIf(ray is None, "ray is not installed in this venv: run validation/setup "
                              "(validation/requirements.txt pins it)")
class DistributedTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        t0 = time.perf_counter()
        ray.init(num_cpus=2, include_dashboard=False, _node_ip_address="127.0.0.1",
                 log_to_driver=True)
        print(f"\nray.init: {time.perf_counter() - t0:.1f} s", file=sys.stderr)

    @classmethod
    def tearDownClass(cls):
        ray.shutdown()

    def test_pieces_on_two_workers_equal_the_single_render_and_frames_too(self):
        d = tmpdir(self)
        other = os.path.join(d, "other.xml")
        with open(SIMPLE) as f:
            xml = f.read().replace("0.7, 0.4, 0.2", "0.2, 0.4, 0.7")
        with open(other, "w") as f:
            f.write(xml)
        t0 = time.perf_counter()
        infos = []
        frames = rd.render_frames([SIMPLE, other], spp=64, seed=3, defines={"res": 24},
                                  pieces=4, workers=2,
                                  outputs=os.path.join(d, "frame-{:02d}.exr"),
                                  on_piece=lambda f, info: infos.append((f, info)))
        print(f"2 frames x 4 pieces: {time.perf_counter() - t0:.1f} s", file=sys.stderr)
        # What a piece cost besides its render (validation/distributed_scaling.py reports it):
        # each worker's load of each frame's scene once, with its first piece of that frame.
        self.assertEqual(len(infos), 8)
        loads = {}
        for f, i in infos:
            self.assertGreater(i["render_secs"], 0.0)
            self.assertGreaterEqual(i["merge_secs"], 0.0)
            self.assertGreaterEqual(i["arrived_at"], i["finished_at"])   # one clock, one machine
            if i["load_secs"] > 0:
                loads[(f, i["pid"])] = loads.get((f, i["pid"]), 0) + 1
        self.assertEqual(set(loads.values()), {1})
        self.assertEqual(set(loads), {(f, i["pid"]) for f, i in infos})
        for path, img in zip([SIMPLE, other], frames):
            whole = radia.render(radia.load_file(path, res=24), spp=64, seed=3)
            # Box filter, pieces of whole passes: the merge is bit-exact.
            np.testing.assert_array_equal(bits(img), bits(whole))
        self.assertFalse(np.array_equal(frames[0], frames[1]))
        self.assertTrue(os.path.exists(os.path.join(d, "frame-01.exr")))

    def test_a_killed_worker_is_restarted_and_its_piece_rerun(self):
        killed = []

        def kill_the_busy_worker(frame, info):
            # The actor that returned this piece was handed the next one before we are called:
            # it is rendering now. End its process once.
            if not killed:
                os.kill(info["pid"], signal.SIGKILL)
                killed.append(info["pid"])
        infos = []

        def on_piece(frame, info):
            infos.append(info)
            kill_the_busy_worker(frame, info)
        log = io.StringIO()
        t0 = time.perf_counter()
        with contextlib.redirect_stderr(log):
            img = rd.render(SIMPLE, spp=256, seed=5, defines={"res": 48}, pieces=8,
                            workers=2, on_piece=on_piece)
        secs = time.perf_counter() - t0
        sys.stderr.write(log.getvalue())
        print(f"8 pieces with a kill: {secs:.1f} s", file=sys.stderr)
        self.assertEqual(len(killed), 1)
        self.assertEqual(len(infos), 8)
        retried = [i for i in infos if i["restarted"]]
        self.assertTrue(retried, "no piece ran on a restarted worker")
        self.assertNotIn(killed[0], [i["pid"] for i in retried])
        self.assertIn("restarted worker", log.getvalue())
        self.assertIn("a retry", log.getvalue())
        # Unchanged by the kill: the same bits as the same pieces rendered here and merged
        # (pieces of two passes regroup the float sums: vs one render, equal up to rounding).
        scene = radia.load_file(SIMPLE, res=48)
        local = radia.merge([radia.render(scene, spp=256, seed=5, samples=r)
                             for r in rd.piece_ranges(256, 8)]).develop()
        np.testing.assert_array_equal(bits(img), bits(local))
        whole = radia.render(scene, spp=256, seed=5)
        eps = float(np.finfo(np.float32).eps)
        bound = 2 * (2 * (256 - 1) * eps / 2) + eps    # box filter: see test_radia_package
        rel = np.abs(img - whole) / np.maximum(np.abs(whole), np.finfo(np.float32).tiny)
        self.assertLessEqual(float(rel.max()), bound)


class PieceRangesTest(unittest.TestCase):
    def test_ranges_cover_the_samples_in_whole_passes(self):
        self.assertEqual(rd.piece_ranges(64, 4), [(0, 16), (16, 32), (32, 48), (48, 64)])
        for spp, pieces in [(64, 4), (100, 3), (16, 8), (5, 2), (1000, 7)]:
            r = rd.piece_ranges(spp, pieces)
            self.assertEqual(r[0][0], 0)
            self.assertEqual(r[-1][1], spp)
            self.assertTrue(all(a < b for a, b in r))
            self.assertTrue(all(b == c for (_, b), (c, _) in zip(r, r[1:])))
            self.assertTrue(all(b % 16 == 0 for _, b in r[:-1]))
            self.assertLessEqual(len(r), pieces)


if __name__ == "__main__":
    unittest.main()
