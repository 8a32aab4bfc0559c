#!/usr/bin/env python3
"""Cross-check dsc-seg's volume I/O against tifffile and nibabel.

  python3 .ci/io_fixtures.py make DIR   # write TIFF/NIfTI fixtures + manifest.json
  DSC_SEG_IO_FIXTURES=DIR cargo test --lib io::volume -- --ignored
  python3 .ci/io_fixtures.py check DIR  # read the files the Rust test wrote back

`make` writes volumes in the layouts Fiji/ImageJ, tifffile and nibabel produce,
with the values dsc-seg should load (normalised as documented in
src/io/volume.rs) in manifest.json. The ignored Rust test loads each one and
compares, then writes `rust_labels.tif` and `rust_volume.nii.gz`, which `check`
verifies with tifffile and nibabel. Needs numpy, tifffile and nibabel.
"""
import json
import os
import sys

import nibabel as nib
import numpy as np
import tifffile

NX, NY, NZ = 5, 4, 3


def ramp(dtype, lo, hi):
    """A (NZ, NY, NX) ramp from lo to hi in the given dtype."""
    v = np.linspace(lo, hi, NX * NY * NZ).reshape(NZ, NY, NX)
    return v.astype(dtype)


def minmax(a):
    a = a.astype(np.float64)
    return (a - a.min()) / (a.max() - a.min())


def make(d):
    os.makedirs(d, exist_ok=True)
    manifest = {}

    def add(name, zyx, expected, spacing=(1.0, 1.0, 1.0)):
        manifest[name] = {
            "dims": [NX, NY, NZ],
            "spacing": list(spacing),
            "data": [float(x) for x in np.asarray(expected).ravel()],  # x fastest
        }

    # TIFF stacks, (z, y, x) arrays -> one page per z. photometric="minisblack"
    # stops tifffile from guessing planar RGB for a leading dimension of 3.
    a = ramp(np.uint8, 0, 255)
    tifffile.imwrite(os.path.join(d, "tf_u8.tif"), a, photometric="minisblack")
    add("tf_u8.tif", a, a / 255.0)
    a = ramp(np.uint16, 0, 65535)
    tifffile.imwrite(os.path.join(d, "tf_u16_zlib.tif"), a, compression="zlib",
                     photometric="minisblack")
    add("tf_u16_zlib.tif", a, a / 65535.0)
    a = ramp(np.float32, -3.0, 5.0)
    tifffile.imwrite(os.path.join(d, "tf_f32.tif"), a, photometric="minisblack")
    add("tf_f32.tif", a, minmax(a))
    a = ramp(np.int16, -500, 1500)
    tifffile.imwrite(os.path.join(d, "tf_i16.tif"), a, photometric="minisblack")
    add("tf_i16.tif", a, minmax(a))
    a = ramp(np.uint16, 100, 4000)
    tifffile.imwrite(os.path.join(d, "ij_u16.tif"), a, imagej=True,
                     resolution=(1 / 0.25, 1 / 0.5), metadata={"spacing": 2.5, "unit": "um"})
    add("ij_u16.tif", a, a / 65535.0, (0.25, 0.5, 2.5))
    a = ramp(np.float32, 0.0, 1.0)
    tifffile.imwrite(os.path.join(d, "ij_f32.tif"), a, imagej=True)
    add("ij_f32.tif", a, minmax(a))
    a = ramp(np.uint8, 0, 255)
    tifffile.imwrite(os.path.join(d, "tf_u8_big.tif"), a, bigtiff=True, byteorder=">",
                     photometric="minisblack")
    add("tf_u8_big.tif", a, a / 255.0)

    # NIfTI-1: nibabel arrays are (x, y, z); the file stores x fastest.
    aff = np.diag([0.5, 0.75, 2.0, 1.0])
    for name, dtype, lo, hi, endian, slope in [
        ("nb_u8.nii", np.uint8, 0, 255, "<", None),
        ("nb_i16_le.nii", np.int16, -1000, 3000, "<", None),
        ("nb_i16_be.nii", np.int16, -1000, 3000, ">", None),
        ("nb_u16.nii.gz", np.uint16, 0, 65535, "<", None),
        ("nb_i32.nii.gz", np.int32, -7, 100000, ">", None),
        ("nb_f32.nii", np.float32, -1.5, 2.5, "<", None),
        ("nb_f64_be.nii.gz", np.float64, 10.0, 20.0, ">", None),
        ("nb_u8_scaled.nii", np.uint8, 0, 200, "<", (2.0, -10.0)),
    ]:
        zyx = ramp(dtype, lo, hi)
        xyz = np.ascontiguousarray(zyx.transpose(2, 1, 0))
        hdr = nib.Nifti1Header(endianness=endian)
        hdr.set_data_dtype(dtype)
        img = nib.Nifti1Image(xyz, aff, header=hdr)
        if slope is not None:
            img.header.set_slope_inter(*slope)
        nib.save(img, os.path.join(d, name))
        raw = zyx.astype(np.float64)
        if slope is not None:
            expected = minmax(raw * slope[0] + slope[1])
        elif dtype == np.uint8:
            expected = raw / 255.0
        elif dtype == np.uint16:
            expected = raw / 65535.0
        else:
            expected = minmax(raw)
        add(name, zyx, expected, (0.5, 0.75, 2.0))
    with open(os.path.join(d, "manifest.json"), "w") as f:
        json.dump(manifest, f)
    print(f"wrote {len(manifest)} fixtures to {d}")


def check(d):
    """Verifies the files written by the ignored Rust test."""
    ok = True
    labels = tifffile.imread(os.path.join(d, "rust_labels.tif"))
    z, y, x = np.mgrid[0:NZ, 0:NY, 0:NX]
    want = ((x + 2 * y + 3 * z) % 256).astype(np.uint8)
    if labels.shape != want.shape or labels.dtype != np.uint8 or not (labels == want).all():
        print(f"FAIL rust_labels.tif: shape {labels.shape} dtype {labels.dtype}")
        ok = False
    else:
        print("ok rust_labels.tif (tifffile)")
    img = nib.load(os.path.join(d, "rust_volume.nii.gz"))
    vol = img.get_fdata()
    want = ((x + 10 * y + 100 * z) / 1000.0).transpose(2, 1, 0)
    zooms = img.header.get_zooms()
    if vol.shape != want.shape or not np.allclose(vol, want, atol=1e-6) \
            or not np.allclose(zooms, (0.5, 0.75, 2.0)):
        print(f"FAIL rust_volume.nii.gz: shape {vol.shape} zooms {zooms}")
        ok = False
    else:
        print("ok rust_volume.nii.gz (nibabel)")
    return ok


if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] not in ("make", "check"):
        sys.exit(__doc__)
    if sys.argv[1] == "make":
        make(sys.argv[2])
    else:
        sys.exit(0 if check(sys.argv[2]) else 1)
