#!/usr/bin/env python3
"""dsc-seg against its peers, side by side on the same phantoms with the same metric.

Writes the phantoms with `dsc-seg phantom` (2D) and `dsc-seg phantom3d` (3D:
two-phase shapes, three and four phases meeting along junction curves, and the
four-class brain-like volume),
segments each with `dsc-seg segment --phases K` / `dsc-seg segment3d` (all
other options at their defaults) and with every peer of `peers.py` that
handles its phase count and dimension, and scores every result against the
ground truth with `score.py` (Hungarian matching, Dice per phase). Prints
Markdown tables and writes OUT/results.json (after every case).

Times are the segmentation alone, without reading or writing files, for
dsc-seg (report.json `times.segment`) and the peers alike; each is the
minimum over --repeat runs, all methods in the same run (so under the same
machine load). Peak memory is the resident set of the dsc-seg process,
measured with GNU time (`/usr/bin/time`, Debian package `time`) when it is
installed.

usage (from the repository root, after `cargo build --release` and
`pip install -r benches/compare/requirements.txt`):

  python3 benches/compare/compare.py --out OUT            # the README's tables
  python3 benches/compare/compare.py --out OUT --only 2d --sizes 256 --sigmas 0.2 --repeat 1
  python3 benches/compare/compare.py --out OUT --only 3d --sizes3d 64 --methods3d mbo multi_otsu
  python3 benches/compare/compare.py --out OUT --only 3d --sizes3d --brain 0.1 --methods3d mbo multi_otsu
  python3 benches/compare/compare.py --out OUT --only 2d --sizes 256 512 --sigmas 0.1 0.25 \
      --phantoms three_close four_close two_phase_specks four_phase_specks
"""
from __future__ import annotations

import argparse
import json
import os
import shlex
import subprocess
import sys
import time

import numpy as np
from PIL import Image

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import peers  # noqa: E402
import score  # noqa: E402

PHANTOMS_2D = {"two_phase": 2, "four_phase": 4}
# Harder phantoms (--phantoms): close means, salt-and-pepper specks.
PHANTOMS_2D_HARD = {"three_close": 3, "four_close": 4, "two_phase_specks": 2, "four_phase_specks": 4}
# 3D phantoms (name -> phases): two-phase shapes, and three and four phases
# meeting along junction curves.
PHANTOMS_3D = {"two_balls": 2, "torus": 2, "hollow_sphere": 2, "three_phase": 3, "four_phase": 4}
# The brain-like volume: four classes, 160 x 190 x 150 at --size 190.
BRAIN_SIZE = 190
# The 2D cases without --sizes/--sigmas: 256² and 512² at both noise levels,
# 1024² at the higher one.
DEFAULT_CASES_2D = [(256, 0.1), (256, 0.2), (512, 0.1), (512, 0.2), (1024, 0.2)]
PEER_ORDER = ["multi_otsu", "blur_multi_otsu", "mbo", "chan_vese", "morph_chan_vese"]


GNU_TIME = "/usr/bin/time"


def run_measured(cmd: list[str], scratch: str) -> float | None:
    """Runs a command and fails loudly if it fails. Returns its peak resident
    memory in MiB, measured by GNU time (a process forked from Python would
    count Python's own memory), or None without GNU time."""
    os.makedirs(scratch, exist_ok=True)
    rss_file = os.path.join(scratch, "peak_rss_kib")
    measured = os.access(GNU_TIME, os.X_OK)
    full = [GNU_TIME, "-f", "%M", "-o", rss_file] + cmd if measured else cmd
    done = subprocess.run(full, stdout=subprocess.DEVNULL)
    if done.returncode != 0:
        sys.exit(f"error: {' '.join(cmd)} exited with {done.returncode}")
    if not measured:
        return None
    with open(rss_file) as f:
        return int(f.read().split()[-1]) / 1024


def read_image(path: str) -> np.ndarray:
    if path.endswith(".tif"):
        import tifffile

        return tifffile.imread(path)
    return np.asarray(Image.open(path).convert("L"))


