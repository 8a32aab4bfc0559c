#!/bin/sh
# Side-by-side timing of dsc-seg and the peers of shared/bench/peers.py on the
# same images, with the same metric; prints a ratio table (Markdown).
#
# usage: benches/compare.sh DATA_DIR OUT_DIR [--repeat N] [--peers-json FILE] [--memory]
#   DATA_DIR    images made by `python3 shared/bench/peers.py gen --out DATA_DIR ...`
#               (NAME.png and NAME_gt.png; four_phase* images get --phases 4)
#   --repeat N  runs of each method per image; the time is the minimum (default 3)
#   --peers-json FILE  reuse a `peers.py run --json` result instead of running the
#               peers now (e.g. /work/peers-data/peers.json; not side by side then)
#   --memory    also report peak resident memory (/usr/bin/time -f %M) of
#               two-phase runs on 1024² and 4096² phantoms (made by `dsc-seg phantom`)
# env: DSC_SEG (binary; default $CARGO_TARGET_DIR/release/dsc-seg), PEERS_PY.
#
# Times are segmentation times excluding file loading and writing on both
# sides: report.json `times.segment` for dsc-seg, peers.py's `time_s` for the
# peers. "best peer" is the fastest peer whose mean Dice is at least ours
# minus 0.002 (the issue's "fastest peer that reaches our Dice"); ratio =
# our time / that peer's time (below 0.5 meets the issue's target). The last
# two columns restrict this to the variational peers (Chan-Vese, morphological
# Chan-Vese, MBO), leaving out blur + multi-Otsu thresholding.
set -e
data=$1; out=$2; shift 2
repeat=3; peers_json=; memory=0
while [ $# -gt 0 ]; do
  case $1 in
    --repeat) repeat=$2; shift 2;;
    --peers-json) peers_json=$2; shift 2;;
    --memory) memory=1; shift;;
    *) echo "unknown option $1" >&2; exit 2;;
  esac
done
bin=${DSC_SEG:-${CARGO_TARGET_DIR:-target}/release/dsc-seg}
peers=${PEERS_PY:-/work/shared/bench/peers.py}
mkdir -p "$out"

if [ -z "$peers_json" ]; then
  peers_json=$out/peers.json
  python3 "$peers" run --data "$data" --repeat "$repeat" --json "$peers_json" --no-save \
    --methods chan_vese morph_chan_vese gauss2+multiotsu mbo_pcms > "$out/peers.log"
fi

: > "$out/ours.tsv"
for f in "$data"/*.png; do
  case $f in *_gt.png) continue;; esac
  n=$(basename "$f" .png); k=2
  case $n in four*) k=4;; esac
  best=
  r=0
  while [ $r -lt "$repeat" ]; do
    "$bin" segment "$f" --phases $k --out "$out/ours/$n" --quiet
    t=$(python3 -c "import json;print(json.load(open('$out/ours/$n/report.json'))['times']['segment'])")
    best=$(python3 -c "print(min(float('$t'), float('${best:-inf}')))")
    r=$((r + 1))
  done
  dice=$(python3 "$peers" score --gt "$data/${n}_gt.png" --pred "$out/ours/$n/labels.png" |
    python3 -c "import json,sys;print(json.loads(sys.stdin.readline())['mean_dice'])")
  printf '%s\t%s\t%s\n' "$n" "$best" "$dice" >> "$out/ours.tsv"
done

python3 - "$out/ours.tsv" "$peers_json" <<'EOF'
import json, sys
ours = {}
for line in open(sys.argv[1]):
    n, t, d = line.split()
    ours[n] = (float(t), float(d))
peers = {}
for r in json.load(open(sys.argv[2]))["rows"]:
    d = r.get("mean_dice")
    if d is None:
        d = sum(r["dice"]) / len(r["dice"])
    peers.setdefault(r["image"], {})[r["method"]] = (r["time_s"], d)
methods = ["chan_vese", "morph_chan_vese", "gauss2+multiotsu", "mbo_pcms"]
head = "| image | ours s | ours Dice | " + " | ".join(f"{m} s (Dice)" for m in methods)
print(head + " | best peer ≥ our Dice | ours / best | best variational peer ≥ our Dice | ours / it | ours / MBO |")
print("|---" * (len(methods) + 8) + "|")
for n in sorted(ours):
    t, d = ours[n]
    p = peers.get(n, {})
    cells = []
    for m in methods:
        cells.append(f"{p[m][0]:.3f} ({p[m][1]:.4f})" if m in p else "–")
    def best(allowed):
        ok = [(pt, m) for m, (pt, pd) in p.items() if m in allowed and pd >= d - 0.002]
        if not ok:
            return "none", "–"
        pt, m = min(ok)
        return f"{m} {pt:.3f}", f"{t / pt:.2f}"
    b1, r1 = best(set(p))
    b2, r2 = best({"chan_vese", "chan_vese_tol1e-4", "morph_chan_vese", "mbo_pcms"})
    mbo = f"{t / p['mbo_pcms'][0]:.2f}" if "mbo_pcms" in p else "–"
    print(f"| {n} | {t:.3f} | {d:.4f} | " + " | ".join(cells) + f" | {b1} | {r1} | {b2} | {r2} | {mbo} |")
EOF

if [ "$memory" = 1 ]; then
  echo
  echo "| two-phase phantom | peak RSS MB | segment s | iterations |"
  echo "|---|---|---|---|"
  for s in 1024 4096; do
    mkdir -p "$out/mem$s"
    [ -f "$out/mem$s/two_phase.png" ] || "$bin" phantom two_phase --size $s --noise 0.2 --out "$out/mem$s" > /dev/null
    /usr/bin/time -f %M -o "$out/mem$s/rss" "$bin" segment "$out/mem$s/two_phase.png" --phases 2 --out "$out/mem$s/run" --quiet
    python3 -c "import json;r=json.load(open('$out/mem$s/run/report.json'));print('| %d² | %.0f | %.3f | %d |' % ($s, int(open('$out/mem$s/rss').read().split()[-1]) / 1024, r['times']['segment'], r['iterations']))"
  done
fi
