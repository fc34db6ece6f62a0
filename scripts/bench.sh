#!/usr/bin/env bash
# Builds the release preset and runs every microbenchmark: each kernel as <kernel>/rgbl next to
# <kernel>/reference in the same run, 10 repetitions, medians reported. Pin to one core for the
# single-core figures: `taskset -c 1 ./scripts/bench.sh`. Extra arguments go to rgbl_bench
# (e.g. --benchmark_filter=projection).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
cmake --preset release > /dev/null
cmake --build --preset release --target rgbl_bench
exec ./build/release/bin/rgbl_bench --benchmark_repetitions=10 --benchmark_report_aggregates_only=true \
  --benchmark_display_aggregates_only=true "$@"
