#!/usr/bin/env bash
# The layers of module/src and module/include/ridgeline (docs/architecture.md, "Layers"): every
# file may include only headers of its own level or below, so no component reaches up into one
# built on it; and the core (Ridgeline::terrain, everything but io/) includes no GL, windowing,
# Lua, image, glTF, JSON or physics header. Fails naming the file, the line and both levels.
# Usage: check_layers.sh REPO_ROOT
set -u
root=${1:?usage: check_layers.sh REPO_ROOT}
cd "$root/module" || exit 1

# level FILE: the level of a file (a path under module/, or an include as written: "x/y.h" or
# "ridgeline/z.h"); empty for files outside the table (standard and third-party headers).
level() {
  case $1 in
    # 0: plain data and utilities every layer may use.
    */result.h | */log.h | src/log.cpp | */heightfield.h | */world.h | */camera.h | src/camera.cpp | \
      */lattice_cell.h | */edit_limits.h | */budget_controller.h | src/budget_controller.cpp | \
      format.h | src/format.h | platform/* | src/platform/*) echo 0 ;;
    # 1: the stored pages, and the procedural detail function and its tiles.
    world/* | src/world/* | */detail.h | src/detail/detail.cpp | src/detail/detail_cache.cpp) echo 1 ;;
    # 2: the surface: heightfield, Surface, its queries, lattices, the edit layer, rays.
    surface/* | src/surface/* | */surface.h) echo 2 ;;
    # 3: the terrain: surface + ray hierarchy + change log.
    */terrain.h | src/terrain.cpp | change_log.h | src/change_log.h) echo 3 ;;
    # 4: what reads a terrain without changing it: the measurement of drawn meshes, detail
    #    streaming for a camera.
    */mesh_error.h | src/mesh_error.cpp | */detail_stream.h | src/detail/detail_stream.cpp) echo 4 ;;
    # 5: the edit transaction and its file, the tessellator (a view's leaves included).
    edit/* | src/edit/* | */edit.h | roam/* | src/roam/* | */landscape.h | */roam_view.h | \
      */roam_memory.h | src/leaves_mesh.cpp) echo 5 ;;
    # 6: Ridgeline::io (files, images, glTF, JSON, baked worlds).
    io/* | src/io/* | */io.h | */edit_file.h | */edit_json.h | */camera_path.h | \
      */gltf_export.h | */world_file.h) echo 6 ;;
  esac
}

failed=0
checked=0
while IFS= read -r f; do
  own=$(level "$f")
  if [ -z "$own" ]; then
    echo "FAIL: module/$f has no level: add it to tests/cli/check_layers.sh (and docs/architecture.md)"
    failed=1
    continue
  fi
  checked=$((checked + 1))
  n=0
  while IFS= read -r line; do
    n=$((n + 1))
    [[ "$line" =~ ^[[:space:]]*#[[:space:]]*include[[:space:]]*[\"\<]([^\"\>]+)[\"\>] ]] || continue
    inc=${BASH_REMATCH[1]}
    if [ "$own" -lt 6 ]; then
      case $inc in
        GL/* | GLFW/* | EGL/* | lua.h* | lauxlib.h | lualib.h | OpenImageIO/* | tiffio.h | png.h | \
          tiny_gltf.h | nlohmann/* | btBulletCollisionCommon.h | btBulletDynamicsCommon.h | \
          BulletCollision/* | BulletDynamics/* | imgui* | CLI/* | libdeflate.h)
          echo "FAIL: module/$f:$n: the core includes <$inc> (GL, windowing, Lua, images, glTF, JSON and physics stay out of Ridgeline::terrain)"
          failed=1
          continue ;;
      esac
    fi
    dep=$(level "$inc")
    [ -z "$dep" ] && continue
    if [ "$dep" -gt "$own" ]; then
      echo "FAIL: module/$f:$n includes $inc: level $own reaches up to level $dep"
      failed=1
    fi
  done < "$f"
done < <(find src include/ridgeline -name '*.cpp' -o -name '*.h' | sort)
[ $failed -eq 0 ] && echo "layers: $checked files include only their own level or below"
exit $failed
