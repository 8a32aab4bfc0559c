#!/usr/bin/env python3
"""How often `--phases auto` finds the phases of images of small spots, and what
it chooses on scikit-image's sample photographs.

Spots: 192² images, twelve disks of radius R (2, 3, 4, 6 px) at 0.9, either
beside a large 140 × 80 rectangle at 0.5 on a 0.2 background (three phases)
or alone on a 0.2 background (two phases), blurred by a Gaussian of 1 px and
with Gaussian noise of σ 0.05 to 0.2, noise seeds 1 and 2, stored as 8-bit
PNGs. Photographs: scikit-image's camera, coins, text, cell, moon, page,
horse and checkerboard (shipped with the package, no download), which have no
true count: the script prints what is chosen and how many warnings the run
gives.

usage (from the repository root, after `cargo build --release` and
`pip install -r benches/compare/requirements.txt`):

  python3 benches/auto_spots.py --out OUT [--bin target/release/dsc-seg]
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess

import numpy as np
import skimage.data
import skimage.filters
from PIL import Image

SIZE = 192
RADII = (2, 3, 4, 6)
SIGMAS = (0.05, 0.1, 0.15, 0.2)
PHOTOGRAPHS = ("camera", "coins", "text", "cell", "moon", "page", "horse", "checkerboard")


def spots_image(radius: int, with_rectangle: bool, sigma: float, seed: int) -> np.ndarray:
    """The spots image as 8-bit samples."""
    yy, xx = np.mgrid[0:SIZE, 0:SIZE]
    image = np.full((SIZE, SIZE), 0.2)
    if with_rectangle:
        image[30:170, 10:90] = 0.5
    for k in range(12):
        cy, cx = 20 + (k // 4) * 30, 110 + (k % 4) * 20
        image[(yy - cy) ** 2 + (xx - cx) ** 2 <= radius * radius] = 0.9
    rng = np.random.default_rng(seed)
    image = skimage.filters.gaussian(image, 1.0) + rng.normal(0, sigma, image.shape)
    return (np.clip(image, 0, 1) * 255).astype(np.uint8)


def inputs(out: str):
    """(path, true count or None) of every image, written into `out`."""
    for sigma in SIGMAS:
        for radius in RADII:
            for seed in (1, 2):
                for phases in (3, 2):
                    path = f"{out}/spots{phases}_r{radius}_s{sigma}_{seed}.png"
                    Image.fromarray(spots_image(radius, phases == 3, sigma, seed)).save(path)
                    yield path, phases
    for name in PHOTOGRAPHS:
        image = getattr(skimage.data, name)()
        if image.dtype == bool:
            image = image.astype(np.uint8) * 255
        path = f"{out}/{name}.png"
        Image.fromarray(image).save(path)
        yield path, None


def choose(binary: str, path: str) -> tuple[int, int]:
    """The count `--phases auto` chooses for `path` and the run's warnings."""
    out = path[:-4] + "_auto"
    subprocess.run(
        [binary, "segment", path, "--phases", "auto", "--out", out, "--outputs", "report", "--quiet"],
        check=True,
        capture_output=True,
    )
    with open(f"{out}/report.json") as f:
        report = json.load(f)
    return report["phase_choice"]["phases"], len(report["warnings"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", required=True)
    parser.add_argument("--bin", default="target/release/dsc-seg")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    right = {2: [0, 0], 3: [0, 0]}
    for path, truth in inputs(args.out):
        chosen, warnings = choose(args.bin, path)
        print(f"{os.path.basename(path)}\ttrue {truth}\tchosen {chosen}\twarnings {warnings}", flush=True)
        if truth is not None:
            right[truth][0] += chosen == truth
            right[truth][1] += 1
    for truth, (ok, total) in right.items():
        print(f"spots, {truth} phases: {ok}/{total} right")


if __name__ == "__main__":
    main()
