"""examples/dask_batch.py on a LocalCluster with 2 workers: the same labels
as sequential runs, outputs per input, a bad input in its own row."""

import csv
import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest
import tifffile

import dsc_seg

pytest.importorskip("dask.distributed")

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "dask_batch.py"


def load_example():
    spec = importlib.util.spec_from_file_location("dask_batch", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_dask_example_matches_sequential_runs(tmp_path):
    example = load_example()
    volumes = tmp_path / "volumes"
    volumes.mkdir()
    names = []
    for i, name in enumerate(["two_balls", "torus", "hollow_sphere"] * 3):
        volume, _ = dsc_seg.phantom(name, size=20, noise=0.1, seed=i + 1)
        tifffile.imwrite(volumes / f"v{i}_{name}.tif", volume)
        names.append(f"v{i}_{name}")
    (volumes / "broken.tif").write_bytes(b"II*\0 not a tiff")
    out = tmp_path / "out"

    from dask.distributed import Client

    with example.local_cluster(2) as cluster, Client(cluster) as client:
        assert len(client.scheduler_info()["workers"]) == 2
        rows = example.run(client, volumes, out, phases=2, outputs="labels,report", max_iterations=15)

    by_name = {r["name"]: r for r in rows}
    assert len(rows) == 10
    assert by_name["broken"]["status"] == "error" and by_name["broken"]["error"]
    with open(out / "summary.csv") as f:
        summary = list(csv.DictReader(f))
    assert [r["name"] for r in summary] == sorted(names + ["broken"])
    assert "warnings" in summary[0], "the column of the command line's batch summary"
    for name in names:
        assert by_name[name]["status"] == "done", by_name[name]
        labels = tifffile.imread(out / name / "labels.tif")
        sequential = dsc_seg.segment(
            tifffile.imread(volumes / f"{name}.tif"), phases=2, max_iterations=15
        )
        assert np.array_equal(labels, sequential.labels), name
        assert (out / name / "report.json").is_file()
        assert not (out / name / "mesh.vtu").exists()


def test_a_stacks_voxel_size_is_read_as_the_cli_reads_it(tmp_path, cli):
    """A Fiji stack of 0.5 × 0.5 × 2.5 µm voxels is segmented and measured in
    those voxels, with the command line's labels, not as cubes."""
    example = load_example()
    volume, _ = dsc_seg.phantom("two_balls", size=20, noise=0.1, seed=1)
    stack = tmp_path / "fiji.tif"
    tifffile.imwrite(
        stack,
        volume,
        imagej=True,
        resolution=(2.0, 2.0),
        metadata={"spacing": 2.5, "unit": "um", "axes": "ZYX"},
    )
    row = example.segment_file(
        str(stack), str(tmp_path / "out"), 2, "labels,report", {"max_iterations": 15}
    )
    assert row["status"] == "done", row
    report = json.loads((tmp_path / "out" / "fiji" / "report.json").read_text())
    assert report["frame"]["spacing"] == [0.5, 0.5, 2.5]
    cli("segment3d", stack, "--phases", 2, "--max-iterations", 15, "--outputs", "labels,report",
        "--quiet", "--out", tmp_path / "cli")
    cli_report = json.loads((tmp_path / "cli" / "report.json").read_text())
    assert report["frame"]["unit"] == cli_report["frame"]["unit"] == "um"
    assert report["phases"]["unit"] == "um"
    assert np.array_equal(
        tifffile.imread(tmp_path / "out" / "fiji" / "labels.tif"),
        tifffile.imread(tmp_path / "cli" / "labels.tif"),
    )


def test_a_plain_tiffs_pixel_units_are_kept_as_the_cli_keeps_them(tmp_path, cli):
    """tifffile writes a resolution of 1 per unit, no unit, by default: the
    row's report gives the command line's frame ("px", spacing 1), not a
    size given in an unnamed "unit"."""
    example = load_example()
    volume, _ = dsc_seg.phantom("two_balls", size=20, noise=0.1, seed=1)
    plain = tmp_path / "plain.tif"
    tifffile.imwrite(plain, volume)
    row = example.segment_file(str(plain), str(tmp_path / "out"), 2, "report", {})
    assert row["status"] == "done", row
    cli("segment3d", plain, "--phases", 2, "--outputs", "report", "--quiet",
        "--out", tmp_path / "cli")
    frames = [
        json.loads((d / "report.json").read_text())["frame"]
        for d in (tmp_path / "out" / "plain", tmp_path / "cli")
    ]
    assert [f["unit"] for f in frames] == ["px", "px"]
    assert frames[0]["spacing"] == frames[1]["spacing"] == [1.0, 1.0, 1.0]


def test_a_time_series_is_refused_as_the_cli_refuses_it(tmp_path):
    """Time points of one plane (tifffile's ``TYX`` with ``imagej=True``) are
    no volume: its row fails, naming the time series, as ``segment3d`` does."""
    example = load_example()
    frames, _ = dsc_seg.phantom("two_balls", size=20, noise=0.1, seed=1)
    series = tmp_path / "time_lapse.tif"
    tifffile.imwrite(series, frames, imagej=True, metadata={"axes": "TYX"})
    row = example.segment_file(str(series), str(tmp_path / "out"), 2, "report", {})
    assert row["status"] == "error", row
    assert "time series of 20 time points" in row["error"], row
    assert not (tmp_path / "out" / "time_lapse").exists()


def test_a_spacing_option_overrides_the_files(tmp_path):
    example = load_example()
    volume, _ = dsc_seg.phantom("two_balls", size=20, noise=0.1, seed=1)
    stack = tmp_path / "fiji.tif"
    tifffile.imwrite(stack, volume, imagej=True, resolution=(2.0, 2.0), metadata={"spacing": 2.5})
    options = {"max_iterations": 15, "spacing": (1, 1, 1)}
    row = example.segment_file(str(stack), str(tmp_path / "out"), 2, "report", options)
    assert row["status"] == "done", row
    report = json.loads((tmp_path / "out" / "fiji" / "report.json").read_text())
    assert report["frame"]["spacing"] == [1.0, 1.0, 1.0]


def test_a_pngs_pixel_size_is_in_millimetres_as_the_cli_reads_it(tmp_path, cli):
    from PIL import Image

    example = load_example()
    image, _ = dsc_seg.phantom("two_phase", size=48, noise=0.1, seed=1)
    path = tmp_path / "scan.png"
    Image.fromarray(image).save(path, dpi=(254, 254))  # 0.1 mm pixels
    row = example.segment_file(str(path), str(tmp_path / "out"), 2, "report", {})
    assert row["status"] == "done", row
    cli("segment", path, "--outputs", "report", "--quiet", "--out", tmp_path / "cli")
    frames = [
        json.loads((d / "report.json").read_text())["frame"]
        for d in (tmp_path / "out" / "scan", tmp_path / "cli")
    ]
    assert [f["unit"] for f in frames] == ["mm", "mm"]
    assert frames[0]["spacing"] == pytest.approx(frames[1]["spacing"])


def test_a_palette_or_gray_alpha_png_is_read_as_its_gray_values(tmp_path, cli):
    """A PNG of gray values saved with a palette (a quantiser's, its entries
    in any order) or with an alpha channel gives the command line's labels,
    not those of its palette indices or of a volume two voxels wide."""
    from PIL import Image

    example = load_example()
    image, _ = dsc_seg.phantom("two_phase", size=48, noise=0.1, seed=1)
    order = np.random.default_rng(1).permutation(256)  # palette entry of each gray
    palette = Image.fromarray(order[image].astype(np.uint8), "P")
    palette.putpalette(np.repeat(np.argsort(order), 3).astype(np.uint8).tobytes())
    alpha = Image.fromarray(np.stack([image, np.full_like(image, 255)], axis=2), "LA")
    for name, picture in (("palette", palette), ("alpha", alpha)):
        path = tmp_path / f"{name}.png"
        picture.save(path)
        row = example.segment_file(str(path), str(tmp_path / "out"), 2, "labels", {})
        assert row["status"] == "done", row
        cli("segment", path, "--outputs", "labels", "--quiet", "--out", tmp_path / name)
        expected = np.asarray(Image.open(tmp_path / name / "labels.png"))
        labels = np.asarray(Image.open(tmp_path / "out" / name / "labels.png"))
        assert np.array_equal(labels, expected), name


def test_an_ome_tiffs_voxel_size_is_read_as_the_cli_reads_it(tmp_path, cli):
    """An OME-TIFF of 0.5 × 0.5 × 2 µm voxels (PhysicalSize, no resolution
    tags) is segmented in those voxels, with the command line's labels; one
    of two channels is refused, as the command line refuses it."""
    example = load_example()
    volume, _ = dsc_seg.phantom("two_balls", size=20, noise=0.1, seed=1)
    stack = tmp_path / "ome.ome.tif"
    sizes = {"PhysicalSizeX": 0.5, "PhysicalSizeY": 0.5, "PhysicalSizeZ": 2.0}
    tifffile.imwrite(stack, volume, ome=True, metadata={"axes": "ZYX", **sizes})
    row = example.segment_file(
        str(stack), str(tmp_path / "out"), 2, "labels,report", {"max_iterations": 15}
    )
    assert row["status"] == "done", row
    report = json.loads((tmp_path / "out" / "ome.ome" / "report.json").read_text())
    assert report["frame"]["spacing"] == [0.5, 0.5, 2.0]
    cli("segment3d", stack, "--phases", 2, "--max-iterations", 15, "--outputs", "labels,report",
        "--quiet", "--out", tmp_path / "cli")
    cli_report = json.loads((tmp_path / "cli" / "report.json").read_text())
    assert cli_report["frame"]["spacing"] == [0.5, 0.5, 2.0]
    assert report["frame"]["unit"] == cli_report["frame"]["unit"]
    assert np.array_equal(
        tifffile.imread(tmp_path / "out" / "ome.ome" / "labels.tif"),
        tifffile.imread(tmp_path / "cli" / "labels.tif"),
    )

    channels = tmp_path / "channels.ome.tif"
    tifffile.imwrite(channels, np.stack([volume, volume]), ome=True,
                     metadata={"axes": "CZYX", **sizes})
    row = example.segment_file(str(channels), str(tmp_path / "out"), 2, "report", {})
    assert row["status"] == "error" and "2 channels" in row["error"], row
