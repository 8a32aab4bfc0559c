"""dsc_seg.segment against the command line: same labels on the phantoms in
2D and 3D, dtypes, options as keywords, errors, written outputs, and the GIL
released during a run."""

import signal
import sys
import threading
import time
import warnings

import numpy as np
import pytest
import tifffile
from PIL import Image

import dsc_seg


@pytest.mark.parametrize("name,phases", [("two_phase", 2), ("four_phase", 4)])
def test_labels_identical_to_the_cli_2d(tmp_path, cli, name, phases):
    cli("phantom", name, "--size", 128, "--noise", 0.2, "--out", tmp_path)
    png = tmp_path / f"{name}.png"
    image, truth = dsc_seg.phantom(name, size=128, noise=0.2)
    assert np.array_equal(np.asarray(Image.open(png)), image)
    cli("segment", png, "--phases", phases, "--quiet", "--out", tmp_path / "cli")
    cli_labels = np.asarray(Image.open(tmp_path / "cli" / "labels.png"))

    result = dsc_seg.segment(image, phases=phases)
    assert result.labels.dtype == np.uint8
    assert result.labels.shape == image.shape
    assert np.array_equal(result.labels, cli_labels)
    assert (result.labels == truth).mean() > 0.85
    # The same mesh as the command line's report counts.
    report = result.report
    assert report["cells"] == len(result.cells) == len(result.cell_phases)
    assert report["vertices"] == len(result.vertices)
    assert result.vertices.shape[1] == 2 and result.cells.shape[1] == 3
    assert set(np.unique(result.cell_phases)) <= set(range(phases))


def test_labels_identical_to_the_cli_3d(tmp_path, cli):
    cli("phantom3d", "two_balls", "--size", 24, "--noise", 0.1, "--out", tmp_path)
    tif = tmp_path / "two_balls.tif"
    volume, truth = dsc_seg.phantom("two_balls", size=24, noise=0.1)
    assert np.array_equal(tifffile.imread(tif), volume)
    cli("segment3d", tif, "--max-iterations", 30, "--quiet", "--out", tmp_path / "cli")
    cli_labels = tifffile.imread(tmp_path / "cli" / "labels.tif")

    result = dsc_seg.segment(volume, max_iterations=30)
    assert result.labels.shape == volume.shape == (24, 24, 24)
    assert np.array_equal(result.labels, cli_labels)
    assert (result.labels == truth).mean() > 0.9
    assert result.vertices.shape[1] == 3 and result.cells.shape[1] == 4
    assert result.report["cells"] == len(result.cells)


def test_dtypes_map_as_the_file_readers_do():
    image, truth = dsc_seg.phantom("two_phase", size=64)
    reference = dsc_seg.segment(image).labels
    as_u16 = image.astype(np.uint16) * 257
    as_f32 = image.astype(np.float32) / np.float32(255)
    for same in (as_u16, as_f32):
        assert np.array_equal(dsc_seg.segment(same).labels, reference), same.dtype
    for other in (image.astype(np.int32) - 100, image.astype(np.int64) * 1000):
        labels = dsc_seg.segment(other).labels
        assert (labels == truth).mean() > 0.9, other.dtype


def test_a_boolean_mask_is_read_as_its_uint8_values():
    """A mask is a (trivial) two-level image: its labels are those of the
    same 0/1 values as uint8, 2D and 3D, and the report's means are 0 and 1."""
    _, truth = dsc_seg.phantom("two_phase", size=64)
    _, truth3 = dsc_seg.phantom("two_balls", size=24)
    for mask in (truth > 0, truth3 > 0):
        result = dsc_seg.segment(mask, max_iterations=30)
        as_uint8 = dsc_seg.segment(mask.astype(np.uint8), max_iterations=30)
        assert np.array_equal(result.labels, as_uint8.labels)
        assert (result.labels == mask).mean() > 0.98
        given = result.report["input"]
        assert given["sample_type"] == "uint8"
        assert (given["min"], given["max"]) == (0, 1)
        assert [round(m) for m in given["phase_means"]] == [0, 1]


