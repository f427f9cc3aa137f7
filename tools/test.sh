#!/usr/bin/env bash
# The README's second command: build drape and run the whole test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/build.sh
BUILD_DIR=${BUILD_DIR:-build}
ctest --test-dir "$BUILD_DIR" -j"${JOBS:-2}" --output-on-failure
