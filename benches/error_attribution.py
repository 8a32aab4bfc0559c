#!/usr/bin/env python3
"""Where the wrong pixels of a two-phase segmentation are: dsc-seg against blur +
multi-Otsu on the two-phase benchmark phantom (`dsc-seg phantom two_phase`) and
its variant with salt-and-pepper specks (`two_phase_specks`).

Every wrong pixel goes to one place, in this order: a speck (a pixel the specks
changed, found against the same phantom without specks), a corner (within 4 px
of one of the 18 corners of the plate, its square hole, the two squares and the
bar), the crossing (within 4 px of the point where the two squares touch), or
the nearest structure (disk, annulus, plate with its holes, squares, ellipse,
bar). Per structure the table gives the pixels wrongly added (+) and lost (-)
and the mean signed offset of the boundary, (added - lost) / perimeter in
pixels: positive where the foreground grew. The geometry below transcribes
`two_phase_labels` of src/phantom/shapes2d.rs and is checked against the
phantom's ground truth on every run.

usage (from the repository root, after `cargo build --release` and
`pip install -r benches/compare/requirements.txt`):

  python3 benches/error_attribution.py --out OUT
  python3 benches/error_attribution.py --out OUT --images two_phase:512:0.1 --args "--rigidity 5"
"""
from __future__ import annotations

import argparse
import math
import os
import shlex
import subprocess
import sys

import numpy as np
from PIL import Image
from scipy import ndimage

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "compare"))
import peers  # noqa: E402
import score  # noqa: E402

DEFAULT_IMAGES = ["two_phase:512:0.1", "two_phase:1024:0.1", "two_phase_specks:256:0.25",
                  "two_phase_specks:512:0.1"]
CORNERS = [(0.09, 0.53), (0.43, 0.53), (0.09, 0.79), (0.43, 0.79),  # plate
           (0.13, 0.61), (0.23, 0.61), (0.13, 0.71), (0.23, 0.71),  # its square hole
           (0.61, 0.61), (0.73, 0.61), (0.61, 0.73), (0.85, 0.73),  # the two squares
           (0.73, 0.85), (0.85, 0.85),
           (0.92, 0.45), (0.94, 0.45), (0.92, 0.85), (0.94, 0.85)]  # bar
CROSSING = (0.73, 0.73)
CORNER_RADIUS_PX = 4.0


def structures(n: int):
    """The pixel-centre coordinates, each structure's foreground mask and its
    perimeter in pixels."""
    c = (np.arange(n) + 0.5) / n
    x, y = np.meshgrid(c, c)
    th = math.radians(30)
    masks = {}
    masks["disk"] = (x - 0.2) ** 2 + (y - 0.2) ** 2 < 0.11 ** 2
    r2 = (x - 0.7) ** 2 + (y - 0.24) ** 2
    masks["annulus"] = (r2 < 0.17 ** 2) & (r2 > 0.08 ** 2)
    plate = (abs(x - 0.26) < 0.17) & (abs(y - 0.66) < 0.13)
    square_hole = (abs(x - 0.18) < 0.05) & (abs(y - 0.66) < 0.05)
    round_hole = (x - 0.34) ** 2 + (y - 0.66) ** 2 < 0.05 ** 2
    masks["plate with holes"] = plate & ~square_hole & ~round_hole
    s = 0.12
    q1 = (x > 0.73 - s) & (x < 0.73) & (y > 0.73 - s) & (y < 0.73)
    q2 = (x >= 0.73) & (x < 0.73 + s) & (y >= 0.73) & (y < 0.73 + s)
    masks["squares"] = q1 | q2
    u = (x - 0.55) * math.cos(th) + (y - 0.92) * math.sin(th)
    v = -(x - 0.55) * math.sin(th) + (y - 0.92) * math.cos(th)
    masks["ellipse"] = (u / 0.10) ** 2 + (v / 0.04) ** 2 < 1
    masks["bar"] = (abs(x - 0.93) < 0.01) & (y > 0.45) & (y < 0.85)
    a, b = 0.10, 0.04
    ellipse = math.pi * (3 * (a + b) - math.sqrt((3 * a + b) * (a + 3 * b)))
    perimeter = {"disk": 2 * math.pi * 0.11, "annulus": 2 * math.pi * 0.25,
                 "plate with holes": 2 * (0.34 + 0.26) + 0.4 + 2 * math.pi * 0.05,
                 "squares": 8 * 0.12, "ellipse": ellipse, "bar": 2 * (0.02 + 0.4)}
    return x, y, masks, {k: p * n for k, p in perimeter.items()}


