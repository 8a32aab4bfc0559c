"""Multiphase segmentation of NumPy images and volumes with the deformable
simplicial complex (DSC).

>>> import dsc_seg
>>> image, truth = dsc_seg.phantom("two_phase", size=128)
>>> result = dsc_seg.segment(image, phases=2)
>>> result.labels.shape
(128, 128)

``segment`` runs the same code as the ``dsc-seg segment`` / ``segment3d``
command line: its keywords are the command line's options with ``_`` for
``-`` (``edge_length=4`` is ``--edge-length 4``), and its labels are those
the command line writes for the same samples.
"""

from __future__ import annotations

import json
import warnings
from functools import cached_property
from os import PathLike
from typing import Any, Union

import numpy as np

from . import _native

__all__ = ["segment", "phantom", "Segmentation", "SegmentationWarning"]
__version__ = _native.__version__


class SegmentationWarning(UserWarning):
    """What the command line prints as ``warning: ...``: a phase lost or
    absorbed by its neighbours, a run stopped at the iteration cap, the
    choice of ``phases="auto"``, noise that comes in blobs, a smooth trend of
    intensity inside a phase (uneven illumination). :func:`segment`
    issues one per warning of the run, so a result with a lost phase does not
    pass for a good one in a notebook; ``warnings.simplefilter("error",
    dsc_seg.SegmentationWarning)`` makes them errors, and
    :attr:`Segmentation.warnings` lists them."""


def _option_args(options: dict[str, Any]) -> list[str]:
    """Keywords as command-line arguments: ``True`` is a flag, ``False`` and
    ``None`` leave the option out, a sequence of numbers is one
    comma-separated value (``spacing=(1, 1, 2)``), a list of sequences or
    strings repeats the option (``disk=[(40, 40, 10), (90, 60, 8, 2)]``)."""
    args: list[str] = []
    for key, value in options.items():
        flag = "--" + key.replace("_", "-")
        if value is None or value is False:
            continue
        if value is True:
            args.append(flag)
        elif isinstance(value, (list, tuple)) and any(
            isinstance(v, (list, tuple, str)) for v in value
        ):
            for v in value:
                args += [flag, _one_value(v)]
        else:
            args += [flag, _one_value(value)]
    return args


def _one_value(value: Any) -> str:
    if isinstance(value, (list, tuple, np.ndarray)):
        return ",".join(str(v) for v in value)
    if isinstance(value, PathLike):
        return str(value.__fspath__())
    return str(value)


class Segmentation:
    """The result of :func:`segment`.

    Attributes
    ----------
    labels : numpy.ndarray
        Phase index per pixel/voxel (uint8, the input's shape), phases
        ``0..N-1`` ordered by increasing mean: the command line's
        ``labels.png`` / ``labels.tif``.
    vertices : numpy.ndarray
        The final mesh's vertex positions (float64, ``n × 2`` or ``n × 3``;
        x, y[, z], x along the last array axis) in the units of ``spacing``
        (1 per pixel/voxel without it), from the outer corner of the first
        pixel/voxel, in 2D as in 3D; pixel ``(i, j)``'s centre is at
        ``((i + 0.5)·sx, (j + 0.5)·sy)``.
    cells : numpy.ndarray
        Its triangles (2D) or tetrahedra (3D) as vertex indices (uint32).
    cell_phases : numpy.ndarray
        Each cell's phase index (uint8), as in ``labels``.
    report : dict
        What ``report.json`` holds: parameters, energy per iteration,
        convergence, timings, counts.
    warnings : list of str
        The run's warnings (the report's ``warnings``), each also issued as
        a :class:`SegmentationWarning` by :func:`segment`; empty when all is
        well.
    """

    def __init__(self, native: Any):
        self._native = native

    @cached_property
    def labels(self) -> np.ndarray:
        return self._native.labels

    @cached_property
    def vertices(self) -> np.ndarray:
        return self._native.vertices

    @cached_property
    def cells(self) -> np.ndarray:
        return self._native.cells

    @cached_property
    def cell_phases(self) -> np.ndarray:
        return self._native.cell_phases

    @cached_property
    def warnings(self) -> list[str]:
        return list(self._native.warnings)

    @cached_property
    def report(self) -> dict[str, Any]:
        return json.loads(self._native.report_json)

    def write(self, dir: Union[str, PathLike], outputs: str = "all") -> None:
        """Writes the command line's output files into ``dir`` (created if
        missing; all or nothing): the labels (``labels.png`` / ``labels.tif``),
        the overlay (2D), the VTK mesh, interface, image and scene, the
        per-phase tables and ``report.json``. ``outputs`` chooses some, as
        ``--outputs`` does (e.g. ``"labels,report"``). The VTK files lie in
        the report's ``frame`` (``index_to_world``), where VTK's readers place
        the array saved as an image: pixel/voxel centres at ``(i·sx, …)``
        (half a pixel off :attr:`vertices`) and, in 2D, rows upwards as a
        PNG's. Raises OSError if the directory cannot be written."""
        self._native.write(str(dir), outputs)

    def __repr__(self) -> str:
        r = self.report
        return (
            f"<Segmentation {'×'.join(map(str, self.labels.shape))}, "
            f"{len(r['ordered_means'])} phases, {r['iterations']} iterations, "
            f"converged={r['converged']}>"
        )


