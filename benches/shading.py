#!/usr/bin/env python3
"""Uneven illumination: the trend fitted inside each phase, and whether the run warns.

Phantoms: the 2D phantoms two_phase, four_phase, three_close, four_close,
two_phase_specks and four_phase_specks at 256², noise σ 0.1 and 0.2 (seed 1),
as written (8-bit PNG) and with a synthetic shading of strength a: a
multiplicative ramp across x (factor 1 − a/2 to 1 + a/2), a multiplicative
vignette (factor 1 − a·r²/r_corner² from the centre) and an additive ramp
(a·255·(x/(W − 1) − 1/2)), a = 0.1, 0.2, 0.4, clipped and rounded to 8 bits.
3D: two_balls, three_phase and four_phase at 64³, σ 0.1, as written and with
a multiplicative ramp along z (a = 0.2, 0.4), and the brain-like volume at
--size 96 (its own ±12 % bias field). Each is segmented with the defaults and
its number of phases; the script prints, per run, the mean Dice against the
truth, the largest trend/gap ratio over the phases (`segmentation.shading`),
the figures of the phase warned of (its significance and the slope of its
residuals on the trend within its parts) and whether the run warned.

Real images: scikit-image's camera, coins, moon, page, astronaut (gray),
cell, text, horse, clock, brick, grass, gravel, coffee (gray) and rocket
(gray), 8-bit PNG, segmented with --phases 2 and 3.

usage (from the repository root, after `cargo build --release` and
`pip install -r benches/compare/requirements.txt scikit-image`):

  python3 benches/shading.py --out OUT [--bin target/release/dsc-seg] [--no-3d]
"""
from __future__ import annotations

import argparse
import glob
import json
import os
import subprocess

import imageio.v3 as iio
import numpy as np
import tifffile

PHANTOMS_2D = {"two_phase": 2, "four_phase": 4, "three_close": 3, "four_close": 4,
               "two_phase_specks": 2, "four_phase_specks": 4}
PHANTOMS_3D = {"two_balls": 2, "three_phase": 3, "four_phase": 4}
STRENGTHS = (0.1, 0.2, 0.4)
REAL = ("camera", "coins", "moon", "page", "astronaut", "cell", "text", "horse", "clock",
        "brick", "grass", "gravel", "coffee", "rocket")


def shade(image: np.ndarray, kind: str, a: float) -> np.ndarray:
    """`image` (uint8, x the last axis; in 3D z the first) shaded by `kind` of strength `a`."""
    v = image.astype(np.float64)
    if kind == "none":
        return image
    if kind == "ramp_z":
        z = np.linspace(-0.5, 0.5, image.shape[0]).reshape((-1,) + (1,) * (image.ndim - 1))
        v = v * (1.0 + a * 2.0 * z)
    else:
        h, w = image.shape[-2:]
        x = np.linspace(-0.5, 0.5, w)[None, :]
        y = np.linspace(-0.5, 0.5, h)[:, None]
        if kind == "ramp":
            v = v * (1.0 + a * 2.0 * x)
        elif kind == "vignette":
            v = v * (1.0 - a * (x * x + y * y) / 0.5)
        elif kind == "additive":
            v = v + a * 255.0 * x
    return np.clip(np.rint(v), 0, 255).astype(np.uint8)


def segment(binary: str, command: str, path: str, phases: int, out: str) -> tuple[dict, str]:
    """Runs dsc-seg; returns its report and the labels' path."""
    run = subprocess.run([binary, command, path, "--phases", str(phases), "--out", out, "--force",
                          "--outputs", "labels,report"], capture_output=True, text=True)
    if run.returncode:
        raise SystemExit(f"{command} {path} failed: {run.stderr.strip()}")
    with open(os.path.join(out, "report.json")) as f:
        report = json.load(f)
    return report, glob.glob(os.path.join(out, "labels.*"))[0]


def read(path: str) -> np.ndarray:
    return tifffile.imread(path) if path.endswith(".tif") else iio.imread(path)


def dice(pred: np.ndarray, truth: np.ndarray, phases: int) -> float:
    total = 0.0
    for k in range(phases):
        a, b = pred == k, truth == k
        n = a.sum() + b.sum()
        total += 1.0 if n == 0 else 2.0 * (a & b).sum() / n
    return total / phases


