#!/usr/bin/env bash
# Regenerates tests/golden/<scene>.csv from short runs of every shipped scene. The golden
# regression test compares against these files; run this only when a change of results is
# intended, and say why in the commit.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
DRAPE="$BUILD_DIR/app/drape"
# OpenBLAS picks its kernels for the processor, and CHOLMOD's supernodal factorisation calls
# them: pinned to the Nehalem kernels (any x86-64-v2 processor), as the golden test runs, so the
# files hold the same bits on every machine (tests/app/drape_process.h, REPRODUCIBLE_BLAS).
export OPENBLAS_CORETYPE=Nehalem
declare -A FRAMES=([drape_sphere]=12 [hanging]=15 [flag]=10 [cloth_fold]=10 [mesh_obstacle]=8 [fast_drop]=3 [pile]=2 [tablecloth]=4 [cusick_drape]=2 [cantilever]=20)
mkdir -p tests/golden
for scene in scenes/*.json; do
  name=$(basename "$scene" .json)
  frames=${FRAMES[$name]:-10}
  out=$(mktemp -d)
  "$DRAPE" run "$scene" --quiet --frames "$frames" --out "$out"
  cp "$out/stats.csv" "tests/golden/$name.csv"
  rm -rf "$out"
  echo "tests/golden/$name.csv: $frames frames"
done
