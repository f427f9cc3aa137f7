#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (AddressSanitizer, UBSan, coverage) in
# ${BUILD_DIR:-build-fuzz} and runs each (the scene parser, the query-file parser, the mesh
# reader: OBJ and PLY through assimp, the run folder's OBJ frame reader), seeded with the shipped scenes, query files and meshes:
# ${FUZZ_RUNS:-100000} inputs from a fixed seed (repeatable, as CI runs it), or for
# FUZZ_SECONDS seconds per target when that is set (exploration, a new seed each time).
#   bash tools/fuzz.sh            # CI: 100,000 inputs a parser, 25,000 for the mesh reader; a few minutes
#   bash tools/fuzz.sh --long     # the benchmark-length run: 10 minutes a target (FUZZ_SECONDS=600)
# A crash leaves its input in tests/data/fuzz-regressions/ (fix it, keep the file: tests replay
# every file there through the parsers).
set -euo pipefail
cd "$(dirname "$0")/.."
if [ "${1:-}" = "--long" ]; then FUZZ_SECONDS=${FUZZ_SECONDS:-600}; fi
bash tools/install-deps.sh
BUILD_DIR=${BUILD_DIR:-build-fuzz}
if [ -n "${FUZZ_SECONDS:-}" ]; then LIMIT="-max_total_time=$FUZZ_SECONDS"; else LIMIT="-runs=${FUZZ_RUNS:-100000} -seed=20261122"; fi
# The Debug type's debug information is line tables only (CMAKE_CXX_FLAGS_DEBUG below), as in
# test-sanitized.sh: a crash's stack keeps its files and lines.
FLAGS="-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all -O1"
# The CCD kernels for Highway's portable target alone: the fuzzers test the readers, and clang
# 14 with the fuzzer's instrumentation and ASan took over 45 minutes of CPU on the kernels'
# four instruction sets (kernels_batch.cpp alone), where GCC's sanitized build takes a minute.
CC=clang CXX=clang++ cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG=-gline-tables-only -DDRAPE_BUILD_TESTS=OFF -DDRAPE_BUILD_BENCH=OFF \
  -DDRAPE_PORTABLE_KERNELS=ON -DDRAPE_BUILD_FUZZERS=ON -DCMAKE_CXX_FLAGS="$FLAGS" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" >/dev/null
cmake --build "$BUILD_DIR" -j"${JOBS:-2}" --target fuzz_scene fuzz_query_file fuzz_mesh fuzz_frame
export ASAN_OPTIONS=${ASAN_OPTIONS:-"detect_leaks=0"}
mkdir -p tests/data/fuzz-regressions "$BUILD_DIR/corpus/scene" "$BUILD_DIR/corpus/query_file" "$BUILD_DIR/corpus/mesh" "$BUILD_DIR/corpus/frame"
cp scenes/*.json "$BUILD_DIR/corpus/scene/"
cp tests/data/ccd-queries/unit-tests/*/*.csv "$BUILD_DIR/corpus/query_file/" 2>/dev/null || true
# The mesh fuzzer's first byte picks the reader (even: OBJ, odd: PLY), the rest is the file.
for mesh in scenes/meshes/*.obj; do
  { printf '\000'; cat "$mesh"; } > "$BUILD_DIR/corpus/mesh/$(basename "$mesh")"
done
{ printf '\001'; printf 'ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n'
  printf 'element face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n'
} > "$BUILD_DIR/corpus/mesh/square.ply"
# The frame fuzzer's first byte picks the grid (resolution 1 + b % 4 by 1 + b / 4 % 4).
printf '\000v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n' > "$BUILD_DIR/corpus/frame/square.obj"
printf '\000v -0.5 -0.5 1e6\nv 0.5 -0.5 1e6\nv 0.5 0.5 1e6\nv -0.5 0.5 1e6\nf 1/1 2/2 3/3\nf -4 -2 -1\n' > "$BUILD_DIR/corpus/frame/far.obj"
for target in scene query_file mesh frame; do
  # assimp reads a mesh a hundred times slower than drape parses a scene: the mesh fuzzer's
  # inputs are kept to 8 KiB and its CI share to a quarter of the runs.
  max_len=65536
  limit=$LIMIT
  if [ "$target" = mesh ]; then
    max_len=8192
    [ -z "${FUZZ_SECONDS:-}" ] && limit="-runs=$(( ${FUZZ_RUNS:-100000} / 4 )) -seed=20261122"
  fi
  echo "fuzzing the $target reader ($limit)"
  # shellcheck disable=SC2086
  "$BUILD_DIR/tests/fuzz/fuzz_$target" $limit -max_len=$max_len -rss_limit_mb=4096 -timeout=10 \
    -artifact_prefix=tests/data/fuzz-regressions/"$target"- "$BUILD_DIR/corpus/$target" > "$BUILD_DIR/fuzz_$target.log" 2>&1 \
    || { tail -30 "$BUILD_DIR/fuzz_$target.log"; echo "fuzz_$target found a crash: see tests/data/fuzz-regressions/"; exit 1; }
  tail -1 "$BUILD_DIR/fuzz_$target.log"
done
