#!/usr/bin/env bash
# Whole frames with the cloth's contacts with itself held in the implicit solve
# (collisions.self_in_solve, the default) beside the same scene without them (the response
# alone, as before session 22), one run of each, alternating when repeated. Prints, for each
# heavy frame (the run without them has at least a tenth of its most elementary tests there,
# scene_bench's rule), both runs' wall time, broad and narrow phase, halvings and proximity
# impulses, and the ratio of the frames' times; then the medians and totals over the heavy
# frames, the frames where the broad phase costs more than the narrow phase, and each run's
# penetrations (--check), warnings and largest stretch. A benchmark, not a test: the pile in full
# takes about 4 minutes held and 10 without.
# Usage: bench/self_contacts_runs.sh [BUILD_DIR] [OUT] [SCENE] [FRAMES] [REPEATS]
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${1:-build}
OUT=${2:-out/self_contacts_runs}
SCENE=${3:-scenes/pile.json}
FRAMES=${4:-}
REPEATS=${5:-1}
DRAPE="$BUILD_DIR/app/drape"
mkdir -p "$OUT"
# The scene with the option off: a copy in OUT, beside a link to the scene's meshes folder so
# that its relative mesh paths resolve alike.
name=$(basename "$SCENE" .json)
off_scene="$OUT/${name}_self_in_solve_off.json"
"$DRAPE" validate "$SCENE" > /dev/null
scene_dir=$(cd "$(dirname "$SCENE")" && pwd)
[ -d "$scene_dir/meshes" ] && ln -sfn "$scene_dir/meshes" "$OUT/meshes"
awk 'BEGIN { done = 0 }
     /"collisions"[[:space:]]*:[[:space:]]*\{/ && !done { sub(/"collisions"[[:space:]]*:[[:space:]]*\{/, "\"collisions\": {\"self_in_solve\": false, "); done = 1 }
     { print }
     END { if (!done) exit 1 }' "$SCENE" > "$off_scene" || { echo "self_contacts_runs.sh: $SCENE has no collisions section" >&2; exit 2; }
frames_flag=()
[ -n "$FRAMES" ] && frames_flag=(--frames "$FRAMES")
for r in $(seq 1 "$REPEATS"); do
  for mode in on off; do
    scene=$SCENE
    [ "$mode" = off ] && scene=$off_scene
    start=$(date +%s%N)
    "$DRAPE" run "$scene" "${frames_flag[@]}" --check --quiet --overwrite --out "$OUT/$mode-$r"
    echo "run $r, self contacts in the solve $mode: $(awk -v a="$start" -v b="$(date +%s%N)" 'BEGIN { printf "%.1f", (b - a) / 1e9 }') s"
  done
done
# Per heavy frame, from the first repeat of each (the later repeats' totals are printed below);
# bench/heavy_frames.awk reads the files.
awk -F, -f bench/heavy_frames.awk -f /dev/stdin "$OUT/on-1/stats.csv" "$OUT/off-1/stats.csv" <<'AWK'
  END {
    most = most_tests(2); last_frame = last[1] > last[2] ? last[1] : last[2]
    printf "\n%5s %12s %12s %7s %10s %10s %10s %10s %6s %6s %7s %7s\n", "frame", "held_ms", "response_ms", "ratio", \
      "held_broad", "held_narr", "resp_broad", "resp_narr", "h_halv", "r_halv", "h_prox", "r_prox"
    n = 0
    for (f = 1; f <= last_frame; ++f) {
      if (!heavy(2, f, most)) continue
      n++; ratio[n] = wall[1, f] / wall[2, f]; on_total += wall[1, f]; off_total += wall[2, f]
      if (broad[1, f] > narrow[1, f]) dearer++
      printf "%5d %12.1f %12.1f %7.3f %10.1f %10.2f %10.1f %10.2f %6d %6d %7d %7d\n", f, wall[1, f], wall[2, f], ratio[n], \
        broad[1, f], narrow[1, f], broad[2, f], narrow[2, f], halv[1, f], halv[2, f], prox[1, f], prox[2, f]
    }
    if (n == 0) { print "no heavy frame (no elementary tests without the held contacts)"; exit }
    median = sorted_median(ratio, n)
    printf "\n%d heavy frames (at least a tenth of the most tests, %d, of the run without held contacts)\n", n, most
    printf "a heavy frame, held against the response alone: median ratio %.3f (%.3f to %.3f), total %.1f s against %.1f s (%.3f)\n", \
      median, ratio[1], ratio[n], on_total / 1000, off_total / 1000, on_total / off_total
    printf "heavy frames whose broad phase (held) costs more than their narrow phase: %d of %d\n", dearer, n
    printf "held: penetrations %d, warnings %d, largest stretch %.4f; the response alone: penetrations %d, warnings %d, largest stretch %.4f\n", \
      pen[1], warn[1], stretch[1], pen[2], warn[2], stretch[2]
  }
AWK
if [ "$REPEATS" -gt 1 ]; then
  for r in $(seq 1 "$REPEATS"); do
    for mode in on off; do
      awk -F, -v label="repeat $r, $mode" 'NR == 1 { for (i = 1; i <= NF; ++i) c[$i] = i; next } { s += $c["wall_ms"] }
        END { printf "%s: %.1f s of frames\n", label, s / 1000 }' "$OUT/$mode-$r/stats.csv"
    done
  done
fi
