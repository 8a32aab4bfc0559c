"""Segment every image or volume of a folder on a Dask cluster.

Each input (``.tif``/``.tiff`` image or stack, ``.png``, ``.npy``) is read,
segmented with ``dsc_seg.segment`` at the pixel/voxel size the file gives (as
``dsc-seg`` reads it) and written to ``OUT/<stem>/`` by the worker that takes
it; the client collects one row per input into
``OUT/summary.csv`` (the columns of ``dsc-seg segment``'s batch summary). A
bad input fails its own row only.

    # A LocalCluster of 2 single-threaded worker processes on this machine
    python dask_batch.py volumes/ results/ --workers 2 --phases 2 max_iterations=200
    # Any running Dask cluster (dask-scheduler / dask-jobqueue / Kubernetes ...)
    python dask_batch.py volumes/ results/ --scheduler tcp://scheduler:8786

Options after the folders are ``dsc_seg.segment`` keywords (``NAME=VALUE``).
"""

from __future__ import annotations

import argparse
import csv
import os
import time
from pathlib import Path
from typing import Any

import numpy as np

import dsc_seg

EXTENSIONS = {".tif", ".tiff", ".png", ".npy"}
COLUMNS = [
    "name", "input", "phases", "iterations", "converged", "seconds", "status", "error", "warnings"
]


def read_input(path: Path) -> tuple[np.ndarray, dict[str, Any]]:
    """The samples of an image or volume file, and the ``spacing`` and
    ``unit`` keywords when the file gives a pixel/voxel size: without them a
    Fiji stack of 0.5 × 0.5 × 2.5 µm voxels would be segmented, and
    measured, as cubes of no unit."""
    suffix = path.suffix.lower()
    if suffix == ".npy":
        return np.load(path), {}
    if suffix in (".tif", ".tiff"):
        import tifffile

        with tifffile.TiffFile(path) as tif:
            refuse_time_series(tif)
            pixels = ome_pixels(tif)
            if pixels is not None:
                refuse_ome_channels_and_times(pixels, tif.pages[0].samplesperpixel)
            array = tif.asarray()
            spacing, unit = ome_spacing(pixels, array.ndim) if pixels is not None else (None, "")
            if spacing is None:
                spacing, unit = tiff_spacing(tif, array.ndim)
    else:
        from PIL import Image

        with Image.open(path) as image:
            # A palette image's samples are indices into its palette, not intensities.
            array = np.asarray(image.convert("RGBA") if image.mode in ("P", "PA") else image)
            dpi = image.info.get("dpi")
        array = gray_if_gray(array)
        spacing = tuple(25.4 / d for d in dpi) if dpi and min(dpi) > 0 else None
        unit = "mm"
    if spacing is None:
        return array, {}
    # "px" too (ImageJ's "pixel", or resolution tags without a unit, as tifffile
    # writes 1 per unit by default): the command line keeps it, and a size
    # passed without a unit would be reported in "unit".
    return array, {"spacing": spacing, "unit": unit}


def refuse_time_series(tif) -> None:
    """Refuses an ImageJ TIFF of time points (``frames=``), as ``dsc-seg``
    does: read as an array it has the shape of a volume, and segmenting it
    as one would mesh time as depth."""
    frames = (tif.imagej_metadata or {}).get("frames", 1)
    if isinstance(frames, int) and frames > 1:
        raise ValueError(
            f"an ImageJ time series of {frames} time points, not the slices of a volume: "
            "segment each time point as an image (the dsc-seg CLI chooses one with "
            "--time-point T, and a channel with --channel C)"
        )


#: OME's length units (``UnitsLength``) in micrometres, OME's default unit.
OME_MICROMETRES = {"nm": 1e-3, "µm": 1.0, "μm": 1.0, "um": 1.0, "mm": 1e3, "cm": 1e4, "m": 1e6}


