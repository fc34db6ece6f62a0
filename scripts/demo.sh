#!/usr/bin/env bash
# The README's first command: installs what is missing, builds the release preset and runs the main job
# on the embedded default: a synthetic street with exact ground truth (no dataset needed).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
cmake --preset release
cmake --build --preset release
./build/release/bin/rgbl demo "$@"