def test_the_report_gives_the_arrays_type_and_units_2d_and_3d():
    image, _ = dsc_seg.phantom("two_phase", size=64)
    volume, _ = dsc_seg.phantom("two_balls", size=24, noise=0.1)
    # CT-like signed values: the report's range and means are in them, not on [0, 1].
    for array in (image.astype(np.int16) * 4 - 1000, volume.astype(np.int16) * 4 - 1000):
        report = dsc_seg.segment(array, max_iterations=30).report
        given = report["input"]
        assert given["sample_type"] == "int"
        assert given["intensity_unit"] == "file"
        assert (given["min"], given["max"]) == (array.min(), array.max())
        low, high = given["phase_means"]
        assert array.min() <= low < high <= array.max()
        assert high - low > 100, given  # on [0, 1] it would be below 1
    as_u16 = image.astype(np.uint16) * 257
    given = dsc_seg.segment(as_u16).report["input"]
    assert given["sample_type"] == "uint16"
    assert (given["min"], given["max"]) == (as_u16.min(), as_u16.max())
    assert given["phase_means"][1] > 255


def test_options_are_the_cli_options_as_keywords():
    image, _ = dsc_seg.phantom("two_phase", size=64)
    r = dsc_seg.segment(
        image,
        max_iterations=5,
        edge_length=4,
        no_label_flips=True,
        init="disks",
        disk=[(32, 32, 12), (10, 10, 4, 1)],
    )
    params = r.report["params"]
    assert r.report["iterations"] <= 5
    assert params["edge_length"] == 4
    assert params["label_flips"] is False
    assert len(params["init"]["disks"]) == 2


def test_spacing_scales_a_volume():
    volume, _ = dsc_seg.phantom("two_balls", size=16)
    plain = dsc_seg.segment(volume, max_iterations=3)
    spaced = dsc_seg.segment(volume, max_iterations=3, spacing=(1, 1, 2))
    assert plain.vertices.max(axis=0).tolist() == [16, 16, 16]
    assert spaced.vertices.max(axis=0).tolist() == [16, 16, 32]
    with pytest.raises(ValueError, match="3 positive numbers"):
        dsc_seg.segment(volume, spacing=(1, 0, 1))


def test_unit_names_the_length_unit_of_spacing_in_the_report_and_files(tmp_path):
    """``unit`` is carried where the command line carries a file's unit: the
    report's frame and measurements, ``labels.tif``'s ImageJ unit and
    resolution (3D), ``labels.png``'s pHYs (2D, in mm)."""
    import tifffile
    from PIL import Image

    volume, _ = dsc_seg.phantom("two_balls", size=16)
    spaced = dsc_seg.segment(volume, max_iterations=3, spacing=(0.5, 0.5, 2), unit="um")
    assert spaced.report["frame"]["unit"] == "um"
    assert spaced.report["phases"]["unit"] == "um"
    spaced.write(tmp_path / "3d", outputs="labels")
    with tifffile.TiffFile(tmp_path / "3d" / "labels.tif") as tif:
        assert tif.imagej_metadata["unit"] == "micron"
        assert tif.imagej_metadata["spacing"] == 2
        pixels, length = tif.pages[0].tags["XResolution"].value
        assert length / pixels == 0.5

    image, _ = dsc_seg.phantom("two_phase", size=64)
    spaced = dsc_seg.segment(image, max_iterations=5, spacing=(0.25, 0.25), unit="mm")
    assert spaced.report["frame"]["unit"] == spaced.report["phases"]["unit"] == "mm"
    spaced.write(tmp_path / "2d", outputs="labels")
    with Image.open(tmp_path / "2d" / "labels.png") as png:
        assert png.info["dpi"] == pytest.approx((25.4 / 0.25, 25.4 / 0.25), rel=1e-3)
    # Without spacing, one pixel is 1 in the unit.
    unit_pixels = dsc_seg.segment(image, max_iterations=5, unit="um").report["frame"]
    assert (unit_pixels["unit"], unit_pixels["spacing"][:2]) == ("um", [1.0, 1.0])
    with pytest.raises(ValueError, match="length unit"):
        dsc_seg.segment(image, spacing=(0.5, 0.5), unit="\u00b5m")


