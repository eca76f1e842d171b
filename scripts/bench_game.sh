#!/usr/bin/env bash
# Game frame-time benchmark (docs/game.md, "Frame time"): the default scenario as scripts/game.sh
# runs it (the detail world, the debug panel, four vehicles, artillery, earthworks, the budget
# controller with target 33 ms) at 1280 x 720 offscreen under Xvfb, one fixed step per frame:
#   steady   1200 frames, statistics from frame 600;
#   busy     1800 frames; two busy loops (one per core) started 20 s after the game and stopped
#            15 s later by this script;
#   spike    1500 frames with scripts/game/load_spike.lua (20 ms of work per step, t = 10..15 s);
#   parts    where the frame goes: a fixed 2 px threshold without the controller at render scales
#            1, 0.75 and 0.5 (fill = what scales with the pixel count), with the per-pixel
#            fragment path, and unsorted patches (600 frames each, statistics from frame 300).
# llvmpipe's thread count is fixed (LP_NUM_THREADS, default 2 = this machine's cores). The load
# average is recorded before and after every run: the machine is shared, so wall times move with
# it; CPU times (process and game thread) are recorded per frame too.
# Writes docs/benchmarks/game.json and the plots docs/images/game_budget_{busy,spike}.png; the
# per-frame files stay in out/bench_game/.
# Usage: scripts/bench_game.sh [BUILD_DIR]   (default build/release, configured and built as every
#        script does; another, already configured folder is only built)
#        BENCH_GAME_ONLY="steady busy" scripts/bench_game.sh   (a subset; the others are kept
#        from the previous docs/benchmarks/game.json)
#        BENCH_GAME_QUIET=1.5 scripts/bench_game.sh   (before each run, wait up to 20 minutes for
#        the 1-minute load average to fall below 1.5: a shared machine has quiet moments)
set -euo pipefail
source "$(dirname "$0")/lib/common.sh"
cd "$RIDGELINE_ROOT"
ensure_packages "${RIDGELINE_PACKAGES[@]}" "${RIDGELINE_REPORT_PACKAGES[@]}"
build=${1:-$RIDGELINE_RELEASE_DIR}
if [ "$build" = "$RIDGELINE_RELEASE_DIR" ]; then
  build_release ridgeline_game > /dev/null
else  # a build folder the caller configured
  cmake --build "$build" --target ridgeline_game > /dev/null
fi
game=$build/sample_game/ridgeline_game
out=out/bench_game
mkdir -p "$out" docs/images
export LP_NUM_THREADS=${LP_NUM_THREADS:-2}
only=${BENCH_GAME_ONLY:-steady busy spike parts}
S=scripts/game
defaults=(--script $S/default.lua --script $S/artillery.lua --script $S/budget.lua
          --script $S/earthworks.lua)
loadavg() { cut -d' ' -f1-3 /proc/loadavg; }
quiet=${BENCH_GAME_QUIET:-}
wait_quiet() {
  [ -n "$quiet" ] || return 0
  local t0=$SECONDS
  while awk -v q="$quiet" '{ exit !($1 >= q) }' /proc/loadavg && [ $((SECONDS - t0)) -lt 1200 ]; do
    sleep 10
  done
}
want() { [[ " $only " == *" $1 "* ]]; }

# run NAME FRAMES [args...]: one offscreen run; its load averages go to NAME.load.
run() {
  local name=$1 frames=$2; shift 2
  wait_quiet
  echo "--- $name ($frames frames, load $(loadavg))"
  local before; before=$(loadavg)
  with_display "$game" --offscreen --frames "$frames" --width 1280 --height 720 \
    --stats "$out/$name.json" "$@" > "$out/$name.log" 2>&1 ||
    { tail -20 "$out/$name.log"; exit 1; }
  printf '%s\n%s\n' "$before" "$(loadavg)" > "$out/$name.load"
}

if want steady; then run steady 1200 --steady-from 600 "${defaults[@]}"; fi
if want busy; then
  # The busy loops: started and stopped here, by process id.
  wait_quiet
  echo "--- busy (1800 frames; two busy loops from 20 s to 35 s of wall time, load $(loadavg))"
  before=$(loadavg)
  with_display "$game" --offscreen --frames 1800 --width 1280 --height 720 \
    --stats "$out/busy.json" "${defaults[@]}" > "$out/busy.log" 2>&1 &
  game_pid=$!
  sleep 20
  busy_pids=()
  for _ in 1 2; do
    bash -c 'while :; do :; done' &
    busy_pids+=($!)
  done
  date +%s.%N > "$out/busy.window"
  sleep 15
  kill "${busy_pids[@]}"
  wait "${busy_pids[@]}" 2> /dev/null || true
  date +%s.%N >> "$out/busy.window"
  wait "$game_pid" || { tail -20 "$out/busy.log"; exit 1; }
  printf '%s\n%s\n' "$before" "$(loadavg)" > "$out/busy.load"
fi
if want spike; then run spike 1500 "${defaults[@]}" --script $S/load_spike.lua; fi
if want parts; then
  part=(--threshold 2 --tess-ms 0 --steady-from 300 "${defaults[@]}")
  run parts_scale100 600 "${part[@]}"
  run parts_scale075 600 "${part[@]}" --render-scale 0.75
  run parts_scale050 600 "${part[@]}" --render-scale 0.5
  run parts_full_fragments 600 "${part[@]}" --full-fragments
  run parts_unsorted 600 "${part[@]}" --unsorted
fi

python3 scripts/lib/bench_game_report.py "$out" docs/benchmarks/game.json docs/images
echo "wrote docs/benchmarks/game.json and docs/images/game_budget_{busy,spike}.png"
