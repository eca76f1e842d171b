#!/usr/bin/env bash
# The main job: builds Ridgeline and runs the `ridge` tool on the built-in default terrain,
# printing what a person can judge (size, heights, a profile, query speed).
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
cd "$RIDGELINE_ROOT"
ensure_packages "${RIDGELINE_PACKAGES[@]}"
configure_and_build build/release -DCMAKE_BUILD_TYPE=Release -DRIDGELINE_BUILD_TESTS=OFF > /dev/null
ridge=build/release/module/ridge
echo "--- ridge info --default-terrain"
"$ridge" info --default-terrain
echo "--- ridge profile --default-terrain (heights along the diagonal)"
"$ridge" profile --default-terrain --from 0,0 --to 2048,2048 --steps 48
echo "--- ridge bench queries --default-terrain"
"$ridge" bench queries --default-terrain --points 200000 --repetitions 3
