#!/usr/bin/env python3
"""dsc-seg on real photographs and micrographs against the MBO peer: every phase
present, and the piecewise-constant data energy sum (I - c_label)^2.

The images are scikit-image's sample data shipped with the package (no
download): camera (CC0, Lav Varshney), coins (Brooklyn Museum, no known
copyright restrictions), text (public domain), and the cell quantitative-phase
micrograph, each at 2, 3 and 4 phases, plus 16-bit re-encodings (value * 64 +
1000, stored as uint16 PNG) of camera and coins. Both methods get the same
number of phases and the same intensities (the file's values divided by the
type's maximum, as dsc-seg loads them); the energy is computed here, the same
way for both, in the 8-bit image's units (0..1). The MBO scheme is
benches/compare/peers.py's (multi-Otsu start, length weight mu = 0.25).

usage (from the repository root, after `cargo build --release` and
`pip install -r benches/compare/requirements.txt`):

  python3 benches/real_images.py --out OUT
  python3 benches/real_images.py --out OUT --args=--adaptive     # any further segment options
"""
from __future__ import annotations

import argparse
import json
import os
import shlex
import subprocess
import sys

import numpy as np
from PIL import Image

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "compare"))
import peers  # noqa: E402

IMAGES = ["camera", "coins", "text", "cell"]
SIXTEEN_BIT = ["camera", "coins"]


def data_energy(image: np.ndarray, labels: np.ndarray) -> float:
    total = 0.0
    for k in np.unique(labels):
        values = image[labels == k]
        total += float(((values - values.mean()) ** 2).sum())
    return total


def fractions(labels: np.ndarray, phases: int) -> list[float]:
    counts = np.bincount(np.unique(labels, return_inverse=True)[1].ravel(), minlength=phases)
    return list(counts / labels.size)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--bin", default=os.path.join("target", "release", "dsc-seg"))
    ap.add_argument("--phases", type=int, nargs="+", default=[2, 3, 4])
    ap.add_argument("--args", default="",
                    help="further dsc-seg segment options as one string, e.g. --args=--adaptive")
    a = ap.parse_args()
    import skimage.data

    os.makedirs(a.out, exist_ok=True)
    inputs = []
    for name in IMAGES:
        image = getattr(skimage.data, name)()
        path = os.path.join(a.out, f"{name}.png")
        Image.fromarray(image).save(path)
        inputs.append((name, "uint8", path, image.astype(np.float64) / 255.0))
        if name in SIXTEEN_BIT:
            wide = image.astype(np.uint16) * 64 + 1000
            path16 = os.path.join(a.out, f"{name}_16bit.png")
            Image.fromarray(wide).save(path16)
            inputs.append((name + "_16bit", "uint16", path16, wide.astype(np.float64) / 65535.0))
    rows = []
    print("| image | type | phases | dsc-seg data energy | MBO data energy | ratio | smallest phase dsc-seg / MBO |")
    print("|---|---|---|---|---|---|---|")
    for name, dtype, path, image in inputs:
        scale = 1.0 if dtype == "uint8" else 65535.0 / 64.0 / 255.0
        for k in a.phases:
            out = os.path.join(a.out, f"{name}_{k}")
            subprocess.run([a.bin, "segment", path, "--phases", str(k), "--out", out, "--quiet",
                            "--outputs", "labels,report"] + shlex.split(a.args), check=True)
            ours = np.asarray(Image.open(os.path.join(out, "labels.png")))
            theirs = peers.mbo(image, k)
            # energies in the 8-bit image's units: the 16-bit copies are 64x the 8-bit values
            e_ours = data_energy(image * scale, ours)
            e_mbo = data_energy(image * scale, theirs)
            f_ours, f_mbo = min(fractions(ours, k)), min(fractions(theirs, k))
            present = len(np.unique(ours)) == k and f_ours >= 0.005
            rows.append(dict(image=name, type=dtype, phases=k, ours=e_ours, mbo=e_mbo,
                             ratio=e_ours / e_mbo, smallest_ours=float(f_ours), smallest_mbo=float(f_mbo),
                             all_present=bool(present)))
            print(f"| {name} | {dtype} | {k} | {e_ours:.1f} | {e_mbo:.1f} | {e_ours / e_mbo:.3f} | "
                  f"{100 * f_ours:.1f} % / {100 * f_mbo:.1f} % |", flush=True)
    with open(os.path.join(a.out, "results.json"), "w") as f:
        json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
