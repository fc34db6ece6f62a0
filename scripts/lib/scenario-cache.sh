# Shared by scripts/accuracy.sh and scripts/jump-table.sh (sourced): the simulator's scenarios as
# datasets on disk, cached under a key of everything that shapes a written street.

# scenario_key REPO: the cache key (the simulator, the demo's options, the image writers).
scenario_key() {
  cat "$1"/src/sim/* "$1"/include/rgbl/sim/* "$1"/apps/rgbl/demo_command.cpp "$1"/src/pipeline/demo.cpp \
    "$1"/include/rgbl/pipeline/demo.hpp "$1"/src/io/file_sequence.cpp | sha1sum | cut -c1-12
}

# scenario_length LISTING NAME: a scenario's default frame count from `rgbl demo --scenario list`.
scenario_length() {
  awk -v s="$2" '$1 == s { if (match($0, /default [0-9]+ frames/)) print substr($0, RSTART + 8, RLENGTH - 15) }' <<< "$1"
}

# scenario_dataset RGBL CACHE KEY SCENARIO SEED FRAMES LOG [exact]: renders the scenario into the cache
# unless it is there, and prints its dataset folder (sequences/00); returns 1 when rendering failed.
# The street is written with the simulator's exact depth images (sequences/00/depth, `rgbl demo --depth
# precomputed`; the images, scans and poses are the same bytes either way); with `exact`, a cached
# street from before that is rendered again to get them.
scenario_dataset() {
  local rgbl="$1" cache="$2" key="$3" s="$4" seed="$5" n="$6" log="$7" exact="${8:-}"
  local dir="$cache/$s-s$seed-f$n-$key"
  if [ ! -f "$dir/.complete" ] || { [ -n "$exact" ] && [ ! -d "$dir/sequences/00/depth" ]; }; then
    rm -rf "$dir"
    echo "== generate $s seed $seed, $n frames" >> "$log"
    local tmp
    tmp="$(mktemp -d)"
    "$rgbl" -q demo --scenario "$s" --seed "$seed" --frames "$n" --depth precomputed --keep "$dir" --out "$tmp" >> "$log" 2>&1 \
      && touch "$dir/.complete" || { rm -rf "$tmp"; return 1; }
    rm -rf "$tmp"
  fi
  echo "$dir/sequences/00"
}
