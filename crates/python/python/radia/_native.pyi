"""Type stubs of radia's native module (re-exported by ``radia``)."""
from os import PathLike
from typing import Dict, List, Literal, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

_Path = Union[str, "PathLike[str]"]
_Image = npt.NDArray[np.float32]

class LoadError(ValueError):
    """A scene, or a file it references, could not be loaded."""
    file: str
    """The file the problem is in (the scene or a mesh/texture it references)."""
    line: Optional[int]
    """1-based line, when known."""
    column: Optional[int]
    """1-based column, when known."""
    message: str
    """The problem, without its location."""

class MergeError(ValueError):
    """Parts of different renders, or parts sharing samples."""

class Scene:
    """A loaded scene, ready to render."""
    @property
    def resolution(self) -> Tuple[int, int]:
        """(width, height) of the film in pixels."""
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def spp(self) -> int:
        """Samples per pixel the scene's sampler asks for."""
    @property
    def sampler(self) -> str:
        """The scene's sampler: "independent", "stratified", "sobol", ..."""
    def render_spp(self, spp: Optional[int] = None) -> int:
        """The sample count render() renders for spp (default the scene's), rounded as the
        sampler requires."""
    @property
    def emitters(self) -> int:
        """Number of emitters, area lights included."""
    @property
    def shapes(self) -> int:
        """Number of shapes."""
    @property
    def primitives(self) -> int:
        """Number of BVH primitives (triangles and analytic shapes)."""
    @property
    def path(self) -> str:
        """The file it was loaded from."""
    @property
    def fingerprint(self) -> str:
        """Hash of the scene's content (16 hex digits)."""

class Part:
    """The accumulated film of some sample ranges of a render. Picklable."""
    @property
    def samples(self) -> List[Tuple[int, int]]:
        """Its sample ranges [(a, b), ...], b excluded, sorted."""
    @property
    def sample_count(self) -> int:
        """Samples per pixel it holds."""
    @property
    def spp(self) -> int:
        """The whole render's samples per pixel."""
    @property
    def seed(self) -> int: ...
    @property
    def sampler(self) -> str: ...
    @property
    def scene(self) -> str:
        """The scene's fingerprint."""
    @property
    def resolution(self) -> Tuple[int, int]:
        """(width, height) in pixels."""
    def gaps(self) -> List[Tuple[int, int]]:
        """The ranges of [0, spp) it does not hold."""
    def develop(self) -> _Image:
        """The image of its samples: float32 (height, width, 3)."""
    def sums(self) -> npt.NDArray[np.float32]:
        """float32 (height, width, 4): (Σw·r, Σw·g, Σw·b, Σw) per pixel."""
    def write(self, path: _Path) -> None:
        """Writes it as a partial EXR (what `radia merge` reads)."""

def load_file(path: _Path, *, resolution: Union[int, Tuple[int, int], None] = None,
              rfilter: Optional[str] = None, **defines: object) -> Scene:
    """Loads a Mitsuba 3 XML scene; keyword arguments override its <default> parameters (as
    Mitsuba's -D), except resolution (an int or (width, height)) and rfilter ("box" or
    "gaussian"), which override its film as `radia render --resolution/--rfilter`. Raises
    LoadError, and ValueError for a bad override."""

class RenderStats:
    """What a render did: render(..., stats=True) returns it beside the result."""
    spp: int
    """Samples per pixel rendered."""
    samples: int
    """Camera samples traced."""
    rays: int
    """Rays traced, shadow rays included."""
    invalid_samples: int
    """NaN/Inf samples dropped (the CLI's "invalid samples dropped")."""
    seconds: float
    """Wall time of the render (not the load)."""

_Result = Union[_Image, Part, Tuple[_Image, Dict[str, _Image]]]

@overload
def render(scene: Scene, spp: Optional[int] = None, seed: int = 0,
           threads: Optional[int] = None, samples: None = None,
           aovs: None = None, sampler: Optional[str] = None,
           stats: Literal[False] = False) -> Union[_Image, Tuple[_Image, Dict[str, _Image]]]: ...
@overload
def render(scene: Scene, spp: Optional[int] = None, seed: int = 0,
           threads: Optional[int] = None, samples: None = None, *,
           aovs: str, sampler: Optional[str] = None,
           stats: Literal[False] = False) -> Tuple[_Image, Dict[str, _Image]]: ...
@overload
def render(scene: Scene, spp: Optional[int] = None, seed: int = 0,
           threads: Optional[int] = None, *, samples: Tuple[int, int],
           sampler: Optional[str] = None, stats: Literal[False] = False) -> Part: ...
@overload
def render(scene: Scene, spp: Optional[int] = None, seed: int = 0,
           threads: Optional[int] = None, samples: Optional[Tuple[int, int]] = None,
           aovs: Optional[str] = None, sampler: Optional[str] = None, *,
           stats: Literal[True]) -> Tuple[_Result, RenderStats]: ...
def render(scene: Scene, spp: Optional[int] = None, seed: int = 0,
           threads: Optional[int] = None,
           samples: Optional[Tuple[int, int]] = None,
           aovs: Optional[str] = None,
           sampler: Optional[str] = None,
           stats: bool = False
           ) -> Union[_Result, Tuple[_Result, RenderStats]]:
    """Renders scene: a float32 (height, width, 3) linear RGB array; with samples=(a, b) only
    sample indices a..b of the spp of every pixel, as a Part. spp defaults to the scene's,
    seed to 0, threads to all cores, sampler to the scene's (a name overrides it, as
    `radia render --sampler`). Releases the GIL; Ctrl-C raises KeyboardInterrupt.

    With AOVs, aovs="dd.y:depth,nn:sh_normal" (Mitsuba's aov integrator string, as
    `radia render --aov`) or a scene whose integrator is `aov`: (image, layers), layers a
    dict of float32 (height, width, C) arrays keyed by layer name, in the EXR's order and
    with its values: the nested integrator's layer (R, G, B, A) if the scene names one, then
    each AOV (depth: T; position, normals, dp_du, dp_dv: X, Y, Z; uv: U, V; albedo: R, G, B;
    prim_index, shape_index: I). Refused (ValueError) with samples, for a malformed string,
    and when the scene already has an aov integrator.

    With stats=True: (result, RenderStats), result as above."""

def write_image(array: npt.ArrayLike, path: _Path) -> None:
    """Writes a float32 (height, width, 3) linear RGB array as EXR or PNG (by extension)."""

def read_part(path: _Path) -> Part:
    """Reads a partial EXR."""

def _merge(parts: Sequence[Part], names: Optional[Sequence[str]] = None) -> Part: ...
