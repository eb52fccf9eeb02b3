"""Types of the rangesynth package (docs/python.md)."""

from os import PathLike
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

_Path = Union[str, "PathLike[str]"]
_Keys = Mapping[str, Any]
_Sensed = Union[_Path, Mapping[str, Any]]

class Error(Exception):
    """Every error rangesynth raises; its message is the library's."""

class Mesh:
    """A triangle mesh: vertices (V, 3), faces (F, 3), each face's surface (1, 2, ...)."""

    def __init__(
        self,
        vertices: npt.ArrayLike,
        faces: npt.ArrayLike,
        surfaces: Optional[npt.ArrayLike] = None,
    ) -> None: ...
    @staticmethod
    def load(path: _Path) -> "Mesh":
        """A model file the command line reads (OBJ, PLY or STL)."""
    @property
    def vertex_count(self) -> int: ...
    @property
    def triangle_count(self) -> int: ...
    @property
    def surface_count(self) -> int: ...

class Renderer:
    """A renderer on one device, made once and reused, from any thread."""

    def __init__(
        self,
        device: Optional[Union[int, str]] = None,
        memory_budget: Optional[str] = None,
        raster: Optional[str] = None,
    ) -> None: ...
    def render(self, scene: _Path) -> Dict[str, Any]:
        """A scene file's arrays, as render_scene gives them."""
    @property
    def device_name(self) -> str: ...
    @property
    def validation_enabled(self) -> bool:
        """Whether Vulkan validation is on (RANGESYNTH_VALIDATION=1 where it was made)."""

class Verifier:
    """A verifier on one device, made once and reused, from any thread."""

    def __init__(
        self,
        device: Optional[Union[int, str]] = None,
        memory_budget: Optional[str] = None,
        raster: Optional[str] = None,
    ) -> None: ...
    def verify(
        self,
        sensed: _Sensed,
        model: Union[Mesh, _Path],
        poses: npt.ArrayLike,
        bindings: Sequence[Tuple[int, int]],
        shadow: Optional[Union[str, _Keys]] = None,
        effects: Optional[_Keys] = None,
        tolerance: float = 0.1,
        progress: Optional[Callable[[int], None]] = None,
    ) -> Dict[str, np.ndarray]:
        """As verify(), calling progress(poses done) after each chunk."""
    @property
    def device_name(self) -> str: ...
    @property
    def validation_enabled(self) -> bool:
        """Whether Vulkan validation is on (RANGESYNTH_VALIDATION=1 where it was made)."""

def render_scene(path: _Path, raster: Optional[str] = None) -> Dict[str, Any]:
    """A scene file's "xyz" (H, W, 3) float32 (NaN where nothing was measured), "label"
    (H, W) uint32, "reason" (H, W) uint8 and, where the sensor has witnesses, "witness"
    (H, W) uint32; "labels", the labels table (a structured array of label, object, model,
    surface, surface_name); and "sensor", a dict of the [sensor] keys. verify() takes it as
    its sensed image."""

def verify(
    sensed: _Sensed,
    model: Union[Mesh, _Path],
    poses: npt.ArrayLike,
    bindings: Sequence[Tuple[int, int]],
    shadow: Optional[Union[str, _Keys]] = None,
    effects: Optional[_Keys] = None,
    tolerance: float = 0.1,
    raster: Optional[str] = None,
) -> Dict[str, np.ndarray]:
    """Scores each of the (N, 4, 4) poses of model against the sensed image (an EXR path, or a
    dict of "xyz", "label" and "sensor"): "s", "s1" ... "s6" float64; "n1_plus", "n1_minus",
    "n0", "n1", "n_s", "n_i" uint64; "surface_population" (N, model surfaces) uint64;
    "overlaps", each pose's (K, 3) uint64 array of [scene label, model surface, pixels]; and
    "rejected" (str, empty where not rejected)."""

def devices() -> List[Dict[str, Any]]:
    """The Vulkan devices the loader lists: "index", "name", "uuid", "kind"."""

def validation_messages() -> List[str]:
    """What Vulkan validation (on where RANGESYNTH_VALIDATION=1) reported since the last call,
    on every device this process opened."""

def read_range_image(path: _Path) -> Dict[str, Any]:
    """A range EXR's "xyz", "label", and "reason", "witness" and "sensor" (a dict of the
    [sensor] keys) where the file has them."""
