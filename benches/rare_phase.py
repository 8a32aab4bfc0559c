#!/usr/bin/env python3
"""A rare bright phase: a class of under a thousandth of the pixels.

Each image is 256² 8-bit: a background of 0 (left half) and 100 (right half)
and one 8×8 square at 255 (64 pixels, 0.098 % of the image, so beyond the
robust range's 0.1 % tail), with Gaussian noise of σ 10 (noise seeds 1–6),
clipped and rounded to 8 bits. Each is segmented with `--phases 3` and the
defaults; the script prints the final phase means, the re-seeds, the
iterations, whether the run converged and how many pixels of the square
carry the brightest phase ("not found" where no phase mean
lies near the square's).

usage (from the repository root, after `cargo build --release` and
`pip install -r benches/compare/requirements.txt`):

  python3 benches/rare_phase.py --out OUT [--bin target/release/dsc-seg]
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess

import numpy as np
from PIL import Image

SIDE = 256
SQUARE = (slice(100, 108), slice(180, 188))


def image(seed: int) -> np.ndarray:
    """The two halves, the square and the noise of `seed`, as 8 bits."""
    rng = np.random.default_rng(seed)
    a = np.zeros((SIDE, SIDE))
    a[:, SIDE // 2:] = 100.0
    a[SQUARE] = 255.0
    a += rng.normal(0.0, 10.0, a.shape)
    return np.clip(a, 0, 255).round().astype(np.uint8)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--bin", default=os.path.join("target", "release", "dsc-seg"))
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    print("| noise seed | phase means | re-seeds | iterations | converged | square pixels "
          "in the brightest phase |")
    print("|---|---|---|---|---|---|")
    for seed in range(1, 7):
        path = os.path.join(args.out, f"rare_{seed}.png")
        Image.fromarray(image(seed)).save(path)
        out = os.path.join(args.out, f"rare_{seed}")
        subprocess.run([args.bin, "segment", path, "--phases", "3", "--out", out, "--force",
                        "--outputs", "labels,report", "--quiet"], check=True,
                       capture_output=True)
        report = json.load(open(os.path.join(out, "report.json")))
        seg = report["segmentation"]
        labels = np.asarray(Image.open(os.path.join(out, "labels.png")))
        means = ", ".join("–" if m is None else f"{m:.3f}" for m in seg["final_means"])
        found = max(m for m in seg["final_means"] if m is not None) > 0.7
        kept = f"{int((labels[SQUARE] == labels.max()).sum())} of 64" if found else "not found"
        print(f"| {seed} | {means} | {seg['reseeds']} | {report['iterations']} | "
              f"{report['converged']} | {kept} |")


if __name__ == "__main__":
    main()
