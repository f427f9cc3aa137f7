#!/usr/bin/env bash
# The README's first command: build drape, then run the main job: simulate the default scene
# and render its video.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/build.sh
BUILD_DIR=${BUILD_DIR:-build}
# --overwrite: running the main job again replaces its earlier output.
"$BUILD_DIR/app/drape" run scenes/drape_sphere.json --render --overwrite "$@"
echo "video: out/drape_sphere/video.mp4 (frames: out/drape_sphere/render/*.png, meshes and stats.csv: out/drape_sphere/)"
