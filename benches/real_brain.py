#!/usr/bin/env python3
"""dsc-seg on a real brain MRI volume against the 3D peers, scored against
tissue probability maps.

The volume is the ICBM 2009a nonlinear symmetric T1 template (the MNI152
average of 152 adult brains, 1 mm isotropic, 197 x 233 x 189 voxels,
skull-stripped, uint8 NIfTI), with its grey- and white-matter probability
maps, as shipped inside the nilearn Python package (BSD licence; the template
itself is Copyright (C) 1993-2009 Louis Collins, McConnell Brain Imaging
Centre, Montreal Neurological Institute, McGill University, free to use,
copy, modify and distribute with that notice). Without --data the script
fetches the nilearn wheel with `pip download --no-deps` (about 11 MB) into
OUT and takes the three files out of it; nothing is installed.

The reference has four classes: background (T1 = 0), and inside the brain
the largest of CSF (1 - GM - WM, at least 0), GM and WM. dsc-seg runs
`segment3d T1 --phases 4` with its defaults, the peers (peers.py: 3D MBO,
multi-Otsu) on the same intensities divided by 255. Dice per class after
the Hungarian matching of score.py; the mean over the three tissue classes
leaves out the background, which is three quarters of the voxels.

usage (from the repository root, after `cargo build --release` and
`pip install -r benches/compare/requirements.txt`):

  python3 benches/real_brain.py --out OUT
  python3 benches/real_brain.py --out OUT --downsample 2            # 2 mm: block means
  python3 benches/real_brain.py --out OUT --downsample 2 --crop 25,30,40,48   # a 48^3 block
  python3 benches/real_brain.py --out OUT --data DIR --args="--phases 4 --max-iterations 60"

--downsample and --crop write the reduced volumes (T1 and maps alike, the
affine scaled and shifted to match) to OUT/reduced and run on those.
"""
from __future__ import annotations

import argparse
import glob
import json
import os
import shlex
import subprocess
import sys
import time
import zipfile

import nibabel
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "compare"))
import peers  # noqa: E402
import score  # noqa: E402

NILEARN = "nilearn==0.14.1"
DATA_DIR = "nilearn/datasets/data"
FILES = {
    "t1": "mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz",
    "gm": "mni_icbm152_gm_tal_nlin_sym_09a_converted.nii.gz",
    "wm": "mni_icbm152_wm_tal_nlin_sym_09a_converted.nii.gz",
}
CLASSES = ["background", "CSF", "GM", "WM"]


def fetch(out: str) -> str:
    """The three NIfTI files, taken out of the nilearn wheel; returns their folder."""
    wheel_dir = os.path.join(out, "wheel")
    if not glob.glob(os.path.join(wheel_dir, "nilearn-*.whl")):
        subprocess.run([sys.executable, "-m", "pip", "download", "--quiet", "--no-deps",
                        NILEARN, "-d", wheel_dir], check=True)
    wheel = zipfile.ZipFile(glob.glob(os.path.join(wheel_dir, "nilearn-*.whl"))[0])
    folder = os.path.join(out, "data")
    os.makedirs(folder, exist_ok=True)
    for name in FILES.values():
        with open(os.path.join(folder, name), "wb") as f:
            f.write(wheel.read(f"{DATA_DIR}/{name}"))
    return folder


