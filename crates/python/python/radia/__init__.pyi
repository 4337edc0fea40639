from typing import Optional, Sequence

from ._native import (LoadError as LoadError, MergeError as MergeError, Part as Part,
                      RenderStats as RenderStats, Scene as Scene, load_file as load_file,
                      read_part as read_part, render as render)
import numpy.typing as npt
from os import PathLike
from typing import Union

def merge(parts: Sequence[Part], names: Optional[Sequence[str]] = None) -> Part:
    """Adds up parts of one render; raises MergeError for mismatched or overlapping parts and
    warns when samples are missing."""

def write_image(array: npt.ArrayLike, path: Union[str, "PathLike[str]"]) -> None:
    """Writes a (height, width, 3) linear RGB array as EXR (float32) or PNG (by extension)."""
