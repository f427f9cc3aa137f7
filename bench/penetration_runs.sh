#!/usr/bin/env bash
# Full runs of every shipped scene with the vincent and the conservative CCD methods, each
# frame checked by the independent penetration check (--check, then drape check over the saved
# meshes). Prints one line per run: scene, method, seconds, frames, the energy (kinetic plus
# potential) at frame 0 and its largest value after it, the largest energy beyond the bound
# (stats.csv's energy_excess: the energy less its start and the sources' work; at most 0 when
# the bound holds), the frames that passed a limit (warnings), penetrations found by --check,
# the largest stretch, drape check's verdict, and the run's own: OK when the run completed
# (status 0), no frame warned, --check and drape check found nothing, and the energy never rose
# above its bound (largest energy_excess at most 0); FAIL otherwise, and the script then exits
# with status 1. Long (tens of minutes): a benchmark, not a test.
# Usage: bench/penetration_runs.sh [BUILD_DIR] [OUT]; METHODS="vincent" for one method, SCENES
# for other scene files than scenes/*.json.
set -uo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${1:-build}
OUT=${2:-out/penetration_runs}
DRAPE="$BUILD_DIR/app/drape"
printf "%-14s %-13s %9s %7s %10s %10s %10s %5s %5s %8s %-7s %s\n" scene method seconds frames E_start E_max excess warn pen \
  stretch verdict "drape check"
failed=0
for method in ${METHODS:-vincent conservative}; do
  for scene in ${SCENES:-scenes/*.json}; do
    name=$(basename "$scene" .json)
    out="$OUT/$name-$method"
    rm -rf "$out"
    start=$(date +%s%N)
    "$DRAPE" run "$scene" --ccd "$method" --check --quiet --out "$out"
    status=$?
    seconds=$(awk -v a="$start" -v b="$(date +%s%N)" 'BEGIN { printf "%.1f", (b - a) / 1e9 }')
    frames=$(($(wc -l < "$out/stats.csv") - 1))
    # Columns by name from the header.
    read -r e0 emax excess warn pen stretch < <(awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) c[$i] = i; next }
      { e = $c["kinetic_energy"] + $c["potential_energy"]; if (NR == 2) e0 = e; else if (e > m || NR == 3) m = e;
        if (NR == 2 || $c["energy_excess"] > x) x = $c["energy_excess"]; w += $c["warnings"]; p += $c["penetrations"];
        if ($c["max_stretch"] > s) s = $c["max_stretch"] }
      END { printf "%.4g %.4g %.3g %d %d %.4f\n", e0, m, x, w, p, s }' "$out/stats.csv")
    check=$("$DRAPE" check "$out" 2>&1)
    check_status=$?
    ok=OK
    if [ "$status" -ne 0 ] || [ "$check_status" -ne 0 ] || [ "$warn" -ne 0 ] || [ "$pen" -ne 0 ] ||
      awk -v x="$excess" 'BEGIN { exit !(x > 0) }'; then
      ok=FAIL
      failed=1
    fi
    printf "%-14s %-13s %9.1f %7d %10s %10s %10s %5s %5s %8s %-7s %s (run status %d)\n" "$name" "$method" "$seconds" "$frames" \
      "$e0" "$emax" "$excess" "$warn" "$pen" "$stretch" "$ok" "$(tail -1 <<< "$check")" "$status"
  done
done
exit $failed
