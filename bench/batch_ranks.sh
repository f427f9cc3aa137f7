#!/usr/bin/env bash
# drape batch on one process beside two MPI ranks (mpirun -np 2, one narrow-phase thread per
# run), on the same manifest of independent runs whose costs differ by about 10x: short and
# long hanging cloths, the flag, the fold, the box. Each repeat runs both into fresh folders,
# alternately; prints the seconds of each, their medians and the median of the pairs' ratios
# (the target is at most 0.6 on a 2-core machine) and checks that the two tables agree except
# for their time columns.
# Usage: bench/batch_ranks.sh [BUILD_DIR] [OUT] [REPEATS]
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${1:-build}
OUT=${2:-out/batch_ranks}
REPEATS=${3:-3}
DRAPE="$(pwd)/$BUILD_DIR/app/drape"
command -v mpirun >/dev/null || { echo "batch_ranks: mpirun is missing (bash tools/install-deps.sh)" >&2; exit 2; }
rm -rf "$OUT"
mkdir -p "$OUT"
manifest="$OUT/runs.csv"
{
  echo "scene,frames,out"
  for frames in 10 20 40 80; do echo "$(pwd)/scenes/hanging.json,$frames,hanging_$frames"; done
  echo "$(pwd)/scenes/flag.json,30,flag"
  echo "$(pwd)/scenes/cloth_fold.json,20,cloth_fold"
  echo "$(pwd)/scenes/mesh_obstacle.json,20,mesh_obstacle"
  echo "$(pwd)/scenes/drape_sphere.json,20,drape_sphere"
} > "$manifest"
# Root may start mpirun only when it says so.
MPIRUN=(mpirun --oversubscribe -np 2)
[ "$(id -u)" -eq 0 ] && MPIRUN+=(--allow-run-as-root)
seconds() { local a b; a=$(date +%s%N); "$@" > /dev/null 2>&1 || [ $? -eq 1 ]; b=$(date +%s%N); awk -v a="$a" -v b="$b" 'BEGIN { printf "%.2f", (b - a) / 1e9 }'; }
printf "%-7s %10s %10s %7s\n" repeat "1 process" "2 ranks" ratio
serial=() ranks=() ratios=()
for ((r = 1; r <= REPEATS; ++r)); do
  s=$(seconds "$DRAPE" batch "$manifest" --quiet --out "$OUT/serial_$r")
  m=$(seconds "${MPIRUN[@]}" "$DRAPE" batch "$manifest" --quiet --out "$OUT/ranks_$r")
  ratio=$(awk -v s="$s" -v m="$m" 'BEGIN { printf "%.3f", m / s }')
  serial+=("$s") ranks+=("$m") ratios+=("$ratio")
  printf "%-7s %10s %10s %7s\n" "$r" "$s" "$m" "$ratio"
done
median() { printf "%s\n" "$@" | sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
printf "%-7s %10s %10s %7s   (target: ratio at most 0.6)\n" median "$(median "${serial[@]}")" "$(median "${ranks[@]}")" "$(median "${ratios[@]}")"
# The tables, without their time columns (wall_s and every *_ms).
timeless() { awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) keep[i] = ($i !~ /_ms$/ && $i != "wall_s") } { line = ""; for (i = 1; i <= NF; ++i) if (keep[i]) line = line $i ","; print line }' "$1"; }
if diff <(timeless "$OUT/serial_1/batch.csv") <(timeless "$OUT/ranks_1/batch.csv") > /dev/null; then
  echo "tables: the same but for time columns"
else
  echo "tables: DIFFER (beyond time columns)"; exit 1
fi
