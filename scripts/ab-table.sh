#!/usr/bin/env bash
# Two builds compared over several samples of the accuracy suite, not over one. A tracking run is
# chaotic: a change that moves a few keypoints by a pixel sends a 51-frame drive to another of its
# outcomes, which differ by more than most changes do (docs/accuracy.md, "One table is one sample").
# Each sample runs the suite with another ORBextractor.nFeatures (default 1800 1900 2000 2100 2200);
# per run, the script prints both builds' mean ATE over the samples and how often B beat A.
#
#   scripts/ab-table.sh (--a BUILD_DIR | --a-saved PREFIX) --b BUILD_DIR [--features "1800 ... 2200"]
#                       [--out DIR] [--a-settings FILE] [--b-settings FILE]
#                       [-- ARGS for scripts/accuracy.sh, e.g. --no-variants --scenarios "traffic"]
#
# --a-settings / --b-settings: settings keys (lines of a settings YAML, e.g. Tracking.BoundedDepthError: 1)
# added to that side's runs, so one build can be compared with itself under another option.
# --a-saved PREFIX: side A's results are not run but read from PREFIX-<nFeatures>.json, saved by an
# earlier ab-table run (e.g. --a-saved /tmp/ab/cand/b: that run's B side), which halves the time of
# judging candidates against one main. They must come from the same suite arguments and samples; runs
# missing from either side are left out of the summary, which names them.
# Each build directory needs bin/rgbl and bin/rgbl_accuracy_table. With --no-variants one sample of
# one build took 1.1-2.2 min here (2 cores, a CI run beside it): about 18 min for the defaults.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
a=""
a_saved=""
b=""
features="1800 1900 2000 2100 2200"
a_settings=""
b_settings=""
out="$repo/build/ab"
suite=()
while [ $# -gt 0 ]; do
  case "$1" in
    --a) a="$2"; shift 2 ;;
    --a-saved) a_saved="$2"; shift 2 ;;
    --b) b="$2"; shift 2 ;;
    --features) features="$2"; shift 2 ;;
    --a-settings) a_settings="$2"; shift 2 ;;
    --b-settings) b_settings="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --) shift; suite=("$@"); break ;;
    -h|--help) sed -n '2,21p' "$0"; exit 0 ;;
    *) echo "ab-table: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
if [ -n "$a" ] && [ -n "$a_saved" ]; then echo "ab-table: give --a or --a-saved, not both" >&2; exit 2; fi
[ -n "$a$a_saved" ] && [ -n "$b" ] || { echo "ab-table: give both sides, --a DIR (or --a-saved PREFIX) --b DIR" >&2; exit 2; }
b="$(cd "$b" && pwd)"
builds=("$b")
if [ -n "$a" ]; then
  a="$(cd "$a" && pwd)"
  builds+=("$a")
else
  [ -z "$a_settings" ] || { echo "ab-table: --a-settings has no effect with --a-saved" >&2; exit 2; }
  for n in $features; do
    [ -r "$a_saved-$n.json" ] || { echo "ab-table: --a-saved: cannot read $a_saved-$n.json" >&2; exit 2; }
  done
fi
for build in "${builds[@]}"; do
  for tool in rgbl rgbl_accuracy_table; do
    [ -x "$build/bin/$tool" ] || { echo "ab-table: $build/bin/$tool not built" >&2; exit 2; }
  done
done
for f in "$a_settings" "$b_settings"; do
  [ -z "$f" ] || [ -r "$f" ] || { echo "ab-table: cannot read the settings file '$f'" >&2; exit 2; }
done
mkdir -p "$out"
for n in $features; do
  case "$n" in ''|*[!0-9]*) echo "ab-table: --features takes whole numbers, got '$n'" >&2; exit 2 ;; esac
  for side in a b; do
    if [ "$side" = a ] && [ -n "$a_saved" ]; then
      [ "$a_saved-$n.json" -ef "$out/a-$n.json" ] || cp "$a_saved-$n.json" "$out/a-$n.json"
      continue
    fi
    build="$a"
    settings="$a_settings"
    [ "$side" = b ] && build="$b" && settings="$b_settings"
    config="$out/$side-features-$n.yaml"
    printf '%%YAML:1.0\nORBextractor.nFeatures: %d\n' "$n" > "$config"
    # the side's own keys, without their file's YAML header
    [ -z "$settings" ] || grep -v '^%YAML' "$settings" >> "$config"
    echo "ab-table: nFeatures $n, build $side ($build)"
    # each sample's figures are saved for the summary
    "$repo/scripts/accuracy.sh" --build "$build" --out "$out/$side-$n" --no-baseline \
        --save-baseline "$out/$side-$n.json" "${suite[@]}" -- --config "$config" > "$out/$side-$n.log" 2>&1 ||
      { echo "ab-table: the suite failed, see $out/$side-$n.log" >&2; exit 1; }
  done
done
# shellcheck disable=SC2086  # the sample list is split on purpose
python3 "$repo/scripts/ab_table.py" "$out" $features | tee "$out/summary.md"
