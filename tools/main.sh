#!/usr/bin/env bash
# The README's first command: build drape, then run the main job: simulate the default scene.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/build.sh
BUILD_DIR=${BUILD_DIR:-build}
"$BUILD_DIR/app/drape" run scenes/drape_sphere.json "$@"
echo "frames and statistics: out/drape_sphere/ (frame_*.obj, stats.csv)"
