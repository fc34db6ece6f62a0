#!/usr/bin/env bash
# The real drives at low frame rates: every real excerpt of 30 frames or more tracked from frame 0 and 3 at every
# --step 2..12 (10 Hz down to 0.8 Hz), by two builds, one line per run with both ATEs and whether the
# two trajectories are byte-identical. Tracking changes that touch the LiDAR's say or the step checks
# are judged on these runs too (docs/accuracy.md).
#
#   scripts/step-runs.sh --a BUILD_DIR --b BUILD_DIR [--out DIR] [--steps "2 3 ..."] [--firsts "0 3"]
#                        [--a-config FILE] [--b-config FILE]
#
# --a-config / --b-config: a settings YAML passed as `rgbl run --config` to that side's runs, so one
# build can be compared with itself under another option (the same build for --a and --b).
# Real data from $RGBL_DATA (default ../shared/data); prints "skipped: no data" without it.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
a=""
b=""
out="$repo/build/step-runs"
steps="2 3 4 5 6 7 8 9 10 11 12"
firsts="0 3"
a_config=""
b_config=""
while [ $# -gt 0 ]; do
  case "$1" in
    --a) a="$2"; shift 2 ;;
    --b) b="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --steps) steps="$2"; shift 2 ;;
    --firsts) firsts="$2"; shift 2 ;;
    --a-config) a_config="$2"; shift 2 ;;
    --b-config) b_config="$2"; shift 2 ;;
    -h|--help) sed -n '2,13p' "$0"; exit 0 ;;
    *) echo "step-runs: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[ -n "$a" ] && [ -n "$b" ] || { echo "step-runs: give both builds, --a DIR --b DIR" >&2; exit 2; }
for build in "$a" "$b"; do
  [ -x "$build/bin/rgbl" ] || { echo "step-runs: $build/bin/rgbl not built" >&2; exit 2; }
done
for f in "$a_config" "$b_config"; do
  [ -z "$f" ] || [ -r "$f" ] || { echo "step-runs: cannot read the settings file '$f'" >&2; exit 2; }
done
data="${RGBL_DATA:-$repo/../shared/data}"
[ -d "$data/kitti" ] || { echo "skipped: no data ($data/kitti absent; set RGBL_DATA)"; exit 0; }
drives=()
for seq in "$data"/kitti/odometry/sequences/*/; do [ -d "$seq" ] && drives+=("${seq%/}"); done
for drive in "$data"/kitti/raw*/*/*_sync/; do [ -d "$drive" ] && drives+=("${drive%/}"); done
mkdir -p "$out"
ate() {  # summary.json -> ATE RMSE in m, or the reason there is none
  [ -f "$1" ] || { echo "failed"; return; }
  grep -o '"ate_rmse_m": [-0-9.e]*' "$1" | head -1 | awk '{printf "%.3f", $2}'
}
printf '%-44s %8s %8s  %s\n' "run" "A ATE m" "B ATE m" "trajectories"
for drive in "${drives[@]}"; do
  # a 10-frame excerpt has no low-rate run worth the name
  [ "$(ls "$drive"/image_0/ "$drive"/image_00/data/ 2> /dev/null | grep -c '\.png$')" -ge 30 ] || continue
  name="$(basename "$(dirname "$drive")")-$(basename "$drive")"
  for first in $firsts; do
    for step in $steps; do
      run="$name-first$first-step$step"
      for side in a b; do
        build="$a"
        config="$a_config"
        [ "$side" = b ] && build="$b" && config="$b_config"
        extra=()
        [ -z "$config" ] || extra=(--config "$config")
        rm -rf "$out/$side/$run"
        "$build/bin/rgbl" -q run "$drive" --first "$first" --step "$step" --out "$out/$side/$run" "${extra[@]}" \
            > "$out/$side-$run.log" 2>&1 || true
      done
      same="differ"
      cmp -s "$out/a/$run/trajectory_kitti.txt" "$out/b/$run/trajectory_kitti.txt" && same="identical"
      printf '%-44s %8s %8s  %s\n' "$run" "$(ate "$out/a/$run/summary.json")" "$(ate "$out/b/$run/summary.json")" "$same"
    done
  done
done
