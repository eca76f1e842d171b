#!/usr/bin/env bash
# Builds and runs every test: the normal build and its tests, the core and its unit tests on the
# portable fallbacks (RIDGELINE_PORTABLE=ON), an AddressSanitizer + UndefinedBehaviorSanitizer
# build of the tests, then the fuzz targets (libFuzzer, bounded time).
# Installs missing Debian packages first.
# Usage: scripts/test.sh            (all stages)
#        STAGES="release" scripts/test.sh   (a subset: release portable asan fuzz)
#        FUZZ_SECONDS=600 FUZZ_SEED=$RANDOM STAGES=fuzz scripts/test.sh   (a longer, fresh fuzz run;
#        default 30 s a target with the fixed seed 1, so that CI explores the same inputs each run)
set -uo pipefail
source "$(dirname "$0")/lib/common.sh"
cd "$RIDGELINE_ROOT"

STAGES=${STAGES:-"release portable asan fuzz"}
JOBS=$(nproc)
total0=$SECONDS

# node and npm for Khronos' glTF-Validator (the .glb export test), unless the machine has them.
test_packages=(clang-14 libclang-rt-14-dev)
command -v node > /dev/null || test_packages+=(nodejs)
command -v npm > /dev/null || test_packages+=(npm)
stage "packages" ensure_packages "${RIDGELINE_PACKAGES[@]}" "${test_packages[@]}" || exit 1
# What the tests fetch themselves through ctest fixtures, fetched once up front so that a
# missing network shows here: the real DEMs of the loader tests (build/test-data) and the
# validator (build/tools/gltf-validator, shared by both builds).
fetch_test_data || echo "note: the real-DEM tests will fail (fixture fetch_terra_data)"
bash tests/cli/install_gltf_validator.sh "$RIDGELINE_ROOT/build/tools/gltf-validator" ||
  echo "note: the .glb validation test will fail (fixture install_gltf_validator)"

