#!/usr/bin/env bash
# Offscreen render test: GAME runs the default scenario (the detail world) for 120 fixed steps
# with a fixed threshold, no panel and the detail tiles prefilled (each view update waits for the
# tiles it asked for, so the picture does not depend on when tiles arrive), writes a screenshot
# and stats; CHECK compares the picture's pixel statistics and (offscreen) the committed
# reference. Exit 77 (ctest: skipped) when no OpenGL context can be created (GAME exits 3), or for
# the hidden-window flavour when there is no X display.
# Usage: run_offscreen.sh GAME CHECK REFERENCE OUT_DIR FLAVOUR   (FLAVOUR: xvfb | egl | window)
set -uo pipefail
game=$1 check=$2 reference=$3 out=$4 flavour=$5
mkdir -p "$out"
args=(--frames 120 --no-panel --threshold 2 --tess-ms 0 --width 640 --height 360 --prefill-detail
      --screenshot "$out/shot_$flavour.png" --stats "$out/shot_$flavour.json")
case $flavour in
  xvfb|window)
    if [ -z "${DISPLAY:-}" ]; then echo "no X display: skipped"; exit 77; fi
    [ "$flavour" = xvfb ] && args+=(--offscreen) ;;
  egl) args+=(--offscreen --egl) ;;
esac
"$game" "${args[@]}"
rc=$?
if [ $rc -eq 3 ]; then echo "no OpenGL context: skipped"; exit 77; fi
[ $rc -eq 0 ] || { echo "game failed with exit $rc"; exit 1; }
grep -q '"script_errors": 0' "$out/shot_$flavour.json" || { echo "script errors in the run"; exit 1; }
# The picture is of the detail world: tiles were resident.
grep -q '"detail_levels": [1-9]' "$out/shot_$flavour.json" || { echo "no detail in the world"; exit 1; }
grep -Eq '"detail_tiles_resident_max": [1-9]' "$out/shot_$flavour.json" ||
  { echo "no detail tile was resident"; exit 1; }
# A window steps by wall-clock time (as a game must), so its picture differs from run to run:
# pixel statistics only. The offscreen flavours take one fixed step per frame: reference too.
if [ "$flavour" = window ]; then
  "$check" "$out/shot_$flavour.png"
else
  "$check" "$out/shot_$flavour.png" "$reference"
fi
