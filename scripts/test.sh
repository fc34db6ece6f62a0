#!/usr/bin/env bash
# The README's test command: installs what is missing, builds with warnings as errors and runs every
# test (unit, real-data when ../shared/data or $RGBL_DATA_DIR is there, the find_package consumer and the
# Python module's pytest suite).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
export CTEST_PARALLEL_LEVEL="${CTEST_PARALLEL_LEVEL:-$(nproc)}"
export CMAKE_BUILD_PARALLEL_LEVEL="${CMAKE_BUILD_PARALLEL_LEVEL:-$(nproc)}"
cmake --workflow --preset ci
