#!/bin/sh
# Runs the release dsc-seg on the peers.py images and scores them like the peers.
# usage: scripts/bench-peers.sh DATA_DIR OUT_DIR [extra dsc-seg segment options...]
# (DATA_DIR made by: python3 shared/bench/peers.py gen --out DATA_DIR --sizes 256 512 --sigmas 0.1 0.2)
set -e
data=$1; out=$2; shift 2
bin=${DSC_SEG:-${CARGO_TARGET_DIR:-target}/release/dsc-seg}
peers=${PEERS_PY:-/work/shared/bench/peers.py}
printf '| image | mean Dice | pixel acc | iterations | converged | segment s | total s |\n|---|---|---|---|---|---|---|\n'
for f in "$data"/*.png; do
  case $f in *_gt.png) continue;; esac
  n=$(basename "$f" .png); k=2
  case $n in four*) k=4;; esac
  t0=$(date +%s.%N)
  "$bin" segment "$f" --phases $k --out "$out/$n" --quiet "$@"
  t1=$(date +%s.%N)
  s=$(python3 "$peers" score --gt "$data/${n}_gt.png" --pred "$out/$n/labels.png" | tail -1)
  acc=$(echo "$s" | cut -d'|' -f8 | tr -d ' ')
  dice=$(echo "$s" | cut -d'|' -f9 | tr -d ' ')
  meta=$(python3 -c "import json;r=json.load(open('$out/$n/report.json'));print(r['iterations'], r['converged'], '%.3f' % r['times']['segment'])")
  printf '| %s | %s | %s | %s | %s | %s | %.3f |\n' "$n" "$dice" "$acc" $(echo $meta) "$(echo "$t1 - $t0" | bc)"
done