def reduce(folder: str, out: str, factor: int, crop: list[int] | None) -> str:
    """The three files as block means over factor^3 voxels, then cropped to
    the cube crop = [x0, y0, z0, size] (in reduced voxels); returns their folder."""
    reduced = os.path.join(out, "reduced")
    os.makedirs(reduced, exist_ok=True)
    for name in FILES.values():
        image = nibabel.load(os.path.join(folder, name))
        data = np.asarray(image.dataobj).astype(np.float64)
        shape = [n // factor for n in data.shape]
        data = data[:shape[0] * factor, :shape[1] * factor, :shape[2] * factor]
        data = data.reshape(shape[0], factor, shape[1], factor, shape[2], factor).mean(axis=(1, 3, 5))
        affine = image.affine.copy()
        affine[:3, :3] *= factor
        affine[:3, 3] += image.affine[:3, :3] @ np.full(3, (factor - 1) / 2.0)
        if crop:
            x, y, z, n = crop
            data = data[x:x + n, y:y + n, z:z + n]
            affine[:3, 3] += affine[:3, :3] @ np.array([x, y, z], dtype=np.float64)
        nibabel.save(nibabel.Nifti1Image(np.rint(data).astype(np.uint8), affine),
                     os.path.join(reduced, name))
    return reduced


def reference(folder: str) -> tuple[np.ndarray, np.ndarray]:
    """The T1 intensities (voxel order of the file) and the four reference classes."""
    t1, gm, wm = (np.asarray(nibabel.load(os.path.join(folder, FILES[k])).dataobj)
                  for k in ("t1", "gm", "wm"))
    gm, wm = gm.astype(np.float64), wm.astype(np.float64)
    csf = np.clip(255.0 - gm - wm, 0.0, None)
    tissue = np.argmax(np.stack([csf, gm, wm]), axis=0) + 1
    return t1, np.where(t1 > 0, tissue, 0).astype(np.uint8)


def scored(truth: np.ndarray, labels: np.ndarray) -> dict:
    result = score.score(truth, labels)
    result["tissue_mean_dice"] = float(np.mean(result["dice"][1:]))
    return result


def run_ours(binary: str, t1_path: str, args: list[str], out: str, truth: np.ndarray) -> dict:
    folder = os.path.join(out, "dsc-seg")
    cmd = ["/usr/bin/time", "-f", "%e %U %M", "-o", os.path.join(out, "dsc-seg.time"),
           binary, "segment3d", t1_path, "--out", folder, "--quiet"] + args
    subprocess.run(cmd, check=True)
    with open(os.path.join(folder, "report.json")) as f:
        report = json.load(f)
    labels = np.asarray(nibabel.load(os.path.join(folder, "labels.nii.gz")).dataobj)
    wall, cpu, kib = open(os.path.join(out, "dsc-seg.time")).read().split()[-3:]
    result = scored(truth, labels)
    result.update(time_s=report["times"]["segment"], wall_s=float(wall), cpu_s=float(cpu),
                  peak_mib=int(kib) / 1024, iterations=report["iterations"],
                  cells=report["cells"], warnings=report.get("warnings", []))
    return result


def run_peer(name: str, image: np.ndarray, truth: np.ndarray) -> dict:
    start = time.perf_counter()
    labels = peers.PEERS[name][0](image, 4)
    result = scored(truth, labels)
    result["time_s"] = time.perf_counter() - start
    return result


def table(results: dict) -> str:
    lines = ["| method | " + " | ".join(f"Dice {c}" for c in CLASSES)
             + " | tissue mean | s |", "|---" * (len(CLASSES) + 3) + "|"]
    for method, r in results.items():
        lines.append(f"| {method} | " + " | ".join(f"{d:.4f}" for d in r["dice"])
                     + f" | {r['tissue_mean_dice']:.4f} | {r['time_s']:.1f} |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--bin", default=os.path.join("target", "release", "dsc-seg"))
    ap.add_argument("--data", help="folder holding the three NIfTI files (default: fetch them)")
    ap.add_argument("--downsample", type=int, default=1, metavar="N",
                    help="block means over N^3 voxels (2: a 2 mm volume)")
    ap.add_argument("--crop", metavar="X,Y,Z,SIZE",
                    help="a cube of SIZE voxels at X,Y,Z (after --downsample)")
    ap.add_argument("--methods", nargs="*", default=["mbo", "multi_otsu"])
    ap.add_argument("--args", default="--phases 4",
                    help="dsc-seg segment3d options as one string (default: --phases 4)")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    folder = a.data or fetch(a.out)
    if a.downsample > 1 or a.crop:
        crop = [int(v) for v in a.crop.split(",")] if a.crop else None
        folder = reduce(folder, a.out, a.downsample, crop)
    t1, truth = reference(folder)
    results = {"dsc-seg": run_ours(a.bin, os.path.join(folder, FILES["t1"]),
                                   shlex.split(a.args), a.out, truth)}
    image = t1.astype(np.float64) / 255.0
    for method in a.methods:
        results[method] = run_peer(method, image, truth)
    with open(os.path.join(a.out, "results.json"), "w") as f:
        json.dump(results, f, indent=1)
    print(table(results))
    ours = results["dsc-seg"]
    print(f"\ndsc-seg: {ours['iterations']} iterations, {ours['cells']} tets, "
          f"{ours['wall_s']:.1f} s wall, {ours['cpu_s']:.1f} s CPU, {ours['peak_mib']:.0f} MiB peak")


if __name__ == "__main__":
    main()
