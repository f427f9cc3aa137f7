#!/usr/bin/env bash
# The cost of the hinge bending model beside the bending springs (issue 20's target: the step
# within 25 % of the spring model's at the same resolution), in one run: the default scene
# (scenes/drape_sphere.json, 40 x 40 quads, self-collision) with three materials, run in turn,
# PAIRS times each (alternating, so that a shared machine's load falls on all alike):
#   springs:  the scene's former material, stretch 2000 N, shear 200 N, bend springs 0.5 N;
#   hinges:   the same stretch and shear springs, bending on hinges (bending_rigidity 1e-5 N m);
#   preset:   the scene as shipped (white-dots-on-blk: the fabric's springs and hinges).
# Prints each run's ms a frame (its wall time over its frames) and, per material, the median
# of those and its ratio to the springs' median.
# Usage: bench/bending_speed.sh [BUILD_DIR] [OUT]; FRAMES (30) and PAIRS (3) from the environment.
set -uo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${1:-build}
OUT=${2:-out/bending_speed}
DRAPE="$BUILD_DIR/app/drape"
FRAMES=${FRAMES:-30}
PAIRS=${PAIRS:-3}
[[ "$PAIRS" =~ ^[1-9][0-9]*$ && "$FRAMES" =~ ^[1-9][0-9]*$ ]] || { echo "bending_speed.sh: expected PAIRS and FRAMES of 1 or more" >&2; exit 2; }
mkdir -p "$OUT"
declare -A MATERIAL=(
  [springs]='{"density": 0.15, "stretch": 2000, "shear": 200, "bend": 0.5, "damping": 0.002}'
  [hinges]='{"density": 0.15, "stretch": 2000, "shear": 200, "bending_rigidity": 1e-5, "damping": 0.002}'
  [preset]='{"preset": "white-dots-on-blk"}'
)
for name in springs hinges preset; do
  sed -E "s|\"material\": \{[^}]*\}|\"material\": ${MATERIAL[$name]}|" scenes/drape_sphere.json > "$OUT/$name.json"
done
declare -A TIMES
for pair in $(seq 1 "$PAIRS"); do
  for name in springs hinges preset; do
    start=$(date +%s%N)
    if ! "$DRAPE" run "$OUT/$name.json" --frames "$FRAMES" --quiet --overwrite --out "$OUT/$name"; then
      echo "$name: the run failed" >&2
      exit 1
    fi
    ms=$(awk -v a="$start" -v b="$(date +%s%N)" -v f="$FRAMES" 'BEGIN { printf "%.1f", (b - a) / 1e6 / f }')
    TIMES[$name]="${TIMES[$name]:-} $ms"
    echo "pair $pair, $name: $ms ms a frame"
  done
done
median() { tr ' ' '\n' | grep . | sort -g | awk '{ a[NR] = $1 } END { print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2 }'; }
base=$(echo "${TIMES[springs]}" | median)
printf "\n%-8s %12s %8s   (drape_sphere, %d frames, %d runs each)\n" material "ms a frame" ratio "$FRAMES" "$PAIRS"
for name in springs hinges preset; do
  m=$(echo "${TIMES[$name]}" | median)
  printf "%-8s %12s %8s\n" "$name" "$m" "$(awk -v a="$m" -v b="$base" 'BEGIN { printf "%.2fx", a / b }')"
done
