"""compare.py's radia passes through the Python package (radiaval.common.PackageRenderer: the
scene loaded once, a radia.render per pass) are the passes of the binary (RadiaRenderer: a
process and an EXR per pass) bit for bit, with the same film, filter, sampler and define
overrides and the same rendered spp; a missing or stale package is refused with the remedy.

Run:  validation/.venv/bin/python -m unittest -v tests.test_package_renderer   (from validation/)
"""
import os
import sys
import unittest
from unittest import mock

import numpy as np

from .helpers import NODEFAULTS, SIMPLE, tmpdir
from radiaval import common
from radiaval.common import PackageRenderer, RadiaRenderer, ValidationError, radia_package
from radiaval.sources import source_hash


def bits(a):
    return np.ascontiguousarray(a, dtype=np.float32).view(np.uint32)


class PackageRendererTest(unittest.TestCase):
    def test_passes_equal_the_binarys_bit_for_bit(self):
        for scene, kw in [(SIMPLE, dict(extra_defines=["spp=3"], sampler="independent")),
                          (NODEFAULTS, dict(sampler="stratified")),   # 8 spp rounds to 9
                          (NODEFAULTS, dict(sampler=None, rfilter="gaussian"))]:
            with self.subTest(scene=os.path.basename(scene), **kw):
                pkg = PackageRenderer(scene, 12, 8, threads=2, **kw)
                cli = RadiaRenderer(scene, 12, 8, threads=2, **kw)
                a, b = pkg.passes(3, seed0=5), cli.passes(3, seed0=5)
                self.assertEqual(a.shape, (3, 12, 12, 3))
                self.assertGreater(float(a.mean()), 0.01)
                np.testing.assert_array_equal(bits(a), bits(b))
                self.assertEqual([i["spp"] for i in pkg.infos], [i["spp"] for i in cli.infos])
                self.assertEqual(pkg.infos[0]["sampler"], cli.infos[0]["sampler"])
                self.assertEqual(pkg.invalid, cli.invalid)
        self.assertEqual(pkg.infos[0]["spp"], 9)   # nodefaults.xml's own stratified sampler
        # A bias multiplies both alike (compare.py --inject-bias).
        a = PackageRenderer(SIMPLE, 8, 4, bias=1.5).render(1)
        b = RadiaRenderer(SIMPLE, 8, 4, bias=1.5).render(1)
        np.testing.assert_array_equal(bits(a), bits(b))

    def test_load_errors_are_validation_errors(self):
        d = tmpdir(self)
        bad = os.path.join(d, "bad.xml")
        with open(bad, "w") as f:
            f.write('<scene version="3.0.0">\n<shape type="nope"/>\n</scene>\n')
        with self.assertRaisesRegex(ValidationError, r"bad\.xml"):
            PackageRenderer(bad, 8, 4)
        with self.assertRaisesRegex(ValidationError, "NAME=VALUE"):
            PackageRenderer(SIMPLE, 8, 4, extra_defines=["spp"])

    def test_a_stale_package_is_refused(self):
        d = tmpdir(self)
        with mock.patch.object(sys, "prefix", d):
            radia_package()                       # no stamp: installed by other means
            with open(os.path.join(d, ".radia-package-stamp"), "w") as f:
                f.write("0" * 64 + "\n")
            with self.assertRaisesRegex(ValidationError, "validation/setup.*--radia"):
                radia_package()
            # A tool without --radia (compare_aov.py) is not told to pass it.
            with self.assertRaises(ValidationError) as caught:
                radia_package(binary_option=False)
            self.assertIn("validation/setup", str(caught.exception))
            self.assertNotIn("--radia", str(caught.exception))
            with open(os.path.join(d, ".radia-package-stamp"), "w") as f:
                f.write(source_hash(common.REPO_ROOT) + "\n")
            radia_package()

    def test_a_missing_package_is_refused(self):
        with mock.patch.dict(sys.modules, {"radia": None}):   # import radia raises ImportError
            with self.assertRaisesRegex(ValidationError, "not installed.*validation/setup"):
                radia_package()

    def test_the_installed_package_is_current(self):
        """validation/setup stamped this venv with the hash of the sources it built."""
        stamp = os.path.join(sys.prefix, ".radia-package-stamp")
        if not os.path.exists(stamp):
            self.skipTest(f"{sys.prefix} has no package stamp (not validation/.venv)")
        radia_package()


if __name__ == "__main__":
    unittest.main()
