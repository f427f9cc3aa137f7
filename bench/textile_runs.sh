#!/usr/bin/env bash
# The textile laboratory's two tests on every fabric preset (issue 20; docs/materials.md):
# - the Cusick drape test (scenes/cusick_drape.json with each preset) on the 30 cm disc at three
#   resolutions, each twice the last: the disc cut from a square grid 12.5, 6.25 and 3.125 mm
#   apart along the fabric's warp and weft (scenes/meshes/disc_30cm_grid_12mm.obj, 441
#   vertices; disc_30cm_grid.obj, 1,793; disc_30cm_grid_3mm.obj, 7,213), whose right triangles
#   hold the fabric's tension and shear exactly but in the rim's band (docs/materials.md); the
#   ring discs (disc_30cm_12mm.obj, 12 rings 12.5 mm apart, 469 vertices; disc_30cm.obj, the
#   shipped scene's, 25 rings, 1,951; disc_30cm_3mm.obj, 50 rings, 7,651), near-equilateral
#   triangles that shear near the isotropic sheet's 3 T / 8 whatever the fabric's shear, and the
#   discs of whole half cells (disc_30cm_cells_12mm.obj, disc_30cm_cells.obj,
#   disc_30cm_cells_3mm.obj: every triangle exact, the rim within half a cell of the circle;
#   *_turned30.obj turned against the warp), by MESHES (docs/benchmarks.md compares them).
#   Each run in full (2 s) with the independent
#   penetration check (--check): the drape coefficient and nodes at the last frame (and at
#   frame 2N/3 of N, to show how settled it is; with the shallowest node's depth, to show a count that
#   hangs on the 0.45 cm threshold), and the coefficient's change from each resolution to the
#   next;
# - the cantilever test (scenes/cantilever.json's strip) with each preset: measured / elastica.
# The source of the presets publishes no Cusick figures for them: the table says so.
# Prints one line per preset and exits 1 when a run fails or finds an intersection. Long
# (about 7 minutes on this 2-core machine in session 35, most of it the 3 mm discs): a benchmark, not a test.
# Usage: bench/textile_runs.sh [BUILD_DIR] [OUT]; PRESETS="royal-target ..." for a subset,
# MESHES="disc_30cm_grid_12mm.obj disc_30cm_grid.obj" for fewer resolutions or
# MESHES="disc_30cm_12mm.obj disc_30cm.obj disc_30cm_3mm.obj" for the ring discs, COMPRESSION=0.01 to give
# every run's material that `compression` (docs/materials.md; default: the presets' linear springs),
# MEMBRANE=triangles to give it constant strain triangles in place of the fitted edge springs
# (`membrane`, docs/materials.md; the cantilever's grid keeps its springs; not with COMPRESSION,
# which the triangles do not model: refused),
# THICKNESS=M (metres) for the Cusick runs' collision thickness in place of the scene's default
# 5 mm, the cloth and its clamp moved to rest on the support at it (the coefficient follows the
# thickness: docs/benchmarks.md, session 31),
# SPECIMENS=K for K specimens a resolution in place of one: the apparatus (support, clamp and
# disc) tilted by TILT degrees (0.5) about a level axis at K azimuths 360/K apart, as it is never
# set perfectly level (gravity turned the other way, so the clamp and the support stay parallel
# to the disc; the shadow is cast along it); a
# limp fabric's single run can land on one of several fold patterns (docs/benchmarks.md), so
# the table then gives the specimens' mean coefficient, its spread (largest - smallest) and
# their nodes, and the changes of the means (about K times as long; at 0.5 degrees most
# presets' specimens keep the level disc's pattern: docs/benchmarks.md, session 34).
# FRAMES=N runs each Cusick specimen N frames (the scene's 60, 2 s, by default) and measures it
# at frame N and at 2N/3: a coefficient that moved by more than 0.01 between them is marked
# unsettled (a fold can still deepen after 2 s: docs/benchmarks.md, session 31).
set -uo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
BUILD_DIR=${1:-build}
OUT=${2:-out/textile_runs}
DRAPE="$BUILD_DIR/app/drape"
PRESETS=${PRESETS:-11oz-black-denim royal-target white-dots-on-blk gray-interlock navy-sparkle-sweat}
mkdir -p "$OUT"
failed=0

