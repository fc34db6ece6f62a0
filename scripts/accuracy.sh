#!/usr/bin/env bash
# The accuracy suite (docs/accuracy.md): every real KITTI excerpt found in the data folder and every
# simulator scenario with several seeds, tracked with default settings; one table (ATE, drift, RPE,
# fewest inliers on an ok frame, weak and lost frames, keyframes per 100 frames, median ms) and the
# difference to a saved baseline. Judge every tracking change on the whole table.
#
#   scripts/accuracy.sh [--build DIR] [--out DIR] [--seeds "1 2 3"] [--frames N] [--scenarios "a b"]
#                       [--baseline FILE | --no-baseline] [--save-baseline FILE] [--no-real] [--no-variants] [--no-sim]
#                       [--exact-depth] [-- ARGS for rgbl run, e.g. --threaded --realtime]
#
# --exact-depth: the scenarios only, each tracked on the simulator's exact depth images instead of its
# LiDAR (`--depth precomputed:<street>/depth`); set against the default table, it tells how much of a
# scenario's error the LiDAR's depth carries (compare with --no-baseline: the baseline is the LiDAR's).
#
# Each scenario runs at its default length (`rgbl demo --scenario list`) unless --frames is given; the
# plain street runs at every length used (`plain@<frames>-s<seed>`), so each scenario's ATE is compared
# with the plain street's at the same frame count and seed.
# Each real drive of at least 30 frames also runs as harder variants of itself: at 3.3 and 1.7 Hz
# (--step 3, --step 6), with a forward-driving camera's motion blur (60 per mille: 37 px at the side
# edges), with exposure jumps (+-30 %), blurred at 3.3 Hz, and with a sparser LiDAR: every second ring
# of the HDL-64 (a 32-ring sensor) and every fourth (16 rings) (scripts/degrade.py, which needs Debian's
# python3-opencv; those rows are skipped without it). The ground truth stays real.
# Data: $RGBL_DATA, else ../shared/data next to the repository. Generated scenarios are cached in
# $RGBL_CACHE (default ~/.cache/rgbl/scenarios), keyed by the simulator's sources, so a rerun after a
# tracker change only tracks.
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# shellcheck source=lib/scenario-cache.sh
source "$repo/scripts/lib/scenario-cache.sh"
build="$repo/build/release"
out="$repo/build/accuracy"
seeds="1 2 3"
frames=""   # empty: each scenario at its own default length
scenarios=""
baseline="$repo/docs/accuracy-baseline.json"
save=""
real=1
variants=1
sim=1
exact=""
extra=()
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --seeds) seeds="$2"; shift 2 ;;
    --frames) frames="$2"; shift 2 ;;
    --scenarios) scenarios="$2"; shift 2 ;;
    --baseline) baseline="$2"; shift 2 ;;
    --no-baseline) baseline=""; shift ;;
    --save-baseline) save="$2"; shift 2 ;;
    --no-real) real=0; shift ;;
    --no-variants) variants=0; shift ;;
    --no-sim) sim=0; shift ;;
    --exact-depth) exact=exact; real=0; shift ;;
    --) shift; extra=("$@"); break ;;
    -h|--help) awk 'NR > 1 && !/^#/ { exit } NR > 1' "$0"; exit 0 ;;
    *) echo "accuracy.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done

rgbl="$build/bin/rgbl"
table="$build/bin/rgbl_accuracy_table"
for b in "$rgbl" "$table"; do
  [ -x "$b" ] || { echo "accuracy.sh: $b not built (cmake --preset release && cmake --build build/release)" >&2; exit 1; }
done
data="${RGBL_DATA:-$repo/../shared/data}"
cache="${RGBL_CACHE:-$HOME/.cache/rgbl/scenarios}"
rm -rf "$out"
mkdir -p "$out/runs" "$cache"
log="$out/log.txt"
: > "$log"

track() {  # name, then rgbl arguments
  local name="$1"; shift
  echo "== $name: rgbl $*" >> "$log"
  if "$rgbl" -q "$@" --out "$out/runs/$name" >> "$log" 2>&1; then
    printf '  %-28s %s\n' "$name" "$(grep -h -o 'ATE RMSE [0-9.]* m' "$log" | tail -1)"
  else
    printf '  %-28s FAILED (see %s)\n' "$name" "$log"
  fi
}

