#!/usr/bin/env bash
# The Dask example over N 3D phantoms (two_balls, torus, hollow_sphere, side
# SIZE, seeds 1..N) on a LocalCluster of 1 and then 2 single-threaded worker
# processes, ROUNDS times; the example times the mapping from the first task
# to the summary (cluster start-up excluded). Needs a Python with the package
# and Dask:
#
#   pip install ./python "dask[distributed]" tifffile pillow
#   bash benches/dask_workers.sh [N] [SIZE] [ROUNDS]
set -euo pipefail
n=${1:-16}
size=${2:-40}
rounds=${3:-2}
python=${PYTHON:-python3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$python" - "$work/in" "$n" "$size" <<'PY'
import sys
from pathlib import Path
import tifffile
import dsc_seg
out, n, size = Path(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
out.mkdir()
for i in range(n):
    name = ["two_balls", "torus", "hollow_sphere"][i % 3]
    volume, _ = dsc_seg.phantom(name, size=size, noise=0.1, seed=i + 1)
    tifffile.imwrite(out / f"v{i:02}_{name}.tif", volume)
PY
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
for r in $(seq 1 "$rounds"); do
  for w in 1 2; do
    rm -rf "$work/out"
    echo -n "round $r, $w worker(s): "
    "$python" python/examples/dask_batch.py "$work/in" "$work/out" --workers "$w" 2>/dev/null
    cp -r "$work/out" "$work/out_w$w"
  done
  for f in "$work"/out_w1/*/labels.tif; do
    cmp -s "$f" "$work/out_w2/$(basename "$(dirname "$f")")/labels.tif" || { echo "labels differ: $f"; exit 1; }
  done
  rm -rf "$work"/out_w*
  echo "round $r: labels identical with 1 and 2 workers"
done
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
