"""AOVs from the radia Python package: `radia.render(scene, aovs=...)` and scenes whose
integrator is `aov` return (image, layers), with the same values as the EXR layers that
`radia render --aov` writes, bit for bit; the refusals (split renders, malformed strings, an
aov scene given aovs=) are ValueErrors that say why.

Run:  validation/.venv/bin/python -m unittest -v tests.test_radia_package_aov   (from validation/)
"""
import os
import unittest

import numpy as np

from .helpers import VALIDATION, tmpdir
from .test_radia_package import bits, cli, radia
from radiaval.common import mitsuba

CORNELL = os.path.join(os.path.dirname(VALIDATION), "scenes", "cornell-box.xml")
AOVS = "dd.y:depth,nn:sh_normal,g:geo_normal,albedo:albedo,uv:uv,p:position,s:shape_index"
# The suffixes of each AOV type's channels, in Mitsuba's order.
SUFFIXES = {"dd.y": "T", "nn": "XYZ", "g": "XYZ", "albedo": "RGB", "uv": "UV", "p": "XYZ",
            "s": "I"}


def exr_channels(path):
    """{channel name: (H, W) float32} of an EXR, the root RGB as R, G, B."""
    mi = mitsuba("scalar_rgb")
    out = {}
    for name, b in mi.Bitmap(path).split():
        a = np.array(b, dtype=np.float32)
        if a.ndim == 2:
            a = a[..., None]
        for c, field in enumerate(b.struct_()):
            suffix = field.name.split(".")[-1]
            out[suffix if name == "<root>" else f"{name}.{suffix}"] = a[..., c]
    return out


def aov_scene(d, nested):
    """The Cornell box with its integrator nested in an aov integrator, `nested` the nested
    integrator's XML (or "" for none)."""
    with open(CORNELL) as f:
        xml = f.read()
    start = xml.index("<integrator")
    end = xml.index("</integrator>", start) + len("</integrator>")
    aov = (f'<integrator type="aov"><string name="aovs" value="dd.y:depth,s:shape_index"/>'
           f'{nested}</integrator>')
    path = os.path.join(d, "aov-cornell.xml")
    with open(path, "w") as f:
        f.write(xml[:start] + aov + xml[end:])
    # The scene's meshes are found relative to it.
    os.symlink(os.path.join(os.path.dirname(CORNELL), "meshes"), os.path.join(d, "meshes"))
    return path


class AovTest(unittest.TestCase):
    def test_aovs_equal_the_cli_layers_bit_for_bit(self):
        d = tmpdir(self)
        out = os.path.join(d, "cli.exr")
        cli("render", CORNELL, "-D", "res=20", "--spp", 16, "--seed", 3, "--aov", AOVS,
            "-q", "-o", out)
        ref = exr_channels(out)
        scene = radia.load_file(CORNELL, res=20)
        image, layers = radia.render(scene, spp=16, seed=3, threads=2, aovs=AOVS)
        self.assertEqual(list(layers), list(SUFFIXES))
        self.assertEqual(image.shape, (20, 20, 3))
        np.testing.assert_array_equal(bits(image), bits(np.stack(
            [ref["R"], ref["G"], ref["B"]], axis=-1)))
        for name, suffixes in SUFFIXES.items():
            with self.subTest(layer=name):
                a = layers[name]
                self.assertEqual((a.dtype, a.shape), (np.float32, (20, 20, len(suffixes))))
                for c, s in enumerate(suffixes):
                    np.testing.assert_array_equal(bits(a[..., c]), bits(ref[f"{name}.{s}"]))
        # Not all zero: every camera ray hits the box (depth > 0) and the walls are shapes 1-3.
        self.assertGreater(float(layers["dd.y"].min()), 0.0)
        self.assertTrue(set(np.unique(layers["s"])) >= {1.0, 2.0, 3.0})
        # The image is the one rendered without AOVs.
        plain = radia.render(scene, spp=16, seed=3, threads=2)
        np.testing.assert_array_equal(bits(plain), bits(image))

    def test_an_aov_scene_returns_its_layers_and_the_beauty_layer(self):
        d = tmpdir(self)
        path = aov_scene(d, '<integrator type="path" name="my_image"/>')
        out = os.path.join(d, "cli.exr")
        cli("render", path, "-D", "res=16", "--spp", 8, "-q", "-o", out)
        ref = exr_channels(out)
        scene = radia.load_file(path, res=16)
        image, layers = radia.render(scene, spp=8, threads=2)
        self.assertEqual(list(layers), ["my_image", "dd.y", "s"])
        self.assertEqual(layers["my_image"].shape, (16, 16, 4))
        for c, s in enumerate("RGBA"):
            np.testing.assert_array_equal(bits(layers["my_image"][..., c]),
                                          bits(ref[f"my_image.{s}"]))
        np.testing.assert_array_equal(bits(layers["my_image"][..., :3]), bits(image))
        np.testing.assert_array_equal(bits(layers["dd.y"][..., 0]), bits(ref["dd.y.T"]))
        # aovs= on a scene that already is an aov integrator is refused, as --aov is.
        with self.assertRaisesRegex(ValueError, "already is an aov integrator"):
            radia.render(scene, spp=8, aovs="u:uv")
        # Parts carry no AOVs: refused rather than dropped.
        with self.assertRaisesRegex(ValueError, "split renders do not carry AOVs"):
            radia.render(scene, spp=8, samples=(0, 4))

    def test_malformed_aovs_are_value_errors(self):
        scene = radia.load_file(CORNELL, res=8)
        for spec, needle in [("dd.y:depht", 'invalid AOV type "depht"'),
                             ("depth", "expected a <name>:<type> pair"),
                             ("a:uv,a:depth", 'the AOV name "a" is used twice')]:
            with self.subTest(spec=spec), self.assertRaisesRegex(ValueError, needle):
                radia.render(scene, spp=1, aovs=spec)
        with self.assertRaisesRegex(ValueError, "split renders do not carry AOVs"):
            radia.render(scene, spp=4, samples=(0, 2), aovs="u:uv")


if __name__ == "__main__":
    unittest.main()