def ome_pixels(tif):
    """The first ``Pixels`` element of an OME-TIFF's OME-XML (its first
    series, the one ``asarray`` reads), or None for another TIFF."""
    import xml.etree.ElementTree as ElementTree

    if not tif.is_ome or not tif.ome_metadata:
        return None
    root = ElementTree.fromstring(tif.ome_metadata)
    return next((e for e in root.iter() if e.tag.split("}")[-1] == "Pixels"), None)


def refuse_ome_channels_and_times(pixels, samples_per_pixel: int) -> None:
    """Refuses an OME-TIFF of several channels or time points, as ``dsc-seg``
    does: read as an array they are axes of their own, not a volume's (an
    RGB page counts as one channel)."""
    channels = int(pixels.get("SizeC", "1")) // max(samples_per_pixel, 1)
    times = int(pixels.get("SizeT", "1"))
    if channels > 1 or times > 1:
        raise ValueError(
            f"an OME-TIFF of {channels} channels × {times} time points: "
            "save one channel at one time point as a file of its own and segment that "
            "(the dsc-seg CLI chooses one with --channel C --time-point T)"
        )


def ome_spacing(pixels, ndim: int) -> tuple[tuple[float, ...] | None, str]:
    """The pixel size (x, y), or voxel size (x, y, z), in micrometres, that
    an OME-TIFF's ``PhysicalSizeX``/``Y``/``Z`` give (each in its unit,
    micrometres when none is named; z 1 µm without ``PhysicalSizeZ``), as
    ``dsc-seg`` reads them ahead of the resolution tags; None without x and y."""

    def size(axis: str) -> float | None:
        value, unit = pixels.get(f"PhysicalSize{axis}"), pixels.get(f"PhysicalSize{axis}Unit", "µm")
        if value is None or unit not in OME_MICROMETRES or float(value) <= 0:
            return None
        return float(value) * OME_MICROMETRES[unit]

    x, y = size("X"), size("Y")
    if x is None and y is None:
        return None, "px"
    x, y = x or y, y or x
    return (x, y, size("Z") or 1.0)[:ndim], "um"


def gray_if_gray(array: np.ndarray) -> np.ndarray:
    """A picture's gray values where its colour channels are equal (gray
    with an alpha channel, or a palette of grays), its alpha left out, as
    ``dsc-seg segment`` reads it; other colour pictures as they are, which
    ``dsc_seg.segment`` refuses (pass one channel or the luminance)."""
    if array.ndim != 3:
        return array
    colour = array[..., :3] if array.shape[2] >= 3 else array[..., :1]
    return colour[..., 0] if (colour == colour[..., :1]).all() else array


def tiff_spacing(tif, ndim: int) -> tuple[tuple[float, ...] | None, str]:
    """The pixel size (x, y), or voxel size (x, y, z), that ``dsc-seg``
    reads from a TIFF, and its length unit: the resolution tags (pixels per
    inch or centimetre give millimetres, pixels per unit Fiji/ImageJ's
    ``unit``) and ImageJ's ``spacing`` for z (1 without it); None and
    ``"px"`` without resolution tags."""
    tags = tif.pages[0].tags

    def step(name: str) -> float | None:
        tag = tags.get(name)
        if tag is None:
            return None
        pixels, length = tag.value
        return length / pixels if pixels > 0 and length > 0 else None

    x = step("XResolution")
    if x is None:
        return None, "px"
    y = step("YResolution") or x
    imagej = tif.imagej_metadata or {}
    unit_tag = tags.get("ResolutionUnit")
    unit = None if unit_tag is None else int(unit_tag.value)
    if unit == 3:  # centimetre
        scale, name = 10.0, "mm"
    elif unit == 1 or (unit is None and "unit" in imagej):  # none: ImageJ's unit
        scale, name = 1.0, imagej_unit(str(imagej.get("unit", "")))
    else:  # inch, TIFF's default
        scale, name = 25.4, "mm"
    z = imagej.get("spacing")
    z = z * scale if isinstance(z, (int, float)) and z > 0 else 1.0
    return (x * scale, y * scale, z)[:ndim], name


