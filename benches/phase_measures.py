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

  python3 benches/phase_measures.py --out OUT [--sizes 256 512] [--sizes3d 64 128] [--seeds 1 2 ... 8]
  python3 benches/phase_measures.py --out OUT --images DIR

--images measures 2D images made by another generator instead of the built-in
phantoms: every NAME.png in DIR with its ground-truth label image NAME_gt.png
beside it (any label values; the number of distinct values is the number of
phases). Each phase found is compared with the ground-truth label it overlaps
most.
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


def errors(estimate, truth):
    return 100 * (estimate / truth - 1)


def collect_2d(out, sizes, sigmas, seeds):
    """{(image, phase): [(truth, pv, se, count, mesh) per seed]}"""
    found = {}
    for name, phases in (("two_phase", 2), ("four_phase", 4)):
        for n in sizes:
            for s in sigmas:
                tag = f"{name}_{n}_s{s:.2f}"
                for seed in seeds:
                    data = os.path.join(out, f"{tag}_seed{seed}")
                    run("phantom", name, "--size", n, "--noise", s, "--seed", seed, "--out", data)
                    res = data + "_out"
                    run("segment", os.path.join(data, name + ".png"), "--phases", phases,
                        "--quiet", "--outputs", "labels,phases", "--out", res)
                    truth = np.array(Image.open(os.path.join(data, name + "_labels.png")))
                    measured = phases_csv(os.path.join(res, "phases.csv"))
                    for p, (pv, se, area, mesh) in enumerate(measured):
                        count = int((truth == p).sum())
                        found.setdefault((tag, p), []).append((count, pv, se, area, mesh))
    return found


def collect_images(out, folder):
    """{(image, phase): [(truth, pv, se, count, mesh)]} for the NAME.png /
    NAME_gt.png pairs of `folder`."""
    found = {}
    for name in sorted(f[:-len("_gt.png")] for f in os.listdir(folder) if f.endswith("_gt.png")):
        image = os.path.join(folder, name + ".png")
        if not os.path.exists(image):
            continue
        truth = np.array(Image.open(os.path.join(folder, name + "_gt.png")))
        res = os.path.join(out, name + "_out")
        run("segment", image, "--phases", len(np.unique(truth)),
            "--quiet", "--outputs", "labels,phases", "--out", res)
        labels = np.array(Image.open(os.path.join(res, "labels.png")))
        measured = phases_csv(os.path.join(res, "phases.csv"))
        for p, (pv, se, area, mesh) in enumerate(measured):
            values, overlap = np.unique(truth[labels == p], return_counts=True)
            count = int((truth == values[np.argmax(overlap)]).sum())
            found.setdefault((name, p), []).append((count, pv, se, area, mesh))
    return found


def collect_3d(out, sizes, sigmas, seeds):
    """{(volume, 1): [(truth, pv, se, count, mesh) per seed]} and the
    analytic and noise-free model volumes per volume."""
    found, extra = {}, {}
    for n in sizes:
        for name in ANALYTIC:
            clean = os.path.join(out, f"{name}_{n}_clean")
            run("phantom3d", name, "--size", n, "--noise", 0, "--out", clean)
            model = model_volume(read_stack(os.path.join(clean, name + ".tif")).astype(float))
            for s in sigmas:
                tag = f"{name}_{n}_s{s:.2f}"
                for seed in seeds:
                    data = os.path.join(out, f"{tag}_seed{seed}")
                    run("phantom3d", name, "--size", n, "--noise", s, "--seed", seed, "--out", data)
                    res = data + "_out"
                    run("segment3d", os.path.join(data, name + ".tif"), "--quiet",
                        "--outputs", "labels,phases", "--out", res)
                    count = int((read_stack(os.path.join(data, name + "_labels.tif")) == 1).sum())
                    pv, se, vol, mesh = phases_csv(os.path.join(res, "phases.csv"))[1]
                    found.setdefault((tag, 1), []).append((count, pv, se, vol, mesh))
                extra[tag] = (ANALYTIC[name] * n**3, model)
    return found, extra


def first_seed_2d(found):
    print("| image | phase | truth px | partial volume (± s.e.) | labels | mesh |")
    print("|---|---|---|---|---|---|")
    for (tag, p), runs in found.items():
        count, pv, se, area, mesh = runs[0]
        print(f"| {tag} | {p} | {count} | {pct(pv, count)} ± {100 * se / count:.2f}% "
              f"| {pct(area, count)} | {pct(mesh, count)} |")


def first_seed_3d(found, extra):
    print("| volume | truth voxels | analytic | partial volume (± s.e.) | labels | mesh "
          "| model (noise-free) |")
    print("|---|---|---|---|---|---|---|")
    for (tag, _), runs in found.items():
        count, pv, se, vol, mesh = runs[0]
        analytic, model = extra[tag]
        print(f"| {tag} | {count} | {pct(analytic, count)} "
              f"| {pct(pv, count)} ± {100 * se / count:.2f}% | {pct(vol, count)} "
              f"| {pct(mesh, count)} | {pct(model, count)} |")


def over_seeds(found, seeds):
    """Per image and phase: the partial-volume and label-count errors over
    the seeds (mean, sample standard deviation, largest magnitude) and the
    root mean square of error / standard error (about 1 when the standard
    error covers the error)."""
    print(f"\nOver noise seeds {seeds[0]}-{seeds[-1]} ({len(seeds)} runs per row):\n")
    print("| image | phase | partial volume: mean | s.d. | largest | rms(error/s.e.) "
          "| labels: mean | s.d. | largest |")
    print("|---|---|---|---|---|---|---|---|---|")
    for (tag, p), runs in found.items():
        a = np.array(runs, dtype=float)
        truth, pv, se, count = a[:, 0], a[:, 1], a[:, 2], a[:, 3]
        e_pv, e_count = errors(pv, truth), errors(count, truth)
        z = np.sqrt(np.mean(((pv - truth) / se) ** 2))
        sd = (lambda e: e.std(ddof=1)) if len(runs) > 1 else (lambda e: 0.0)
        largest = lambda e: e[np.argmax(np.abs(e))]
        print(f"| {tag} | {p} | {e_pv.mean():+.2f}% | {sd(e_pv):.2f}% | {largest(e_pv):+.2f}% "
              f"| {z:.2f} | {e_count.mean():+.2f}% | {sd(e_count):.2f}% "
              f"| {largest(e_count):+.2f}% |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--sizes", type=int, nargs="*", default=[256, 512])
    ap.add_argument("--sizes3d", type=int, nargs="*", default=[64, 128])
    ap.add_argument("--sigmas", type=float, nargs="*", default=[0.1, 0.2])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1],
                    help="noise seeds of the phantoms: the first one's table, then the "
                         "errors' statistics over all")
    ap.add_argument("--images", metavar="DIR",
                    help="measure the NAME.png / NAME_gt.png pairs of DIR instead of the phantoms")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    if a.images:
        first_seed_2d(collect_images(a.out, a.images))
        return
    if a.sizes:
        found = collect_2d(a.out, a.sizes, a.sigmas, a.seeds)
        first_seed_2d(found)
        if len(a.seeds) > 1:
            over_seeds(found, a.seeds)
    if a.sizes3d:
        if a.sizes:
            print()
        found, extra = collect_3d(a.out, a.sizes3d, a.sigmas, a.seeds)
        first_seed_3d(found, extra)
        if len(a.seeds) > 1:
            over_seeds(found, a.seeds)


if __name__ == "__main__":
    main()
