#!/usr/bin/env python3
"""phases.csv against the phantoms' ground truth: per phase the area (2D) or
volume (3D) by partial volume (`pv_area_*`/`pv_volume_*`, the estimate to
use, with its noise standard error), from the label count and from the
mesh, against the ground-truth pixel/voxel count and (3D) the analytic solid; for 3D also the noise-free
optimum of the two-phase piecewise-constant model (the threshold halfway
between the means of the voxels above and below it, at its fixed point),
which is where the model puts a blurred edge.

usage (from the repository root, after `cargo build --release` and
`pip install -r benches/compare/requirements.txt`):

  python3 benches/phase_measures.py --out OUT [--sizes 256 512] [--sizes3d 64 128] [--seed 1]
"""
from __future__ import annotations

import argparse
import csv
import math
import os
import subprocess

import numpy as np
from PIL import Image

BIN = os.path.join(os.path.dirname(__file__), "..", "target", "release", "dsc-seg")

# Phase-1 solids of the 3D phantoms, in units of the side n (src/phantom/shapes3d.rs).
ANALYTIC = {
    "two_balls": 2 * 4 / 3 * math.pi * 0.22**3,
    "torus": 2 * math.pi**2 * 0.28 * 0.11**2,
    "hollow_sphere": 4 / 3 * math.pi * (0.36**3 - 0.22**3),
}


def run(*args):
    subprocess.run([BIN, *map(str, args)], check=True, stdout=subprocess.DEVNULL)


def read_stack(path):
    im = Image.open(path)
    frames = []
    for i in range(im.n_frames):
        im.seek(i)
        frames.append(np.array(im))
    return np.array(frames)


def phases_csv(path):
    """Per phase (partial volume, its standard error, count measure, mesh measure)."""
    rows = list(csv.DictReader(open(path)))
    keys = list(rows[0])

    def column(prefix):
        return next(k for k in keys if k.startswith(prefix) and "_se_" not in k)

    pv, count, mesh = column("pv_"), column("count_"), column("mesh_")
    se = next(k for k in keys if k.startswith("pv_") and "_se_" in k)
    return [(float(r[pv]), float(r[se]), float(r[count]), float(r[mesh])) for r in rows]


def pct(a, b):
    return f"{100 * (a / b - 1):+.2f}%"


def model_volume(image):
    t = 0.5 * (float(image.min()) + float(image.max()))
    for _ in range(100):
        above = image > t
        nxt = 0.5 * (image[above].mean() + image[~above].mean())
        if abs(nxt - t) < 1e-9:
            break
        t = nxt
    return int((image > t).sum())


def two_d(out, sizes, sigmas, seed):
    print("| image | phase | truth px | partial volume (± s.e.) | labels | mesh |")
    print("|---|---|---|---|---|---|")
    for name, phases in (("two_phase", 2), ("four_phase", 4)):
        for n in sizes:
            for s in sigmas:
                tag = f"{name}_{n}_s{s:.2f}"
                data = os.path.join(out, tag)
                run("phantom", name, "--size", n, "--noise", s, "--seed", seed, "--out", data)
                res = os.path.join(out, tag + "_out")
                run("segment", os.path.join(data, name + ".png"), "--phases", phases,
                    "--quiet", "--outputs", "labels,phases", "--out", res)
                truth = np.array(Image.open(os.path.join(data, name + "_labels.png")))
                for p, (pv, se, area, mesh) in enumerate(phases_csv(os.path.join(res, "phases.csv"))):
                    count = int((truth == p).sum())
                    print(f"| {tag} | {p} | {count} | {pct(pv, count)} ± {100 * se / count:.2f}% "
                          f"| {pct(area, count)} | {pct(mesh, count)} |")


def three_d(out, sizes, sigmas, seed):
    print("| volume | truth voxels | analytic | partial volume (± s.e.) | labels | mesh "
          "| model (noise-free) |")
    print("|---|---|---|---|---|---|---|")
    for n in sizes:
        for name in ANALYTIC:
            clean = os.path.join(out, f"{name}_{n}_clean")
            run("phantom3d", name, "--size", n, "--noise", 0, "--out", clean)
            model = model_volume(read_stack(os.path.join(clean, name + ".tif")).astype(float))
            for s in sigmas:
                tag = f"{name}_{n}_s{s:.2f}"
                data = os.path.join(out, tag)
                run("phantom3d", name, "--size", n, "--noise", s, "--seed", seed, "--out", data)
                res = os.path.join(out, tag + "_out")
                run("segment3d", os.path.join(data, name + ".tif"), "--quiet",
                    "--outputs", "labels,phases", "--out", res)
                count = int((read_stack(os.path.join(data, name + "_labels.tif")) == 1).sum())
                analytic = ANALYTIC[name] * n**3
                pv, se, vol, mesh = phases_csv(os.path.join(res, "phases.csv"))[1]
                print(f"| {tag} | {count} | {pct(analytic, count)} "
                      f"| {pct(pv, count)} ± {100 * se / count:.2f}% | {pct(vol, count)} "
                      f"| {pct(mesh, count)} | {pct(model, count)} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--sizes", type=int, nargs="*", default=[256, 512])
    ap.add_argument("--sizes3d", type=int, nargs="*", default=[64, 128])
    ap.add_argument("--sigmas", type=float, nargs="*", default=[0.1, 0.2])
    ap.add_argument("--seed", type=int, default=1, help="noise seed of the phantoms")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    if a.sizes:
        two_d(a.out, a.sizes, a.sigmas, a.seed)
    if a.sizes3d:
        three_d(a.out, a.sizes3d, a.sigmas, a.seed)


if __name__ == "__main__":
    main()