def test_phases_auto_chooses_the_count_of_the_four_phase_phantom():
    image, truth = dsc_seg.phantom("four_phase", size=128)
    r = dsc_seg.segment(image, phases="auto", max_phases=6)
    assert r.report["params"]["phases"] == 4
    assert sorted(np.unique(r.labels)) == [0, 1, 2, 3]
    trials = r.report["phase_choice"]["trials"]
    assert [t["phases"] for t in trials][:3] == [2, 3, 4]
    assert (r.labels == truth).mean() > 0.95


def test_spacing_gives_an_image_its_pixel_size():
    image, _ = dsc_seg.phantom("two_phase", size=64)
    plain = dsc_seg.segment(image, max_iterations=5)
    spaced = dsc_seg.segment(image, max_iterations=5, spacing=(0.5, 0.25))
    assert np.array_equal(plain.labels, spaced.labels)
    assert spaced.report["frame"]["spacing"][:2] == [0.5, 0.25]
    assert plain.report["phases"]["unit"] == "px"
    assert spaced.report["phases"]["unit"] == "unit"
    for a, b in zip(plain.report["phases"]["phases"], spaced.report["phases"]["phases"]):
        assert b["count"] == a["count"]
        for key in ("count_measure", "mesh_measure", "partial_volume", "partial_volume_se"):
            assert b[key] == pytest.approx(a[key] * 0.125)
    # The vertices are in the units of spacing, as a volume's are.
    assert np.allclose(spaced.vertices, plain.vertices * [0.5, 0.25])
    assert plain.vertices.max(axis=0).tolist() == [64, 64]
    with pytest.raises(ValueError, match="2 positive numbers"):
        dsc_seg.segment(image, spacing=(1, 1, 1))
    with pytest.raises(ValueError, match="channel"):
        dsc_seg.segment(image, channel=1)


def test_bad_arguments_raise_value_error_with_the_cli_message(tmp_path):
    image, _ = dsc_seg.phantom("two_phase", size=32)
    with pytest.raises(ValueError, match="unexpected keyword argument 'no_such_option'"):
        dsc_seg.segment(image, no_such_option=1)
    with pytest.raises(ValueError, match="number of phases must be between 2 and 64"):
        dsc_seg.segment(image, phases=70)
    with pytest.raises(ValueError, match="--init disks needs at least one --disk"):
        dsc_seg.segment(image, init="disks")
    with pytest.raises(ValueError, match="dimensions"):
        dsc_seg.segment(np.zeros(10))
    with pytest.raises(ValueError, match="unsupported array type"):
        dsc_seg.segment(np.zeros((32, 32), dtype=np.complex64))
    with pytest.raises(ValueError, match="NaN"):
        dsc_seg.segment(np.full((32, 32), np.nan))
    with pytest.raises(OSError, match="nope.png"):
        dsc_seg.segment(image, init="labels", init_labels=tmp_path / "nope.png")
    with pytest.raises(ValueError, match="unknown"):
        dsc_seg.phantom("no_such_phantom")


def test_the_runs_warnings_are_python_warnings_as_on_the_command_line(tmp_path, cli):
    image, _ = dsc_seg.phantom("four_phase", size=64)
    png = tmp_path / "four_phase.png"
    Image.fromarray(image).save(png)
    # Eight phases asked of a four-phase image: lost phases, as on the command line.
    done = cli("segment", png, "--phases", 8, "--quiet", "--out", tmp_path / "cli")
    printed = [l[len("warning: "):] for l in done.stderr.splitlines() if l.startswith("warning: ")]
    assert printed
    with pytest.warns(dsc_seg.SegmentationWarning) as caught:
        result = dsc_seg.segment(image, phases=8)
    assert [str(w.message) for w in caught] == printed
    assert result.warnings == printed == result.report["warnings"]
    assert caught[0].filename == __file__, "issued at the caller's line"
    # They can be made errors; a run without them issues none.
    with warnings.catch_warnings():
        warnings.simplefilter("error", dsc_seg.SegmentationWarning)
        with pytest.raises(dsc_seg.SegmentationWarning, match="iteration cap"):
            dsc_seg.segment(image, phases=4, max_iterations=2)
        assert dsc_seg.segment(image, phases=4).warnings == []


