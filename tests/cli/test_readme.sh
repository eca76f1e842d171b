#!/usr/bin/env bash
# Runs the README's snippets as a newcomer would, so that they fail here when they drift:
#  - every ```sh block, as written, from the repository's root (HOME points at a scratch folder,
#    so the quick start's `--prefix "$HOME/ridgeline"` installs there), except the block of the
#    three scripts (scripts/test.sh is what CI runs; it would run itself);
#  - the ```cpp block compiled and run inside main() (the engine's `upload` stubbed), built by a
#    CMake project made of the ```cmake block, against the package the quick start installed.
# Usage: test_readme.sh SOURCE_DIR SCRATCH_DIR CXX_COMPILER
set -uo pipefail
src=$1 work=$2 cxx=$3
readme=$src/README.md
rm -rf "$work"; mkdir -p "$work/home"
failed=0 ran=0
rm -f "$src/out/m.glb"  # the ridge block writes it again

# blocks LANG: writes each ```LANG block of the README to $work/LANG.N, prints their count.
blocks() {
  awk -v lang="$1" -v dir="$work" '
    $0 == "```" lang { n++; on = 1; file = dir "/" lang "." n; printf "" > file; next }
    on && $0 == "```" { on = 0; close(file); next }
    on { print > file }
    END { print n + 0 }' "$readme"
}

n=$(blocks sh)
[ "$n" -ge 4 ] || { echo "FAIL: README has $n sh blocks; expected the scripts, the quick start, Lua and ridge"; exit 1; }
quick_start=""
for k in $(seq 1 "$n"); do
  b=$work/sh.$k
  if grep -q '^scripts/test.sh' "$b"; then
    echo "block $k: the three scripts: not run here ($(grep -c '^scripts/' "$b") commands)"
    continue
  fi
  grep -q '^cmake --install\|cmake --install' "$b" && quick_start=$k
  echo "block $k: running $(grep -vc '^\s*$' "$b") lines"
  (cd "$src" && HOME=$work/home bash -euo pipefail "$b") > "$work/sh.$k.out" 2> "$work/sh.$k.err"
  rc=$?
  ran=$((ran + 1))
  if [ $rc -ne 0 ]; then
    failed=$((failed + 1))
    echo "FAIL: README sh block $k exited $rc:"; sed 's/^/  | /' "$b"
    echo "  stderr:"; tail -20 "$work/sh.$k.err" | sed 's/^/  | /'
  elif [ ! -s "$work/sh.$k.out" ] && ! grep -q '^cmake' "$b"; then
    failed=$((failed + 1)); echo "FAIL: README sh block $k printed nothing"
  fi
done
# What the blocks say they do, checked.
lua_out=$(grep -l 'lua5.4' "$work"/sh.*[0-9] 2>/dev/null | head -1)
if [ -n "$lua_out" ]; then
  h=$(tail -1 "$lua_out.out")
  awk -v h="$h" 'BEGIN { exit !(h + 0 > 16 && h + 0 < 219) }' ||
    { failed=$((failed + 1)); echo "FAIL: the Lua one-liner printed '$h', not a height of the default terrain"; }
else
  failed=$((failed + 1)); echo "FAIL: no Lua one-liner in the README"
fi
[ -s "$src/out/m.glb" ] || { failed=$((failed + 1)); echo "FAIL: the ridge block wrote no out/m.glb"; }

# The C++ and CMake snippets against the installed package.
if [ -z "$quick_start" ] || [ ! -d "$work/home/ridgeline" ]; then
  failed=$((failed + 1)); echo "FAIL: no quick start installed into \$HOME/ridgeline"
else
  [ "$(blocks cpp)" = 1 ] && [ "$(blocks cmake)" = 1 ] ||
    { echo "FAIL: expected one cpp and one cmake block in the README"; exit 1; }
  p=$work/consumer; mkdir -p "$p"
  {
    echo 'cmake_minimum_required(VERSION 3.25)'
    echo 'project(ReadmeSnippet LANGUAGES CXX)'
    echo 'set(CMAKE_CXX_STANDARD 20)'
    echo 'add_executable(mygame main.cpp)'
    cat "$work/cmake.1"
  } > "$p/CMakeLists.txt"
  {
    grep '^#include' "$work/cpp.1"
    echo '#include <cstdint>'
    echo '#include <cstdio>'
    echo '// The engine uploads a patch mesh to the GPU; here nothing.'
    echo 'template <class Mesh> void upload(std::uint32_t, const Mesh&) {}'
    echo 'int main() {'
    grep -v '^#include' "$work/cpp.1"
    echo '  std::printf("readme C++ snippet: %u triangles\n", stats.triangles);'
    echo '  return stats.triangles > 0 ? 0 : 1;'
    echo '}'
  } > "$p/main.cpp"
  if cmake -S "$p" -B "$p/build" -G Ninja -DCMAKE_CXX_COMPILER="$cxx" \
       -DCMAKE_PREFIX_PATH="$work/home/ridgeline" > "$p/configure.log" 2>&1 &&
     cmake --build "$p/build" > "$p/build.log" 2>&1 && "$p/build/mygame"; then
    ran=$((ran + 1))
  else
    failed=$((failed + 1))
    echo "FAIL: the README's C++ snippet (in main(), built by its CMake lines) did not build or run:"
    tail -30 "$p/configure.log" "$p/build.log" 2>/dev/null | sed 's/^/  | /'
  fi
fi
echo "README snippets: $ran ran, $failed failed"
[ "$failed" = 0 ]