def unit_range(values: np.ndarray) -> np.ndarray:
    return values.astype(np.float64) / float(np.iinfo(values.dtype).max)


def run_ours(binary: str, args: list[str], out: str, truth: np.ndarray, repeat: int) -> dict:
    best, peak = float("inf"), None
    for _ in range(repeat):
        rss = run_measured([binary] + args + ["--out", out, "--quiet"], out + "-rss")
        peak = rss if peak is None else max(peak, rss)
        with open(os.path.join(out, "report.json")) as f:
            report = json.load(f)
        best = min(best, report["times"]["segment"])
    labels_file = "labels.tif" if args[0] == "segment3d" else "labels.png"
    result = score.score(truth, read_image(os.path.join(out, labels_file)))
    result.update(time_s=best, peak_mib=peak, iterations=report["iterations"],
                  converged=report["converged"], cells=report["cells"])
    return result


def run_peer(name: str, image: np.ndarray, phases: int, truth: np.ndarray, repeat: int) -> dict:
    function = peers.PEERS[name][0]
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        labels = function(image, phases)
        best = min(best, time.perf_counter() - start)
    result = score.score(truth, labels)
    result["time_s"] = best
    return result


def case(binary, kind, name, size, noise, phases, seed, out, repeat, methods, extra=()):
    """One phantom: writes it, runs dsc-seg and the peers; returns a result row."""
    tag = f"{name}_{size}_s{noise:.2f}"
    folder = os.path.join(out, "3d" if kind == "3d" else "2d", tag)
    phantom_cmd = "phantom3d" if kind == "3d" else "phantom"
    run_measured([binary, phantom_cmd, name, "--size", str(size), "--noise", str(noise),
                  "--seed", str(seed), "--out", folder], folder)
    if kind == "3d":
        source, truth_file = f"{name}.tif", f"{name}_labels.tif"
        ours_args = ["segment3d", os.path.join(folder, source), "--phases", str(phases)]
    else:
        source, truth_file = f"{name}.png", f"{name}_gt.png"
        ours_args = ["segment", os.path.join(folder, source), "--phases", str(phases)]
    image = unit_range(read_image(os.path.join(folder, source)))
    truth = read_image(os.path.join(folder, truth_file))
    row = {"image": tag, "phantom": name, "size": size, "noise": noise, "phases": phases,
           "dsc-seg": run_ours(binary, ours_args + list(extra), os.path.join(folder, "dsc-seg"), truth, repeat)}
    for method in methods:
        if peers.applicable(method, phases, image.ndim):
            row[method] = run_peer(method, image, phases, truth, repeat)
    return row


def cell(result: dict | None) -> str:
    if result is None:
        return "–"
    return f"{result['mean_dice']:.4f} ({result['time_s']:.3f} s)"


def mib(value: float | None) -> str:
    return "–" if value is None else f"{value:.0f}"


def full_table(rows: list[dict], methods: list[str]) -> str:
    header = ["image", "dsc-seg Dice (s)", "iterations", "peak MiB"] + [f"{m} Dice (s)" for m in methods]
    lines = ["| " + " | ".join(header) + " |", "|---" * len(header) + "|"]
    for row in rows:
        ours = row["dsc-seg"]
        cells = [row["image"], cell(ours), str(ours["iterations"]), mib(ours["peak_mib"])]
        lines.append("| " + " | ".join(cells + [cell(row.get(m)) for m in methods]) + " |")
    return "\n".join(lines)


def summary_table(rows: list[dict]) -> str:
    """The README's table: ours, the best peer by Dice, and the MBO scheme's time."""
    lines = ["| image | dsc-seg Dice | dsc-seg s | best peer Dice (method, s) | MBO s |",
             "|---|---|---|---|---|"]
    for row in rows:
        ours = row["dsc-seg"]
        others = {m: r for m, r in row.items() if m in peers.PEERS}
        if others:
            best_name = max(others, key=lambda m: others[m]["mean_dice"])
            best = others[best_name]
            best_text = f"{best['mean_dice']:.4f} ({best_name}, {best['time_s']:.3f})"
        else:
            best_text = "–"
        mbo = f"{row['mbo']['time_s']:.3f}" if "mbo" in row else "–"
        lines.append(f"| {row['image']} | {ours['mean_dice']:.4f} | {ours['time_s']:.3f} | {best_text} | {mbo} |")
    return "\n".join(lines)