def segment(image: Any, phases: Union[int, str] = 2, **options: Any) -> Segmentation:
    """Segments a 2D image (rows × columns) or a 3D volume (slices × rows ×
    columns) into ``phases`` phases.

    Any integer, floating-point or boolean dtype is accepted (float16 as
    float32, bool as the uint8 values 0 and 1, a mask's two levels),
    with the intensities the file readers would give: uint8 divided by 255,
    uint16 by 65535, every other type as it is in 2D and mapped by its own
    range to [0, 1] in 3D. A colour image (rows × columns × 2 to 4
    channels) is refused: pass one channel or its luminance. So is a 2D array
    of 32/64-bit values that float32 would round by more than a thousandth
    of their range (values far from zero that vary little): subtract an
    offset such as the minimum first.
    The report's ``input`` block gives the array's sample type, its range
    and the phase means in the array's own values (HU for a CT array), as it
    does for a file.

    Every option of ``dsc-seg segment`` (2D) or ``dsc-seg segment3d`` (3D)
    is a keyword, ``-`` written ``_``: for example ``edge_length=4``,
    ``max_iterations=200``, ``no_label_flips=True``, ``init="disks",
    disk=[(64, 64, 20)]``, ``rigidity=0.5``; ``spacing=(x, y)`` for an image or
    ``spacing=(x, y, z)`` for a volume, the pixel/voxel size (x along the array's last axis). Run ``dsc-seg segment
    --help`` / ``dsc-seg segment3d --help`` for the list. One keyword is
    the array's own: ``unit``, the length unit of ``spacing`` (``"um"``,
    ``"mm"``; 1 per pixel/voxel in it without ``spacing``), which the
    command line takes from the file: the report's ``frame`` and
    measurements and the written files (``labels.tif``'s resolution, a
    ``labels.png``'s ``pHYs`` in mm) carry it, as they carry a file's
    (without it a given size is in ``"unit"``).

    The GIL is released while the segmentation runs, so threads (or a Dask
    worker's threads) can segment several images at once.

    Every warning of the run (a lost phase, the iteration cap, ...; the
    command line's ``warning:`` lines) is issued as a
    :class:`SegmentationWarning` and kept in the result's ``warnings``.

    Raises ValueError for bad arguments or an unusable image, OSError when a
    file named by an option cannot be read.
    """
    array = _checked_array(image)
    args = _option_args({"phases": phases, **options})
    result = Segmentation(_native.segment(array, args))
    for message in result.warnings:
        warnings.warn(message, SegmentationWarning, stacklevel=2)
    return result


def _checked_array(image: Any) -> np.ndarray:
    """``image`` as the native code takes it: a NumPy array in the machine's
    byte order (FITS and some NIfTI data come big-endian), half-precision
    floats widened to float32 (the native code reads 32- and 64-bit floats),
    booleans as the uint8 values 0 and 1, and a colour image or a masked
    array refused rather than segmented as a volume or with its mask
    ignored.

    A colour image as NumPy and image libraries hold it (rows × columns ×
    3 or 4 channels, or 2 for gray + alpha) has the shape of a volume of as
    many slices as rows, 2 to 4 voxels wide: segmented as one, it gives
    labels of the right shape and a plausible look, but mixes the channels
    along a spatial axis.
    """
    if isinstance(image, (str, bytes, PathLike)):
        raise ValueError(
            f"segment() takes an array, not the file name {image!r}: read the "
            "file first (tifffile.imread, PIL.Image.open, nibabel) or run "
            "`dsc-seg segment FILE`"
        )
    if isinstance(image, np.ma.MaskedArray) and np.ma.getmask(image).any():
        raise ValueError(
            "the image is a masked array: segment() has no mask and would "
            "segment the masked samples' values; fill them first "
            "(image.filled(value)) or segment the unmasked region"
        )
    array = np.asarray(image)
    if not array.dtype.isnative:
        array = array.astype(array.dtype.newbyteorder("="))
    if array.ndim == 3 and array.shape[2] in (2, 3, 4) and min(array.shape[:2]) > 4:
        raise ValueError(
            f"the array's shape {array.shape} is that of a colour image "
            f"(rows × columns × {array.shape[2]} channels), not of a volume "
            "(slices × rows × columns): pass one channel (image[..., 0]) or "
            "the luminance as a 2D array; a volume only 2 to 4 voxels wide "
            "along its last axis is taken with that axis moved first "
            "(np.moveaxis(volume, 2, 0))"
        )
    if array.dtype == np.float16:
        return array.astype(np.float32)
    if array.dtype == np.bool_:
        # A mask: its 0/1 values, as the uint8 array `mask.astype(np.uint8)` is read.
        return array.astype(np.uint8)
    return array


def phantom(
    name: str = "two_phase",
    size: int = 256,
    noise: float = 0.1,
    seed: int = 1,
    ndim: int | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """A test image and its true labels, as uint8 arrays: the images
    ``dsc-seg phantom`` (2D: ``two_phase``, ``four_phase``, ``fig2`` ...
    ``fig6``, ``thin``) or ``dsc-seg phantom3d`` (3D: ``two_balls``, ``torus``,
    ``hollow_sphere``, ``three_phase``, ``four_phase``, ``brain``) writes, of
    side ``size`` with Gaussian noise of standard deviation ``noise``
    (intensities in [0, 1]). A name both know (``four_phase``) gives the 2D
    image unless ``ndim=3``.

    Returns ``(image, truth)``; ``truth`` holds the phase per pixel/voxel."""
    return _native.phantom(name, size, noise, seed, ndim)
