#!/usr/bin/env bash
# Installs missing Debian packages, then configures and builds drape (Release) in ${BUILD_DIR:-build}.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-deps.sh
BUILD_DIR=${BUILD_DIR:-build}
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=${BUILD_TYPE:-Release} >/dev/null
cmake --build "$BUILD_DIR" -j"${JOBS:-2}"
