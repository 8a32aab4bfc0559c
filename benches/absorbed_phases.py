#!/usr/bin/env python3
"""How much of what looks like each phase the result holds: the measure behind
the absorbed-phase warning, over phantoms, small volumes and photographs.

A phase is absorbed when it holds fewer than a quarter of the pixels or voxels
whose value, in the image smoothed by a Gaussian of one pixel, lies in the
middle half of its nearest-mean range (src/segment/absorbed.rs). This script
computes that share for every phase of dsc-seg's result (SciPy's
gaussian_filter with mode "nearest", as the Rust blur) and prints, per input,
the smallest share and whether the run warned. The inputs: the 2D phantoms
(`dsc-seg phantom`: disks2 ... disks6, three_close, four_close, the specks,
thin, two_phase, four_phase) at 256 px, noise 0.1 and 0.25; the 3D phantoms
(`dsc-seg phantom3d`) at 40 and 64 voxels, noise 0.1 and 0.2; scikit-image's
photographs (camera, coins, text, cell, moon, page, brick, grass, gravel,
rocket, astronaut; shipped with the package, grey) at 2, 3 and 4 phases; and,
with --brain DIR, the result folders of benches/real_brain.py runs (their
reduced T1 beside them).

usage (from the repository root, after `cargo build --release` and
`pip install -r benches/compare/requirements.txt`):

  python3 benches/absorbed_phases.py --out OUT
  python3 benches/absorbed_phases.py --out OUT --only 3d
  python3 benches/absorbed_phases.py --out OUT --only none --brain BRAIN_OUT
"""
from __future__ import annotations

import argparse
import glob
import json
import os
import subprocess

import numpy as np
import tifffile
from PIL import Image
from scipy import ndimage

PHANTOMS_2D = {"disks2": 2, "disks3": 3, "disks4": 4, "disks5": 5, "disks6": 6,
               "three_close": 3, "four_close": 4, "two_phase_specks": 2,
               "four_phase_specks": 4, "thin": 2, "two_phase": 2, "four_phase": 4}
PHANTOMS_3D = {"three_phase": 3, "four_phase": 4, "two_balls": 2, "torus": 2,
               "hollow_sphere": 2}
PHOTOS = ["camera", "coins", "text", "cell", "moon", "page", "brick", "grass",
          "gravel", "rocket", "astronaut"]


def load(path: str) -> np.ndarray:
    if path.endswith(".tif"):
        return tifffile.imread(path).astype(float)
    if path.endswith(".nii.gz"):
        import nibabel
        return np.asarray(nibabel.load(path).dataobj).astype(float)
    return np.asarray(Image.open(path)).astype(float)


def shares(image: np.ndarray, labels: np.ndarray) -> list[float]:
    """Each phase's pixels over those that look like it, by increasing mean."""
    phases = np.unique(labels)
    means = np.array([image[labels == k].mean() for k in phases])
    order = np.argsort(means)
    m = means[order]
    gaps = np.diff(m)
    low = np.r_[-np.inf, m[1:] - 0.25 * gaps]
    high = np.r_[m[:-1] + 0.25 * gaps, np.inf]
    smooth = ndimage.gaussian_filter(image, 1.0, mode="nearest")
    out = []
    for r, i in enumerate(order):
        looks_like = np.count_nonzero((smooth > low[r]) & (smooth < high[r]))
        out.append(np.count_nonzero(labels == phases[i]) / max(looks_like, 1))
    return out


def row(name: str, image_path: str, result: str) -> dict:
    image = load(image_path)
    labels = load(glob.glob(os.path.join(result, "labels.*"))[0]).reshape(image.shape)
    with open(os.path.join(result, "report.json")) as f:
        warnings = json.load(f)["warnings"]
    s = shares(image, labels)
    absorbed = sum("went to its neighbours" in w for w in warnings)
    print(f"{name:28s} smallest share {min(s):.3f}  absorbed warnings {absorbed}", flush=True)
    return dict(name=name, shares=s, absorbed_warnings=absorbed, warnings=warnings)


def segment(binary: str, command: str, image: str, phases: int, out: str) -> None:
    subprocess.run([binary, command, image, "--phases", str(phases), "--out", out, "--quiet"],
                   check=True, capture_output=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--bin", default=os.path.join("target", "release", "dsc-seg"))
    ap.add_argument("--only", choices=["2d", "3d", "photos", "none"], nargs="*",
                    default=["2d", "3d", "photos"])
    ap.add_argument("--brain", nargs="*", default=[],
                    help="benches/real_brain.py output folders to score as they are")
    a = ap.parse_args()
    rows = []
    data = os.path.join(a.out, "data")
    if "2d" in a.only:
        for sigma in [0.1, 0.25]:
            for name, phases in PHANTOMS_2D.items():
                tag = f"{name}_256_s{sigma}"
                subprocess.run([a.bin, "phantom", name, "--size", "256", "--noise", str(sigma),
                                "--out", os.path.join(data, tag)], check=True, capture_output=True)
                image = os.path.join(data, tag, f"{name}.png")
                segment(a.bin, "segment", image, phases, os.path.join(a.out, tag))
                rows.append(row(tag, image, os.path.join(a.out, tag)))
    if "3d" in a.only:
        for name, phases in PHANTOMS_3D.items():
            for size in [40, 64]:
                for sigma in [0.1, 0.2]:
                    tag = f"{name}_{size}_s{sigma}"
                    subprocess.run([a.bin, "phantom3d", name, "--size", str(size), "--noise",
                                    str(sigma), "--out", os.path.join(data, tag)],
                                   check=True, capture_output=True)
                    image = os.path.join(data, tag, f"{name}.tif")
                    segment(a.bin, "segment3d", image, phases, os.path.join(a.out, tag))
                    rows.append(row(tag, image, os.path.join(a.out, tag)))
    if "photos" in a.only:
        import skimage.data
        os.makedirs(data, exist_ok=True)
        for name in PHOTOS:
            picture = getattr(skimage.data, name)()
            grey = np.asarray(Image.fromarray(picture).convert("L")) if picture.ndim == 3 else picture
            image = os.path.join(data, f"{name}.png")
            Image.fromarray(grey.astype(np.uint8)).save(image)
            for phases in [2, 3, 4]:
                tag = f"{name}_{phases}"
                segment(a.bin, "segment", image, phases, os.path.join(a.out, tag))
                rows.append(row(tag, image, os.path.join(a.out, tag)))
    for folder in a.brain:
        t1 = glob.glob(os.path.join(folder, "reduced", "*t1*.nii.gz")) or glob.glob(
            os.path.join(folder, "data", "*t1*.nii.gz"))
        rows.append(row(f"brain {os.path.basename(folder.rstrip('/'))}", t1[0],
                        os.path.join(folder, "dsc-seg")))
    with open(os.path.join(a.out, "results.json"), "w") as f:
        json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
