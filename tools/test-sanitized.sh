#!/usr/bin/env bash
# Builds drape with AddressSanitizer and UndefinedBehaviorSanitizer (Debug, -O1) in
# ${BUILD_DIR:-build-sanitized} and runs the whole test suite under them. Any report fails.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/install-deps.sh
BUILD_DIR=${BUILD_DIR:-build-sanitized}
# The Debug type's debug information is line tables only (CMAKE_CXX_FLAGS_DEBUG=-g1, in place
# of -g): the reports keep their files and lines, and GCC's variable tracking over the CCD
# kernels' four instruction sets, which took kernels_batch.cpp alone over 20 minutes to
# compile, is not done (7.5 minutes with -g1, the same as without debug information).
FLAGS="-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer -O1"
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG=-g1 -DDRAPE_BUILD_BENCH=OFF \
  -DCMAKE_CXX_FLAGS="$FLAGS" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" >/dev/null
cmake --build "$BUILD_DIR" -j"${JOBS:-2}"
# Leaks are checked too, except inside Mesa's llvmpipe (OSMesa), whose JIT keeps allocations
# for the process's life.
export ASAN_OPTIONS=${ASAN_OPTIONS:-"detect_leaks=1:abort_on_error=0"}
export LSAN_OPTIONS=${LSAN_OPTIONS:-"suppressions=$PWD/tools/lsan.supp"}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-"print_stacktrace=1:halt_on_error=1"}
# The whole-scene energy runs (tests/core/test_energy.cpp: mesh_obstacle's 60 frames, a
# tablecloth's 45, a piling ribbon's 25) take several minutes under the sanitizers and exercise
# no code the other tests do not; the README's test command runs them.
ctest --test-dir "$BUILD_DIR" -j"${JOBS:-2}" --output-on-failure -E 'Energy[.](TheMeshObstacleScene|ATablecloth|ARibbonPiling)'
