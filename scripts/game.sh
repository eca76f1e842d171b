#!/usr/bin/env bash
# The main command: builds Ridgeline and runs the sample game's default scenario (a convoy on a
# loop of waypoints over the hills of the detail world while artillery drops craters and
# engineers reshape the ground near it, with the LOD budget controller holding the frame time by
# the pixel threshold and the render scale).
#  - With a display: opens a window (close it to quit). Keys in docs/game.md.
#  - Without one: renders offscreen (under xvfb-run when it is installed, else EGL surfaceless)
#    for FRAMES frames (default 600 = 10 s of game time) and writes screenshots and per-frame
#    statistics into out/game/.
# Extra arguments go to the game (ridgeline_game --help).
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
cd "$RIDGELINE_ROOT"
ensure_packages "${RIDGELINE_PACKAGES[@]}"
echo "building the game (build/release)..."
mkdir -p build
build_release ridgeline_game ridgeline_lua_module > build/release.build.log 2>&1 || { tail -40 build/release.build.log; exit 1; }
game=build/release/sample_game/ridgeline_game
if [ -n "${DISPLAY:-}" ] && [ -z "${RIDGELINE_OFFSCREEN:-}" ]; then
  echo "running the game in a window (Tab: camera, F1: wireframe, F5: reload scripts)"
  exec "$game" "$@"
fi
frames=${FRAMES:-600}
out=out/game
rm -rf "$out" && mkdir -p "$out"
echo "no display: running $frames frames offscreen; screenshots and stats go to $out/"
args=(--offscreen --frames "$frames" --screenshot-every 120 --out "$out"
      --screenshot "$out/last_frame.png" --stats "$out/stats.json" "$@")
if command -v xvfb-run > /dev/null; then
  xvfb-run -a -s "-screen 0 1280x720x24" "$game" "${args[@]}"
else
  "$game" --egl "${args[@]}"
fi
python3 - "$out/stats.json" <<'PY' 2>/dev/null || true
import json, sys
d = json.load(open(sys.argv[1]))
s = d["summary"]
print("frame ms p50 %.1f p90 %.1f p99 %.1f (target %.0f ms); threshold p50 %.2f px; render scale "
      "p50 %.2f; %d craters; %d script errors" % (s["frame_ms"]["p50"], s["frame_ms"]["p90"],
      s["frame_ms"]["p99"], s["target_ms"], s["threshold_px"]["p50"], s["render_scale"]["p50"],
      s["craters"], s["script_errors"]))
b = s["frame_time_breakdown_ms"]
print("where the frame goes (median ms): " + ", ".join("%s %.1f" % (k, b[k]["p50"]) for k in
      ("scripts", "physics", "tessellation", "upload", "render", "panel")))
print("procedural detail: %d level(s); tiles resident up to %d, pending up to %d; view converged "
      "in %.0f %% of frames" % (s["detail_levels"], s["detail_tiles_resident_max"],
      s["detail_tiles_pending_max"], 100 * s["view_stop_fraction"]["converged"]))
last = d["frames"][-1]
names = ["grass", "rock", "sand", "snow", "mud", "gravel"]
for v in last["vehicles"]:
    m = v["material"]
    print("vehicle %d at (%.0f, %.0f, %.0f) on %s, %d waypoints reached, %d collisions" % (
          v["id"], *v["position"], names[m] if m < len(names) else m, v["waypoints_reached"],
          v["collisions"]))
PY
echo "done: $(ls "$out"/*.png | wc -l) screenshots in $out/ (last: $out/last_frame.png), per-frame statistics in $out/stats.json"
