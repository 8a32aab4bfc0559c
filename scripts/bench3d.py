#!/usr/bin/env python3
"""3D phantoms: dsc-seg segment3d (defaults) vs scikit-image's morphological_chan_vese.

For every phantom, size and noise level: write the volume and its ground truth
with `dsc-seg phantom3d`, segment it with `dsc-seg segment3d VOLUME` (all
defaults), run `skimage.segmentation.morphological_chan_vese` in 3D on the
same 8-bit volume (scaled to [0, 1]; default checkerboard start, smoothing 1,
lambda1 = lambda2 = 1, --morph-iterations iterations), and score both with the
mean Dice over the two phases (as `dsc-seg`'s `mean_dice`; the morphological
result's phase with the larger mean intensity is phase 1, as our labels are
ordered by increasing mean).

usage: scripts/bench3d.py --out DIR [--sizes 64 128] [--noises 0.1 0.2]
       [--phantoms two_balls torus hollow_sphere] [--morph-iterations 100]
       [--bin PATH] [--seed 1] [--skip-morph] [-- extra segment3d options]
Prints a markdown table and writes DIR/results.json.
"""
import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np
import tifffile
from skimage.segmentation import morphological_chan_vese


def mean_dice(pred, truth, phases=2):
    total = 0.0
    for k in range(phases):
        p, t = pred == k, truth == k
        n = p.sum() + t.sum()
        total += 1.0 if n == 0 else 2.0 * np.logical_and(p, t).sum() / n
    return total / phases


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", required=True)
    ap.add_argument("--sizes", type=int, nargs="+", default=[64])
    ap.add_argument("--noises", type=float, nargs="+", default=[0.1, 0.2])
    ap.add_argument("--phantoms", nargs="+", default=["two_balls", "torus", "hollow_sphere"])
    ap.add_argument("--morph-iterations", type=int, default=100)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--skip-morph", action="store_true")
    ap.add_argument("--skip-ours", action="store_true")
    ap.add_argument(
        "--bin",
        default=os.environ.get("DSC_SEG")
        or os.path.join(os.environ.get("CARGO_TARGET_DIR", "target"), "release", "dsc-seg"),
    )
    ap.add_argument("extra", nargs="*", help="extra segment3d options (after --)")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    rows = []
    print("| phantom | size | noise | ours Dice | ours s | iterations | converged | tets "
          "| morph CV Dice | morph CV s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for size in a.sizes:
        for noise in a.noises:
            for name in a.phantoms:
                tag = f"{name}_{size}_{noise}"
                d = os.path.join(a.out, tag)
                subprocess.run(
                    [a.bin, "phantom3d", name, "--size", str(size), "--noise", str(noise),
                     "--seed", str(a.seed), "--out", d],
                    check=True,
                    stdout=subprocess.DEVNULL,
                )
                vol = tifffile.imread(os.path.join(d, f"{name}.tif"))
                truth = tifffile.imread(os.path.join(d, f"{name}_labels.tif"))
                row = {"phantom": name, "size": size, "noise": noise}
                if not a.skip_ours:
                    t0 = time.perf_counter()
                    subprocess.run(
                        [a.bin, "segment3d", os.path.join(d, f"{name}.tif"), "--out",
                         os.path.join(d, "ours"), "--quiet"] + a.extra,
                        check=True,
                    )
                    row["ours_wall_s"] = time.perf_counter() - t0
                    rep = json.load(open(os.path.join(d, "ours", "report.json")))
                    pred = tifffile.imread(os.path.join(d, "ours", "labels.tif"))
                    row.update(
                        ours_dice=mean_dice(pred, truth),
                        ours_s=rep["segmentation"]["times"]["total"],
                        iterations=rep["iterations"],
                        converged=rep["converged"],
                        tets=rep["cells"],
                    )
                if not a.skip_morph:
                    img = vol.astype(np.float64) / 255.0
                    t0 = time.perf_counter()
                    ls = morphological_chan_vese(img, a.morph_iterations)
                    row["morph_s"] = time.perf_counter() - t0
                    ls = ls.astype(np.uint8)
                    if ls.any() and (~ls.astype(bool)).any():
                        if img[ls == 1].mean() < img[ls == 0].mean():
                            ls = 1 - ls
                    row["morph_dice"] = mean_dice(ls, truth)
                rows.append(row)

                def f(k, fmt):
                    return fmt % row[k] if k in row else "-"

                print(f"| {name} | {size} | {noise} | {f('ours_dice', '%.4f')} | "
                      f"{f('ours_s', '%.1f')} | {f('iterations', '%d')} | "
                      f"{row.get('converged', '-')} | {f('tets', '%d')} | "
                      f"{f('morph_dice', '%.4f')} | {f('morph_s', '%.1f')} |", flush=True)
    json.dump(rows, open(os.path.join(a.out, "results.json"), "w"), indent=1)
    for key in ("ours_dice", "morph_dice"):
        vals = [r[key] for r in rows if key in r]
        if vals:
            print(f"mean {key}: {np.mean(vals):.4f} (min {np.min(vals):.4f})", file=sys.stderr)


if __name__ == "__main__":
    main()
