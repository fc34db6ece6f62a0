#!/usr/bin/env bash
# Runs the test suite under AddressSanitizer + UndefinedBehaviorSanitizer (preset asan), and the
# threaded-mapping tests under ThreadSanitizer (preset tsan) when they exist.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
export CTEST_PARALLEL_LEVEL="${CTEST_PARALLEL_LEVEL:-$(nproc)}"
export CMAKE_BUILD_PARALLEL_LEVEL="${CMAKE_BUILD_PARALLEL_LEVEL:-$(nproc)}"
cmake --workflow --preset asan
if [ -d tests/tracking ]; then
  cmake --preset tsan
  cmake --build --preset tsan --target test_tracking
  ctest --preset tsan -L threaded
fi
