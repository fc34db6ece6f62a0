#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (ASan + UBSan) and runs each for a bounded time on a scratch
# copy of its corpus in fuzz/corpus/<name> (the repo's corpus stays small and unchanged).
# Usage: scripts/fuzz.sh [seconds per target, default 60]; RGBL_FUZZ_JOBS targets at a time (default: the cores)
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
# One libFuzzer process per core at a time (each is single-threaded); the results are reported in
# the targets' order once all have run.
parallel="${RGBL_FUZZ_JOBS:-$(nproc)}"
case "$parallel" in
  ''|*[!0-9]*|0) echo "fuzz: RGBL_FUZZ_JOBS takes a whole number >= 1, got '$parallel'" >&2; exit 2 ;;
esac
RGBL_FUZZ=1 ./scripts/install-deps.sh
cmake --preset fuzz
cmake --build --preset fuzz
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
run_one() {
  local fuzzer="$1" name="$2"
  if "$fuzzer" "$scratch/$name" -max_total_time="$seconds" -rss_limit_mb=4096 -timeout=10 \
       -artifact_prefix="$scratch/crash-$name-" > "$scratch/$name.log" 2>&1; then
    echo 0 > "$scratch/$name.status"
  else
    echo 1 > "$scratch/$name.status"
  fi
}
names=()
for fuzzer in build/fuzz/bin/fuzz_*; do
  name="$(basename "$fuzzer")"; name="${name#fuzz_}"
  names+=("$name")
  mkdir -p "$scratch/$name"
  cp -r "fuzz/corpus/$name/." "$scratch/$name/" 2>/dev/null || true
  while [ "$(jobs -rp | wc -l)" -ge "$parallel" ]; do wait -n || true; done
  echo "fuzz: $name for ${seconds}s"
  run_one "$fuzzer" "$name" &
done
wait
status=0
for name in "${names[@]}"; do
  if [ "$(cat "$scratch/$name.status" 2>/dev/null || echo 1)" != 0 ]; then
    echo "fuzz: $name FAILED"; tail -40 "$scratch/$name.log"
    for a in "$scratch"/crash-"$name"-*; do [ -e "$a" ] && { echo "reproducer: $a"; xxd "$a" | head -20; }; done
    status=1
  else
    echo -n "fuzz: $name: "; grep -E "^Done [0-9]+ runs" "$scratch/$name.log" || echo "done"
  fi
done
exit $status