# A shipped scene ($1) with another preset ($2) and its meshes' paths made absolute; for the
# Cusick scene, the disc's mesh is $3, given $4, the apparatus is tilted by TILT degrees about a
# level axis at azimuth $4 degrees, by gravity turned by -TILT about it (the scene's gravity must
# be the one matched here),
# and given $5, the run is $5 frames long.
scene_with() {
  local tilt="" thickness=""
  if [ -n "${THICKNESS:-}" ] && [ -n "${3:-}" ]; then
    # The cloth rests on the support (its top at 0.3 m) at the thickness: it and the clamp move.
    local height
    height=$(awk -v t="$THICKNESS" 'BEGIN { printf "%.9g", 0.3 + t }')
    # The top clamp disc rests on the cloth at the thickness.
    local clamp
    clamp=$(awk -v t="$THICKNESS" 'BEGIN { printf "%.9g", 0.3 + 2 * t }')
    thickness='s|"collisions": \{"self": true, "obstacles": true\}|"collisions": {"self": true, "obstacles": true, "thickness": '"$THICKNESS"'}|;/cusick_clamp/!s|\[0, 0, 0\.305\]|[0, 0, '"$height"']|g;/cusick_clamp/s|\[0, 0, 0\.31\]|[0, 0, '"$clamp"']|'
  fi
  if [ -n "${4:-}" ]; then
    # Rodrigues' rotation of (0, 0, -g) by -TILT about (cos a, sin a, 0).
    tilt=$(awk -v t="$TILT" -v a="$4" 'BEGIN { pi = atan2(0, -1); r = a * pi / 180; t = t * pi / 180; g = 9.81
      printf "\"gravity\": [%.12g, %.12g, %.12g],", g * sin(r) * sin(t), -g * cos(r) * sin(t), -g * cos(t) }')
  fi
  sed -E -e "s/\"preset\": \"[a-z0-9-]+\"/\"preset\": \"$2\"${COMPRESSION:+, \"compression\": $COMPRESSION}${MEMBRANE:+${3:+, \"membrane\": \"$MEMBRANE\"}}/" -e "s|meshes/disc_30cm\.obj|meshes/${3:-disc_30cm.obj}|" \
    -e "${tilt:+s|^  \"gravity\": \[0, 0, -9.81\],|  $tilt|}" \
    -e "${5:+s|^  \"frames\": [0-9]+,|  \"frames\": $5,|}" \
    -e "$thickness" \
    -e "s|\"mesh\": \"meshes/|\"mesh\": \"$ROOT/scenes/meshes/|" "scenes/$1.json"
}

# "coefficient nodes shallowest" of a run's frame: the shallowest node's depth in cm ("-" for
# no node; a count that hangs on a node near the 0.45 cm threshold shows there).
measure() {
  "$DRAPE" measure cusick "$1" --frame "$2" --json |
    sed -E 's/.*"drape_coefficient": ([0-9.-]+), "nodes": ([0-9]+), "node_depths_m": \[([^]]*)\].*/\1 \2 \3/' |
    awk '{ low = ""; for (i = 3; i <= NF; ++i) { d = $i; sub(",", "", d); if (low == "" || d + 0 < low + 0) low = d }
           printf "%s %s %s\n", $1, $2, (low == "" ? "-" : sprintf("%.2f", 100 * low)) }'
}

UNSETTLED=0.01  # a coefficient that moved by more from the earlier frame is still moving

# ", unsettled" where a run's coefficients at the last and the earlier frame ($1, $2) differ
# by more than UNSETTLED.
unsettled() { awk -v a="$1" -v b="$2" -v u="$UNSETTLED" 'BEGIN { d = a - b; if (d < 0) d = -d; if (d > u) printf ", unsettled" }'; }

MESHES=${MESHES:-disc_30cm_grid_12mm.obj disc_30cm_grid.obj disc_30cm_grid_3mm.obj}
SPECIMENS=${SPECIMENS:-1}
TILT=${TILT:-0.5}
FRAMES=${FRAMES:-60}
[[ "$FRAMES" =~ ^[1-9][0-9]*$ && "$FRAMES" -ge 3 ]] || { echo "textile_runs.sh: expected FRAMES of 3 or more" >&2; exit 2; }
EARLIER=$((FRAMES * 2 / 3))
[[ -z "${THICKNESS:-}" || "$THICKNESS" =~ ^(0|[1-9][0-9]*)(\.[0-9]+)?([eE]-?[0-9]+)?$ ]] ||
  { echo "textile_runs.sh: expected THICKNESS in metres (a JSON number such as 0.002)" >&2; exit 2; }
[[ -z "${MEMBRANE:-}" || "$MEMBRANE" == springs || "$MEMBRANE" == triangles ]] ||
  { echo "textile_runs.sh: expected MEMBRANE springs or triangles" >&2; exit 2; }
# The membrane's triangles have no compression model (drape refuses the two together).
[[ -n "${COMPRESSION:-}" && "${MEMBRANE:-springs}" == triangles ]] &&
  { echo "textile_runs.sh: COMPRESSION applies to springs only; MEMBRANE=triangles has no compression model (docs/materials.md)" >&2; exit 2; }
[[ "$SPECIMENS" =~ ^[1-9][0-9]*$ && "$TILT" =~ ^[0-9]+(\.[0-9]+)?$ ]] ||
  { echo "textile_runs.sh: expected SPECIMENS of 1 or more and TILT in degrees (a number)" >&2; exit 2; }
