"""The three- and four-phase 3D phantoms over sizes, noise levels and noise seeds.

Small volumes are where a phase is most easily lost or judged lost (a thin
wedge, a start whose thresholds fall in the background's noise), so this
grid records, per volume, what `dsc-seg segment3d` did beside its Dice: the
iterations, why it stopped, the re-seeds kept and undone, and the warnings.
Writes OUT/results.json (after every volume) and prints one line per volume
and a Markdown table per phantom (the three seeds side by side).

usage (from the repository root, after `cargo build --release`):

  python3 benches/small_volumes.py --out OUT
  python3 benches/small_volumes.py --out OUT --sizes 48 --sigmas 0.2 --seeds 1 --phantoms four_phase
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "compare"))
import score  # noqa: E402
import tifffile  # noqa: E402

PHASES = {"three_phase": 3, "four_phase": 4}


def run(binary: str, name: str, size: int, sigma: float, seed: int, out: str) -> dict:
    """Writes the phantom, segments it with the defaults, scores it."""
    tag = f"{name}_{size}_s{sigma}_{seed}"
    phantom, result = os.path.join(out, "phantoms", tag), os.path.join(out, tag)
    subprocess.run([binary, "phantom3d", name, "--size", str(size), "--noise", str(sigma),
                    "--seed", str(seed), "--out", phantom], check=True, capture_output=True)
    subprocess.run([binary, "segment3d", os.path.join(phantom, f"{name}.tif"), "--phases",
                    str(PHASES[name]), "--out", result, "--quiet"], check=True)
    with open(os.path.join(result, "report.json")) as f:
        report = json.load(f)
    run_report = report["segmentation"]
    truth = tifffile.imread(os.path.join(phantom, f"{name}_labels.tif"))
    scored = score.score(truth, tifffile.imread(os.path.join(result, "labels.tif")))
    return dict(name=name, size=size, sigma=sigma, seed=seed, dice=scored["mean_dice"],
                dice_per_phase=scored["dice"], iterations=run_report["iterations"],
                stop_reason=run_report["stop_reason"], reseeds=run_report["reseeds"],
                reseeds_undone=run_report.get("reseeds_undone", 0),
                warnings=report["warnings"])


def table(rows: list[dict], name: str, seeds: list[int]) -> str:
    """One line per size and noise level: Dice, iterations, re-seeds kept and
    undone, warnings, per seed."""
    lines = ["| volume | Dice | iterations | re-seeds (undone) | warnings |", "|---|---|---|---|---|"]
    keys = sorted({(r["size"], r["sigma"]) for r in rows if r["name"] == name})
    for size, sigma in keys:
        cell = [r for s in seeds for r in rows
                if (r["name"], r["size"], r["sigma"], r["seed"]) == (name, size, sigma, s)]
        lines.append(f"| {name} {size}³ σ {sigma} | " + " / ".join(
            [" ".join(f"{r['dice']:.3f}" for r in cell),
             "/".join(f"{r['iterations']}" for r in cell),
             "/".join(f"{r['reseeds']} ({r['reseeds_undone']})" for r in cell),
             "/".join(str(len(r["warnings"])) for r in cell)]).replace(" / ", " | ") + " |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--bin", default=os.path.join("target", "release", "dsc-seg"))
    ap.add_argument("--sizes", type=int, nargs="+", default=[32, 40, 48, 56, 64])
    ap.add_argument("--sigmas", type=float, nargs="+", default=[0.1, 0.2])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--phantoms", nargs="+", choices=sorted(PHASES), default=["four_phase", "three_phase"])
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    rows = []
    for name in a.phantoms:
        for size in a.sizes:
            for sigma in a.sigmas:
                for seed in a.seeds:
                    row = run(a.bin, name, size, sigma, seed, a.out)
                    rows.append(row)
                    print(f"{name} {size}³ σ {sigma} seed {seed}: Dice {row['dice']:.4f}, "
                          f"{row['iterations']} iterations ({row['stop_reason']}), "
                          f"{row['reseeds']} re-seeds ({row['reseeds_undone']} undone), "
                          f"{len(row['warnings'])} warnings", flush=True)
                    with open(os.path.join(a.out, "results.json"), "w") as f:
                        json.dump(rows, f, indent=1)
    for name in a.phantoms:
        print()
        print(table(rows, name, a.seeds))
    dice = [r["dice"] for r in rows]
    print(f"\nmean Dice {sum(dice) / len(dice):.4f}; at the iteration cap "
          f"{sum(r['stop_reason'] == 'max_iterations' for r in rows)} of {len(rows)}; "
          f"with warnings {sum(bool(r['warnings']) for r in rows)}")


if __name__ == "__main__":
    main()
