#!/usr/bin/env bash
# Builds drape with the CCD kernels and the spring pass for Highway's portable one-lane target alone (no SIMD
# instructions compiled: -DDRAPE_PORTABLE_KERNELS=ON) in ${BUILD_DIR:-build-portable} and runs the
# whole test suite, so the guarantees never rest on the SSE4, AVX2 or AVX-512 code paths.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-deps.sh
BUILD_DIR=${BUILD_DIR:-build-portable}
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release -DDRAPE_PORTABLE_KERNELS=ON -DDRAPE_BUILD_BENCH=OFF >/dev/null
cmake --build "$BUILD_DIR" -j"${JOBS:-2}"
ctest --test-dir "$BUILD_DIR" -j"${JOBS:-2}" --output-on-failure