# check_skips STAGE LOG: prints how many tests ctest skipped in LOG and fails on any that may not
# skip. Only the OpenGL tests may, and only outside CI on a machine with neither an X display
# nor xvfb-run (they exit 77 where no GL context can be made); CI runs them under xvfb-run.
check_skips() {
  local stage=$1 log=$2 allowed=" " name skipped=() unexpected=()
  mapfile -t skipped < <(sed -n 's/^.*Test *#[0-9]*: \([^ ]*\) .*\*\*\*Skipped.*$/\1/p' "$log")
  if [ -z "${CI:-}" ] && [ -z "${DISPLAY:-}" ] && ! command -v xvfb-run > /dev/null; then
    allowed=" game_render_xvfb game_render_window game_render_egl game_geomorph_gl "
  fi
  for name in "${skipped[@]}"; do
    [[ "$allowed" == *" $name "* ]] || unexpected+=("$name")
  done
  echo "=== $stage: ${#skipped[@]} tests skipped, ${#unexpected[@]} unexpected ${unexpected[*]}"
  [ ${#unexpected[@]} -eq 0 ]
}

# run_ctest STAGE DIR [PREFIX...] [-- CTEST_ARGS...]: ctest in DIR (run under the PREFIX command,
# e.g. with_display) with its output kept in DIR/ctest.log, then the skip check.
run_ctest() {
  local stage=$1 dir=$2 rc prefix=() args=(); shift 2
  while [ $# -gt 0 ] && [ "$1" != -- ]; do prefix+=("$1"); shift; done
  [ $# -gt 0 ] && { shift; args=("$@"); }
  (cd "$dir" && "${prefix[@]}" ctest --output-on-failure -j "$JOBS" "${args[@]}") 2>&1 |
    tee "$dir/ctest.log"
  rc=${PIPESTATUS[0]}
  check_skips "$stage" "$dir/ctest.log" || rc=1
  return $rc
}

release() {
  build_release || return 1
  # Under Xvfb when there is no display: the game's OpenGL tests need an X server for GLFW
  # (they skip with exit 77 where no context can be made; EGL needs none).
  LP_NUM_THREADS=2 run_ctest release build/release with_display
}

# The core on its portable fallbacks (docs/architecture.md, "Portability"): Ridgeline::terrain,
# Ridgeline::io and the unit tests (ctest label `unit`: tests/unit, the source layers and the
# symbols the core calls), built with RIDGELINE_PORTABLE=ON; no tool, Lua, Bullet, game,
# benchmark or fuzz target. A few minutes on two cores.
PORTABLE_CMAKE_ARGS=(-DCMAKE_BUILD_TYPE=Release -DRIDGELINE_PORTABLE=ON -DRIDGELINE_BUILD_TESTS=ON
  -DRIDGELINE_BUILD_TOOLS=OFF -DRIDGELINE_BUILD_LUA=OFF -DRIDGELINE_BUILD_BULLET=OFF
  -DRIDGELINE_BUILD_GAME=OFF -DRIDGELINE_BUILD_BENCHMARKS=OFF)

portable() {
  configure build/portable "${PORTABLE_CMAKE_ARGS[@]}" || return 1
  cmake --build build/portable -j "$JOBS" --target unit_tests || return 1
  run_ctest portable build/portable -- -L unit
}

# One clang build with ASan, UBSan and libFuzzer instrumentation serves the sanitizer tests and
# the fuzz stage (the fuzz targets are libFuzzer binaries there; ctest replays their corpus). It
# also checks every ROAM view's invariants after each phase of each update (RIDGELINE_ROAM_PARANOID).
ASAN_CMAKE_ARGS=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++-14
  -DRIDGELINE_SANITIZE=address,undefined -DRIDGELINE_FUZZ=ON -DRIDGELINE_BUILD_BENCHMARKS=OFF
  -DRIDGELINE_ROAM_PARANOID=ON)

asan() {
  configure_and_build build/asan "${ASAN_CMAKE_ARGS[@]}" || return 1
  # Readable sanitizer stacks where llvm-symbolizer is installed (suppressions do not need it).
  local sym=/usr/lib/llvm-14/bin/llvm-symbolizer
  [ -x "$sym" ] && export ASAN_SYMBOLIZER_PATH=$sym
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    run_ctest asan build/asan with_display
}

# libFuzzer targets (tests/fuzz, docs/reliability/fuzzing.md) from the asan stage's build (built here if
# that stage did not run), each run for FUZZ_SECONDS on a copy of its committed corpus. A crash
# fails the stage; the input is kept in build/asan/crashes/ (commit it under tests/fuzz/corpus/
# with the fix).
read -r -a FUZZ_TARGETS <<< "${FUZZ_TARGETS:-fuzz_raw fuzz_camera_path fuzz_image fuzz_edit_json fuzz_edit_state fuzz_lua fuzz_world}"
fuzz() {
  local dir=build/asan t rc=0 secs=${FUZZ_SECONDS:-30}
  mkdir -p "$dir/crashes"
  configure "$dir" "${ASAN_CMAKE_ARGS[@]}" || return 1
  cmake --build "$dir" -j "$JOBS" --target "${FUZZ_TARGETS[@]}" || return 1
  local sym=/usr/lib/llvm-14/bin/llvm-symbolizer
  [ -x "$sym" ] && export ASAN_SYMBOLIZER_PATH=$sym
  for t in "${FUZZ_TARGETS[@]}"; do
    local work=$dir/fuzz_corpus/$t dict=tests/fuzz/$t.dict extra=()
    mkdir -p "$work"
    [ -f "$dict" ] && extra+=(-dict="$dict")
    ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
      "$dir/tests/fuzz/$t" -max_total_time="$secs" -seed="${FUZZ_SEED:-1}" -timeout=20 -rss_limit_mb=2560 -max_len=8192 \
      -print_final_stats=1 -artifact_prefix="$dir/crashes/$t-" "${extra[@]}" \
      "$work" "tests/fuzz/corpus/$t" > "$dir/$t.log" 2>&1
    local r=$?
    # One line per target: executions, coverage, corpus size (docs/reliability/fuzzing.md quotes these).
    echo "$t: exit $r, $(grep -o 'stat::number_of_executed_units: *[0-9]*' "$dir/$t.log" |
      grep -o '[0-9]*$') execs, $(grep -o 'cov: [0-9]* ft: [0-9]*' "$dir/$t.log" | tail -1),"\
      "corpus $(find "$work" -type f | wc -l) files"
    if [ $r -ne 0 ]; then rc=1; tail -60 "$dir/$t.log"; fi
  done
  return $rc
}

rc=0
for s in $STAGES; do
  stage "$s" "$s" || rc=1
done
echo "=== all stages took $((SECONDS - total0)) s"
exit $rc
