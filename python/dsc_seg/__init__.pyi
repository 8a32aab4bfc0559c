from os import PathLike
from typing import Any, Union

import numpy as np
import numpy.typing as npt

__version__: str

class SegmentationWarning(UserWarning):
    """A warning of the run (a lost phase, the iteration cap, ...), issued by :func:`segment`."""

class Segmentation:
    """The result of :func:`segment`: labels, final mesh and report."""

    @property
    def labels(self) -> npt.NDArray[np.uint8]:
        """Phase index per pixel/voxel, the input's shape, 0..N-1 by increasing mean."""
    @property
    def vertices(self) -> npt.NDArray[np.float64]:
        """Vertex positions of the final mesh, n × 2 (2D) or n × 3 (3D), x first."""
    @property
    def cells(self) -> npt.NDArray[np.uint32]:
        """Triangles (2D) or tetrahedra (3D) as vertex indices."""
    @property
    def cell_phases(self) -> npt.NDArray[np.uint8]:
        """Each cell's phase index."""
    @property
    def warnings(self) -> list[str]:
        """The run's warnings, each also issued as a SegmentationWarning; empty when all is well."""
    @property
    def report(self) -> dict[str, Any]:
        """What report.json holds."""
    def write(self, dir: Union[str, PathLike[str]], outputs: str = "all") -> None:
        """Writes the command line's output files into dir (all or nothing)."""

def segment(
    image: npt.ArrayLike, phases: Union[int, str] = 2, **options: Any
) -> Segmentation:
    """Segments a 2D image or 3D volume; keywords are the command line's
    options, and ``unit``, the length unit of ``spacing``."""

def phantom(
    name: str = "two_phase",
    size: int = 256,
    noise: float = 0.1,
    seed: int = 1,
    ndim: int | None = None,
) -> tuple[npt.NDArray[np.uint8], npt.NDArray[np.uint8]]:
    """A test image (2D or 3D by name; ``ndim=3`` for the 3D ``four_phase``)
    and its true labels, as uint8 arrays."""