def test_big_endian_arrays_give_the_native_labels():
    # FITS images, and NIfTI data read raw, come big-endian.
    image, _ = dsc_seg.phantom("two_phase", size=48, noise=0.2)
    for native in (image.astype(np.float32) / 255, image.astype(np.int16) - 100,
                   image.astype(np.uint16) * 257):
        swapped = native.astype(native.dtype.newbyteorder(">" if sys.byteorder == "little" else "<"))
        assert not swapped.dtype.isnative and np.array_equal(swapped, native)
        assert np.array_equal(dsc_seg.segment(swapped).labels, dsc_seg.segment(native).labels)


def test_a_masked_array_or_a_file_name_is_refused_not_misread():
    image, _ = dsc_seg.phantom("two_phase", size=32)
    with pytest.raises(ValueError, match="masked array"):
        dsc_seg.segment(np.ma.masked_array(image, mask=image > 200))
    # A mask that masks nothing hides nothing.
    unmasked = dsc_seg.segment(np.ma.masked_array(image, mask=False))
    assert np.array_equal(unmasked.labels, dsc_seg.segment(image).labels)
    with pytest.raises(ValueError, match="read the file first"):
        dsc_seg.segment("image.png")


def test_a_colour_image_is_refused_not_segmented_as_a_volume():
    image, _ = dsc_seg.phantom("two_phase", size=32)
    for channels in (2, 3, 4):  # gray + alpha, RGB, RGBA
        colour = np.repeat(image[:, :, None], channels, axis=2)
        with pytest.raises(ValueError, match="colour image"):
            dsc_seg.segment(colour)
    # Its channel, or a volume with the short axis first, is segmented.
    assert dsc_seg.segment(colour[..., 0]).labels.shape == image.shape
    volume = np.moveaxis(np.repeat(image[:, :, None], 3, axis=2), 2, 0)
    assert dsc_seg.segment(volume, max_iterations=2).labels.shape == volume.shape


def test_half_precision_floats_give_the_float32_labels():
    image, _ = dsc_seg.phantom("two_phase", size=48, noise=0.2)
    as_float = image.astype(np.float32) / 255
    half = dsc_seg.segment(as_float.astype(np.float16))
    single = dsc_seg.segment(as_float.astype(np.float16).astype(np.float32))
    assert np.array_equal(half.labels, single.labels)
    assert half.report["input"]["sample_type"] == "float"


def test_an_array_that_32_bit_floats_would_coarsen_is_refused():
    image, _ = dsc_seg.phantom("two_phase", size=32)
    with pytest.raises(ValueError, match="more precision"):
        dsc_seg.segment(image.astype(np.uint32) + 2**26)
    with pytest.raises(ValueError, match="more precision"):
        dsc_seg.segment(1.0 + image.astype(np.float64) * 1e-9)
    assert dsc_seg.segment(image.astype(np.uint32) * 2**20).labels.shape == image.shape


def test_write_gives_the_cli_files(tmp_path):
    image, _ = dsc_seg.phantom("two_phase", size=48)
    result = dsc_seg.segment(image)
    result.write(tmp_path / "all")
    names = {p.name for p in (tmp_path / "all").iterdir()}
    assert {"labels.png", "overlay.png", "overlay.svg", "mesh.vtu", "report.json"} <= names
    assert not [n for n in names if n.startswith(".")], names
    assert np.array_equal(np.asarray(Image.open(tmp_path / "all" / "labels.png")), result.labels)
    result.write(tmp_path / "some", outputs="labels,report")
    assert {p.name for p in (tmp_path / "some").iterdir()} == {"labels.png", "report.json"}
    with pytest.raises(ValueError, match="unknown output"):
        result.write(tmp_path / "bad", outputs="labels,nonsense")
    (tmp_path / "file").write_text("x")
    with pytest.raises(OSError, match="not a directory"):
        result.write(tmp_path / "file")


def _vtu_points(path):
    """The points of a mesh.vtu as written (one binary DataArray, base64 of a
    UInt64 byte count and the little-endian values)."""
    import base64
    import re

    text = path.read_text()
    m = re.search(r'<Points><DataArray type="Float(32|64)"[^>]*format="binary"[^>]*>([^<]*)<', text)
    raw = base64.b64decode(m.group(2).strip())[8:]
    return np.frombuffer(raw, dtype="<f4" if m.group(1) == "32" else "<f8").reshape(-1, 3)


