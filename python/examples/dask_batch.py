"""Segment every image or volume of a folder on a Dask cluster.

Each input (``.tif``/``.tiff`` image or stack, ``.png``, ``.npy``) is read,
segmented with ``dsc_seg.segment`` and written to ``OUT/<stem>/`` by the
worker that takes it; the client collects one row per input into
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


def read_array(path: Path) -> np.ndarray:
    """The samples of an image or volume file."""
    suffix = path.suffix.lower()
    if suffix == ".npy":
        return np.load(path)
    if suffix in (".tif", ".tiff"):
        import tifffile

        return tifffile.imread(path)
    from PIL import Image

    return np.asarray(Image.open(path))


def segment_file(
    path: str, out_dir: str, phases: Any, outputs: str, options: dict[str, Any]
) -> dict[str, Any]:
    """Runs on a worker: reads, segments and writes one input; its summary row."""
    start = time.perf_counter()
    row = dict.fromkeys(COLUMNS, "")
    row.update(name=Path(path).stem, input=path)
    try:
        result = dsc_seg.segment(read_array(Path(path)), phases=phases, **options)
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
