#!/usr/bin/env bash
# Full runs of every shipped scene with the vincent and the conservative CCD methods, each
# frame checked by the independent penetration check (--check, then drape check over the saved
# meshes). Prints one line per run: scene, method, seconds, frames with intersections.
# Long (several minutes): a benchmark, not a test. Usage: bench/penetration_runs.sh [BUILD_DIR] [OUT]
set -uo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${1:-build}
OUT=${2:-out/penetration_runs}
DRAPE="$BUILD_DIR/app/drape"
printf "%-14s %-13s %9s %8s %s\n" scene method seconds frames "drape check"
for method in vincent conservative; do
  for scene in scenes/*.json; do
    name=$(basename "$scene" .json)
    out="$OUT/$name-$method"
    start=$(date +%s%N)
    "$DRAPE" run "$scene" --ccd "$method" --check --quiet --out "$out"
    status=$?
    seconds=$(awk -v a="$start" -v b="$(date +%s%N)" 'BEGIN { printf "%.1f", (b - a) / 1e9 }')
    frames=$(($(wc -l < "$out/stats.csv") - 1))
    verdict=$("$DRAPE" check "$out" | tail -1)
    printf "%-14s %-13s %9.1f %8d %s (run status %d)\n" "$name" "$method" "$seconds" "$frames" "$verdict" "$status"
  done
done
