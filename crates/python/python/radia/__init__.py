"""radia from Python: load a Mitsuba 3 scene, render it into a numpy array, split a render by
sample index and merge the parts exactly, write images.

    import radia
    scene = radia.load_file("scenes/cornell-box.xml", res=64)
    image = radia.render(scene, spp=64)             # float32 (64, 64, 3), linear RGB
    # Film overrides as `radia render --resolution 32 --rfilter box`; what the render did:
    small = radia.load_file("scenes/cornell-box.xml", resolution=32, rfilter="box")
    image, stats = radia.render(small, spp=16, seed=3, sampler="independent", stats=True)
    stats.invalid_samples, stats.rays                # NaN/Inf samples dropped, rays traced
    radia.write_image(image, "cornell.exr")

    # AOVs (Mitsuba's aov integrator string): the image and a dict of layers.
    image, layers = radia.render(scene, spp=16, aovs="dd.y:depth,nn:sh_normal")
    depth, normals = layers["dd.y"][..., 0], layers["nn"]   # (64, 64), (64, 64, 3)

    # The same image from four pieces rendered anywhere (same seed, same spp):
    parts = [radia.render(scene, spp=64, samples=(a, a + 16)) for a in range(0, 64, 16)]
    same = radia.merge(parts).develop()             # == image up to float rounding

`radia.distributed` renders on a Ray cluster (`pip install ray`).
"""
import warnings as _warnings

import numpy as _np

from ._native import (LoadError, MergeError, Part, RenderStats, Scene, load_file, read_part,
                      render)
from . import _native

__all__ = ["LoadError", "MergeError", "Part", "RenderStats", "Scene", "load_file", "merge",
           "read_part", "render", "write_image"]


def merge(parts, names=None):
    """Adds up parts of one render (each from ``render(..., samples=(a, b))`` or
    :func:`read_part`) into one :class:`Part`; ``.develop()`` gives the image.

    Parts are added in ascending order of their first sample whatever the order given, so the
    result has the same bits every time. Raises :class:`MergeError` for parts of different
    scenes, seeds, samplers or sample counts, or parts that share samples (the message names
    both); warns (UserWarning) when samples of [0, spp) are in no part.
    """
    merged = _native._merge(list(parts), names)
    gaps = merged.gaps()
    if gaps:
        _warnings.warn("samples %s of 0..%d are in no part: the image has %d of %d spp" % (
            ", ".join("%d..%d" % g for g in gaps), merged.spp, merged.sample_count, merged.spp),
            stacklevel=2)
    return merged


def write_image(array, path):
    """Writes a (height, width, 3) linear RGB array as OpenEXR (float32) or PNG (sRGB, 8 bit),
    chosen by the extension of ``path``. Other float dtypes are converted to float32."""
    _native.write_image(_np.ascontiguousarray(array, dtype=_np.float32), path)
