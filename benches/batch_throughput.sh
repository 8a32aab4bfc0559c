#!/usr/bin/env bash
# Throughput of batch runs: N two-phase 256² phantoms (σ 0.2, seeds 1..N)
# segmented by N single `dsc-seg segment IMAGE` calls one after another,
# against one `dsc-seg segment FOLDER --jobs J` call; process start and file
# I/O included, every output written. The two are run alternately ROUNDS
# times and the labels compared byte for byte.
#
#   cargo build --release && bash benches/batch_throughput.sh [N] [J] [ROUNDS]
set -euo pipefail
n=${1:-64}
jobs=${2:-2}
rounds=${3:-3}
bin=${DSC_SEG:-target/release/dsc-seg}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/in"
for i in $(seq 1 "$n"); do
  "$bin" phantom two_phase --size 256 --noise 0.2 --seed "$i" --out "$work/gen" >/dev/null
  mv "$work/gen/two_phase.png" "$work/in/img$i.png"
done
# Wall, user and system seconds of the command given.
TIMEFORMAT='%R %U %S'
timed() { { time "$@" >/dev/null 2>&1; } 2>&1; }
sequential() {
  for f in "$work"/in/*.png; do
    "$bin" segment "$f" --quiet --out "$work/seq/$(basename "$f" .png)"
  done
}
echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
for r in $(seq 1 "$rounds"); do
  rm -rf "$work/seq" "$work/batch"
  read -r s_wall s_user s_sys < <(timed sequential)
  read -r b_wall b_user b_sys < <(timed "$bin" segment "$work/in" --jobs "$jobs" --quiet --out "$work/batch")
  for f in "$work"/in/*.png; do
    s=$(basename "$f" .png)
    cmp -s "$work/seq/$s/labels.png" "$work/batch/$s/labels.png" || { echo "labels differ: $s"; exit 1; }
  done
  awk -v sw="$s_wall" -v su="$s_user" -v ss="$s_sys" -v bw="$b_wall" -v bu="$b_user" \
      -v bs="$b_sys" -v n="$n" -v j="$jobs" -v r="$r" 'BEGIN {
    sc = su + ss; bc = bu + bs;
    printf "round %d: %d sequential calls %.2f s wall (%.2f s CPU), one call --jobs %d %.2f s wall (%.2f s CPU): wall ratio %.2f; labels identical\n",
      r, n, sw, sc, j, bw, bc, bw / sw }'
done
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