def summary(report: dict) -> tuple[float, str, bool]:
    """The largest trend/gap ratio, the figures of the phase warned of (else of the phase of
    the largest ratio: trend / gap in the file's units, significance, the slope of the
    residuals on the trend within the phase's parts), and whether the run warned."""
    trends = report["segmentation"]["shading"] or []
    if not trends:
        return 0.0, "-", False
    warned = [t for t in trends if t["warned"]]
    t = max(warned or trends, key=lambda t: t["ratio"])
    largest = max(t["ratio"] for t in trends)
    z = max(t["significance"] for t in trends)
    figures = (f"phase {t['phase']}: {t['trend']:.3g} / {t['gap']:.3g} = {t['ratio']:.2f}, "
               f"z {t['significance']:.1f}, within {t['within']:.2f} (largest z {z:.1f})")
    return largest, figures, bool(warned)


def phantom_runs(binary: str, out: str, three_d: bool) -> None:
    print("| phantom | σ | shading | Dice | largest ratio | figures | warned |")
    print("|---|---|---|---|---|---|---|")
    runs = []
    for name, phases in PHANTOMS_2D.items():
        for sigma in (0.1, 0.2):
            runs.append(("phantom", "segment", name, phases, 256, sigma, "png",
                         [("none", 0.0)] + [(k, a) for k in ("ramp", "vignette", "additive")
                                            for a in STRENGTHS]))
    if three_d:
        for name, phases in PHANTOMS_3D.items():
            runs.append(("phantom3d", "segment3d", name, phases, 64, 0.1, "tif",
                         [("none", 0.0), ("ramp_z", 0.2), ("ramp_z", 0.4)]))
        runs.append(("phantom3d", "segment3d", "brain", 4, 96, 0.1, "tif", [("none", 0.0)]))
    for maker, command, name, phases, size, sigma, ext, shadings in runs:
        folder = os.path.join(out, f"{name}_{size}_s{sigma}")
        subprocess.run([binary, maker, name, "--size", str(size), "--noise", str(sigma),
                        "--seed", "1", "--out", folder], check=True, capture_output=True)
        image = read(os.path.join(folder, f"{name}.{ext}"))
        truth = read(os.path.join(folder, f"{name}_labels.{ext}"))
        for kind, a in shadings:
            path = os.path.join(folder, f"{kind}_{a:g}.{ext}")
            shaded = shade(image, kind, a)
            if ext == "tif":
                tifffile.imwrite(path, shaded)
            else:
                iio.imwrite(path, shaded)
            report, labels = segment(binary, command, path, phases,
                                     os.path.join(folder, f"run_{kind}_{a:g}"))
            d = dice(read(labels), truth, phases)
            ratio, figures, warned = summary(report)
            label = "none" if kind == "none" else f"{kind} {a:g}"
            print(f"| {name} {size} | {sigma:g} | {label} | {d:.4f} | {ratio:.3f} | {figures} | "
                  f"{'yes' if warned else 'no'} |", flush=True)


def real_runs(binary: str, out: str) -> None:
    import skimage.color
    import skimage.data

    print("| image | phases | largest ratio | figures | warned |")
    print("|---|---|---|---|---|")
    folder = os.path.join(out, "real")
    os.makedirs(folder, exist_ok=True)
    for name in REAL:
        image = getattr(skimage.data, name)()
        if image.ndim == 3:
            image = skimage.color.rgb2gray(image[..., :3])
        if image.dtype != np.uint8:
            image = np.rint(255 * (image.astype(np.float64) / image.max())).astype(np.uint8)
        path = os.path.join(folder, f"{name}.png")
        iio.imwrite(path, image)
        for phases in (2, 3) if len(np.unique(image)) > 2 else (2,):
            report, _ = segment(binary, "segment", path, phases,
                                os.path.join(folder, f"run_{name}_{phases}"))
            ratio, figures, warned = summary(report)
            print(f"| {name} | {phases} | {ratio:.3f} | {figures} | {'yes' if warned else 'no'} |",
                  flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--bin", default="target/release/dsc-seg")
    ap.add_argument("--no-3d", action="store_true", help="only the 2D phantoms and images")
    ap.add_argument("--only-real", action="store_true", help="only the real images")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    real_runs(args.bin, args.out)
    if not args.only_real:
        phantom_runs(args.bin, args.out, not args.no_3d)


if __name__ == "__main__":
    main()
