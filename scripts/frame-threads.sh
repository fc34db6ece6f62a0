#!/usr/bin/env bash
# Issue 17's speed figures on KITTI odometry 04 (51 frames, camera 0, LiDAR depth): `rgbl run` with
# --threads 1 and --threads 2 alternately, inline and with --threaded mapping, each repeated, in the
# same session. Per run: the median of front_ms (depth + extraction + tracking: the frame's wall cost
# on the tracking thread until its pose), the mean of total_ms (mapping included) and the whole
# process's wall time, start-up included. The ratios are of medians over the repetitions.
#
#   scripts/frame-threads.sh [--build DIR] [--repeat N] [--data DIR]
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="$repo/build/release"
repeat=5
data="${RGBL_DATA:-$repo/../shared/data}"
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --repeat) repeat="$2"; shift 2 ;;
    --data) data="$2"; shift 2 ;;
    *) echo "frame-threads: unknown option '$1' (see the header of $0)" >&2; exit 2 ;;
  esac
done
seq="$data/kitti/odometry/sequences/04"
[ -d "$seq" ] || { echo "frame-threads: no KITTI 04 at $seq (set RGBL_DATA or --data)" >&2; exit 2; }
[ -x "$build/bin/rgbl" ] || { cmake --preset release -S "$repo" > /dev/null; cmake --build "$build" --target rgbl_cli; }
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
results="$scratch/results.txt"
for r in $(seq 1 "$repeat"); do
  for mapping in inline threaded; do
    for threads in 1 2; do
      flag=(); [ "$mapping" = threaded ] && flag=(--threaded)
      start=$(date +%s.%N)
      "$build/bin/rgbl" -q run "$seq" --camera 0 --threads "$threads" ${flag[@]+"${flag[@]}"} --out "$scratch/out" > /dev/null
      end=$(date +%s.%N)
      python3 - "$scratch/out/summary.json" "$mapping" "$threads" "$start" "$end" >> "$results" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
s = j["stage_ms"]
print(sys.argv[2], sys.argv[3], s["depth_extraction_tracking"]["median"], s["total"]["mean"],
      float(sys.argv[5]) - float(sys.argv[4]), j["metrics"]["ate_rmse_m"])
PY
    done
  done
done
python3 - "$results" <<'PY'
import statistics, sys
rows = [l.split() for l in open(sys.argv[1])]
def med(mapping, threads, col):
    return statistics.median(float(r[col]) for r in rows if r[0] == mapping and r[1] == threads)
print(f"{'mapping':9} {'threads':>7} {'front median ms':>16} {'total mean ms':>14} {'process wall s':>15} {'ATE m':>7}")
for mapping in ("inline", "threaded"):
    for threads in ("1", "2"):
        print(f"{mapping:9} {threads:>7} {med(mapping, threads, 2):16.2f} {med(mapping, threads, 3):14.2f} "
              f"{med(mapping, threads, 4):15.3f} {med(mapping, threads, 5):7.3f}")
for mapping in ("inline", "threaded"):
    print(f"{mapping}: front median, 2 threads / 1 thread = {med(mapping, '2', 2) / med(mapping, '1', 2):.2f}x; "
          f"total mean {med(mapping, '2', 3) / med(mapping, '1', 3):.2f}x")
print(f"threaded / inline mapping, total mean per frame at 2 threads: {med('threaded', '2', 3) / med('inline', '2', 3):.2f}x")
PY
