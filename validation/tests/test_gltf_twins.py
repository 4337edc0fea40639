"""Issue #10: each glTF scene in scenes/gltf/ renders the same as its hand-written XML twin,
by compare.py's test. Mitsuba cannot load the twins (they use radia's extensions:
`<shape type="gltf">`, `cooktorrance`), so both sides are radia: the twin's independent passes
stand where compare.py has Mitsuba's reference, and the glTF file's passes (other seeds) are
the candidate, through the same per-pixel and per-block Welch test (radiaval.stats).
crates/formats/tests/parity.rs compares the same pairs with one seed, block by block."""

import os
import unittest

import numpy as np

from .helpers import VALIDATION
from radiaval.common import DEFAULT_RADIA, RadiaRenderer
from radiaval.stats import compare_to_reference, pass_moments

SCENES = os.path.join(os.path.dirname(VALIDATION), "scenes", "gltf")
RES, SPP, PASSES = 32, 16, 12


def passes(path, seed0, bias=1.0):
    r = RadiaRenderer(path, RES, SPP, binary=DEFAULT_RADIA, threads=2,
                      sampler="independent", bias=bias)
    return r.passes(PASSES, seed0=seed0)


@unittest.skipUnless(os.path.exists(DEFAULT_RADIA), f"{DEFAULT_RADIA} not built")
class GltfTwinsTest(unittest.TestCase):
    def test_each_gltf_scene_renders_as_its_xml_twin(self):
        for name in ("textured", "spheres", "hierarchy"):
            with self.subTest(name):
                twin = passes(os.path.join(SCENES, f"{name}.xml"), seed0=0)
                mean, var, k = pass_moments(twin)
                self.assertGreater(float(mean.mean()), 0.0, f"{name}: black")
                gltf = passes(os.path.join(SCENES, f"{name}.glb"), seed0=1000)
                result = compare_to_reference(gltf, mean, var, k)
                self.assertTrue(result.passed, f"{name}: {result.summary_rows()}")
                if name == "textured":
                    # The test sees a 5% brighter glTF render.
                    brighter = passes(os.path.join(SCENES, f"{name}.glb"), seed0=1000,
                                      bias=1.05)
                    self.assertFalse(compare_to_reference(brighter, mean, var, k).passed,
                                     "a 5% brighter render went unnoticed")


if __name__ == "__main__":
    unittest.main()