cusick_heading="DC at frame $FRAMES (at frame $EARLIER; 'unsettled' where they differ by over $UNSETTLED) nodes (the shallowest node's depth), seconds"
[ "$SPECIMENS" -gt 1 ] && cusick_heading="$SPECIMENS specimens tilted $TILT degrees: mean DC, spread, nodes, seconds"
printf "%-19s | %s | %-8s | %-6s | %-11s | %s\n" preset "Cusick per mesh ($MESHES; compression ${COMPRESSION:-1}; membrane ${MEMBRANE:-springs}; thickness ${THICKNESS:-default}): $cusick_heading" \
  "DC changes" "pen" "cantilever" "published DC, nodes"
for preset in $PRESETS; do
  cells=()
  last=()
  pen=0
  for mesh in $MESHES; do
    values=()  # "coefficient coefficient-at-EARLIER nodes" of each specimen
    start=$(date +%s%N)
    for ((k = 0; k < SPECIMENS; ++k)); do
      run="$OUT/cusick-$preset-${mesh%.obj}"
      azimuth=""
      if [ "$SPECIMENS" -gt 1 ]; then
        run+="-specimen$k"
        azimuth=$(awk -v k="$k" -v n="$SPECIMENS" 'BEGIN { printf "%g", 360 * k / n }')
      fi
      scene_with cusick_drape "$preset" "$mesh" "$azimuth" "$FRAMES" > "$run.json"
      if [ -n "$azimuth" ] && grep -q '"gravity": \[0, 0, -9.81\]' "$run.json"; then
        echo "textile_runs.sh: scenes/cusick_drape.json's gravity is not the one this script tilts" >&2
        exit 2
      fi
      if ! "$DRAPE" run "$run.json" --check --quiet --overwrite --out "$run"; then
        echo "$preset on $mesh: the run failed" >&2
        failed=1
        continue
      fi
      read -r dc nodes shallowest < <(measure "$run" "$FRAMES")
      read -r dc40 _ _ < <(measure "$run" "$EARLIER")
      if ! [[ "$dc" =~ ^-?[0-9.]+$ && "$dc40" =~ ^-?[0-9.]+$ && "$nodes" =~ ^[0-9]+$ ]]; then
        echo "$preset on $mesh: drape measure cusick failed" >&2
        failed=1
        continue
      fi
      pen=$((pen + $(awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) c[$i] = i; next } { p += $c["penetrations"] } END { print p + 0 }' "$run/stats.csv")))
      values+=("$dc $dc40 $nodes $shallowest")
    done
    seconds=$(awk -v a="$start" -v b="$(date +%s%N)" 'BEGIN { printf "%.0f", (b - a) / 1e9 }')
    if [ "${#values[@]}" -ne "$SPECIMENS" ]; then
      cells+=("failed")
      last+=("")
    elif [ "$SPECIMENS" -eq 1 ]; then
      read -r dc dc40 nodes shallowest <<< "${values[0]}"
      cells+=("$(printf "%.3f (%.3f%s) %d (shallowest %s cm), %s s" "$dc" "$dc40" "$(unsettled "$dc" "$dc40")" "$nodes" "$shallowest" "$seconds")")
      last+=("$dc")
    else
      mean=$(printf "%s\n" "${values[@]}" | awk '{ s += $1 } END { printf "%.4f", s / NR }')
      cells+=("$(printf "%s\n" "${values[@]}" | awk -v t="$seconds" -v u="$UNSETTLED" '
        { s += $1; lo = (NR == 1 || $1 < lo) ? $1 : lo; hi = (NR == 1 || $1 > hi) ? $1 : hi; n = n (NR > 1 ? "/" : "") $3
          d = $1 - $2; if (d < 0) d = -d; if (d > u) u_n++ }
        END { printf "%.3f spread %.3f nodes %s%s, %s s", s / NR, hi - lo, n, (u_n ? sprintf(", %d unsettled", u_n) : ""), t }')")
      last+=("$mean")
    fi
  done
  diff=""
  for ((k = 1; k < ${#last[@]}; ++k)); do  # a failed resolution leaves its changes as "-"
    if [ -n "${last[k - 1]}" ] && [ -n "${last[k]}" ]; then
      diff+=$(awk -v a="${last[k - 1]}" -v b="${last[k]}" 'BEGIN { printf "%+.3f ", b - a }')
    else
      diff+="- "
    fi
  done
  # The cantilever with this preset.
  scene_with cantilever "$preset" > "$OUT/cantilever-$preset.json"
  ratio=failed
  if "$DRAPE" run "$OUT/cantilever-$preset.json" --quiet --overwrite --out "$OUT/cantilever-$preset"; then
    ratio=$("$DRAPE" measure cantilever "$OUT/cantilever-$preset" --json | sed -nE 's/.*"drop_over_elastica": ([0-9.]+).*/\1/p')
  fi
  [ -n "$ratio" ] && [ "$ratio" != failed ] || { ratio=failed; failed=1; }
  [ "$pen" -eq 0 ] || failed=1
  joined=$(printf "%s; " "${cells[@]}")
  printf "%-19s | %s | %-8s | %-6s | %-11s | %s\n" "$preset" "${joined%; }" "${diff:--}" "$pen" "$ratio" \
    "none published (Wang et al. 2011)"
done
exit $failed
