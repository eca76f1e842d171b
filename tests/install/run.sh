#!/usr/bin/env bash
# Installs the build tree into a scratch prefix, then configures, builds and runs an outside
# project that uses find_package(Ridgeline CONFIG REQUIRED) (all four targets) and, separately,
# pkg-config (the core), and loads the installed ridgeline.so into the stock lua5.4.
set -euo pipefail
build=$1 work=$2 cxx=$3
here=$(cd "$(dirname "$0")" && pwd)
rm -rf "$work"; mkdir -p "$work"
cmake --install "$build" --prefix "$work/prefix" > "$work/install.log"
cmake -S "$here/consumer" -B "$work/build" -G Ninja -DCMAKE_CXX_COMPILER="$cxx" \
  -DCMAKE_PREFIX_PATH="$work/prefix" > "$work/configure.log"
cmake --build "$work/build" > "$work/build.log"
"$work/build/consumer"
# Ridgeline::io and Ridgeline::lua, and ridgeline.so from the stock interpreter.
if [ -f "$work/prefix/lib/lua/5.4/ridgeline.so" ]; then
  "$work/build/consumer_full" "$work/flat.r16"
  LUA_CPATH="$work/prefix/lib/lua/5.4/?.so" lua5.4 -e \
    'local r = require "ridgeline"; local t = r.default_terrain(); assert(type(t:height(10, 10)) == "number"); print("lua5.4: require ridgeline ok")'
else
  echo "install consumer: the package was built without Ridgeline::lua" >&2; exit 1
fi
# Ridgeline::bullet (optional: built when Bullet was found): a Bullet world on the installed shape.
if grep -q '^RIDGELINE_BUILD_BULLET:BOOL=ON' "$build/CMakeCache.txt"; then
  [ -x "$work/build/consumer_bullet" ] ||
    { echo "install consumer: Ridgeline::bullet was built but the package lacks it" >&2; exit 1; }
  "$work/build/consumer_bullet"
else
  echo "install consumer: built without Ridgeline::bullet (RIDGELINE_BUILD_BULLET=OFF): not tried"
fi
# pkg-config route
PKG_CONFIG_PATH="$work/prefix/lib/pkgconfig:$work/prefix/lib/x86_64-linux-gnu/pkgconfig" \
  "$cxx" -std=c++20 "$here/consumer/main.cpp" -o "$work/consumer_pc" \
  $(PKG_CONFIG_PATH="$work/prefix/lib/pkgconfig:$work/prefix/lib/x86_64-linux-gnu/pkgconfig" pkg-config --cflags --libs ridgeline)
"$work/consumer_pc"
echo "install consumer: ok"