def mbo_table(rows: list[dict]) -> str:
    """3D: ours against the MBO scheme, and whether ours is at least as
    accurate in at most its time."""
    lines = ["| volume | dsc-seg Dice | dsc-seg s | iterations | tets | MBO Dice | MBO s | ≥ Dice, ≤ time |",
             "|---|---|---|---|---|---|---|---|"]
    for row in rows:
        ours, mbo = row["dsc-seg"], row.get("mbo")
        if mbo is None:
            continue
        holds = ours["mean_dice"] >= mbo["mean_dice"] and ours["time_s"] <= mbo["time_s"]
        lines.append(f"| {row['image']} | {ours['mean_dice']:.4f} | {ours['time_s']:.2f} | {ours['iterations']} | "
                     f"{ours['cells']} | {mbo['mean_dice']:.4f} | {mbo['time_s']:.2f} | {'yes' if holds else 'no'} |")
    return "\n".join(lines)


def memory_table(binary: str, out: str, sizes: list[int]) -> tuple[str, list[dict]]:
    """Peak memory of dsc-seg on large two-phase phantoms (σ = 0.2)."""
    lines = ["| two-phase phantom | peak MiB | segment s | iterations |", "|---|---|---|---|"]
    rows = []
    for size in sizes:
        folder = os.path.join(out, "memory", str(size))
        run_measured([binary, "phantom", "two_phase", "--size", str(size), "--noise", "0.2",
                      "--out", folder], folder)
        truth = read_image(os.path.join(folder, "two_phase_gt.png"))
        ours = run_ours(binary, ["segment", os.path.join(folder, "two_phase.png"), "--phases", "2"],
                        os.path.join(folder, "dsc-seg"), truth, 1)
        rows.append({"size": size, **ours})
        lines.append(f"| {size}² | {mib(ours['peak_mib'])} | {ours['time_s']:.3f} | {ours['iterations']} |")
    return "\n".join(lines), rows


def parse_args() -> argparse.Namespace:
    default_bin = os.environ.get("DSC_SEG") or os.path.join(
        os.environ.get("CARGO_TARGET_DIR", "target"), "release", "dsc-seg")
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True, help="folder for the phantoms, the outputs and results.json")
    ap.add_argument("--bin", default=default_bin, help="the dsc-seg binary (default: target/release/dsc-seg)")
    ap.add_argument("--only", choices=["2d", "3d"], help="run only the 2D images or only the 3D volumes")
    ap.add_argument("--repeat", type=int, default=3, help="runs per method and 2D image; time = minimum")
    ap.add_argument("--repeat3d", type=int, default=1, help="runs per method and volume")
    ap.add_argument("--sizes", type=int, nargs="+", help="2D sizes (default: 256 512 at both noise "
                    "levels and 1024 at 0.2)")
    ap.add_argument("--sigmas", type=float, nargs="+", help="2D noise levels (with --sizes; default 0.1 0.2)")
    ap.add_argument("--sizes3d", type=int, nargs="*", default=[64, 128])
    ap.add_argument("--sigmas3d", type=float, nargs="+", default=[0.1, 0.2])
    ap.add_argument("--phantoms3d", nargs="+", choices=list(PHANTOMS_3D), default=list(PHANTOMS_3D),
                    help="3D phantoms (default: all)")
    ap.add_argument("--brain", type=float, nargs="*", default=[0.1], metavar="SIGMA",
                    help="noise levels of the brain-like volume (160 x 190 x 150, four classes; "
                    "default 0.1; none to skip it)")
    ap.add_argument("--seed", type=int, default=1, help="noise seed of every phantom")
    ap.add_argument("--phantoms", nargs="+", choices=list(PHANTOMS_2D) + list(PHANTOMS_2D_HARD),
                    default=list(PHANTOMS_2D), help="2D phantoms (default: two_phase four_phase)")
    ap.add_argument("--methods", nargs="+", choices=PEER_ORDER, default=PEER_ORDER, help="2D peers")
    ap.add_argument("--methods3d", nargs="+", choices=PEER_ORDER, default=PEER_ORDER,
                    help="3D peers (chan_vese is 2D only; morph_chan_vese is the slowest)")
    ap.add_argument("--args", default="", help="further dsc-seg options as one string "
                    "(e.g. --args=--adaptive); the tables then show dsc-seg with them")
    ap.add_argument("--memory", nargs="*", type=int, metavar="SIZE",
                    help="also measure dsc-seg's peak memory on two-phase phantoms of these sizes "
                    "(default 1024 4096)")
    a = ap.parse_args()
    if not os.access(a.bin, os.X_OK):
        ap.error(f"no dsc-seg binary at {a.bin} (run `cargo build --release` or give --bin)")
    if a.memory is not None and not a.memory:
        a.memory = [1024, 4096]
    return a