[ -n "$exact" ] && echo "exact depth: the scenarios on the simulator's depth images, no real drives"
if [ "$real" = 1 ]; then
  if [ -d "$data/kitti" ]; then
    echo "real excerpts in $data/kitti:"
    drives=()   # "name folder"
    for seq in "$data"/kitti/odometry/sequences/*/; do
      [ -d "$seq" ] && drives+=("real-odometry-$(basename "$seq") ${seq%/}")
    done
    for drive in "$data"/kitti/raw*/*/*_sync/; do
      [ -d "$drive" ] || continue
      set_name="$(basename "$(dirname "$(dirname "$drive")")")"   # raw or raw_extended
      id="$(basename "$drive" | sed -E 's/.*_drive_([0-9]+)_sync/\1/')"
      drives+=("real-$set_name-$id ${drive%/}")
    done
    for d in "${drives[@]}"; do
      read -r name folder <<< "$d"
      track "$name" run "$folder" "${extra[@]}"
    done
    if [ "$variants" = 1 ]; then
      have_cv=1
      /usr/bin/python3 -c "import cv2" 2> /dev/null || have_cv=0
      [ "$have_cv" = 1 ] || echo "  (blurred, exposure and sparse-LiDAR variants skipped: scripts/degrade.py needs python3-opencv)"
      degrade_key="$(sha1sum < "$repo/scripts/degrade.py" | cut -c1-12)"
      for d in "${drives[@]}"; do
        read -r name folder <<< "$d"
        [ "$(ls "$folder"/image_0/ "$folder"/image_00/data/ 2> /dev/null | grep -c '\.png$')" -ge 30 ] || continue
        track "$name-step3" run "$folder" --step 3 "${extra[@]}"
        track "$name-step6" run "$folder" --step 6 "${extra[@]}"
        [ "$have_cv" = 1 ] || continue
        for v in "blur60 --blur 60" "gain30 --gain 0.3" "rings32 --rings 2" "rings16 --rings 4"; do
          read -r vname vargs <<< "$v"
          # the copy keeps the layout: sequences/NN (poses two levels up) or <date>/<drive> (calibration one up)
          root="$cache/degraded/$name-$vname-$degrade_key"
          copy="$root/$(basename "$(dirname "$folder")")/$(basename "$folder")"
          if [ ! -f "$root/.complete" ]; then
            rm -rf "$root"
            "$repo/scripts/degrade.py" "$folder" "$copy" $vargs >> "$log" 2>&1 && touch "$root/.complete" ||
              { printf '  %-28s degrading FAILED\n' "$name-$vname"; continue; }
          fi
          track "$name-$vname" run "$copy" "${extra[@]}"
          [ "$vname" = blur60 ] && track "$name-$vname-step3" run "$copy" --step 3 "${extra[@]}"
        done
      done
    fi
  else
    echo "skipped: no data ($data/kitti absent; set RGBL_DATA)"
  fi
fi

if [ "$sim" = 1 ]; then
  listing="$("$rgbl" demo --scenario list)"
  [ -n "$scenarios" ] || scenarios="$(awk 'NF && $1 !~ /:$/ {print $1}' <<< "$listing")"
  scenarios="$(echo $scenarios)"   # one line, single spaces
  length_of() {  # a scenario's frame count: --frames, else its default from the listing
    if [ -n "$frames" ]; then echo "$frames"; return; fi
    scenario_length "$listing" "$1"
  }
  key="$(scenario_key "$repo")"
  echo "scenarios (seeds $seeds; cache $cache, key $key):"
  runs=()   # "name scenario frames"
  plain_default="$(length_of plain)"
  lengths=""
  for s in $scenarios; do
    n="$(length_of "$s")"
    [ -n "$n" ] || { echo "accuracy.sh: no default length for scenario '$s'" >&2; exit 1; }
    runs+=("$s $s $n")
    lengths="$lengths $n"
  done
  for n in $(tr ' ' '\n' <<< "$lengths" | sort -un); do
    [ "$n" = "$plain_default" ] && [[ " $scenarios " == *" plain "* ]] && continue
    runs+=("plain@$n plain $n")
  done
  for run in "${runs[@]}"; do
    read -r name s n <<< "$run"
    for seed in $seeds; do
      dataset="$(scenario_dataset "$rgbl" "$cache" "$key" "$s" "$seed" "$n" "$log" "$exact")" \
        || { printf '  %-28s generation FAILED\n' "$name-s$seed"; continue; }
      depth=()
      [ -n "$exact" ] && depth=(--depth "precomputed:$dataset/depth")
      track "$name-s$seed" run "$dataset" "${depth[@]}" "${extra[@]}"
    done
  done
fi

echo
table_args=("$out/runs")
[ -n "$baseline" ] && [ -f "$baseline" ] && table_args+=(--baseline "$baseline")
[ -n "$save" ] && table_args+=(--save-baseline "$save")
"$table" "${table_args[@]}" | tee "$out/table.md"
echo
echo "table in $out/table.md, logs in $log"
