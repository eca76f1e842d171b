#!/usr/bin/env bash
# Game frame-time benchmark (docs/benchmarks.md, "Sample game"): the default scenario at
# 1280 x 720 offscreen with the budget controller on (target 33 ms), then the same with the load
# spike script (20 ms of busy work per step from t = 10 s to 15 s). One fixed step per frame.
# llvmpipe's thread count is fixed (LP_NUM_THREADS, default 2 = this machine's cores).
# Writes docs/benchmarks/game.json (summary only; the per-frame files stay in out/bench_game/).
# Usage: scripts/bench_game.sh [BUILD_DIR]   (default build/release; builds ridgeline_game there)
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
cd "$RIDGELINE_ROOT"
build=${1:-build/release}
[ -f "$build/build.ninja" ] || cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build "$build" --target ridgeline_game > /dev/null
game=$build/sample_game/ridgeline_game
out=out/bench_game
mkdir -p "$out"
export LP_NUM_THREADS=${LP_NUM_THREADS:-2}
S=scripts/game
load_before=$(cut -d' ' -f1-3 /proc/loadavg)
run() {  # name frames extra-args...
  local name=$1 frames=$2; shift 2
  echo "--- $name ($frames frames)"
  with_display "$game" --offscreen --frames "$frames" --width 1280 --height 720 \
    --stats "$out/$name.json" "$@"
}
run steady 1200 --steady-from 600
run spike 1500 --script $S/default.lua --script $S/artillery.lua --script $S/budget.lua \
  --script $S/load_spike.lua
python3 - "$out" docs/benchmarks/game.json "$load_before" "$(cut -d' ' -f1-3 /proc/loadavg)" <<'PY'
import json, statistics, subprocess, sys
out, dest = sys.argv[1], sys.argv[2]
def load(n): return json.load(open(f"{out}/{n}.json"))
def pct(v, p):
    v = sorted(v); k = (len(v) - 1) * p / 100; i = int(k)
    return v[i] if i + 1 >= len(v) else v[i] * (1 - (k - i)) + v[i + 1] * (k - i)
def window(frames, a, b, key):
    return [f[key] for f in frames if a <= f["time_s"] < b]
steady = load("steady")
sf = steady["frames"]
ms = window(sf, 10, 99, "frame_ms"); th = window(sf, 10, 99, "threshold_px")
tri = window(sf, 10, 99, "triangles")
spike = load("spike")["frames"]
def phase(a, b):
    m = window(spike, a, b, "frame_ms"); t = window(spike, a, b, "threshold_px")
    return {"seconds": [a, b], "frame_ms_p50": round(statistics.median(m), 2),
            "threshold_px_p50": round(statistics.median(t), 3),
            "threshold_px_max": round(max(t), 3), "threshold_px_min": round(min(t), 3)}
doc = {
  "command": "scripts/bench_game.sh",
  "machine": "2 cores shared with other builds; Mesa llvmpipe (no GPU); LP_NUM_THREADS=2",
  "load_average_before_after": [sys.argv[3], sys.argv[4]],
  "viewport": [1280, 720], "dt_s": steady["dt_s"], "target_ms": steady["summary"]["target_ms"],
  "steady": {
    "scenario": "default.lua + artillery.lua + budget.lua (controller on, 1..12 px, 60000 triangles)",
    "frames": len(ms), "seconds": [10, 20],
    "frame_ms": {p: round(pct(ms, q), 2) for p, q in (("p10", 10), ("p50", 50), ("p90", 90), ("p99", 99))},
    "median_within_10_percent_of_target": abs(statistics.median(ms) / 33.0 - 1) <= 0.10,
    "threshold_px": {p: round(pct(th, q), 3) for p, q in (("p10", 10), ("p50", 50), ("p90", 90))},
    "triangles_p50": pct(tri, 50),
    "craters": steady["summary"]["craters"], "script_errors": steady["summary"]["script_errors"]},
  "load_spike": {
    "scenario": "the same + load_spike.lua (20 ms busy work per step, t = 10 .. 15 s)",
    "before": phase(5, 10), "during": phase(11, 15), "after": phase(20, 25)},
}
json.dump(doc, open(dest, "w"), indent=1)
print(json.dumps(doc, indent=1))
PY
