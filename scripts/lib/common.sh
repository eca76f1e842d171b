# Shared by scripts/game.sh, scripts/demo.sh and scripts/test.sh: package installation and the
# build.
# shellcheck shell=bash

RIDGELINE_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)

# Debian packages the build, the tests and the game need (--no-install-recommends). The game:
# GLFW, Dear ImGui, EGL and Mesa's software renderer; xvfb + xauth give it a display in CI.
RIDGELINE_PACKAGES=(
  g++ cmake ninja-build pkg-config git ca-certificates
  libglm-dev libopenimageio-dev libtinygltf-dev nlohmann-json3-dev libcli11-dev
  libgtest-dev libbenchmark-dev liblua5.4-dev lua5.4
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

# configure_and_build BUILD_DIR [cmake args...]
configure_and_build() {
  local dir=$1; shift
  mkdir -p "$dir"
  cmake -S "$RIDGELINE_ROOT" -B "$dir" -G Ninja "$@" > "$dir.configure.log" 2>&1 || {
    cat "$dir.configure.log"; return 1; }
  cmake --build "$dir" -j "$(nproc)"
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
