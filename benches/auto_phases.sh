#!/bin/sh
# How often `--phases auto` finds the true number of phases: the disks2 ...
# disks6 phantoms (2 to 6 phases, levels evenly spaced in 0.15..0.85) at
# noise 0.05 to 0.25, two noise seeds each, 256² (or $SIZE). Prints one line
# per image and the rate per phase count.
#
# usage (from the repository root, after `cargo build --release`):
#   sh benches/auto_phases.sh [OUT_DIR]
set -e
bin=${DSC_SEG:-target/release/dsc-seg}
out=${1:-target/auto_phases}
size=${SIZE:-256}
mkdir -p "$out"
: > "$out/results.tsv"
for n in 2 3 4 5 6; do
  for sigma in 0.05 0.1 0.15 0.2 0.25; do
    for seed in 1 2; do
      dir=$out/disks${n}_s${sigma}_$seed
      "$bin" segment --phantom disks$n --phantom-size "$size" --phantom-noise $sigma \
        --phantom-seed $seed --phases auto --out "$dir" --outputs report --quiet
      chosen=$(python3 -c "import json;print(json.load(open('$dir/report.json'))['params']['phases'])")
      printf 'disks%s\t%s\t%s\t%s\n' $n $sigma $seed "$chosen" | tee -a "$out/results.tsv"
    done
  done
done
python3 - "$out/results.tsv" <<'PY'
import sys
rows = [l.split() for l in open(sys.argv[1])]
for n in sorted({r[0] for r in rows}):
    mine = [r for r in rows if r[0] == n]
    ok = sum(int(r[3]) == int(n[5:]) for r in mine)
    print(f"{n}: {ok}/{len(mine)} right")
ok = sum(int(r[3]) == int(r[0][5:]) for r in rows)
print(f"all: {ok}/{len(rows)} right ({100 * ok / len(rows):.0f} %)")
PY
