#!/usr/bin/env bash
# Builds and runs every test: the normal build and its tests, then an AddressSanitizer +
# UndefinedBehaviorSanitizer build of the tests. Installs missing Debian packages first.
# Usage: scripts/test.sh            (all stages)
#        STAGES="release" scripts/test.sh   (a subset: release asan)
set -uo pipefail
source "$(dirname "$0")/lib/common.sh"
cd "$RIDGELINE_ROOT"

STAGES=${STAGES:-"release asan"}
JOBS=$(nproc)
total0=$SECONDS

stage "packages" ensure_packages "${RIDGELINE_PACKAGES[@]}" clang-14 libclang-rt-14-dev || exit 1

# Khronos' glTF-Validator for the .glb export test, when npm is there (the test skips otherwise).
install_gltf_validator() {
  local dir=$1/tools/gltf-validator
  [ -d "$dir/node_modules/gltf-validator" ] && return 0
  command -v npm > /dev/null || return 0
  mkdir -p "$dir" && npm install --prefix "$dir" --no-audit --no-fund gltf-validator > /dev/null 2>&1 ||
    echo "note: could not install gltf-validator; the .glb validation test will be skipped"
}

release() {
  configure_and_build build/release -DCMAKE_BUILD_TYPE=Release || return 1
  install_gltf_validator build/release
  # Under Xvfb when there is no display: the game's OpenGL tests need an X server for GLFW
  # (they skip with exit 77 where no context can be made; EGL needs none).
  (cd build/release && LP_NUM_THREADS=2 with_display ctest --output-on-failure -j "$JOBS")
}

asan() {
  # clang for the sanitizer build (the same build will carry the fuzzers).
  configure_and_build build/asan -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_COMPILER=clang++-14 -DRIDGELINE_SANITIZE=address,undefined \
    -DRIDGELINE_BUILD_BENCHMARKS=OFF || return 1
  # Readable sanitizer stacks where llvm-symbolizer is installed (suppressions do not need it).
  local sym=/usr/lib/llvm-14/bin/llvm-symbolizer
  [ -x "$sym" ] && export ASAN_SYMBOLIZER_PATH=$sym
  (cd build/asan && ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 \
     UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 ctest --output-on-failure -j "$JOBS")
}

rc=0
for s in $STAGES; do
  stage "$s" "$s" || rc=1
done
echo "=== all stages took $((SECONDS - total0)) s"
exit $rc
