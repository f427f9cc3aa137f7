#!/usr/bin/env bash
# Whole frames of a scene at an earlier commit beside this build's: issue 18's heavy-frame
# target ("a whole heavy frame takes at most a fifth of today's time", today being the commit
# the issue was filed at) from both commits' figures in alternating runs. The earlier commit's
# drape is built from `git archive` of that commit in OUT (Release, the drape target alone;
# no worktree is registered), each run uses its own commit's copy of the scene, and the runs
# alternate (old, new, old, new, ...) under --check; "new" is the drape in BUILD_DIR as built,
# labelled with HEAD. Prints, for each heavy frame of the first repeat (the earlier run has at
# least a tenth of its most elementary tests there, scene_bench's rule), both runs' wall time,
# the earlier one's collision pipeline (ccd_ms) and solve, this one's broad and narrow phase
# and solve, both runs' halvings, and the ratio new / old of the frames' times; then the median
# and range of that ratio, the totals, the heavy frames whose broad phase costs more than their
# narrow phase, and each run's penetrations, warnings and largest stretch. Later repeats add
# only their run times. A benchmark, not a test: the pile in full took 2.5 to 3 minutes at 8dcf95b, 4 at
# 8f860ac and 27 at b0eb627 (docs/benchmarks.md), plus 2.5 minutes to build the earlier drape.
# Usage: bench/commits_heavy_frames.sh OLD_REV [BUILD_DIR] [OUT] [SCENE] [FRAMES] [REPEATS]
# (SCENE relative to the repository's root.)
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 1 ] || { echo "usage: bench/commits_heavy_frames.sh OLD_REV [BUILD_DIR] [OUT] [SCENE] [FRAMES] [REPEATS]" >&2; exit 2; }
OLD_REV=$1
BUILD_DIR=${2:-build}
OUT=${3:-out/commits_heavy_frames}
SCENE=${4:-scenes/pile.json}
FRAMES=${5:-}
REPEATS=${6:-1}
NEW_DRAPE="$BUILD_DIR/app/drape"
[ -x "$NEW_DRAPE" ] || { echo "commits_heavy_frames.sh: no drape at $NEW_DRAPE (build first)" >&2; exit 2; }
rev=$(git rev-parse --verify --short "$OLD_REV^{commit}") || { echo "commits_heavy_frames.sh: $OLD_REV is not a commit" >&2; exit 2; }
mkdir -p "$OUT"
OUT=$(cd "$OUT" && pwd)
tree="$OUT/tree-$rev"
OLD_DRAPE="$tree/build/app/drape"
if [ ! -x "$OLD_DRAPE" ]; then
  rm -rf "$tree"
  mkdir -p "$tree"
  git archive "$rev" | tar -x -C "$tree"
  echo "building $rev's drape in $tree/build (log: $OUT/build-$rev.log)"
  { cmake -S "$tree" -B "$tree/build" -DCMAKE_BUILD_TYPE=Release -DDRAPE_BUILD_TESTS=OFF -DDRAPE_BUILD_BENCH=OFF &&
    cmake --build "$tree/build" -j2 --target drape; } > "$OUT/build-$rev.log" 2>&1 ||
    { echo "commits_heavy_frames.sh: building $rev failed (see $OUT/build-$rev.log)" >&2; exit 1; }
fi
case "$SCENE" in /*) echo "commits_heavy_frames.sh: give the scene relative to the repository's root (each commit reads its own copy)" >&2; exit 2 ;; esac
[ -f "$tree/$SCENE" ] || { echo "commits_heavy_frames.sh: $rev has no $SCENE" >&2; exit 2; }
cmp -s "$SCENE" "$tree/$SCENE" || echo "note: $SCENE differs between $rev and this tree; each run reads its own commit's copy"
frames_flag=()
[ -n "$FRAMES" ] && frames_flag=(--frames "$FRAMES")
for r in $(seq 1 "$REPEATS"); do
  for side in old new; do
    if [ "$side" = old ]; then drape=$OLD_DRAPE scene="$tree/$SCENE"; else drape=$NEW_DRAPE scene=$SCENE; fi
    # A fresh folder for every run (drape before session 9 has no --overwrite), so that a run
    # that fails early leaves no earlier run's stats.csv to be read as its own.
    rm -rf "${OUT:?}/$side-$r"
    start=$(date +%s%N)
    status=0
    "$drape" run "$scene" "${frames_flag[@]}" --check --quiet --out "$OUT/$side-$r" || status=$?
    echo "run $r, $side ($([ "$side" = old ] && echo "$rev" || echo "this build, $BUILD_DIR, HEAD $(git rev-parse --short HEAD)")): $(awk -v a="$start" -v b="$(date +%s%N)" 'BEGIN { printf "%.1f", (b - a) / 1e9 }') s, status $status"
    if [ "$status" = 2 ]; then echo "commits_heavy_frames.sh: the $side run refused its input (status 2): no table" >&2; exit 1; fi
  done
done
# Per heavy frame, from the first repeat of each (every run's own time is printed above);
# bench/heavy_frames.awk reads the files. Columns a commit's stats.csv lacks (the earlier one
# may have no broad_ms, narrow_ms, step_halvings or warnings) read as 0 in the sums and print
# as n/a in the summary.
awk -F, -v old="$rev" -f bench/heavy_frames.awk -f /dev/stdin "$OUT/old-1/stats.csv" "$OUT/new-1/stats.csv" <<'AWK'
  function shown(f, name, value) { return has(f, name) ? sprintf("%d", value) : "n/a" }
  END {
    most = most_tests(1)
    printf "\n%5s %10s %10s %10s %6s | %9s %9s %9s %9s %6s | %7s\n", "frame", "old_ms", "old_ccd", "old_solve", "o_halv", \
      "new_ms", "new_broad", "new_narr", "new_solve", "n_halv", "ratio"
    n = 0
    for (f = 1; f <= last[1]; ++f) {
      if (!heavy(1, f, most) || !((2, f) in wall)) continue
      n++; ratio[n] = wall[2, f] / wall[1, f]; old_total += wall[1, f]; new_total += wall[2, f]
      if (broad[2, f] > narrow[2, f]) dearer++
      printf "%5d %10.1f %10.1f %10.1f %6d | %9.1f %9.1f %9.2f %9.1f %6d | %7.3f\n", f, wall[1, f], ccd[1, f], solve[1, f], halv[1, f], \
        wall[2, f], broad[2, f], narrow[2, f], solve[2, f], halv[2, f], ratio[n]
    }
    if (n == 0) { print "no heavy frame (no elementary tests in the earlier run, or the later run stopped before them)"; exit }
    median = sorted_median(ratio, n)
    printf "\n%d heavy frames (at least a tenth of the most tests, %d, of the run at %s)\n", n, most, old
    printf "a heavy frame now against at %s: median ratio %.3f (%.3f to %.3f), total %.1f s against %.1f s (%.3f)\n", \
      old, median, ratio[1], ratio[n], new_total / 1000, old_total / 1000, new_total / old_total
    printf "heavy frames whose broad phase (now) costs more than their narrow phase: %d of %d\n", dearer, n
    printf "at %s: penetrations %s, warnings %s, largest stretch %.4f; now: penetrations %s, warnings %s, largest stretch %.4f\n", \
      old, shown(1, "penetrations", pen[1]), shown(1, "warnings", warn[1]), stretch[1], \
      shown(2, "penetrations", pen[2]), shown(2, "warnings", warn[2]), stretch[2]
    if (!has(1, "step_halvings")) printf "(%s has no step_halvings column: o_halv reads 0)\n", old
  }
AWK
