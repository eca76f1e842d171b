#!/usr/bin/env bash
# Builds and runs every test: the normal build and its tests, then an AddressSanitizer +
# UndefinedBehaviorSanitizer build of the tests, then the fuzz targets (libFuzzer, bounded time).
# Installs missing Debian packages first.
# Usage: scripts/test.sh            (all stages)
#        STAGES="release" scripts/test.sh   (a subset: release asan fuzz)
#        FUZZ_SECONDS=600 FUZZ_SEED=$RANDOM STAGES=fuzz scripts/test.sh   (a longer, fresh fuzz run;
#        default 30 s a target with the fixed seed 1, so that CI explores the same inputs each run)
set -uo pipefail
source "$(dirname "$0")/lib/common.sh"
cd "$RIDGELINE_ROOT"

STAGES=${STAGES:-"release asan fuzz"}
JOBS=$(nproc)
total0=$SECONDS

stage "packages" ensure_packages "${RIDGELINE_PACKAGES[@]}" clang-14 libclang-rt-14-dev || exit 1
# Real DEMs for the loader tests (build/test-data; they skip when it cannot be fetched).
fetch_test_data

# Khronos' glTF-Validator for the .glb export test, when npm is there (the test skips otherwise).
install_gltf_validator() {
  local dir=$1/tools/gltf-validator
  [ -d "$dir/node_modules/gltf-validator" ] && return 0
  command -v npm > /dev/null || return 0
  mkdir -p "$dir" && npm install --prefix "$dir" --no-audit --no-fund gltf-validator > /dev/null 2>&1 ||
    echo "note: could not install gltf-validator; the .glb validation test will be skipped"
}

release() {
  build_release || return 1
  install_gltf_validator build/release
  # Under Xvfb when there is no display: the game's OpenGL tests need an X server for GLFW
  # (they skip with exit 77 where no context can be made; EGL needs none).
  (cd build/release && LP_NUM_THREADS=2 with_display ctest --output-on-failure -j "$JOBS")
}

# One clang build with ASan, UBSan and libFuzzer instrumentation serves the sanitizer tests and
# the fuzz stage (the fuzz targets are libFuzzer binaries there; ctest replays their corpus).
ASAN_CMAKE_ARGS=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++-14
  -DRIDGELINE_SANITIZE=address,undefined -DRIDGELINE_FUZZ=ON -DRIDGELINE_BUILD_BENCHMARKS=OFF)

asan() {
  configure_and_build build/asan "${ASAN_CMAKE_ARGS[@]}" || return 1
  # Readable sanitizer stacks where llvm-symbolizer is installed (suppressions do not need it).
  local sym=/usr/lib/llvm-14/bin/llvm-symbolizer
  [ -x "$sym" ] && export ASAN_SYMBOLIZER_PATH=$sym
  (cd build/asan && ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 \
     UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 ctest --output-on-failure -j "$JOBS")
}

# libFuzzer targets (tests/fuzz, docs/reliability.md) from the asan stage's build (built here if
# that stage did not run), each run for FUZZ_SECONDS on a copy of its committed corpus. A crash
# fails the stage; the input is kept in build/asan/crashes/ (commit it under tests/fuzz/corpus/
# with the fix).
FUZZ_TARGETS=(fuzz_raw fuzz_camera_path fuzz_image fuzz_edit_json fuzz_edit_state fuzz_lua)
fuzz() {
  local dir=build/asan t rc=0 secs=${FUZZ_SECONDS:-30}
  mkdir -p "$dir/crashes"
  cmake -S "$RIDGELINE_ROOT" -B "$dir" -G Ninja "${ASAN_CMAKE_ARGS[@]}" > "$dir.configure.log" 2>&1 ||
    { cat "$dir.configure.log"; return 1; }
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
    # One line per target: executions, coverage, corpus size (docs/reliability.md quotes these).
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
