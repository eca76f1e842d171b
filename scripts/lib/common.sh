# Shared by scripts/game.sh, scripts/demo.sh and scripts/test.sh: package installation and the
# build.
# shellcheck shell=bash

RIDGELINE_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)

# Debian packages the build, the tests and the game need (--no-install-recommends). Bullet
# Physics: Ridgeline::bullet, its tests and benchmark, and the game's bodies and vehicles. The game:
# GLFW, Dear ImGui, EGL and Mesa's software renderer; xvfb + xauth give it a display in CI.
RIDGELINE_PACKAGES=(
  g++ cmake ninja-build pkg-config git ca-certificates
  libglm-dev libopenimageio-dev libtinygltf-dev nlohmann-json3-dev libcli11-dev libdeflate-dev
  libgtest-dev libbenchmark-dev liblua5.4-dev lua5.4 libbullet-dev
  libglfw3-dev libimgui-dev libegl-dev libgl1-mesa-dri libegl-mesa0 libglx-mesa0
  xvfb xauth
)
# Only for scripts/report.sh (the speed-versus-error report): plots and the CSV-to-plot step.
RIDGELINE_REPORT_PACKAGES=(gnuplot-nox python3)

# Installs the given Debian packages that are missing, through sudo when not root.
ensure_packages() {
  local missing=() p
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  echo "installing: ${missing[*]}"
  local sudo=()
  [ "$(id -u)" -eq 0 ] || sudo=(sudo)
  export DEBIAN_FRONTEND=noninteractive
  "${sudo[@]}" apt-get update -qq
  "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" > /dev/null
}

# fetch_test_data [DIR]: data no one here made, for the tests that read real files (default
# build/test-data, the tests' RIDGELINE_TEST_EXTERNAL_DATA): Debian's r-cran-terra example
# rasters (elev.tif: a real DEM in degrees; meuse.tif: one in projected metres), taken from the
# package without installing R (apt-get download, dpkg -x). The ctest fixture fetch_terra_data
# runs it too. Returns 1 with a message when the package cannot be fetched (those tests then
# fail, naming the missing file).
fetch_test_data() {
  local dir=${1:-$RIDGELINE_ROOT/build/test-data}
  local ex=$dir/terra/usr/lib/R/site-library/terra/ex
  [ -f "$ex/elev.tif" ] && [ -f "$ex/meuse.tif" ] && return 0
  mkdir -p "$dir"
  local sudo=()
  [ "$(id -u)" -eq 0 ] || sudo=(sudo)
  (cd "$dir" && rm -f r-cran-terra_*.deb &&
    { apt-get download r-cran-terra > /dev/null 2>&1 ||
      { "${sudo[@]}" apt-get update -qq > /dev/null && apt-get download r-cran-terra > /dev/null; }; } &&
    rm -rf terra && dpkg -x r-cran-terra_*.deb terra && rm -f r-cran-terra_*.deb) ||
    { echo "error: could not fetch r-cran-terra (apt-get download); the tests on elev.tif and" \
        "meuse.tif need it"; return 1; }
  [ -f "$ex/elev.tif" ] && [ -f "$ex/meuse.tif" ] ||
    { echo "error: r-cran-terra holds no $ex/elev.tif or meuse.tif"; return 1; }
  echo "r-cran-terra's example rasters: fetched into $dir/terra"
}

# configure BUILD_DIR [cmake args...]: configures BUILD_DIR with Ninja (the log in
# BUILD_DIR.configure.log, printed when configuring fails).
configure() {
  local dir=$1; shift
  mkdir -p "$dir"
  cmake -S "$RIDGELINE_ROOT" -B "$dir" -G Ninja "$@" > "$dir.configure.log" 2>&1 || {
    cat "$dir.configure.log"; return 1; }
}

# configure_and_build BUILD_DIR [cmake args...]: configures, then builds every target.
configure_and_build() {
  local dir=$1; shift
  configure "$dir" "$@" && cmake --build "$dir" -j "$(nproc)"
}

# The one Release build every script and the README's commands share: build/release, configured
# with the defaults (everything on), so that no script's options undo another's. Every script
# builds it through build_release and nothing else (tests/cli/check_scripts.sh, ctest
# `scripts_one_release_layout`, fails on a script that configures it any other way).
RIDGELINE_RELEASE_DIR=build/release
RIDGELINE_RELEASE_ARGS=(-DCMAKE_BUILD_TYPE=Release -DRIDGELINE_BUILD_TESTS=ON
  -DRIDGELINE_BUILD_BENCHMARKS=ON -DRIDGELINE_BUILD_TOOLS=ON -DRIDGELINE_BUILD_LUA=ON
  -DRIDGELINE_BUILD_BULLET=ON -DRIDGELINE_BUILD_GAME=ON -DRIDGELINE_PORTABLE=OFF)

# build_release [TARGET...]: configures build/release and builds the given targets (all when
# none is given).
build_release() {
  local dir=$RIDGELINE_ROOT/$RIDGELINE_RELEASE_DIR targets=()
  [ $# -gt 0 ] && targets=(--target "$@")
  configure "$dir" "${RIDGELINE_RELEASE_ARGS[@]}" || return 1
  cmake --build "$dir" -j "$(nproc)" "${targets[@]}"
}

# stage NAME COMMAND...: runs a stage and prints its wall time.
stage() {
  local name=$1; shift
  local t0=$SECONDS
  echo "=== stage: $name"
  "$@"
  local rc=$?
  echo "=== stage: $name took $((SECONDS - t0)) s (exit $rc)"
  return $rc
}

# Runs a command under a virtual X server when there is no display and xvfb-run exists, so that
# the game's window and hidden-window tests run in CI; runs it directly otherwise.
with_display() {
  if [ -z "${DISPLAY:-}" ] && command -v xvfb-run > /dev/null; then
    xvfb-run -a -s "-screen 0 1280x720x24" "$@"
  else
    "$@"
  fi
}