def near(x, y, points, radius):
    mask = np.zeros(x.shape, dtype=bool)
    for px, py in points:
        mask |= (x - px) ** 2 + (y - py) ** 2 < radius ** 2
    return mask


def attribute(truth: np.ndarray, labels: np.ndarray, specks: np.ndarray) -> dict:
    """Counts of wrong pixels by place; `labels` any two values."""
    n = truth.shape[0]
    x, y, masks, perimeter = structures(n)
    if not np.array_equal(truth, np.any(list(masks.values()), axis=0)):
        sys.exit("error: the transcribed geometry does not match the phantom's ground truth")
    fg = labels == labels.max()
    if (fg == truth).mean() < 0.5:
        fg = ~fg
    added, lost = fg & ~truth, ~fg & truth
    wrong = added | lost
    corners = near(x, y, CORNERS, CORNER_RADIUS_PX / n) & ~specks
    crossing = near(x, y, [CROSSING], CORNER_RADIUS_PX / n) & ~specks
    rest = ~(specks | corners | crossing)
    zone = np.stack([ndimage.distance_transform_edt(~m) for m in masks.values()]).argmin(0)
    row = {"dice": score.score(truth.astype(np.uint8), fg.astype(np.uint8))["mean_dice"],
           "wrong": int(wrong.sum()), "specks": int((wrong & specks).sum()),
           "corners": int((wrong & corners).sum()), "crossing": int((wrong & crossing).sum())}
    for k, name in enumerate(masks):
        z = rest & (zone == k)
        a, l = int((added & z).sum()), int((lost & z).sum())
        row[name] = (a, l, (a - l) / perimeter[name])
    return row


def run(cmd: list[str]) -> None:
    if subprocess.run(cmd, stdout=subprocess.DEVNULL).returncode != 0:
        sys.exit(f"error: {' '.join(cmd)} failed")


def read(path: str) -> np.ndarray:
    return np.asarray(Image.open(path).convert("L"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--bin", default=os.path.join("target", "release", "dsc-seg"))
    ap.add_argument("--images", nargs="+", default=DEFAULT_IMAGES, metavar="PHANTOM:SIZE:SIGMA")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--args", default="", help="further dsc-seg segment options as one string")
    a = ap.parse_args()
    print("| image | method | Dice | wrong | specks | corners | crossing | "
          + " | ".join(structures(8)[2].keys()) + " |")
    for spec in a.images:
        phantom, size, sigma = spec.split(":")
        folder = os.path.join(a.out, f"{phantom}_{size}_s{float(sigma):.2f}")
        common = ["--size", size, "--noise", sigma, "--seed", str(a.seed)]
        run([a.bin, "phantom", phantom, *common, "--out", folder])
        truth = read(os.path.join(folder, f"{phantom}_gt.png")) > 0
        image = read(os.path.join(folder, f"{phantom}.png"))
        specks = np.zeros(truth.shape, dtype=bool)
        if phantom.endswith("_specks"):
            clean = os.path.join(folder, "without_specks")
            run([a.bin, "phantom", phantom.removesuffix("_specks"), *common, "--out", clean])
            specks = read(os.path.join(clean, f"{phantom.removesuffix('_specks')}.png")) != image
        ours = os.path.join(folder, "dsc-seg")
        run([a.bin, "segment", os.path.join(folder, f"{phantom}.png"), "--phases", "2", "--out", ours,
             "--quiet", "--force", *shlex.split(a.args)])
        results = {"dsc-seg": attribute(truth, read(os.path.join(ours, "labels.png")), specks),
                   "blur + multi-Otsu": attribute(truth, peers.blur_multi_otsu(image / 255.0, 2), specks)}
        for method, row in results.items():
            names = [k for k, v in row.items() if isinstance(v, tuple)]
            cells = [f"+{row[k][0]} −{row[k][1]} ({row[k][2]:+.2f})" for k in names]
            print(f"| {phantom}_{size}_s{float(sigma):.2f} | {method} | {row['dice']:.4f} | {row['wrong']} | "
                  f"{row['specks']} | {row['corners']} | {row['crossing']} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