def test_written_vtk_files_lie_in_the_reports_frame(tmp_path):
    # 2D: rows upwards as a PNG's, pixel centres at (i·sx, (H − 1 − j)·sy).
    image, _ = dsc_seg.phantom("four_phase", size=48)
    image = image[:, :40]
    result = dsc_seg.segment(image, phases=4, spacing=(0.5, 2.0))
    result.write(tmp_path / "2d", outputs="mesh")
    points = _vtu_points(tmp_path / "2d" / "mesh.vtu")
    v = result.vertices
    expected = np.c_[v[:, 0] - 0.25, (48 - 0.5) * 2.0 - v[:, 1], np.zeros(len(v))]
    assert np.allclose(points, expected, atol=1e-4)
    # 3D: voxel centres at (i·sx, j·sy, k·sz), half a voxel off the vertices.
    volume, _ = dsc_seg.phantom("two_balls", size=12)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", dsc_seg.SegmentationWarning)
        result = dsc_seg.segment(volume, max_iterations=3, spacing=(1, 1, 2))
    result.write(tmp_path / "3d", outputs="mesh")
    points = _vtu_points(tmp_path / "3d" / "mesh.vtu")
    assert np.allclose(points, result.vertices - [0.5, 0.5, 1.0], atol=1e-4)


def test_the_gil_is_released_during_a_run():
    """With a 10 s switch interval the main thread keeps the GIL unless it
    releases it: another thread counts only while segment() runs without it."""
    image, _ = dsc_seg.phantom("four_phase", size=256)
    count = 0
    stop = False

    def counter():
        nonlocal count
        while not stop:
            count += 1
            time.sleep(0.0005)

    old = sys.getswitchinterval()
    sys.setswitchinterval(10.0)
    thread = threading.Thread(target=counter)
    try:
        thread.start()
        while count == 0:
            time.sleep(0.001)
        before = count
        dsc_seg.segment(image, phases=4)
        during = count - before
    finally:
        stop = True
        thread.join()
        sys.setswitchinterval(old)
    assert during > 5, during


@pytest.mark.skipif(sys.platform == "win32", reason="a POSIX interval timer")
def test_ctrl_c_interrupts_a_run_and_the_interpreter_goes_on():
    """A signal whose handler raises KeyboardInterrupt, as Ctrl-C's (a
    notebook's interrupt) does, during a long 3D run raises it soon after,
    not at the run's end; the next call works. The signal comes from the
    kernel's interval timer (SIGALRM with Python's SIGINT handler), not from a
    Python thread, which must first be scheduled and take the GIL."""
    volume, _ = dsc_seg.phantom("four_phase", size=64, noise=0.2, ndim=3)
    uninterrupted = time.perf_counter()
    dsc_seg.segment(volume, phases=4, max_iterations=12)
    uninterrupted = time.perf_counter() - uninterrupted

    previous = signal.signal(signal.SIGALRM, signal.default_int_handler)
    try:
        start = time.perf_counter()
        signal.setitimer(signal.ITIMER_REAL, 0.2)
        with pytest.raises(KeyboardInterrupt):
            dsc_seg.segment(volume, phases=4, max_iterations=100000)
        interrupted = time.perf_counter() - start
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    # Stopped within a few iterations of the signal, long before a run to
    # convergence (a few seconds at least) would end.
    assert interrupted < 0.2 + uninterrupted, (interrupted, uninterrupted)

    image, truth = dsc_seg.phantom("two_phase", size=64)
    assert (dsc_seg.segment(image, phases=2).labels == truth).mean() > 0.9


def test_a_name_of_both_phantom_commands_is_the_image_unless_ndim_3():
    image, truth = dsc_seg.phantom("four_phase", size=32)
    assert image.shape == truth.shape == (32, 32)
    volume, labels = dsc_seg.phantom("four_phase", size=16, ndim=3)
    assert volume.shape == labels.shape == (16, 16, 16)
    assert dsc_seg.phantom("torus", size=16)[0].ndim == 3
    with pytest.raises(ValueError, match="2D or 3D"):
        dsc_seg.phantom("torus", size=16, ndim=4)
