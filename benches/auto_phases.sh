#!/bin/sh
# How often `--phases auto` finds the true number of phases. Two sets, at
# noise 0.05 to 0.25, two noise seeds each, 256² (or $SIZE):
#   - the disks2 ... disks6 phantoms (2 to 6 phases, levels evenly spaced in
#     0.15..0.85, disks and squares on phase 0);
#   - other geometries: the two- and four-phase benchmark phantoms, three and
#     four phases with close means, fig4 (triple junctions) and fig6.
# Prints one line per image and the rate per phantom and per set.
#
# usage (from the repository root, after `cargo build --release`):
#   sh benches/auto_phases.sh [OUT_DIR]
set -e
bin=${DSC_SEG:-target/release/dsc-seg}
out=${1:-target/auto_phases}
size=${SIZE:-256}
mkdir -p "$out"
: > "$out/results.tsv"
for spec in disks2:2 disks3:3 disks4:4 disks5:5 disks6:6 \
  two_phase:2 four_phase:4 three_close:3 four_close:4 fig4:4 fig6:3; do
  name=${spec%:*}
  truth=${spec#*:}
  for sigma in 0.05 0.1 0.15 0.2 0.25; do
    for seed in 1 2; do
      dir=$out/${name}_s${sigma}_$seed
      "$bin" segment --phantom "$name" --phantom-size "$size" --phantom-noise $sigma \
        --phantom-seed $seed --phases auto --out "$dir" --outputs report --quiet
      chosen=$(python3 -c "import json;print(json.load(open('$dir/report.json'))['params']['phases'])")
      printf '%s\t%s\t%s\t%s\t%s\n' "$name" "$truth" $sigma $seed "$chosen" | tee -a "$out/results.tsv"
    done
  done
done
python3 - "$out/results.tsv" <<'PY'
import sys
rows = [l.split() for l in open(sys.argv[1])]
names = list(dict.fromkeys(r[0] for r in rows))
for name in names:
    mine = [r for r in rows if r[0] == name]
    ok = sum(r[1] == r[4] for r in mine)
    print(f"{name}: {ok}/{len(mine)} right")
for label, pick in [("disks", lambda r: r[0].startswith("disks")),
                    ("other geometries", lambda r: not r[0].startswith("disks")),
                    ("all", lambda r: True)]:
    mine = [r for r in rows if pick(r)]
    ok = sum(r[1] == r[4] for r in mine)
    print(f"{label}: {ok}/{len(mine)} right ({100 * ok / len(mine):.0f} %)")
PY
