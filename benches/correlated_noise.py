#!/usr/bin/env python3
"""dsc-seg on volumes whose noise is spatially correlated, and the warning that
says so.

Each 64^3 phantom of `dsc-seg phantom3d` is written noise-free, then Gaussian
noise smoothed by a Gaussian of --blur voxels (and scaled back to the given
standard deviation, in the phantom's 0..1 units) is added, as in a
reconstructed CT or MRI; --white adds the same standard deviation unsmoothed
for comparison. The table gives the mean Dice against the truth, the noise
correlation figure of report.json, the noise over a patch against the smallest
gap between the final phase means (what the warning compares), whether the run
warned, the tetrahedra at the end and the run's seconds.

usage (from the repository root, after `cargo build --release` and
`pip install -r benches/compare/requirements.txt`):

  python3 benches/correlated_noise.py --out OUT
  python3 benches/correlated_noise.py --out OUT --phantoms two_balls:2 --sigmas 0.05 --white
"""
from __future__ import annotations

import argparse
import json
import math
import os
import subprocess

import numpy as np
import tifffile
from scipy.ndimage import gaussian_filter


def mean_dice(labels: np.ndarray, truth: np.ndarray, phases: int) -> float:
    scores = []
    for k in range(phases):
        a, b = labels == k, truth == k
        scores.append(2.0 * (a & b).sum() / max(a.sum() + b.sum(), 1))
    return float(np.mean(scores))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--bin", default=os.path.join("target", "release", "dsc-seg"))
    ap.add_argument("--phantoms", nargs="+", default=["four_phase:4", "two_balls:2"], metavar="NAME:PHASES")
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--sigmas", type=float, nargs="+", default=[0.03, 0.05, 0.1, 0.15])
    ap.add_argument("--blur", type=float, default=1.5, help="the noise's smoothing, in voxels")
    ap.add_argument("--white", action="store_true", help="also each sigma as white noise")
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    print("| volume | noise | σ | mean Dice | correlation figure | patch noise / gap | warned | tets | s |")
    print("|---|---|---|---|---|---|---|---|---|")
    for spec in a.phantoms:
        name, phases = spec.split(":")
        phases = int(phases)
        clean = os.path.join(a.out, f"{name}_clean")
        subprocess.run([a.bin, "phantom3d", name, "--size", str(a.size), "--noise", "0", "--out", clean],
                       check=True, capture_output=True)
        volume = tifffile.imread(os.path.join(clean, f"{name}.tif")).astype(np.float64) / 255.0
        truth = tifffile.imread(os.path.join(clean, f"{name}_labels.tif"))
        rng = np.random.default_rng(a.seed)
        smooth = gaussian_filter(rng.standard_normal(volume.shape), a.blur)
        smooth /= smooth.std()
        white = rng.standard_normal(volume.shape)
        kinds = [("smoothed", smooth)] + ([("white", white)] if a.white else [])
        for sigma in a.sigmas:
            for kind, noise in kinds:
                tag = f"{name}_{kind}_{sigma}"
                path = os.path.join(a.out, tag + ".tif")
                tifffile.imwrite(path, (volume + sigma * noise).astype(np.float32))
                out = os.path.join(a.out, tag)
                subprocess.run([a.bin, "segment3d", path, "--phases", str(phases), "--outputs", "labels,report",
                                "--out", out, "--quiet"], check=True, capture_output=True)
                report = json.load(open(os.path.join(out, "report.json")))
                seg = report["segmentation"]
                labels = tifffile.imread(os.path.join(out, "labels.tif"))
                rho = seg["intensity"]["noise_correlation"]
                means = sorted(m for m in report["final_means"] if m is not None)
                gap = min(np.diff(means)) if len(means) > 1 else float("nan")
                patch = seg["intensity"]["noise"] / math.sqrt(max(1.0 - rho, 1e-12)) / gap if rho is not None else float("nan")
                warned = any("spatially correlated" in w for w in report["warnings"])
                print(f"| {name} {a.size}³ | {kind} | {sigma} | {mean_dice(labels, truth, phases):.4f} | "
                      f"{rho if rho is None else round(rho, 3)} | {patch:.3f} | {'yes' if warned else 'no'} | "
                      f"{report['cells']} | {seg['times']['total']:.1f} |", flush=True)


if __name__ == "__main__":
    main()
