#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (ASan + UBSan) and runs each for a bounded time on a scratch
# copy of its corpus in fuzz/corpus/<name> (the repo's corpus stays small and unchanged).
# Usage: scripts/fuzz.sh [seconds per target, default 60]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
RGBL_FUZZ=1 ./scripts/install-deps.sh
cmake --preset fuzz
cmake --build --preset fuzz
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
status=0
for fuzzer in build/fuzz/bin/fuzz_*; do
  name="$(basename "$fuzzer")"; name="${name#fuzz_}"
  mkdir -p "$scratch/$name"
  cp -r "fuzz/corpus/$name/." "$scratch/$name/" 2>/dev/null || true
  echo "fuzz: $name for ${seconds}s"
  if ! "$fuzzer" "$scratch/$name" -max_total_time="$seconds" -rss_limit_mb=4096 -timeout=10 \
       -artifact_prefix="$scratch/crash-$name-" > "$scratch/$name.log" 2>&1; then
    echo "fuzz: $name FAILED"; tail -40 "$scratch/$name.log"
    for a in "$scratch"/crash-"$name"-*; do [ -e "$a" ] && { echo "reproducer: $a"; xxd "$a" | head -20; }; done
    status=1
  else
    grep -E "^Done [0-9]+ runs" "$scratch/$name.log" || true
  fi
done
exit $status
