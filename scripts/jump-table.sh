#!/usr/bin/env bash
# Gaps in a drive, bridged or not (docs/loop-closing.md, "Bridging a gap"): every real KITTI excerpt
# in the data folder and every simulator scenario with several seeds, each with gaps of 2 s (frames
# 15-34 left out) and 1 s (frames 30-39), tracked by rgbl_jump three ways (without the gap, with it,
# with it but not bridged). One line per drive and gap: ATE against the truth, and how far the frames
# after the gap are from the run without it.
#
#   scripts/jump-table.sh [--build DIR] [--out FILE] [--seeds "1 2 3"] [--scenarios "a b"] [--no-real] [--no-sim]
#                         [--settings FILE]   (a settings YAML for every run, e.g. to switch an option off)
#
# Data: $RGBL_DATA, else ../shared/data next to the repository; scenarios cached as scripts/accuracy.sh does.
# Two tables compared pair by pair, every column: scripts/jump_compare.py A B.
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# shellcheck source=lib/scenario-cache.sh
source "$repo/scripts/lib/scenario-cache.sh"
build="$repo/build/release"
out="$repo/build/jump-table.txt"
seeds="1 2 3"
scenarios=""
real=1
sim=1
settings=()
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --seeds) seeds="$2"; shift 2 ;;
    --scenarios) scenarios="$2"; shift 2 ;;
    --no-real) real=0; shift ;;
    --no-sim) sim=0; shift ;;
    --settings) settings=(--settings "$(cd "$(dirname "$2")" && pwd)/$(basename "$2")"); shift 2 ;;
    -h|--help) sed -n '2,12p' "$0"; exit 0 ;;
    *) echo "jump-table.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
rgbl="$build/bin/rgbl"
jump="$build/bin/rgbl_jump"
for b in "$rgbl" "$jump"; do
  [ -x "$b" ] || { echo "jump-table.sh: $b not built (cmake --preset release && cmake --build build/release)" >&2; exit 1; }
done
data="${RGBL_DATA:-$repo/../shared/data}"
cache="${RGBL_CACHE:-$HOME/.cache/rgbl/scenarios}"
mkdir -p "$cache" "$(dirname "$out")"
: > "$out"
log="$out.log"
: > "$log"
gaps=("14 35" "29 40")

run_gaps() {  # dataset folder
  for g in "${gaps[@]}"; do
    read -r last resume <<< "$g"
    if ! "$jump" "$1" --last "$last" --resume "$resume" ${settings[@]+"${settings[@]}"} 2>> "$log" | tee -a "$out"; then
      echo "$1 gap $((last + 1))-$((resume - 1)): FAILED (see $log)" | tee -a "$out"
    fi
  done
}

if [ "$real" = 1 ]; then
  for d in "$data"/kitti/odometry/sequences/*/ "$data"/kitti/raw*/*/*_sync/; do
    [ -d "$d" ] && [ "$(ls "$d"/image_0/ "$d"/image_00/data/ 2> /dev/null | grep -c '\.png$')" -ge 45 ] && run_gaps "${d%/}"
  done
fi
if [ "$sim" = 1 ]; then
  listing="$("$rgbl" demo --scenario list)"
  [ -n "$scenarios" ] || scenarios="$(awk 'NF && $1 !~ /:$/ {print $1}' <<< "$listing")"
  key="$(scenario_key "$repo")"
  for s in $scenarios; do
    n="$(scenario_length "$listing" "$s")"
    for seed in $seeds; do
      dataset="$(scenario_dataset "$rgbl" "$cache" "$key" "$s" "$seed" "$n" "$log")" \
        || { echo "$s seed $seed: generation FAILED (see $log)" | tee -a "$out"; continue; }
      run_gaps "$dataset"
    done
  done
fi
echo "table: $out"
