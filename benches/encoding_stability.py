#!/usr/bin/env python3
"""How much a 3D result moves when the data moves a little: each 3D phantom
segmented as 8-bit TIFF, as 16-bit TIFF with 64 levels (a lossy
re-quantisation), and as float32 TIFF with a uniform perturbation of
±0.01 and ±0.1 grey levels (of 255) added, with the 3D default (adaptive
mesh from a coarse start, with the fine finish of two-phase runs), with
`--no-fine-finish` and with `--uniform`. Prints the mean Dice of each
run against the 8-bit run of the same mode, and against the ground truth.

usage (from the repository root, after `cargo build --release` and
`pip install -r benches/compare/requirements.txt`):

  python3 benches/encoding_stability.py --out OUT

`--volumes four_phase:64:4 three_phase:64:3` picks the volumes (phantom,
side, phases), `--noise` and `--seeds` the noise, `--encodings` the
re-encodings. `--images four_phase:128:4` adds 2D phantoms (`dsc-seg
phantom`, segmented with the 2D default), so that the agreement at a given
number of samples across can be set beside the volumes'.
"""
from __future__ import annotations

import argparse
import os
import subprocess

import numpy as np
import tifffile
from PIL import Image

BIN = os.path.join(os.path.dirname(__file__), "..", "target", "release", "dsc-seg")

# (phantom, side, phases), by default at σ = 0.1, noise seed 2.
VOLUMES = [("torus", 48, 2), ("two_balls", 48, 2), ("hollow_sphere", 48, 2), ("four_phase", 64, 4)]
ENCODINGS = ["64 levels", "±0.01 grey", "±0.1 grey"]


def volume_spec(text):
    """`phantom:side:phases` → (phantom, side, phases)."""
    name, side, phases = text.split(":")
    return name, int(side), int(phases)
MODES = {"default": [], "no finish": ["--no-fine-finish"], "uniform": ["--uniform"]}


def mean_dice(a, b, phases):
    scores = []
    for p in range(phases):
        total = (a == p).sum() + (b == p).sum()
        scores.append(2 * ((a == p) & (b == p)).sum() / total if total else 1.0)
    return float(np.mean(scores))


def encodings(volume, names):
    """Name → array of each re-encoding in `names` of an 8-bit volume."""
    rng = np.random.default_rng(7)
    out = {"64 levels": np.rint(volume * 63.0 / 255.0).astype(np.uint16)}
    for amplitude in (0.01, 0.1):
        noise = rng.uniform(-amplitude, amplitude, volume.shape)
        out[f"±{amplitude} grey"] = (volume + noise).astype(np.float32)
    return {name: out[name] for name in names}


def segment(path, phases, extra, out, flat=False):
    """The labels of `segment3d` (or of `segment` for a 2D image, `flat`)."""
    command = "segment" if flat else "segment3d"
    subprocess.run([BIN, command, path, "--phases", str(phases), "--quiet",
                    "--outputs", "labels", "--out", out, *extra],
                   check=True, stdout=subprocess.DEVNULL)
    if flat:
        return np.asarray(Image.open(os.path.join(out, "labels.png")))
    return tifffile.imread(os.path.join(out, "labels.tif"))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--modes", nargs="*", choices=list(MODES), default=list(MODES))
    ap.add_argument("--edge-lengths", type=float, nargs="*", default=[],
                    help="also --no-fine-finish with these interface edge lengths L (voxels)")
    ap.add_argument("--volumes", type=volume_spec, nargs="*", default=VOLUMES,
                    help="phantom:side:phases (default: the four volumes above)")
    ap.add_argument("--images", type=volume_spec, nargs="*", default=[],
                    help="2D phantoms phantom:side:phases, with the default mode only")
    ap.add_argument("--noise", type=float, nargs="*", default=[0.1])
    ap.add_argument("--seeds", type=int, nargs="*", default=[2])
    ap.add_argument("--encodings", nargs="*", choices=ENCODINGS, default=ENCODINGS)
    ap.add_argument("--finish-rigidities", type=float, nargs="*", default=[],
                    help="also the default with each --finish-rigidity F")
    a = ap.parse_args()
    modes = {m: MODES[m] for m in a.modes}
    for length in a.edge_lengths:
        modes[f"no finish, L = {length:g}"] = ["--no-fine-finish", "--edge-length", str(length)]
    for factor in a.finish_rigidities:
        modes[f"finish β ×{factor:g}"] = ["--finish-rigidity", str(factor)]
    os.makedirs(a.out, exist_ok=True)
    print("| volume | mode | re-encoding | Dice vs 8-bit run | Dice vs truth (8-bit run's) |")
    print("|---|---|---|---|---|")
    runs = [(v, s, seed, False) for v in a.volumes for s in a.noise for seed in a.seeds]
    runs += [(v, s, seed, True) for v in a.images for s in a.noise for seed in a.seeds]
    for (name, n, phases), sigma, seed, flat in runs:
        volume_name = f"{name}_{n}" + ("_2d" if flat else "")
        if (sigma, seed) != (0.1, 2):
            volume_name += f"_s{sigma:.2f}_seed{seed}"
        data = os.path.join(a.out, volume_name)
        subprocess.run([BIN, "phantom" if flat else "phantom3d", name, "--size", str(n),
                        "--noise", str(sigma), "--seed", str(seed), "--out", data],
                       check=True, stdout=subprocess.DEVNULL)
        if flat:
            eight = os.path.join(data, name + ".png")
            truth = np.asarray(Image.open(os.path.join(data, name + "_labels.png")))
            volume = np.asarray(Image.open(eight)).astype(np.float64)
        else:
            eight = os.path.join(data, name + ".tif")
            truth = tifffile.imread(os.path.join(data, name + "_labels.tif"))
            volume = tifffile.imread(eight).astype(np.float64)
        for mode, extra in ({"default": []} if flat else modes).items():
            tag = mode.replace(", ", "_").replace(" = ", "").replace(" ", "_")
            base = segment(eight, phases, extra, os.path.join(data, f"{tag}_8bit"), flat)
            base_truth = mean_dice(base, truth, phases)
            for what, encoded in encodings(volume, a.encodings).items():
                path = os.path.join(data, f"{what.replace(' ', '_')}.tif")
                tifffile.imwrite(path, encoded)
                labels = segment(path, phases, extra, os.path.join(data, f"{tag}_{what}"), flat)
                print(f"| {volume_name} | {mode} | {what} | {mean_dice(labels, base, phases):.4f} "
                      f"| {mean_dice(labels, truth, phases):.4f} ({base_truth:.4f}) |")


if __name__ == "__main__":
    main()