def imagej_unit(unit: str) -> str:
    """ImageJ's unit names in the short form ``dsc-seg`` gives them."""
    if unit in ("micron", "\\u00B5m", "\u00b5m", "um"):
        return "um"
    return "px" if unit in ("pixel", "") else unit


def segment_file(
    path: str, out_dir: str, phases: Any, outputs: str, options: dict[str, Any]
) -> dict[str, Any]:
    """Runs on a worker: reads, segments and writes one input; its summary row."""
    start = time.perf_counter()
    row = dict.fromkeys(COLUMNS, "")
    row.update(name=Path(path).stem, input=path)
    try:
        array, geometry = read_input(Path(path))
        # An option given, such as spacing, overrides the file's (as on the command line).
        result = dsc_seg.segment(array, phases=phases, **{**geometry, **options})
        result.write(Path(out_dir) / row["name"], outputs=outputs)
        report = result.report
        row.update(
            phases=len(report["ordered_means"]),
            iterations=report["iterations"],
            converged=report["converged"],
            status="done",
            warnings="; ".join(report["segmentation"]["warnings"]),
        )
    except Exception as e:  # a bad input fails its own row
        row.update(status="error", error=f"{type(e).__name__}: {e}")
    row["seconds"] = round(time.perf_counter() - start, 4)
    return row


def inputs_of(folder: Path) -> list[Path]:
    return sorted(
        p for p in folder.iterdir() if p.suffix.lower() in EXTENSIONS and not p.name.startswith(".")
    )


def run(
    client, input_dir: Path, out_dir: Path, phases: Any = 2, outputs: str = "all", **options: Any
) -> list[dict[str, Any]]:
    """Maps ``segment_file`` over the folder on ``client``'s cluster; writes
    and returns the summary rows in input order."""
    paths = [str(p) for p in inputs_of(Path(input_dir))]
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    futures = client.map(
        segment_file,
        paths,
        out_dir=str(out_dir),
        phases=phases,
        outputs=outputs,
        options=options,
        pure=False,
    )
    rows = client.gather(futures)
    with open(out_dir / "summary.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    return rows


def local_cluster(workers: int):
    """A LocalCluster of single-threaded worker processes, each run on one core."""
    from dask.distributed import LocalCluster

    # Inherited by the worker processes: one thread per segmentation.
    os.environ["RAYON_NUM_THREADS"] = "1"
    return LocalCluster(n_workers=workers, threads_per_worker=1, processes=True)


def keyword(text: str) -> tuple[str, Any]:
    """``NAME=VALUE`` with VALUE read as a number when it is one."""
    name, _, value = text.partition("=")
    for kind in (int, float):
        try:
            return name, kind(value)
        except ValueError:
            pass
    return name, {"true": True, "false": False}.get(value.lower(), value)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("input_dir", type=Path)
    parser.add_argument("out_dir", type=Path)
    parser.add_argument("--phases", default="2")
    parser.add_argument("--outputs", default="all")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--scheduler", help="address of a running Dask scheduler")
    parser.add_argument("options", nargs="*", type=keyword, help="NAME=VALUE keywords")
    a = parser.parse_args()
    phases = int(a.phases) if a.phases.isdigit() else a.phases

    from dask.distributed import Client

    cluster = None if a.scheduler else local_cluster(a.workers)
    with Client(a.scheduler or cluster) as client:
        start = time.perf_counter()
        rows = run(client, a.input_dir, a.out_dir, phases, a.outputs, **dict(a.options))
        wall = time.perf_counter() - start
    if cluster is not None:
        cluster.close()
    failed = sum(r["status"] == "error" for r in rows)
    print(f"{len(rows)} inputs in {wall:.2f} s, {failed} failed; summary in {a.out_dir / 'summary.csv'}")
    raise SystemExit(1 if failed else 0)


if __name__ == "__main__":
    main()
