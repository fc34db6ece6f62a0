#!/usr/bin/env bash
# The simulator loops of docs/loop-closing.md, tracked three ways: without loop closing, with the
# defaults, and with a settings file of your choice (default: LoopClosing.GlobalBA: 1).
# Usage: scripts/loop-table.sh [settings.yaml]   (after a release build; datasets cached in build/loops)
set -euo pipefail
cd "$(dirname "$0")/.."
rgbl=build/release/bin/rgbl
[ -x "$rgbl" ] || { echo "loop-table: build first: cmake --preset release && cmake --build build/release" >&2; exit 1; }
work=build/loops
mkdir -p "$work"
config="${1:-}"
if [ -z "$config" ]; then
  config="$work/global_ba.yaml"
  printf '%%YAML:1.0\nLoopClosing.GlobalBA: 1\n' > "$config"
fi
# name frames laps seed
loops=("400x1-s1 400 1 1" "800x2-s1 800 2 1" "80x1-s1 80 1 1" "80x1-s2 80 1 2" "80x1-s3 80 1 3"
       "160x2-s1 160 2 1" "160x2-s2 160 2 2" "160x2-s3 160 2 3" "201x2-s1 201 2 1")
ate() { grep -o '"ate_rmse_m": [0-9.e+-]*' "$1/summary.json" | head -1 | awk '{print $2}'; }
closures() { grep -o '"closures": [0-9]*' "$1/summary.json" | awk '{print $2}'; }
echo "| loop | no loop closing | default | $(basename "$config") |"
echo "|---|---|---|---|"
for entry in "${loops[@]}"; do
  read -r name frames laps seed <<< "$entry"
  data="$work/$name"
  if [ ! -f "$data/poses/00.txt" ]; then
    rm -rf "$data"
    "$rgbl" -q demo --path loop --frames "$frames" --laps "$laps" --seed "$seed" --keep "$data" \
            --out "$work/$name-demo" > /dev/null
  fi
  row="| $name"
  for mode in none default config; do
    case $mode in
      none) args=(--no-loop-closing) ;;
      default) args=() ;;
      config) args=(--config "$config") ;;
    esac
    "$rgbl" -q run "$data/sequences/00" "${args[@]}" --out "$work/$name-$mode" > /dev/null 2>&1
    row="$row | $(ate "$work/$name-$mode") ($(closures "$work/$name-$mode"))"
  done
  echo "$row |"
done
