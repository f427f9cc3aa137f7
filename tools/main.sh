#!/usr/bin/env bash
# The README's first command: build drape, then run the main job.
# For now the main job compares the CCD methods on the bundled ground-truth queries.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/build.sh
BUILD_DIR=${BUILD_DIR:-build}
"$BUILD_DIR/app/drape" ccd tests/data/ccd-queries
