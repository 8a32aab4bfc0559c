#!/usr/bin/env python3
"""Objects the result leaves out, and whether the run says so.

Spots: 512² micrographs of bright disks (radius 2 to 8 px, 1000 counts) on a
background of 230 counts, blurred by a Gaussian of 2 px (a microscope's
spread), with Gaussian noise of σ 15, 30 and 60 counts, stored as 16-bit
TIFFs. Each is segmented with the defaults; the script counts the true
objects left without a pixel of their phase and prints the run's
`segmentation.missed_objects` (the warning's figures: objects left out, and
objects kept smaller than they look) beside them.

Phantoms: the 2D phantoms two_phase, four_phase, three_close, four_close,
disks3, disks5, two_phase_specks and thin at 256² and 512², σ 0.1 and 0.2,
and the 3D ones two_balls, torus, hollow_sphere, three_phase and four_phase
at 32³, 40³ and 64³, σ 0.1 and 0.2 (not the brain-like volume, a minute a
run): the script prints the runs that report missed objects (the thin
phantom's lines and arcs narrower than the length weight keeps should;
nothing else should).

usage (from the repository root, after `cargo build --release` and
`pip install -r benches/compare/requirements.txt`):

  python3 benches/missed_objects.py --out OUT [--bin target/release/dsc-seg] [--no-phantoms]
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess

import numpy as np
import scipy.ndimage as ndi
import tifffile

SIDE = 512
NOISES = (15.0, 30.0, 60.0)
PHANTOMS_2D = {"two_phase": 2, "four_phase": 4, "three_close": 3, "four_close": 4,
               "disks3": 3, "disks5": 5, "two_phase_specks": 2, "thin": 2}
PHANTOMS_3D = {"two_balls": 2, "torus": 2, "hollow_sphere": 2, "three_phase": 3, "four_phase": 4}


def spots(noise: float, seed: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """A spots micrograph (uint16) and its truth (bool)."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:SIDE, 0:SIDE]
    truth = np.zeros((SIDE, SIDE), bool)
    for _ in range(300):
        r = rng.uniform(2.0, 8.0)
        cx, cy = rng.uniform(0, SIDE, 2)
        truth |= (xx - cx) ** 2 + (yy - cy) ** 2 <= r * r
    image = ndi.gaussian_filter(np.where(truth, 1000.0, 230.0), 2.0)
    image += rng.normal(0.0, noise, image.shape)
    return np.clip(image, 0, 65535).astype(np.uint16), truth


def segment(binary: str, command: str, path: str, phases: int, out: str) -> dict:
    """Runs dsc-seg; returns its report."""
    run = subprocess.run([binary, command, path, "--phases", str(phases), "--out", out, "--force",
                          "--outputs", "labels,report"], capture_output=True, text=True)
    if run.returncode:
        raise SystemExit(f"{command} {path} failed: {run.stderr.strip()}")
    with open(os.path.join(out, "report.json")) as f:
        return json.load(f)


def spots_table(binary: str, out: str) -> None:
    print("| noise (counts) | objects | left out | reported left out | reported kept smaller |")
    print("|---|---|---|---|---|")
    for noise in NOISES:
        image, truth = spots(noise)
        folder = os.path.join(out, f"spots_{noise:g}")
        os.makedirs(folder, exist_ok=True)
        path = os.path.join(folder, "spots.tif")
        tifffile.imwrite(path, image)
        report = segment(binary, "segment", path, 2, os.path.join(folder, "run"))
        labels = tifffile.imread(os.path.join(folder, "run", "labels.tif")) > 0
        objects, n = ndi.label(truth)
        left_out = sum(1 for i in range(1, n + 1) if not labels[objects == i].any())
        reported = report["segmentation"]["missed_objects"] or []

        def listed(entries):
            return "; ".join(f"{m['count']} of phase {m['phase']} in {m['within']} "
                             f"({m['pixels'] + m['labelled']} px, largest {m['largest']})"
                             for m in entries) or "none"

        text_out = listed(m for m in reported if m["labelled"] == 0)
        text_smaller = listed(m for m in reported if m["labelled"] > 0)
        print(f"| {noise:g} | {n} | {left_out} | {text_out} | {text_smaller} |", flush=True)


def phantom_sweep(binary: str, out: str) -> None:
    runs = []
    for name, phases in PHANTOMS_2D.items():
        for size in (256, 512):
            for sigma in (0.1, 0.2):
                runs.append(("phantom", "segment", name, phases, size, sigma, f"{name}.png"))
    for name, phases in PHANTOMS_3D.items():
        for size in (32, 40, 64):
            for sigma in (0.1, 0.2):
                runs.append(("phantom3d", "segment3d", name, phases, size, sigma, f"{name}.tif"))
    reporting = 0
    for maker, command, name, phases, size, sigma, file in runs:
        folder = os.path.join(out, f"{name}_{size}_s{sigma}")
        subprocess.run([binary, maker, name, "--size", str(size), "--noise", str(sigma), "--out",
                        folder], check=True, capture_output=True)
        report = segment(binary, command, os.path.join(folder, file), phases,
                         os.path.join(folder, "run"))
        missed = report["segmentation"]["missed_objects"]
        if missed:
            reporting += 1
            print(f"{name} {size} σ {sigma}: {missed}", flush=True)
    print(f"{reporting} of {len(runs)} phantom runs report missed objects")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--bin", default="target/release/dsc-seg")
    ap.add_argument("--no-phantoms", action="store_true", help="only the spots")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    spots_table(args.bin, args.out)
    if not args.no_phantoms:
        phantom_sweep(args.bin, args.out)


if __name__ == "__main__":
    main()