def save(results: dict, out: str) -> None:
    """Writes OUT/results.json (after every case, so a long run that is
    stopped keeps what it measured)."""
    with open(os.path.join(out, "results.json"), "w") as f:
        json.dump(results, f, indent=1)


def main() -> None:
    a = parse_args()
    os.makedirs(a.out, exist_ok=True)
    results = {"two_d": [], "three_d": [], "memory": []}
    if a.only != "3d":
        cases = ([(n, s) for n in a.sizes for s in (a.sigmas or [0.1, 0.2])] if a.sizes else DEFAULT_CASES_2D)
        known = {**PHANTOMS_2D, **PHANTOMS_2D_HARD}
        for name in a.phantoms:
            phases = known[name]
            for size, noise in cases:
                row = case(a.bin, "2d", name, size, noise, phases, a.seed, a.out, a.repeat, a.methods,
                           shlex.split(a.args))
                results["two_d"].append(row)
                save(results, a.out)
                print(f"{row['image']}: dsc-seg {cell(row['dsc-seg'])}", file=sys.stderr, flush=True)
        methods = [m for m in PEER_ORDER if any(m in r for r in results["two_d"])]
        print("## 2D\n\n" + summary_table(results["two_d"]) + "\n\n" + full_table(results["two_d"], methods) + "\n")
    if a.only != "2d":
        volumes = [(name, size, noise) for size in a.sizes3d for noise in a.sigmas3d for name in a.phantoms3d]
        volumes += [("brain", BRAIN_SIZE, noise) for noise in a.brain]
        for name, size, noise in volumes:
            phases = 4 if name == "brain" else PHANTOMS_3D[name]
            row = case(a.bin, "3d", name, size, noise, phases, a.seed, a.out, a.repeat3d, a.methods3d,
                       shlex.split(a.args))
            results["three_d"].append(row)
            save(results, a.out)
            print(f"{row['image']}: dsc-seg {cell(row['dsc-seg'])}" + "".join(
                f", {m} {cell(row[m])}" for m in a.methods3d if m in row), file=sys.stderr, flush=True)
        rows = results["three_d"]
        methods = [m for m in PEER_ORDER if any(m in r for r in rows)]
        print("## 3D\n\n" + full_table(rows, methods) + "\n\n" + mbo_table(rows) + "\n")
        for method in ["dsc-seg"] + methods:
            dice = [r[method]["mean_dice"] for r in rows if method in r]
            if dice:
                print(f"{method}: mean Dice {np.mean(dice):.4f} (min {np.min(dice):.4f}) over {len(dice)} volumes")
        print()
    if a.memory:
        table, results["memory"] = memory_table(a.bin, a.out, a.memory)
        print("## Peak memory\n\n" + table + "\n")
    save(results, a.out)


if __name__ == "__main__":
    main()
