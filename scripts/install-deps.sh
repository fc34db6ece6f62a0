#!/usr/bin/env bash
# Installs rgbl's build dependencies from Debian 12's packages. Idempotent: installs only what is
# missing, and does nothing (not even apt-get update) when everything is there.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev                               # Eigen 3.4
  libopencv-dev                               # OpenCV 4.6
  libpng-dev libjpeg62-turbo-dev              # image files (src/io/image.cpp; OpenCV's imgcodecs only in tests)
  libceres-dev                                # Ceres 2.1 (brings SuiteSparse)
  libspdlog-dev libfmt-dev                    # spdlog 1.10 on the external fmt 9
  catch2                                      # Catch2 2.13
  libbenchmark-dev                            # Google Benchmark 1.7
  libcli11-dev                                # CLI11
  nlohmann-json3-dev                          # JSON (summary.json, the accuracy suite's table)
  pybind11-dev python3-dev python3-numpy      # the Python module (python/)
  python3-pytest                              # its tests
)
# matplotlib is only for examples/python (python3-matplotlib), never needed to build or test
# fuzzing (scripts/fuzz.sh) needs clang with its libFuzzer/sanitizer runtimes
if [ "${RGBL_FUZZ:-0}" = "1" ]; then
  packages+=(clang-14 libclang-rt-14-dev)
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all build dependencies are installed"
  exit 0
fi

sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install-deps: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  sudo_cmd=(sudo)
fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
